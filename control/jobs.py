"""Compiled closed-loop chunks as jobs, so one run's stepping can be driven alone or beside
other runs' (``control.batch``) without two copies of the stepping logic.

``Simulation.step_jobs(n)`` and ``MissionDriver.advance_jobs`` are generators: where a run
needs the compiled closed-loop kernel for its next chunk they yield a ``ChunkJob`` (the
run's own environment rows and sensor noise, drawn from its own seed, and the run itself
for its state and configuration) and take back a ``ChunkResult``. ``run_jobs`` drives such
a generator alone, running each job with ``loop.run_chunk`` at once; ``control.batch``
drives many, running the jobs of all its runs in one compiled program. Either way a job is
the same arithmetic on the same numbers, so a run gives the same figures.
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from control import loop
from control.columns import N_LOG

if TYPE_CHECKING:
    from control.simulation import Simulation

ChunkResult = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]
"""(x, held_y, xhat, P_cov, cs, log rows (n, N_LOG), steps done): ``loop.run_chunk``'s
return. Steps done < n when the plant state stopped being finite."""

T = TypeVar("T")


@dataclass(eq=False)
class ChunkJob:
    """The next chunk of one run's compiled closed loop: ``len(env)`` steps from the run's
    present state with its present configuration (target, ``C``, ``Q``, ``arrays``)."""

    sim: Simulation
    env: np.ndarray  # (n, N_ENV) environment rows
    noise: np.ndarray  # sensor noise rows
    fresh: np.ndarray  # which sensors have a fresh sample at each step
    out: np.ndarray | None = None
    """Where the chunk's log rows go, (n, the log's width: ``Simulation.log_keep``): a slice
    of its request's rows (C-contiguous); None, a new array. A batch's kernel and ``run``
    (``loop.run_chunk_into``) write the rows straight there."""

    @property
    def n(self) -> int:
        return int(self.env.shape[0])

    def run(self) -> ChunkResult:
        """Run the chunk alone, now (its rows straight into ``out`` when given)."""
        s = self.sim
        args = (
            s.step_index,
            s.x,
            s.held_y,
            s.xhat,
            s.P_cov,
            s.cs,
            s.target,
            self.env,
            self.noise,
            self.fresh,
            s.arrays,
            s.C,
            s.Q,
            s.dt_s,
        )
        if s.log_keep.shape[0] != N_LOG:  # a lean log: the whole rows made, the kept taken
            x, held_y, xhat, P_cov, cs, rows, n_done = loop.run_chunk(*args)
            kept = rows[:, s.log_keep]
            if self.out is None:
                return x, held_y, xhat, P_cov, cs, kept, n_done
            self.out[...] = kept
            return x, held_y, xhat, P_cov, cs, self.out, n_done
        if self.out is None:
            return loop.run_chunk(*args)
        x, held_y, xhat, P_cov, cs, n_done = loop.run_chunk_into(*args, self.out)
        return x, held_y, xhat, P_cov, cs, self.out, n_done


def run_jobs(gen: Generator[ChunkJob, ChunkResult, T]) -> T:
    """Drive a generator of chunk jobs alone: run each job as it comes. Returns the
    generator's return value (exceptions it raises pass through)."""
    try:
        job = next(gen)
        while True:
            job = gen.send(job.run())
    except StopIteration as stop:
        result: Any = stop.value
        return result
