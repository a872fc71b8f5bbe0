"""The twenty-fifth speed pass's comparison: one batch of docking runs
(``batch_benchmark.py``'s runs) with the observers predicting run by run, as before the pass,
alternating with their prediction in blocks of runs (``control.batch_ekf``), in one process,
and whether both ways give every run the same figures.

    .venv/bin/python benchmarks/batch_pass25_ab.py [--runs 32] [--rounds 5]

The kernel is the same both ways: "before" marks every run as on another control model than
the batch's (``_Slots.same_model`` all false), which sends each run's prediction through
``ekf.predict_into`` by itself, as the kernel did before the pass. On this noisy 2-core
machine only rounds measured side by side say anything: each round runs both ways (their
order alternating) and the script prints every rate, the medians and the median of the
rounds' ratios.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import batch_benchmark as bb
from control import batch
from control.jobs import ChunkJob

_put = batch._Slots.put


def _put_run_by_run(self: batch._Slots, r: int, job: ChunkJob) -> bool:
    """``_Slots.put`` with run r kept out of the observers' blocks."""
    started = _put(self, r, job)
    self.same_model[r] = False
    return started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=32)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    bb._warm(args.runs)
    rates: dict[str, list[float]] = {"before": [], "after": []}
    figures: dict[str, list[Any]] = {}
    for rnd in range(args.rounds):
        order = ("before", "after") if rnd % 2 == 0 else ("after", "before")
        for way in order:
            batch._Slots.put = _put_run_by_run if way == "before" else _put  # type: ignore[method-assign]
            try:
                rate, figures[way] = bb.rate_and_figures(args.runs)
            finally:
                batch._Slots.put = _put  # type: ignore[method-assign]
            rates[way].append(rate)
        if figures["before"] != figures["after"]:
            raise SystemExit("the runs' figures differ between the two ways")
    b, a = rates["before"], rates["after"]
    print(f"ekf-blocks: one batch of {args.runs} docking runs on one core, {args.rounds} rounds")
    print(f"  before {', '.join(f'{v:,.0f}' for v in b)}x: median {statistics.median(b):,.0f}")
    print(f"  after  {', '.join(f'{v:,.0f}' for v in a)}x: median {statistics.median(a):,.0f}")
    ratios = [y / x for x, y in zip(b, a, strict=True)]
    print(f"  after / before, round by round: median {statistics.median(ratios):.3f}")
    print("  every run's figures the same both ways")


if __name__ == "__main__":
    main()
