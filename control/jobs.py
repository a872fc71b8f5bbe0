"""A chunk of the compiled closed loop as a named input and a named result.

``Simulation`` hands the kernel a ``ClosedChunk`` (its state, configuration and the chunk's
own inputs, made from the run's own seed) and takes back a ``ChunkResult``; the chunk knows
nothing of the simulation it came from. ``run_closed_chunk`` runs it with
``loop.run_chunk`` (or ``run_chunk_into`` when its rows go into a caller's array);
``run_qp_chunk`` runs it step by step with the QP allocation (not compiled) in the middle.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from typing import Any, NamedTuple

import numpy as np

from control import allocation as alloc
from control import loop
from control.columns import N_LOG
from sim import plant, sensors


class SimulationDiverged(RuntimeError):
    """The plant state (or the MoorDyn wire beside it) stopped being finite."""


class ChunkResult(NamedTuple):
    """What a chunk leaves: the new states and the chunk's log rows."""

    x: np.ndarray
    """plant state at the chunk's end (N_STATE,)"""
    held_y: np.ndarray
    """the sensors' held values"""
    xhat: np.ndarray
    """the observer's estimate"""
    P_cov: np.ndarray
    """the observer's covariance"""
    cs: np.ndarray
    """the controller's state"""
    rows: np.ndarray
    """the chunk's log rows (steps, the kept columns)"""
    steps_done: int
    """steps run: fewer than asked when the plant state stopped being finite"""


@dataclass(frozen=True, eq=False)
class ClosedChunk:
    """``len(env)`` steps of the closed loop from a run's present state."""

    k0: int
    """the run's step index at the chunk's start"""
    x: np.ndarray
    held_y: np.ndarray
    xhat: np.ndarray
    P_cov: np.ndarray
    cs: np.ndarray
    target: np.ndarray
    """the reference model's target, held over the chunk"""
    env: np.ndarray
    """(n, N_ENV) environment rows"""
    noise: np.ndarray
    """sensor noise rows"""
    fresh: np.ndarray
    """which sensors have a fresh sample at each step"""
    arrays: Any
    """the plant's ``PlantArrays``"""
    C: Any
    """the control system's ``ControlArrays``"""
    Q: Any
    """the signal checks' ``QualityState`` (advanced in place)"""
    dt_s: float
    keep: np.ndarray
    """the log columns kept (all N_LOG of them, or a campaign's lean layout)"""
    spring: np.ndarray | None = None
    """(n, 3) the control model's wire spring in force at each step, [k_h, p_eq north, east]
    (``site.chunk_rows_into`` refreshes it on whole seconds); None, ``C``'s throughout. Row 0
    is ``C``'s own. A chunk that runs past whole seconds while the winch or the crane moves
    has others further on: it runs in pieces between the rows where it changes, each with
    ``C`` holding that piece's spring (the chunks of a second the simulator would otherwise
    have cut, with the same numbers)."""
    out: np.ndarray | None = None
    """Where the rows go, (n, len(keep)), C-contiguous (a slice of a request's rows); None,
    a new array."""

    @property
    def n(self) -> int:
        return int(self.env.shape[0])

    def pieces(self) -> list[int]:
        """The rows where the spring changes, with 0 and n."""
        n = self.n
        if self.spring is None or n < 2:
            return [0, n]
        step = self.spring[1:] != self.spring[:-1]
        changed = np.flatnonzero(step[:, 0] | step[:, 1] | step[:, 2]) + 1
        return [0, *changed.tolist(), n]

    def config_at(self, a: int, C: Any) -> Any:
        """``C`` holding row a's spring (``C`` itself when it does already)."""
        if self.spring is None:
            return C
        k_h, p_n, p_e = self.spring[a]
        if k_h != C.k_h or p_n != C.p_eq[0] or p_e != C.p_eq[1]:
            return C._replace(k_h=float(k_h), p_eq=self.spring[a, 1:3].copy())
        return C


