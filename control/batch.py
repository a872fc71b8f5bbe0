"""Many runs stepped together: ``run_together`` drives the chunk-job generators of several
runs (``Simulation.step_jobs``, ``MissionDriver.run_to_end_jobs``) and runs their compiled
closed-loop chunks in one compiled program (``control.batchkernel.batch_steps``).

Each run keeps everything outside the compiled step to itself, as it does alone: its
missions' legs, targets and commands between chunks, its faults, its own environment and
sensor noise drawn from its own seed, its log. Only the compiled chunks go together: when a
run yields a ``ChunkJob``, its state, its chunk's inputs and its configuration are copied
into its slot of arrays stacked over the runs; the kernel advances every run with a chunk
under way, step by step, until one of them ends its chunk; that run's state and rows are
copied back into its ``Simulation`` and its generator goes on to its next chunk. A run's
step is the same arithmetic on the same numbers as alone (``control.loop._closed_steps``),
so each run gives the same figures in a batch as alone (``tests/test_batch.py``).

Runs go into one batch when their arrays have the same shapes (the same mission family: the
same thrusters, docking frame, chunk length and step). A chunk that does not fit the batch
(a run whose configuration changed shape) runs alone, at once, in its generator's place.
"""

from __future__ import annotations

from collections.abc import Generator, Sequence
from typing import Any, NamedTuple, TypeVar

import numpy as np

from control import batch_ekf, loop
from control.batchkernel import batch_steps
from control.jobs import ChunkJob, ChunkResult
from control.loop import ControlArrays
from sim import batch_plant, plant, sensors

T = TypeVar("T")

PLANT_LANES = batch_plant.LANES
"""The plant pass's blocks are padded to multiples of this many runs (``sim.batch_plant``):
the structure-of-arrays loops over the runs then have no scalar remainder."""


def _stacked(template: Any, n_runs: int) -> Any:
    """A NamedTuple like ``template`` with every field stacked over ``n_runs`` runs (zeros)."""
    fields = []
    for value in template:
        a = np.asarray(value)
        fields.append(np.zeros((n_runs, *a.shape), dtype=a.dtype))
    return type(template)(*fields)


_MODEL_FIELDS = tuple(
    ControlArrays._fields.index(name) for name in ("M", "M_inv", "D_l", "D_nl", "T_b", "GQG")
)
"""The fields of ``ControlArrays`` that make the observer's control model (all but the wire
spring, which is each run's own): runs whose values of these are the batch's first run's
predict together (``control.batch_ekf``)."""


def _same_values(a: Any, b: Any) -> bool:
    """Two NamedTuples of arrays and numbers hold the same values, field by field."""
    return all(np.array_equal(u, v) for u, v in zip(a, b, strict=True))


