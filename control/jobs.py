"""Compiled closed-loop chunks as jobs.

``Simulation.step_jobs(n)`` and ``MissionDriver.advance_jobs`` are generators: where a run
needs the compiled closed-loop kernel for its next chunk they yield a ``ChunkJob`` (the
run's own environment rows and sensor noise, drawn from its own seed, and the run itself
for its state and configuration) and take back a ``ChunkResult``. ``run_jobs`` drives such
a generator, running each job with ``loop.run_chunk`` at once.
"""

from __future__ import annotations

import itertools
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
    of its request's rows (C-contiguous); None, a new array. ``run`` (``loop.run_chunk_into``)
    writes the rows straight there."""
    spring: np.ndarray | None = None
    """(n, 3) the control model's wire spring in force at each step, [k_h, p_eq north, east]
    (``site.chunk_rows_into``: it refreshes on whole seconds, as the wire's entries); None,
    ``C``'s throughout. Row 0 is ``C``'s own as the simulation makes a job. A chunk that runs
    past whole seconds while the winch or the crane moves has others further on: ``run`` runs
    the chunk in pieces between the rows where it changes, each with ``C`` holding that
    piece's spring (the chunks of a second the simulator would otherwise have cut, with the
    same numbers)."""

    @property
    def n(self) -> int:
        return int(self.env.shape[0])

    def pieces(self) -> list[int]:
        """The rows where the spring changes, with 0 and n: the pieces ``run`` runs."""
        n = self.n
        if self.spring is None or n < 2:
            return [0, n]
        step = self.spring[1:] != self.spring[:-1]
        changed = np.flatnonzero(step[:, 0] | step[:, 1] | step[:, 2]) + 1
        return [0, *changed.tolist(), n]

    def run(self) -> ChunkResult:
        """Run the chunk alone, now (its rows straight into ``out`` when given)."""
        cuts = self.pieces()
        if len(cuts) == 2:
            return self._run_piece(0, self.n, self._config_at(0, self.sim.C), self.out)
        s = self.sim
        out = self.out if self.out is not None else np.empty((self.n, s.log_keep.shape[0]))
        state = (s.x, s.held_y, s.xhat, s.P_cov, s.cs)
        C = s.C
        for a, b in itertools.pairwise(cuts):
            C = self._config_at(a, C)
            x, held_y, xhat, P_cov, cs, _, done = self._run_piece(a, b, C, out[a:b], state)
            state = (x, held_y, xhat, P_cov, cs)
            if done < b - a:
                return x, held_y, xhat, P_cov, cs, out, a + done
        return (*state, out, self.n)

    def _config_at(self, a: int, C: Any) -> Any:
        """``C`` holding row a's spring (``C`` itself when it does already)."""
        if self.spring is None:
            return C
        k_h, p_n, p_e = self.spring[a]
        if k_h != C.k_h or p_n != C.p_eq[0] or p_e != C.p_eq[1]:  # as ``_sync_site``
            return C._replace(k_h=float(k_h), p_eq=self.spring[a, 1:3].copy())
        return C

    def _run_piece(
        self,
        a: int,
        b: int,
        C: Any,
        out: np.ndarray | None,
        state: tuple[np.ndarray, ...] | None = None,
    ) -> ChunkResult:
        """Rows a to b of the chunk, from ``state`` (x, held_y, xhat, P_cov, cs; None: the
        run's own) with configuration ``C``; the rows straight into ``out`` when given."""
        s = self.sim
        x, held_y, xhat, P_cov, cs = (
            state if state is not None else (s.x, s.held_y, s.xhat, s.P_cov, s.cs)
        )
        args = (
            s.step_index + a,
            x,
            held_y,
            xhat,
            P_cov,
            cs,
            s.target,
            self.env[a:b],
            self.noise[a:b],
            self.fresh[a:b],
            s.arrays,
            C,
            s.Q,
            s.dt_s,
        )
        if s.log_keep.shape[0] != N_LOG:  # a lean log: the whole rows made, the kept taken
            x, held_y, xhat, P_cov, cs, rows, n_done = loop.run_chunk(*args)
            kept = rows[:, s.log_keep]
            if out is None:
                return x, held_y, xhat, P_cov, cs, kept, n_done
            out[...] = kept
            return x, held_y, xhat, P_cov, cs, out, n_done
        if out is None:
            return loop.run_chunk(*args)
        x, held_y, xhat, P_cov, cs, n_done = loop.run_chunk_into(*args, out)
        return x, held_y, xhat, P_cov, cs, out, n_done


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
