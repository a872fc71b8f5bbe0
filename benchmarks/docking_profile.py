"""Where a full-scale docking run spends its time: the campaign benchmark's run (the
``full-docking-current-0.3`` mission, current at random in 0.1-0.5 m/s), timed in CPU seconds
without a profiler (three runs after a warm-up one), then once under ``cProfile`` with the
functions that took the most time of their own.

    .venv/bin/python benchmarks/docking_profile.py [--top 25]

The profiler's own cost inflates the Python parts against the compiled kernel: read the
profile for where the time goes, the timing above it for how much.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.campaign_benchmark import CAMPAIGN
from missions import campaign as cm


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--top", type=int, default=25, help="functions listed")
    args = parser.parse_args()
    campaign, base = cm.parse_text(CAMPAIGN.format(runs=4), "<profile>")
    cm.run_one(campaign, base, 0)  # load the compiled kernels
    print(f"load average {os.getloadavg()}")
    for index in range(3):
        t0 = time.process_time()
        row = cm.run_one(campaign, base, index)
        cpu = time.process_time() - t0
        print(
            f"run {index}: {row['simulated_s']:.0f} simulated s in {cpu:.3f} CPU s, "
            f"{row['simulated_s'] / cpu:,.0f}x"
        )
    profile = cProfile.Profile()
    profile.enable()
    cm.run_one(campaign, base, 1)
    profile.disable()
    pstats.Stats(profile).sort_stats("tottime").print_stats(args.top)


if __name__ == "__main__":
    main()