class _Slots:
    """The stacked arrays of a batch of ``n_runs`` runs shaped like the first job's run."""

    def __init__(self, first: ChunkJob, n_runs: int) -> None:
        s = first.sim
        self.n_runs = n_runs
        self.dt_s = s.dt_s
        self.key = self.key_of(first)
        self.PS = _stacked(s.arrays, n_runs)
        self.CS = _stacked(s.C, n_runs)
        self.QS = _stacked(s.Q, n_runs)
        self.seen_P: list[Any] = [None] * n_runs
        self.seen_C: list[Any] = [None] * n_runs
        self.seen_keep: list[Any] = [None] * n_runs  # a run's log columns, once they matched
        self.pos = np.zeros(n_runs, np.int64)
        self.length = np.zeros(n_runs, np.int64)
        self.ok = np.zeros(n_runs, np.int64)
        self.active = np.zeros(n_runs, np.bool_)
        self.n_rps = np.zeros((n_runs, s.arrays.thr_T.shape[1]))
        self.k0 = np.zeros(n_runs, np.int64)
        self.x = np.zeros((n_runs, *s.x.shape))
        self.held_y = np.zeros((n_runs, *s.held_y.shape))
        self.xhat = np.zeros((n_runs, *s.xhat.shape))
        self.Pc = np.zeros((n_runs, *np.shape(s.P_cov)))
        self.cs = np.zeros((n_runs, *s.cs.shape))
        self.target = np.zeros((n_runs, *s.target.shape))
        # each run's chunk writes its log rows straight into its own (steps, N_LOG) array,
        # kept here while the chunk runs, at the address in ``log_at`` (the kernel's
        # ``row_at``): no slot of rows to zero and copy out
        self.rows: list[np.ndarray | None] = [None] * n_runs
        self.log_at = np.zeros(n_runs, np.int64)
        # each run's chunk inputs are read where its job made them, at these addresses
        # (``batchkernel.row_at``): the environment rows, the sensors' noise and fresh flags
        # and the control model's wire spring, kept alive here while the chunk runs
        self.inputs: list[tuple[np.ndarray, ...] | None] = [None] * n_runs
        self.env_at = np.zeros(n_runs, np.int64)
        self.noise_at = np.zeros(n_runs, np.int64)
        self.fresh_at = np.zeros(n_runs, np.int64)
        self.spring_at = np.zeros(n_runs, np.int64)
        self.work = plant.make_work(s.arrays.thr_T.shape[1])
        self.W = loop.make_control_work()
        # each run's whole row is made here, then the columns its log keeps go to its rows
        self.scratch = np.zeros((n_runs, loop.N_LOG))
        self.keep = s.log_keep
        # the batch's plant (the first run's) and who has it: those runs step together
        self.P0 = s.arrays
        self.same_plant = np.zeros(n_runs, np.bool_)
        # the plant pass's block: the runs under way on the batch's plant are loaded into
        # its columns straight from their rows (``batchkernel.plants_into``), as many as
        # there are, so the step narrows as runs end
        self.bwork = batch_plant.make_batch_work(s.arrays.thr_T.shape[1])
        # the batch's control model (the first run's, copied) and who has it: their
        # observers predict together (``control.batch_ekf``)
        arrays: dict[str, Any] = {
            k: v.copy() for k, v in zip(s.C._fields, s.C, strict=True) if isinstance(v, np.ndarray)
        }
        self.C0 = s.C._replace(**arrays)
        self.same_model = np.zeros(n_runs, np.bool_)
        self.ebwork = batch_ekf.make_ekf_block()
        # the runs whose next step's sensors, signal checks and corrections the kernel has
        # made at the end of their last step (``batchkernel.sense_ahead``): never a run at
        # the end of its chunk, so never one whose chunk is taken back
        self.sensed = np.zeros(n_runs, np.bool_)

    @staticmethod
    def key_of(job: ChunkJob) -> tuple:
        """What runs of one batch must share besides their configuration's shapes: the
        shapes of the states and of the chunk's inputs, and the step."""
        s = job.sim
        return (
            s.dt_s,
            s.x.shape,
            s.held_y.shape,
            s.xhat.shape,
            np.shape(s.P_cov),
            s.cs.shape,
            s.target.shape,
            job.env.shape[1:],
            job.noise.shape[1:],
            job.fresh.shape[1:],
            job.fresh.dtype.str,
        )

    @staticmethod
    def _changed(stack: Any, seen: Any, value: Any) -> list[int] | None:
        """The fields of a run's configuration that are new objects since its last chunk
        (``_replace`` keeps the others), or None when one of them does not fit its stacked
        field (another shape or type: the chunk runs alone)."""
        if seen is value:
            return []
        changed = []
        for i, v in enumerate(value):
            if seen is None or seen[i] is not v:
                a = np.asarray(v)
                if a.shape != stack[i].shape[1:] or a.dtype != stack[i].dtype:
                    return None
                changed.append(i)
        return changed

    @staticmethod
    def _inputs(job: ChunkJob) -> tuple[np.ndarray, ...] | None:
        """The job's environment rows, noise, fresh flags and spring rows as the kernel reads
        them (C-contiguous: the job's own arrays as a rule, a copy of one laid out
        otherwise; a job without spring rows holds ``C``'s throughout), or None when one of
        them is not as wide as the kernel reads."""
        n = job.n
        env = np.ascontiguousarray(job.env, dtype=np.float64)
        noise = np.ascontiguousarray(job.noise, dtype=np.float64)
        fresh = np.ascontiguousarray(job.fresh, dtype=np.bool_)
        if job.spring is not None:
            spring = np.ascontiguousarray(job.spring, dtype=np.float64)
        else:
            spring = np.empty((n, 3))
            spring[:, 0] = job.sim.C.k_h
            spring[:, 1:3] = job.sim.C.p_eq
        if (
            env.shape != (n, plant.N_ENV)
            or noise.shape != (n, sensors.N_Y)
            or fresh.shape != (n, sensors.N_SENSORS)
            or spring.shape != (n, 3)
        ):
            return None
        return env, noise, fresh, spring

    def put(self, r: int, job: ChunkJob) -> bool:
        """Start run r's chunk (its state, configuration and inputs into slot r) and say so;
        False, and nothing started, when the run's arrays do not fit the batch."""
        s = job.sim
        n = job.n
        inputs = self._inputs(job)
        if inputs is None:
            return False  # inputs of another width than the kernel reads (it runs alone)
        env, noise, fresh, spring = inputs
        p_new = self._changed(self.PS, self.seen_P[r], s.arrays)
        c_new = self._changed(self.CS, self.seen_C[r], s.C)
        if p_new is None or c_new is None:
            return False
        if (self.seen_P[r] is None or p_new or c_new) and self.key_of(job) != self.key:
            return False
        if s.log_keep is not self.seen_keep[r]:
            if s.log_keep is not self.keep and not np.array_equal(s.log_keep, self.keep):
                return False  # a log of other columns (it runs alone)
            self.seen_keep[r] = s.log_keep
        for i in p_new:
            self.PS[i][r] = s.arrays[i]
        if p_new:
            if s.arrays is self.P0:
                self.same_plant[r] = True
            elif self.seen_P[r] is None or not self.same_plant[r]:
                self.same_plant[r] = _same_values(s.arrays, self.P0)
            else:
                # the fields kept are the objects that were the batch plant's values
                self.same_plant[r] = all(np.array_equal(s.arrays[i], self.P0[i]) for i in p_new)
        for i in c_new:
            self.CS[i][r] = s.C[i]
        if self.seen_C[r] is None or any(i in _MODEL_FIELDS for i in c_new):
            self.same_model[r] = all(np.array_equal(s.C[i], self.C0[i]) for i in _MODEL_FIELDS)
        self.seen_P[r], self.seen_C[r] = s.arrays, s.C
        for stack, value in zip(self.QS, s.Q, strict=True):
            stack[r] = value
        self.x[r] = s.x
        self.held_y[r] = s.held_y
        self.xhat[r] = s.xhat
        self.Pc[r] = s.P_cov
        self.cs[r] = s.cs
        self.target[r] = s.target
        self.inputs[r] = inputs
        self.env_at[r] = env.ctypes.data
        self.noise_at[r] = noise.ctypes.data
        self.fresh_at[r] = fresh.ctypes.data
        self.spring_at[r] = spring.ctypes.data
        out = job.out
        width = self.keep.shape[0]
        if out is None or not out.flags.c_contiguous or out.shape != (n, width):
            out = np.empty((n, width))  # (copied into ``job.out`` at the chunk's end)
        self.rows[r] = out
        self.log_at[r] = out.ctypes.data
        self.k0[r] = s.step_index
        self.pos[r] = 0
        self.length[r] = n
        self.ok[r] = n
        self.sensed[r] = False
        return True

    def take(self, r: int, job: ChunkJob) -> ChunkResult:
        """End run r's chunk: its signal checks' state back into its own arrays (as the
        kernel alone updates them in place), and the chunk's result."""
        n = job.n
        for stack, value in zip(self.QS, job.sim.Q, strict=True):
            value[...] = stack[r]
        self.length[r] = 0
        self.pos[r] = 0
        rows = self.rows[r]
        assert rows is not None and len(rows) == n
        self.rows[r] = None
        self.log_at[r] = 0
        self.inputs[r] = None
        if job.out is not None and rows is not job.out:
            job.out[...] = rows
            rows = job.out
        return (
            self.x[r].copy(),
            self.held_y[r].copy(),
            self.xhat[r].copy(),
            self.Pc[r].copy(),
            self.cs[r].copy(),
            rows,
            int(self.ok[r]),
        )

    def steps(self) -> int:
        return batch_steps(
            self.pos,
            self.length,
            self.ok,
            self.active,
            self.k0,
            self.x,
            self.held_y,
            self.xhat,
            self.Pc,
            self.cs,
            self.target,
            self.n_rps,
            self.env_at,
            self.noise_at,
            self.fresh_at,
            self.spring_at,
            self.PS,
            self.CS,
            self.QS,
            self.dt_s,
            self.log_at,
            self.work,
            self.W,
            self.same_plant,
            self.P0,
            self.bwork,
            self.scratch,
            self.keep,
            self.same_model,
            self.C0,
            self.ebwork,
            self.sensed,
        )


