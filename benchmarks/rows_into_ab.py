"""The sixteenth speed pass's comparison: a request of several chunks with each chunk's log rows
written straight into the request's array (``loop.run_chunk_into``, ``run_open_chunk_into``)
against the way before, where each chunk made a new array of zeros and the simulation copied it
into the request's (the old path rebuilt here around the same kernels), alternating in one
process, and whether both give the same rows bit for bit.

    .venv/bin/python benchmarks/rows_into_ab.py [--rounds 9] [--seconds 300]

Two loops, each one request of ``--seconds``: the full-scale plant alone
(``plant_benchmark``'s configuration) and the closed loop at model scale
(``control_benchmark``'s). On this noisy 2-core machine only rounds measured side by side say
anything; the script prints each round's ratio and their median.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.chunk_inputs_ab import closed_loop_run
from benchmarks.plant_benchmark import plant_current
from control import loop
from control.config import ControlSettings
from control.simulation import Simulation
from sim import params


def _before_closed(*args):
    """The path before: a new array from ``run_chunk``, copied into the request's rows."""
    *chunk, log = args
    x, held_y, xhat, P_cov, cs, rows, n_done = loop.run_chunk(*chunk)
    log[...] = rows
    return x, held_y, xhat, P_cov, cs, n_done


def _before_open(*args):
    *chunk, log = args
    x, held_y, rows, n_done = loop.run_open_chunk(*chunk)
    log[...] = rows
    return x, held_y, n_done


def open_loop_run(ps: params.ParameterSet, seconds: float) -> tuple[float, np.ndarray]:
    """``plant_benchmark``'s plant alone for ``seconds``: (us a step, its log rows)."""
    sim = Simulation(ps, tree_depth_m=400.0, current=plant_current(), control=False)
    t0 = time.perf_counter()
    rows = sim.run_for(seconds)
    return (time.perf_counter() - t0) / len(rows) * 1e6, rows.data


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--seconds", type=float, default=300.0)
    args = parser.parse_args()
    full, model = params.load("full-scale"), params.load("model-scale")
    settings = ControlSettings(feedback="ekf", allocation="priority", feedforward=True)
    new_forms = (loop.run_chunk_into, loop.run_open_chunk_into)
    loops = {
        "plant alone": lambda: open_loop_run(full, args.seconds),
        "closed loop": lambda: closed_loop_run(model, settings, args.seconds),
    }
    times: dict[tuple[str, str], list[float]] = {}
    for rnd in range(args.rounds):
        order = ("before", "after") if rnd % 2 == 0 else ("after", "before")
        for name, run in loops.items():
            rows = {}
            for way in order:
                if way == "before":
                    loop.run_chunk_into, loop.run_open_chunk_into = _before_closed, _before_open
                try:
                    us, rows[way] = run()
                finally:
                    loop.run_chunk_into, loop.run_open_chunk_into = new_forms
                times.setdefault((name, way), []).append(us)
            if not np.array_equal(rows["before"], rows["after"]):
                raise SystemExit(f"{name}: the rows differ between the two ways")
            b, a = times[(name, "before")][-1], times[(name, "after")][-1]
            print(
                f"round {rnd}: {name:11s} before {b:5.2f} us a step, after {a:5.2f} ({a / b:.3f})"
            )
        sys.stdout.flush()
    print(f"rows bit for bit the same both ways; {args.rounds} rounds of {args.seconds:g} s:")
    for name in loops:
        before, after = times[(name, "before")], times[(name, "after")]
        ratios = [a / b for a, b in zip(after, before, strict=True)]
        print(
            f"  {name}: best {min(before):.2f} -> {min(after):.2f} us a step, median "
            f"{statistics.median(before):.2f} -> {statistics.median(after):.2f}, "
            f"median ratio after/before {statistics.median(ratios):.3f}"
        )


if __name__ == "__main__":
    main()
