"""Speed of the open-loop plant: 600 simulated seconds of the coupled full-scale system
(tree + work-class ROV, current, sensors) at 100 Hz. Prints steps per second and the real-time
factor, the best of several repeats (the first run also compiles, and is reported apart)."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.control_benchmark import (
    _per_call,
    _time_open_step,
    figures,
    load_text,
    plant_costs,
)
from control.simulation import Simulation
from sim import environment as envmod
from sim import params


def plant_current() -> envmod.CurrentParams:
    """The benchmark's current: 0.1 m/s towards 225 deg, walking within +-0.05 m/s and
    +-0.2 rad."""
    d = math.radians(225.0)
    return envmod.CurrentParams(
        speed_mps=0.1,
        direction_rad=d,
        speed_min_mps=0.05,
        speed_max_mps=0.15,
        direction_min_rad=d - 0.2,
        direction_max_rad=d + 0.2,
        speed_walk_mps_per_sqrt_s=0.002,
        direction_walk_rad_per_sqrt_s=0.002,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--duration", type=float, default=600.0, help="simulated seconds")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--params", default="full-scale")
    args = parser.parse_args()
    out = sys.stderr if args.json else sys.stdout  # --json: only the JSON on stdout
    ps = params.load(args.params)
    cur = plant_current()
    t0 = time.perf_counter()
    Simulation(ps, tree_depth_m=400.0, current=cur, control=False).run_for(1.0)
    print(
        f"first run (includes compilation or cache load): {time.perf_counter() - t0:.1f} s",
        file=out,
    )
    best = math.inf
    steps = 0
    for _ in range(args.repeats):
        sim = Simulation(ps, tree_depth_m=400.0, current=cur, control=False)
        t0 = time.perf_counter()
        rows = sim.run_for(args.duration)
        best = min(best, time.perf_counter() - t0)
        steps = len(rows)
    print(f"{args.params}: {args.duration:.0f} s simulated, {steps} steps at 100 Hz", file=out)
    print(
        f"  wall time {best:.3f} s, {steps / best:,.0f} steps/s, "
        f"real-time factor {args.duration / best:,.0f}x, {best / steps * 1e6:.1f} us per step",
        file=out,
    )
    print(f"  ({load_text()})", file=out)
    env = sim._environment_chunk(1)[0]
    n = np.zeros(ps.rov.thrusters.T.shape[1])
    x = sim.plant_state
    cost = {
        **plant_costs(sim),
        "compiled step (RK4, sensors, log row)": _per_call(
            _time_open_step, x, sim.held_y, n, env, sim.arrays
        ),
    }
    if args.json:
        print(json.dumps(figures(steps, args.duration, best, cost), indent=1))
        return
    print(f"cost per call, measured alone, best of 5 (us; {load_text()}):")
    for name, us in cost.items():
        print(f"  {name:38s} {us:7.2f}")


if __name__ == "__main__":
    main()
