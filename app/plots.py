"""Figures of a run, like the thesis's: north, east and heading against the reference over
time; the north-east track; commanded forces and thruster utilisation."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from control import loop


def _legs(ax, legs) -> None:
    for leg in legs:
        ax.axvline(leg.start_s, color="0.85", lw=0.8, zorder=0)


def pose_figure(data: NDArray[np.float64], legs, path: Path, title: str) -> Path:
    t = data[:, loop.L_T]
    fig, axes = plt.subplots(3, 1, figsize=(10, 7.5), sharex=True)
    labels = ("north [m]", "east [m]", "heading [deg]")
    for i, ax in enumerate(axes):
        if i < 2:
            actual, ref = data[:, loop.L_TREE + i], data[:, loop.L_ETA_D + i]
            est = data[:, loop.L_ETA_HAT + i]
        else:
            actual = np.degrees(np.unwrap(data[:, loop.L_TREE + 5]))
            ref = np.degrees(data[:, loop.L_ETA_D + 2])
            est = np.degrees(data[:, loop.L_ETA_HAT + 2])
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


def track_figure(data: NDArray[np.float64], path: Path, title: str,
                 crane_tip_n: NDArray[np.float64] | None = None) -> Path:
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.plot(data[:, loop.L_ETA_D + 1], data[:, loop.L_ETA_D], "k--", lw=1, label="reference")
    ax.plot(data[:, loop.L_TREE + 1], data[:, loop.L_TREE], color="tab:red", lw=1.2,
            label="tree")
    ax.plot(data[:, loop.L_ROV + 1], data[:, loop.L_ROV], color="tab:blue", lw=0.8,
            alpha=0.7, label="ROV")
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


def forces_figure(data: NDArray[np.float64], n_thrusters: int, legs, path: Path,
                  title: str) -> Path:
    t = data[:, loop.L_T]
    fig, axes = plt.subplots(3, 1, figsize=(10, 7.5), sharex=True)
    names = ("surge X [N]", "sway Y [N]", "yaw N [N m]")
    for i, name in enumerate(names):
        axes[0].plot(t, data[:, loop.L_TAU_TREE + i], lw=1, label=name)
    axes[0].set_ylabel("commanded on the tree")
    axes[0].legend(fontsize=8)
    for i, j in enumerate((0, 1, 5)):
        axes[1].plot(t, data[:, loop.L_TAU_ACH + j], lw=1, label=("X", "Y", "N")[i])
    axes[1].set_ylabel("achieved by the ROV")
    axes[1].legend(fontsize=8)
    for k in range(n_thrusters):
        axes[2].plot(t, data[:, loop.L_UTIL + k], lw=0.8, label=f"thruster {k + 1}")
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
    data = result.log.data
    name = result.name
    return [
        pose_figure(data, result.legs, out_dir / f"{name}-pose.png", f"{name}: pose"),
        track_figure(data, out_dir / f"{name}-track.png", f"{name}: north-east track",
                     crane_tip_n),
        forces_figure(data, result.log.n_thrusters, result.legs,
                      out_dir / f"{name}-forces.png", f"{name}: forces and thrusters"),
    ]
