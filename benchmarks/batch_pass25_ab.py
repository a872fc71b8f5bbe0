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
import sys
from pathlib import Path

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
    bb.compare_ways("ekf-blocks", batch._Slots, "put", _put_run_by_run, args.runs, args.rounds)


if __name__ == "__main__":
    main()
