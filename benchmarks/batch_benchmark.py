"""The batch stepper against runs alone: full-scale docking runs (the campaign benchmark's
``full-docking-current-0.3``, current at random in 0.1-0.5 m/s), simulated seconds of all runs
per wall second.

    .venv/bin/python benchmarks/batch_benchmark.py [--runs 64] [--repeat 3] [--json]
    .venv/bin/python benchmarks/batch_benchmark.py --sizes 8,16,32,64 [--repeat 3] [--vary-mass]
    .venv/bin/python benchmarks/batch_benchmark.py --split 32 [--vary-mass]

Three ways over the same runs: one after the other alone in this process (one core), all in
one batch in this process (``control.batch.run_together``, one core), and split over two
processes each running its half as one batch (two cores: the issue's configuration of 64 runs
at once). The compiled kernels are loaded before timing (a warm-up run of each kind).
``--sizes`` instead runs the same runs on one core in batches of each size (what
``missions.campaign.MAX_RUNS_PER_TASK`` was chosen from).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import machine
from benchmarks.campaign_benchmark import CAMPAIGN
from control.batch import run_together
from missions import campaign as cm
from missions.driver import MissionDriver

VARY_MASS = """
[random.tree_mass_scale]
distribution = "uniform"
low = 0.9
high = 1.1
"""
"""Added to the campaign by ``--vary-mass``: every run has a plant of its own (the tree's mass
and inertia), so the batch steps each run's plant by itself, not in the structure-of-arrays
step."""
_text = CAMPAIGN


def _drivers(runs: int, indices: list[int]) -> list[MissionDriver]:
    c, base = cm.parse_text(_text.format(runs=runs), "<batch benchmark>")
    return [MissionDriver(*cm.prepare_run(c, base, i)[1:], keep_log=False) for i in indices]


def alone(runs: int, indices: list[int]) -> tuple[float, float]:
    """(simulated s, wall s) of the runs one after the other."""
    drivers = _drivers(runs, indices)
    t0 = time.perf_counter()
    for d in drivers:
        d.run_to_end(log=False)  # as a campaign's runs: the figures kept, not the log
    return sum(d.sim.t_s for d in drivers), time.perf_counter() - t0


def together(runs: int, indices: list[int]) -> tuple[float, float]:
    """(simulated s, wall s) of the runs in one batch."""
    sim_s, wall, _ = together_results(runs, indices)
    return sim_s, wall


def together_results(runs: int, indices: list[int]) -> tuple[float, float, list[Any]]:
    """``together``, and each run's result (``MissionResult``, no log) in order."""
    drivers = _drivers(runs, indices)
    t0 = time.perf_counter()
    outcomes = run_together([d.run_to_end_jobs(log=False) for d in drivers])
    wall = time.perf_counter() - t0
    bad = [o.error for o in outcomes if o.error is not None]
    if bad:
        raise RuntimeError(f"{len(bad)} runs failed: {bad[0]}")
    return sum(d.sim.t_s for d in drivers), wall, [o.value for o in outcomes]


def rate_and_figures(runs: int) -> tuple[float, list[Any]]:
    """One batch of the runs: simulated s a wall s, and each run's figures (RMS north and
    east, the final pose), for comparisons that check both ways give the same."""
    sim_s, wall, results = together_results(runs, list(range(runs)))
    return sim_s / wall, [(r.rms_north_m, r.rms_east_m, r.final_eta_n) for r in results]


def compare_ways(name: str, owner: Any, attr: str, before: Any, runs: int, rounds: int) -> None:
    """A speed pass's change against the code before it, in one process: ``rounds`` rounds of
    one batch of ``runs`` docking runs each way (their order alternating), "before" with
    ``owner.attr`` set to ``before`` for the batch, "after" as the code is. Prints every
    rate, the medians and the median of the rounds' ratios; exits if any run's figures
    differ between the two ways."""
    after = getattr(owner, attr)
    rates: dict[str, list[float]] = {"before": [], "after": []}
    figures: dict[str, list[Any]] = {}
    for rnd in range(rounds):
        for way in ("before", "after") if rnd % 2 == 0 else ("after", "before"):
            setattr(owner, attr, before if way == "before" else after)
            try:
                rate, figures[way] = rate_and_figures(runs)
            finally:
                setattr(owner, attr, after)
            rates[way].append(rate)
        if figures["before"] != figures["after"]:
            raise SystemExit(f"{name}: the runs' figures differ between the two ways")
    b, a = rates["before"], rates["after"]
    print(f"{name}: one batch of {runs} docking runs on one core, {rounds} rounds")
    print(f"  before {', '.join(f'{v:,.0f}' for v in b)}x: median {statistics.median(b):,.0f}")
    print(f"  after  {', '.join(f'{v:,.0f}' for v in a)}x: median {statistics.median(a):,.0f}")
    ratios = [y / x for x, y in zip(b, a, strict=True)]
    print(f"  after / before, round by round: median {statistics.median(ratios):.3f}")
    print("  every run's figures the same both ways")
    sys.stdout.flush()


