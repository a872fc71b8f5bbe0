"""Figures of a run, like the thesis's: north, east and heading against the reference over
time; the north-east track; commanded forces and thruster utilisation."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from control.columns import LogRows


def _legs(ax, legs) -> None:
    for leg in legs:
        ax.axvline(leg.start_s, color="0.85", lw=0.8, zorder=0)


def pose_figure(rows: LogRows, legs, path: Path, title: str) -> Path:
    t = rows.t_s
    tree, ref_all, est_all = rows["tree_eta_n"], rows["eta_ref_n"], rows["eta_hat_n"]
    fig, axes = plt.subplots(3, 1, figsize=(10, 7.5), sharex=True)
    labels = ("north [m]", "east [m]", "heading [deg]")
    for i, ax in enumerate(axes):
        if i < 2:
            actual, ref, est = tree[:, i], ref_all[:, i], est_all[:, i]
        else:
            actual = np.degrees(np.unwrap(tree[:, 5]))
            ref = np.degrees(ref_all[:, 2])
            est = np.degrees(est_all[:, 2])
        ax.plot(t, ref, "k--", lw=1, label="reference")
        ax.plot(t, est, color="tab:green", lw=0.8, alpha=0.8, label="estimate")
        ax.plot(t, actual, color="tab:red", lw=1.2, label="tree")
        ax.set_ylabel(labels[i])
        _legs(ax, legs)
    axes[0].legend(loc="best", fontsize=8)
    axes[0].set_title(title)
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def track_figure(
    rows: LogRows, path: Path, title: str, crane_tip_n: NDArray[np.float64] | None = None
) -> Path:
    fig, ax = plt.subplots(figsize=(7, 7))
    ref, tree, rov = rows["eta_ref_n"], rows["tree_eta_n"], rows["rov_eta_n"]
    ax.plot(ref[:, 1], ref[:, 0], "k--", lw=1, label="reference")
    ax.plot(tree[:, 1], tree[:, 0], color="tab:red", lw=1.2, label="tree")
    ax.plot(rov[:, 1], rov[:, 0], color="tab:blue", lw=0.8, alpha=0.7, label="ROV")
    if crane_tip_n is not None:
        ax.plot(crane_tip_n[1], crane_tip_n[0], "k^", label="crane tip")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def forces_figure(rows: LogRows, legs, path: Path, title: str) -> Path:
    t = rows.t_s
    tau_tree, tau_ach, util = (
        rows["tau_tree_cmd"],
        rows["tau_rov_ach_b"],
        rows["thruster_utilisation"],
    )
    n_thrusters = rows.n_thrusters
    fig, axes = plt.subplots(3, 1, figsize=(10, 7.5), sharex=True)
    names = ("surge X [N]", "sway Y [N]", "yaw N [N m]")
    for i, name in enumerate(names):
        axes[0].plot(t, tau_tree[:, i], lw=1, label=name)
    axes[0].set_ylabel("commanded on the tree")
    axes[0].legend(fontsize=8)
    for i, j in enumerate((0, 1, 5)):
        axes[1].plot(t, tau_ach[:, j], lw=1, label=("X", "Y", "N")[i])
    axes[1].set_ylabel("achieved by the ROV")
    axes[1].legend(fontsize=8)
    for k in range(n_thrusters):
        axes[2].plot(t, util[:, k], lw=0.8, label=f"thruster {k + 1}")
    axes[2].axhline(1.0, color="tab:red", lw=0.8, ls=":")
    axes[2].set_ylim(0, 1.05)
    axes[2].set_ylabel("utilisation")
    axes[2].legend(fontsize=8, ncol=n_thrusters)
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        _legs(ax, legs)
    axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def mission_figures(result, out_dir: Path, crane_tip_n=None) -> list[Path]:
    """All three figures of a mission result into ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    data = result.log
    name = result.name
    return [
        pose_figure(data, result.legs, out_dir / f"{name}-pose.png", f"{name}: pose"),
        track_figure(data, out_dir / f"{name}-track.png", f"{name}: north-east track", crane_tip_n),
        forces_figure(
            data, result.legs, out_dir / f"{name}-forces.png", f"{name}: forces and thrusters"
        ),
    ]
