"""Thesis control law (eq. 3.9: derivative on the measured velocity) against the same PID with
reference feedforward, on the full-scale rotation and square (thesis 4.1.2).

Prints RMS errors for both and writes figures to docs/figures/:
    law-rotation.png   heading against the reference during the 360 deg turns
    law-square.png     north-east track of the tree around the square

Run: .venv/bin/python scripts/compare_laws.py
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from missions import runner, schema

OUT = Path(__file__).resolve().parents[1] / "docs" / "figures"
LAWS = {"thesis": False, "feedforward": True}


def run_both(name: str) -> dict[str, runner.MissionResult]:
    mission = schema.load_mission(name)
    return {law: runner.run_mission(mission, feedforward=ff) for law, ff in LAWS.items()}


def print_table(name: str, results: dict[str, runner.MissionResult]) -> None:
    print(f"\n{name}")
    print(
        f"  {'law':12s} {'RMS N [m]':>10s} {'RMS E [m]':>10s} {'RMS psi [deg]':>14s} "
        f"{'max util':>9s}"
    )
    for law, r in results.items():
        print(
            f"  {law:12s} {r.rms_north_m:10.4f} {r.rms_east_m:10.4f} "
            f"{r.rms_heading_deg:14.3f} {r.max_thruster_utilisation:9.2f}"
        )
    a, b = results["thesis"], results["feedforward"]
    pos_a = math.hypot(a.rms_north_m, a.rms_east_m)
    pos_b = math.hypot(b.rms_north_m, b.rms_east_m)
    print(
        f"  feedforward: position RMS {pos_a / max(pos_b, 1e-9):.1f}x smaller, heading RMS "
        f"{a.rms_heading_deg / max(b.rms_heading_deg, 1e-9):.1f}x smaller"
    )


def rotation_figure(results: dict[str, runner.MissionResult]) -> Path:
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for law, r in results.items():
        assert r.log is not None
        t = r.log.t_s
        psi = np.degrees(np.unwrap(r.log["tree_eta_n"][:, 5]))
        ref = np.degrees(r.log["eta_ref_n"][:, 2])
        if law == "thesis":
            ax[0].plot(t, ref, "k--", lw=1, label="reference")
        ax[0].plot(t, psi, label=f"heading, {law} law")
        ax[1].plot(t, psi - ref, label=law)
    ax[0].set_ylabel("heading [deg]")
    ax[1].set_ylabel("heading error [deg]")
    ax[1].set_xlabel("time [s]")
    ax[0].legend()
    ax[1].legend()
    ax[0].set_title("Full scale, 400 m: 360 deg CW then CCW")
    path = OUT / "law-rotation.png"
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def square_figure(results: dict[str, runner.MissionResult]) -> Path:
    fig, (ax, ax_err) = plt.subplots(
        1, 2, figsize=(12, 5.5), gridspec_kw={"width_ratios": [1, 1.4]}
    )
    for law, r in results.items():
        assert r.log is not None
        start = int(r.legs[-1].start_s / 0.01)
        ref, tree = r.log["eta_ref_n"][start:], r.log["tree_eta_n"][start:]
        if law == "thesis":
            ax.plot(ref[:, 1], ref[:, 0], "k--", lw=1, label="reference")
        ax.plot(tree[:, 1], tree[:, 0], label=f"tree, {law} law")
        err = np.hypot(tree[:, 0] - ref[:, 0], tree[:, 1] - ref[:, 1])
        ax_err.plot(r.log.t_s[start:], err, label=law)
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal")
    ax.legend()
    ax.set_title("2 x 2 m square, full scale, 400 m")
    ax_err.set_xlabel("time [s]")
    ax_err.set_ylabel("distance from the reference [m]")
    ax_err.set_title("the thesis law lags the moving reference")
    ax_err.legend()
    path = OUT / "law-square.png"
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> None:
    argparse.ArgumentParser(
        description=" ".join(__doc__.split("\n\n")[0].split()), epilog=f"Figures go to {OUT}."
    ).parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    rot = run_both("full-rotation-400")
    print_table("full-rotation-400", rot)
    sq = run_both("full-square-400")
    print_table("full-square-400", sq)
    print(f"\nwrote {rotation_figure(rot)}\nwrote {square_figure(sq)}")


if __name__ == "__main__":
    main()