def _warm(runs: int) -> None:
    alone(runs, [0])
    together(runs, [0, 1])


def split(size: int) -> None:
    """Time one batch of ``size`` runs and, apart, the calls of its compiled kernel
    (``_Slots.steps``); the rest is Python between chunks (environment rows, noise, the
    missions' checks, the slot copies)."""
    from control import batch

    _warm(size)
    spent = [0.0]
    kernel = batch._Slots.steps

    def timed(slots: batch._Slots) -> int:
        t0 = time.perf_counter()
        h = kernel(slots)
        spent[0] += time.perf_counter() - t0
        return h

    batch._Slots.steps = timed  # type: ignore[method-assign]
    try:
        sim_s, wall = together(size, list(range(size)))
    finally:
        batch._Slots.steps = kernel  # type: ignore[method-assign]
    run_steps = sim_s / 0.01  # the docking runs step at 100 Hz
    print(f"one batch of {size} docking runs on one core: {sim_s / wall:,.0f}x")
    print(f"  compiled kernel {spent[0] / run_steps * 1e6:.2f} us per run-step")
    print(f"  the rest        {(wall - spent[0]) / run_steps * 1e6:.2f} us per run-step")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=64, help="docking runs")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        help="time each way this many times (interleaved) and report the best: the machine is "
        "shared, and its speed drifts by 20 %% or more from minute to minute",
    )
    parser.add_argument("--sizes", help="batch sizes to compare on one core, e.g. 8,16,32,64")
    parser.add_argument(
        "--split",
        type=int,
        metavar="SIZE",
        help="one batch of SIZE runs on one core: its compiled kernel and the rest timed apart",
    )
    parser.add_argument(
        "--vary-mass",
        action="store_true",
        help="with --split or --sizes: the tree's mass varies from run to run (every run on a "
        "plant of its own)",
    )
    args = parser.parse_args()
    if args.vary_mass:
        if not (args.split or args.sizes):
            parser.error("--vary-mass goes with --split or --sizes")
        global _text
        _text = CAMPAIGN + VARY_MASS
    runs = args.runs
    indices = list(range(runs))
    load = os.getloadavg()
    if args.split:
        split(args.split)
        return
    _warm(runs)
    if args.sizes:
        sizes = [int(v) for v in args.sizes.split(",")]
        sim_a, wall_a = alone(runs, indices)
        print(f"{runs} docking runs on one core, load before {load}")
        print(f"  alone          {sim_a / wall_a:7,.0f}x")
        rates: dict[int, list[float]] = {size: [] for size in sizes}
        for _ in range(args.repeat):  # the sizes interleaved, round after round
            for size in sizes:
                parts = [together(runs, indices[k : k + size]) for k in range(0, runs, size)]
                rates[size].append(sum(s for s, _ in parts) / sum(w for _, w in parts))
        for size, r in rates.items():
            every = ", ".join(f"{v:,.0f}" for v in r)
            print(
                f"  batches of {size:3d} best {max(r):7,.0f}x, median "
                f"{statistics.median(r):7,.0f}x ({every})"
            )
        return
    halves = [indices[: runs // 2], indices[runs // 2 :]]
    walls: dict[str, list[float]] = {"alone_one_core": [], "batch_one_core": [], "batch_two": []}
    with ProcessPoolExecutor(max_workers=2) as pool:
        list(pool.map(_warm, [runs, runs]))
        for _ in range(args.repeat):
            sim_a, wall = alone(runs, indices)
            walls["alone_one_core"].append(wall)
            sim_b, wall = together(runs, indices)
            walls["batch_one_core"].append(wall)
            t0 = time.perf_counter()
            parts = list(pool.map(together, [runs, runs], halves))
            walls["batch_two"].append(time.perf_counter() - t0)
    sim_2 = sum(s for s, _ in parts)

    def best(sim_s: float, w: list[float]) -> dict:
        return {
            "simulated_s": sim_s,
            "wall_s": min(w),
            "rate": sim_s / min(w),
            "rates": [round(sim_s / v) for v in w],
        }

    figures = {
        "runs": runs,
        "cores": os.cpu_count(),
        "machine": machine.describe(),
        "load_before": load,
        "repeat": args.repeat,
        "alone_one_core": best(sim_a, walls["alone_one_core"]),
        "batch_one_core": best(sim_b, walls["batch_one_core"]),
        "batch_two_processes": best(sim_2, walls["batch_two"]),
    }
    if args.json:
        print(json.dumps(figures))
        return
    where = machine.text(figures["machine"])
    print(f"{runs} full-scale docking runs on {where}, load before {load}")
    for name in ("alone_one_core", "batch_one_core", "batch_two_processes"):
        f = figures[name]
        print(
            f"  {name:20s} {f['simulated_s']:9.0f} simulated s in {f['wall_s']:6.2f} wall s: "
            f"{f['rate']:7,.0f}x" + (f"  (each time: {f['rates']})" if args.repeat > 1 else "")
        )


if __name__ == "__main__":
    main()
