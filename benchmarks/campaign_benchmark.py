"""Throughput of a campaign on Dask: simulated seconds per wall second over a campaign of
full-scale docking runs (``full-docking-current-0.3``, the current from a random direction and
at a random speed in 0.1-0.5 m/s), on an embedded local cluster of one worker process and then
of two.

    .venv/bin/python benchmarks/campaign_benchmark.py [--runs 200] [--workers 1,2]

The wall time counts from submitting the first run to the last row on disk, cluster start-up
included (printed apart), as a user waits for it. On a shared machine the numbers follow the
load: the script prints the load average before and after.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.campaign import runner, store
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
    """Simulated seconds per wall second of one run here, without Dask (the reference)."""
    t0 = time.perf_counter()
    row = cm.run_one(campaign, base, 0)
    return float(row["simulated_s"]) / (time.perf_counter() - t0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200, help="docking runs per campaign")
    parser.add_argument("--workers", default="1,2", help="worker counts to try, e.g. 1,2")
    args = parser.parse_args()
    text = CAMPAIGN.format(runs=args.runs)
    campaign, base = cm.parse_text(text, "<benchmark>")
    print(f"cores: {os.cpu_count()}, load average before: {os.getloadavg()}")
    print(f"one run in this process: {one_run_in_process(campaign, base):.0f} simulated s/s")
    header = ("workers", "runs", "failed", "simulated s", "wall s", "sim s/s")
    print(" ".join(f"{h:>{w}}" for h, w in zip(header, (7, 5, 6, 12, 8, 8), strict=True)))
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
        print(
            f"{n:7d} {len(rows):5d} {p.failed:6d} {simulated:12.0f} {wall:8.1f} "
            f"{simulated / wall:8.0f}   (in the run loop {p.wall_s:.1f} s)"
        )
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
