"""Throughput of a campaign on Dask: simulated seconds per wall second over a campaign of
full-scale docking runs (``full-docking-current-0.3``, the current from a random direction and
at a random speed in 0.1-0.5 m/s), on an embedded local cluster of one worker process and then
of two.

    .venv/bin/python benchmarks/campaign_benchmark.py [--runs 200] [--workers 1,2]

The wall time counts from submitting the first run to the last row on disk, cluster start-up
included (printed apart), as a user waits for it. On a shared machine the numbers follow the
load: the script prints the load average before and after.

``--plain N`` also runs the same runs, in the same blocks as the campaign tool makes for N
workers (``runner.shrinking_blocks``, ``missions.campaign.run_block``), in N plain processes
without Dask (a ``ProcessPoolExecutor``), timed from starting the processes: what Dask itself
costs the campaign, with the same runs and the same start-up (each process imports the
packages and loads the compiled kernels).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.campaign import runner, store
from benchmarks import machine
from missions import campaign as cm

CAMPAIGN = """format_version = 1
name = "benchmark-docking"
description = "benchmark: full-scale docking runs"
mission = "full-docking-current-0.3"
seed = 1
runs_per_point = {runs}

[random.current_speed_mps]
distribution = "uniform"
low = 0.1
high = 0.5

[random.current_direction_deg]
distribution = "uniform"
low = 0.0
high = 360.0
"""


def one_run_in_process(campaign: cm.Campaign, base) -> float:
    """Simulated seconds per wall second of one run here, without Dask (the reference): run 0
    once to load the compiled kernels, then the best of three runs of it."""
    cm.run_one(campaign, base, 0)
    best = 0.0
    for _ in range(3):
        t0 = time.perf_counter()
        row = cm.run_one(campaign, base, 0)
        best = max(best, float(row["simulated_s"]) / (time.perf_counter() - t0))
    return best


def _plain_block(text: str, indices: list[int]) -> float:
    """Simulated seconds of one block of runs, run in this process as a campaign task runs it."""
    campaign, base = cm.parse_text(text, "<benchmark>")
    return sum(float(r["simulated_s"] or 0.0) for r in cm.run_block(campaign, base, indices))


def plain_processes(text: str, runs: int, processes: int) -> dict:
    """The campaign's runs in ``processes`` plain processes (no Dask), in the campaign tool's
    blocks; wall time from starting the processes to the last block's end."""
    blocks = runner.shrinking_blocks(list(range(runs)), processes)
    t0 = time.perf_counter()
    context = multiprocessing.get_context(runner.LOCAL_START_METHOD)  # as the nannies do
    with ProcessPoolExecutor(processes, mp_context=context) as pool:
        simulated = sum(pool.map(_plain_block, [text] * len(blocks), blocks))
    wall = time.perf_counter() - t0
    return {
        "processes": processes,
        "runs": runs,
        "blocks": len(blocks),
        "simulated_s": simulated,
        "wall_s": wall,
        "simulated_s_per_wall_s": simulated / wall,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200, help="docking runs per campaign")
    parser.add_argument("--workers", default="1,2", help="worker counts to try, e.g. 1,2")
    parser.add_argument(
        "--plain",
        type=int,
        default=0,
        metavar="N",
        help="also run the same runs in N plain processes without Dask (0: not)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    text = CAMPAIGN.format(runs=args.runs)
    campaign, base = cm.parse_text(text, "<benchmark>")
    load_before = os.getloadavg()
    if not args.json:
        print(f"{machine.text(machine.describe())}, load average before: {load_before}")
        header = ("workers", "runs", "failed", "simulated s", "wall s", "sim s/s")
        print(" ".join(f"{h:>{w}}" for h, w in zip(header, (7, 5, 6, 12, 8, 8), strict=True)))
    results = []
    for n in (int(v) for v in args.workers.split(",")):
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "results"
            t0 = time.perf_counter()
            p = runner.run_campaign(
                campaign, base, text, out, workers=n, show_progress=False, batch=50
            )
            wall = time.perf_counter() - t0
            rows = store.read_rows(out)
        simulated = sum(r["simulated_s"] or 0.0 for r in rows)
        results.append(
            {
                "workers": n,
                "runs": len(rows),
                "failed": p.failed,
                "simulated_s": simulated,
                "wall_s": wall,
                "run_loop_s": p.wall_s,
                "simulated_s_per_wall_s": simulated / wall,
            }
        )
        if not args.json:
            print(
                f"{n:7d} {len(rows):5d} {p.failed:6d} {simulated:12.0f} {wall:8.1f} "
                f"{simulated / wall:8.0f}   (in the run loop {p.wall_s:.1f} s)"
            )
    plain = plain_processes(text, args.runs, args.plain) if args.plain > 0 else None
    # after the campaigns: their workers are forked from this process, which has imported the
    # packages but not loaded the compiled kernels, as ``rov-console campaign``'s has not
    one_run = one_run_in_process(campaign, base)
    if not args.json:
        print(f"one run in this process: {one_run:.0f} simulated s/s")
    if plain is not None and not args.json:
        print(
            f"the same runs in {plain['processes']} plain processes (no Dask, the same "
            f"{plain['blocks']} blocks): {plain['wall_s']:.1f} s, "
            f"{plain['simulated_s_per_wall_s']:.0f} simulated s/s"
        )
    if args.json:
        print(
            json.dumps(
                {
                    "cores": os.cpu_count(),
                    "machine": machine.describe(),
                    "load_average_before": list(load_before),
                    "load_average_after": list(os.getloadavg()),
                    "one_run_simulated_s_per_s": one_run,
                    "campaigns": results,
                    "plain_processes": plain,
                }
            )
        )
    else:
        print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