class Outcome(NamedTuple):
    """What one run's generator ended with: its return value, or the exception it raised."""

    value: Any
    error: BaseException | None


def run_together(gens: Sequence[Generator[ChunkJob, ChunkResult, T]]) -> list[Outcome]:
    """Drive the runs' generators to their ends, their compiled chunks in one batch. Returns
    one ``Outcome`` per generator, in order; one run raising ends that run only."""
    n_runs = len(gens)
    outcomes: list[Outcome | None] = [None] * n_runs
    jobs: list[ChunkJob | None] = [None] * n_runs
    slots: _Slots | None = None

    def advance(r: int, result: ChunkResult | None) -> None:
        """Send run r its chunk's result (None: start it) and place its next job."""
        nonlocal slots
        gen = gens[r]
        try:
            job = next(gen) if result is None else gen.send(result)
            if slots is None:
                slots = _Slots(job, n_runs)
            while not slots.put(r, job):
                job = gen.send(job.run())  # a chunk of another shape: alone, now
        except StopIteration as stop:
            outcomes[r] = Outcome(stop.value, None)
            jobs[r] = None
            return
        except Exception as err:  # the run's own failure ends that run only
            outcomes[r] = Outcome(None, err)
            jobs[r] = None
            return
        jobs[r] = job

    for r in range(n_runs):
        advance(r, None)
    while slots is not None and any(j is not None for j in jobs):
        slots.steps()
        for r in range(n_runs):
            job = jobs[r]
            if job is not None and slots.pos[r] >= slots.length[r]:
                advance(r, slots.take(r, job))
    return [o if o is not None else Outcome(None, None) for o in outcomes]
