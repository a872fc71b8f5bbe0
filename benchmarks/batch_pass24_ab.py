"""The twenty-fourth speed pass's comparisons: one batch of docking runs
(``batch_benchmark.py``'s runs) with one of the pass's Python-side changes put back the way it
was, alternating with the code as it is in one process, and whether both ways give every run
the same figures.

    .venv/bin/python benchmarks/batch_pass24_ab.py [--runs 32] [--rounds 5] [--only NAME]

The changes, each timed against the code as it is:

- ``long-chunks``: chunks kept to a second while the winch or the crane moves (the old
  ``Simulation._still``: the control model's wire spring refreshed in Python between them);
- ``noise-stream``: the sensors' noise drawn by numpy a chunk at a time (``draw_noise``, as
  before ``sim.sensors.NoiseStream`` drew it ahead in compiled blocks).

On this noisy 2-core machine only rounds measured side by side say anything: each round runs
both ways (their order alternating) and the script prints every rate, the medians and the
median of the rounds' ratios.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import batch_benchmark as bb
from control.simulation import Simulation
from sim import sensors


def _still_at_rest(self: Simulation) -> bool:
    """``Simulation._still`` before the pass: long chunks only with the winch and the crane
    at rest."""
    return (
        not self.faults
        and self.wave_field is None
        and self.wire_model == "quasi-static"
        and self.wire_length_m == self.wire_target_m
        and (
            self.crane_speed_mps <= 0.0
            or bool(np.array_equal(self.crane_tip_n, self.crane_target_n))
        )
    )


def _take_by_chunk(
    self: sensors.NoiseStream, cfg: sensors.SensorConfig, first_step: int, n: int
) -> sensors.NoiseChunk:
    """The noise as before the pass: numpy's draws for the chunk alone (the same numbers)."""
    return sensors.draw_noise(cfg, self.dropouts, self.normals, first_step, n)


CHANGES: dict[str, tuple[Any, str, Callable[..., Any]]] = {
    "long-chunks": (Simulation, "_still", _still_at_rest),
    "noise-stream": (sensors.NoiseStream, "take", _take_by_chunk),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=32)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--only", choices=sorted(CHANGES), action="append")
    args = parser.parse_args()
    bb._warm(args.runs)
    for name in args.only or sorted(CHANGES):
        owner, attr, before = CHANGES[name]
        bb.compare_ways(name, owner, attr, before, args.runs, args.rounds)


if __name__ == "__main__":
    main()
