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
from sim.docking import DockingFrame, DockingLayout


def _legs(ax, legs, t0_s: float, t1_s: float) -> None:
    """A line where each leg starts (its ``start_s`` counts from the first row, at ``t0_s``),
    and the time axis over the rows alone, [t0_s, t1_s]: a run that starts at 410 s in its
    recording is not drawn from 0."""
    if t1_s > t0_s:
        ax.set_xlim(t0_s, t1_s)
    for leg in legs:
        ax.axvline(t0_s + leg.start_s, color="0.85", lw=0.8, zorder=0)


def _robust_limits(ax, *series: NDArray[np.float64], pad: float = 0.15) -> None:
    """Y limits from the 0.5 to 99.5 percentiles of what is drawn: a transient of a second
    (a hook-up, an observer restart) does not squash the rest of the run into a line."""
    values = np.concatenate([np.asarray(v, float).ravel() for v in series])
    values = values[np.isfinite(values)]
    if values.size == 0:
        return
    lo, hi = np.percentile(values, [0.5, 99.5])
    span = max(hi - lo, 1e-6)
    ax.set_ylim(lo - pad * span, hi + pad * span)


def pose_figure(rows: LogRows, legs, path: Path, title: str) -> Path:
    """North, east and heading against the reference and the estimate, each with its error
    (true minus reference) below it."""
    t = rows.t_s
    tree, ref_all, est_all = rows["tree_eta_n"], rows["eta_ref_n"], rows["eta_hat_n"]
    fig, axes = plt.subplots(
        6, 1, figsize=(10, 11), sharex=True, gridspec_kw={"height_ratios": [2, 1] * 3}
    )
    labels = ("north [m]", "east [m]", "heading [deg]")
    for i in range(3):
        ax, ax_err = axes[2 * i], axes[2 * i + 1]
        if i < 2:
            actual, ref, est = tree[:, i], ref_all[:, i], est_all[:, i]
            err = actual - ref
        else:
            actual = np.degrees(np.unwrap(tree[:, 5]))
            ref = np.degrees(ref_all[:, 2])
            est = np.degrees(est_all[:, 2])
            err = np.degrees(np.angle(np.exp(1j * (tree[:, 5] - ref_all[:, 2]))))
        ax.plot(t, ref, "k--", lw=1, label="reference")
        ax.plot(t, est, color="tab:green", lw=0.8, alpha=0.8, label="estimate")
        ax.plot(t, actual, color="tab:red", lw=1.2, label="tree")
        _robust_limits(ax, ref, actual)
        ax.set_ylabel(labels[i])
        ax_err.plot(t, err, color="tab:red", lw=0.8)
        ax_err.axhline(0.0, color="0.5", lw=0.6)
        _robust_limits(ax_err, err)
        ax_err.set_ylabel("error " + labels[i].split(" ")[-1])
        _legs(ax, legs, float(t[0]), float(t[-1]))
        _legs(ax_err, legs, float(t[0]), float(t[-1]))
    axes[0].legend(loc="best", fontsize=8)
    axes[0].set_title(title)
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def track_figure(
    rows: LogRows,
    path: Path,
    title: str,
    crane_tip_n: NDArray[np.float64] | None = None,
    docking: tuple[DockingFrame, DockingLayout] | None = None,
) -> Path:
    """North-east track of the tree, its reference and the ROV, with the crane tip and, when
    the mission has one, the docking frame: its outline and guideposts."""
    fig, ax = plt.subplots(figsize=(7, 7))
    ref, tree, rov = rows["eta_ref_n"], rows["tree_eta_n"], rows["rov_eta_n"]
    ax.plot(ref[:, 1], ref[:, 0], "k--", lw=1, label="reference")
    ax.plot(tree[:, 1], tree[:, 0], color="tab:red", lw=1.2, label="tree")
    ax.plot(rov[:, 1], rov[:, 0], color="tab:blue", lw=0.8, alpha=0.7, label="ROV")
    if crane_tip_n is not None:
        ax.plot(crane_tip_n[1], crane_tip_n[0], "k^", label="crane tip")
    if docking is not None:
        frame, layout = docking
        c, s = np.cos(frame.heading_rad), np.sin(frame.heading_rad)
        half = np.asarray(layout.frame_size_m, float) / 2.0
        corners = np.array([[1, 1], [1, -1], [-1, -1], [-1, 1], [1, 1]]) * half
        north = frame.center_n[0] + c * corners[:, 0] - s * corners[:, 1]
        east = frame.center_n[1] + s * corners[:, 0] + c * corners[:, 1]
        ax.plot(east, north, color="0.35", lw=1.5, label="docking frame")
        posts = np.asarray(frame.post_positions_n(layout))
        ax.plot(posts[:, 1], posts[:, 0], "o", color="0.2", ms=5, label="guideposts")
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
    """Forces [N] and moments [N m] on separate axes, each panel in one frame: the ROV's
    commanded and achieved wrench (ROV axes; they differ where thrusters saturate), the
    controller's demand on the tree (tree axes), and thruster utilisation."""
    t = rows.t_s
    cmd, ach = rows["tau_rov_cmd_b"], rows["tau_rov_ach_b"]
    tau_tree, util = rows["tau_tree_cmd"], rows["thruster_utilisation"]
    n_thrusters = rows.n_thrusters
    fig, axes = plt.subplots(4, 1, figsize=(10, 10), sharex=True)
    for j, (name, color) in enumerate((("surge X", "tab:blue"), ("sway Y", "tab:orange"))):
        axes[0].plot(t, cmd[:, j], color=color, lw=1, label=f"{name} commanded")
        axes[0].plot(t, ach[:, j], color=color, lw=0.8, ls=":", label=f"{name} achieved")
    axes[0].set_ylabel("ROV force [N]\n(ROV axes)")
    axes[0].legend(fontsize=7, ncol=2)
    axes[1].plot(t, cmd[:, 5], color="tab:green", lw=1, label="yaw N commanded")
    axes[1].plot(t, ach[:, 5], color="tab:green", lw=0.8, ls=":", label="yaw N achieved")
    axes[1].set_ylabel("ROV moment [N m]\n(ROV axes)")
    axes[1].legend(fontsize=7)
    axes[2].plot(t, tau_tree[:, 0], lw=1, label="surge X")
    axes[2].plot(t, tau_tree[:, 1], lw=1, label="sway Y")
    axes[2].set_ylabel("demand on the tree [N]\n(tree axes)")
    axes[2].legend(fontsize=7)
    for ax in axes[:3]:
        _robust_limits(ax, *(line.get_ydata() for line in ax.get_lines()))
    for k in range(n_thrusters):
        axes[3].plot(t, util[:, k], lw=0.8, label=f"thruster {k + 1}")
    axes[3].axhline(1.0, color="tab:red", lw=0.8, ls=":")
    axes[3].set_ylim(0, 1.05)
    axes[3].set_ylabel("utilisation [-]")
    axes[3].legend(fontsize=8, ncol=n_thrusters)
    axes[3].set_xlabel("time [s]")
    for ax in axes:
        _legs(ax, legs, float(t[0]), float(t[-1]))
    axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def wire_figure(rows: LogRows, events: list[dict], path: Path, title: str) -> Path:
    """The wire's tension at the tree with the slack limit (10 % of the static tension) and
    the mission's ``wire`` events (missions.seaway): slack spans shaded, snap peaks marked."""
    wire_events = [e for e in events if e.get("kind") == "wire"]
    static = float(wire_events[0]["data"]["static_newton"])
    fig, ax = plt.subplots(figsize=(9, 4))
    ax.plot(rows.t_s, rows["wire_tension"] / 1e3, lw=0.8, label="wire tension at the tree")
    ax.axhline(static / 1e3, color="0.5", ls="--", lw=0.8, label="static (W0)")
    ax.axhline(0.1 * static / 1e3, color="tab:red", ls=":", label="slack limit (10 % of static)")
    for e in wire_events:
        d = e["data"]
        if d["event"] == "slack":
            ax.axvspan(e["t_s"], e["t_s"] + d["duration_s"], color="tab:red", alpha=0.2, lw=0)
        else:
            ax.plot(e["t_s"], d["tension_newton"] / 1e3, "v", color="tab:purple")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tension [kN]")
    ax.set_title(title)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def comparison_figure(
    series: list[tuple[NDArray[np.float64], ...]],
    labels: tuple[str, str],
    aligned_at: str,
    path: Path,
) -> Path:
    """Two runs on one time axis, seconds from the moment they are aligned at: north, east
    and heading errors of the tree against its reference, and the largest thruster use.
    ``series``: per run (t from the alignment, north error, east error, heading error in
    degrees, largest thruster use)."""
    fig, axes = plt.subplots(4, 1, figsize=(10, 9), sharex=True)
    names = ("north error [m]", "east error [m]", "heading error [deg]", "largest thruster use")
    colours = ("tab:blue", "tab:orange")
    for run, label, colour in zip(series, labels, colours, strict=True):
        t = run[0]
        for ax, values in zip(axes, run[1:], strict=True):
            ax.plot(t, values, color=colour, lw=1.0, label=label)
    for ax, name in zip(axes, names, strict=True):
        ax.axvline(0.0, color="0.4", lw=0.8, ls=":")
        ax.axhline(0.0, color="0.8", lw=0.6)
        _robust_limits(ax, *(ax_line.get_ydata() for ax_line in ax.get_lines()[:2]))
        ax.set_ylabel(name)
    axes[0].legend(loc="best", fontsize=8)
    axes[0].set_title(f"two runs, aligned at {aligned_at} (dotted line)")
    axes[-1].set_xlabel("time from the alignment [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def mission_figures(result, out_dir: Path, crane_tip_n=None, docking=None) -> list[Path]:
    """All three figures of a mission result into ``out_dir``, and the wire's tension when the
    mission logged slack wire or snap loads (``wire`` events, elastic wire)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    data = result.log
    name = result.name
    figures = [
        pose_figure(data, result.legs, out_dir / f"{name}-pose.png", f"{name}: pose"),
        track_figure(
            data, out_dir / f"{name}-track.png", f"{name}: north-east track", crane_tip_n, docking
        ),
        forces_figure(
            data, result.legs, out_dir / f"{name}-forces.png", f"{name}: forces and thrusters"
        ),
    ]
    if any(e.get("kind") == "wire" for e in result.events):
        figures.append(
            wire_figure(data, result.events, out_dir / f"{name}-wire.png", f"{name}: lift wire")
        )
    return figures
