"""The fifteenth speed pass's question: what does numba's dispatcher cost a single run's
closed loop, where each chunk's call of ``loop.run_chunk`` types its three NamedTuples (the
plant's, the controller's and the signal checks' arrays, some 95 in all)?

    .venv/bin/python benchmarks/dispatch_ab.py [--rounds 9] [--seconds 100]

First the call alone, for a one-step chunk: through the dispatcher, and through the compiled
overload's entry point directly (which unboxes the same arguments but types nothing). Then
``control_benchmark``'s closed loop both ways, alternating in one process, and whether both
give the same rows bit for bit. The direct call here reuses the overload while the run's
three NamedTuples are the same objects; it is a measurement, not a safe way to call: a wrong
argument type would be read as the overload's type.
"""

from __future__ import annotations

import argparse
import sys
import timeit
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.chunk_inputs_ab import closed_loop_run
from benchmarks.control_benchmark import thesis_current
from control import jobs, loop
from control.config import ControlSettings
from control.simulation import Simulation
from sim import params


def _arguments(job: jobs.ChunkJob) -> tuple[Any, ...]:
    s = job.sim
    return (
        s.step_index, s.x, s.held_y, s.xhat, s.P_cov, s.cs, s.target, job.env, job.noise,
        job.fresh, s.arrays, s.C, s.Q, s.dt_s,
    )  # fmt: skip


def _entry_point(args: tuple[Any, ...]) -> Any:
    """The compiled overload ``loop.run_chunk`` chose for these arguments."""
    signature = tuple(loop.run_chunk.typeof_pyval(a) for a in args)
    return loop.run_chunk.overloads[signature].entry_point


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--seconds", type=float, default=100.0)
    args = parser.parse_args()
    ps = params.load("model-scale")
    settings = ControlSettings(feedback="ekf", allocation="priority", feedforward=True)

    # the call alone: a one-step chunk
    sim = Simulation(ps, tree_depth_m=400.0, current=thesis_current(), settings=settings)
    sim.run_for(1.0)
    job = next(sim.step_jobs(1))
    call = _arguments(job)
    entry = _entry_point(call)
    for _ in range(3):
        through = timeit.timeit(lambda: loop.run_chunk(*call), number=2000) / 2000 * 1e6
        direct = timeit.timeit(lambda: entry(*call), number=2000) / 2000 * 1e6
        print(f"a one-step chunk: dispatcher {through:.1f} us, entry point {direct:.1f} us")

    # the closed loop both ways
    through_dispatcher = jobs.ChunkJob.run
    cached: dict[str, Any] = {}

    def run_direct(self: jobs.ChunkJob) -> jobs.ChunkResult:
        call = _arguments(self)
        s = self.sim
        key = cached.get("key")
        if key is not None and key[0] is s.arrays and key[1] is s.C and key[2] is s.Q:
            result: jobs.ChunkResult = cached["entry"](*call)
            return result
        result = loop.run_chunk(*call)
        cached["entry"], cached["key"] = _entry_point(call), (s.arrays, s.C, s.Q)
        return result

    ways = {"dispatcher": through_dispatcher, "entry point": run_direct}
    us: dict[str, list[float]] = {way: [] for way in ways}
    rows: dict[str, np.ndarray] = {}
    for run in ways.values():  # warm both
        jobs.ChunkJob.run = run  # type: ignore[method-assign]
        closed_loop_run(ps, settings, 1.0)
    try:
        for r in range(args.rounds):
            order = list(ways) if r % 2 == 0 else list(reversed(ways))
            for way in order:
                jobs.ChunkJob.run = ways[way]  # type: ignore[method-assign]
                t, rows[way] = closed_loop_run(ps, settings, args.seconds)
                us[way].append(t)
    finally:
        jobs.ChunkJob.run = through_dispatcher  # type: ignore[method-assign]
    for way, values in us.items():
        print(
            f"{way:11s} us a step: best {min(values):.2f}, median {np.median(values):.2f} "
            f"({', '.join(f'{v:.2f}' for v in values)})"
        )
    same = np.array_equal(rows["dispatcher"].view(np.int64), rows["entry point"].view(np.int64))
    print(f"the same rows bit for bit: {same}")


if __name__ == "__main__":
    main()