def run_closed_chunk(chunk: ClosedChunk) -> ChunkResult:
    """Run ``chunk`` now, in pieces where its wire spring changes (its rows straight into
    ``chunk.out`` when given)."""
    cuts = chunk.pieces()
    if len(cuts) == 2:
        return _run_piece(chunk, chunk.config_at(0, chunk.C))
    out = chunk.out if chunk.out is not None else np.empty((chunk.n, chunk.keep.shape[0]))
    C, part = chunk.C, chunk
    for a, b in itertools.pairwise(cuts):
        C = chunk.config_at(a, C)
        piece = replace(
            part,
            k0=chunk.k0 + a,
            env=chunk.env[a:b],
            noise=chunk.noise[a:b],
            fresh=chunk.fresh[a:b],
            spring=None,
            out=out[a:b],
        )
        res = _run_piece(piece, C)
        if res.steps_done < b - a:
            return res._replace(rows=out, steps_done=a + res.steps_done)
        part = replace(part, x=res.x, held_y=res.held_y, xhat=res.xhat, P_cov=res.P_cov, cs=res.cs)
    return ChunkResult(part.x, part.held_y, part.xhat, part.P_cov, part.cs, out, chunk.n)


def _run_piece(c: ClosedChunk, C: Any) -> ChunkResult:
    """All of ``c``'s rows with configuration ``C``."""
    args = (
        c.k0, c.x, c.held_y, c.xhat, c.P_cov, c.cs, c.target, c.env, c.noise, c.fresh,
        c.arrays, C, c.Q, c.dt_s,
    )  # fmt: skip
    if c.keep.shape[0] != N_LOG:  # a lean log: the whole rows made, the kept taken
        x, held_y, xhat, P_cov, cs, rows, n_done = loop.run_chunk(*args)
        kept = rows[:, c.keep]
        if c.out is not None:
            c.out[...] = kept
            kept = c.out
        return ChunkResult(x, held_y, xhat, P_cov, cs, kept, n_done)
    if c.out is None:
        return ChunkResult(*loop.run_chunk(*args))
    x, held_y, xhat, P_cov, cs, n_done = loop.run_chunk_into(*args, c.out)
    return ChunkResult(x, held_y, xhat, P_cov, cs, c.out, n_done)


def run_qp_chunk(chunk: ClosedChunk, thrusters: alloc.ThrusterConfig) -> ChunkResult:
    """Run ``chunk`` a step at a time: the compiled step's body with the QP allocation on
    ``thrusters`` (not compiled) in the middle. Its rows are whole (N_LOG) and new; its
    spring and ``out`` are left to the caller."""
    c = chunk
    x, held, xhat, pc, cs = c.x.copy(), c.held_y, c.xhat, c.P_cov, c.cs.copy()
    n = c.n
    log = np.zeros((n, N_LOG))
    work = plant.make_work(c.arrays.thr_T.shape[1])  # x is advanced in place
    for j in range(n):
        k = c.k0 + j
        held = sensors.sample(x, held, c.noise[j], c.fresh[j], sensors.Y_SENSOR)
        cs[loop.CS_GRIP] = c.env[j, plant.E_GRIP]  # as the compiled steps (loop._closed_steps)
        tau6, xhat, pc, cs = loop.control_step(
            k * c.dt_s, x, held, c.fresh[j], xhat, pc, cs, c.target, c.C, c.Q, c.dt_s, log[j]
        )
        f = np.asarray(alloc.allocate_qp(thrusters, tau6).force_newton)
        xhat, pc = loop.finish_step(
            x, f, c.env[j], xhat, pc, c.C, c.arrays, c.dt_s, (k + 1) * c.dt_s, held, log[j], work
        )
        if not np.all(np.isfinite(x)):
            return ChunkResult(x, held, xhat, pc, cs, log, j)
    return ChunkResult(x, held, xhat, pc, cs, log, n)
