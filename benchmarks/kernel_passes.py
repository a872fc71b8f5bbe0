"""Where a batch's compiled kernel spends its time: the batch kernel's step, pass by pass, timed
with the processor's time-stamp counter inside the compiled code.

    .venv/bin/python benchmarks/kernel_passes.py [--runs 32] [--json]

Runs ``--runs`` full-scale docking runs in one batch (``benchmarks/batch_benchmark.py``'s runs)
through a copy of ``control.batchkernel.batch_steps`` that reads the counter
(``llvm.readcyclecounter``, a few nanoseconds a read) around each of its passes and adds the
cycles up per pass; prints nanoseconds per run-step for each. The copy calls the same compiled
functions in the same order as the kernel, so the runs go as they do in a campaign (the same
simulated time), a little slower for the counter's reads and the extra bookkeeping; the split
between the passes is what it is for. It also counts how many runs are within reach of the
landing surface at each step (those take the scalar contact in the plant pass) and what the
plant pass costs with and without them. Compiling the copy takes two to three minutes.

``--again`` also runs each step's structure-of-arrays plant step a second time at once, on
the block's columns still loaded (the same inputs and work space; the result thrown away):
the same arithmetic with its data just used, so the difference to the pass itself is what
loading and storing the columns and the rest of the kernel's step cost the plant pass in the
processor's caches (the runs themselves go as without it; only the time around them grows).
With more than ``BLOCK`` runs only the last block is stepped again.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import batch_benchmark as bb
from control import batch, loop
from control.batchkernel import (
    control_view,
    end_column,
    env_row,
    flags_at,
    observe_run,
    plant_view,
    plants_into,
    predict_block,
    prefetch_step,
    quality_view,
    row_at,
    sense_ahead,
    set_spring,
    steps_to_first_end,
)
from control.columns import N_LOG
from sim import batch_plant, plant, sensors


def _cycles(typingctx: Any) -> Any:
    """The time-stamp counter (``llvm.readcyclecounter``) as an int64."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        fnty = ir.FunctionType(ir.IntType(64), [])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.readcyclecounter")
        return builder.call(fn, [])

    return types.int64(), codegen


cycles: Any = intrinsic(_cycles)

PASSES = (
    "step's start: prefetch, spring, views (and the row zeroed, runs not sensed ahead)",
    "sensors (runs not sensed ahead)",
    "control step (the control law; checks and corrections of runs not sensed ahead)",
    "allocation",
    "thrusters",
    "plant pass (all runs, structure of arrays)",
    "EKF prediction and corrections (blocks of runs: control.batch_ekf)",
    "log row's plant columns, and the kept columns written out",
    "next step's row zeroed, sensors and signal checks (sense_ahead)",
)
SENSE = 8
# acc[k] for k < 9: cycles per pass; then these counters
RUN_STEPS, FAR_STEPS, FAR_CYCLES, NEAR_STEPS, NEAR_CYCLES, NEAR_RUNS, ACTIVE, AGAIN = range(9, 17)
N_ACC = 17


@njit(error_model="numpy", _nrt=False, cache=True)
def timed_steps(
    pos, length, ok, active, k0, x, held_y, xhat, Pc, cs, target, n_rps, env_at, noise_at,
    fresh_at, spring_at, PS, CS, QS, dt, log_at, work, W, same_plant, P0, bwork, scratch, keep,
    same_model, C0, ebwork, sensed, acc, again,
):  # fmt: skip
    """``batch_steps`` with the cycles of each pass added into ``acc`` (see ``PASSES``); with
    ``again``, the structure-of-arrays plant step of the pass's last block run once more on
    the columns still loaded in ``bwork`` (its result thrown away: the runs' rows have theirs)
    and its cycles into ``acc[AGAIN]``."""
    n_runs = pos.shape[0]
    m = CS.f_lo.shape[1]
    n_keep = keep.shape[0]
    tau6 = W.vec[loop.W_TAU6, 0:6]
    f = W.vec[loop.W_F, 0:m]
    reach = plant.contact_reach(P0)
    h = steps_to_first_end(pos, length)
    for _ in range(h):
        for r in range(n_runs):
            active[r] = pos[r] < length[r]
            if not active[r]:
                continue
            acc[RUN_STEPS] += 1
            c0 = cycles()
            j = pos[r]
            prefetch_step(r, j, length, env_at, noise_at, fresh_at, spring_at, log_at, n_keep * 8)
            set_spring(CS, r, row_at(spring_at[r] + j * 24, 3))
            C = control_view(CS, r)
            row = scratch[r]
            xr, hr = x[r], held_y[r]
            if sensed[r]:
                sensed[r] = False
                c1 = c2 = cycles()
                loop.control_law_into(tau6, xr, hr, xhat[r], cs[r], target[r], C, dt, row, W)
            else:
                Q = quality_view(QS, r)
                t = (k0[r] + j) * dt
                for i in range(N_LOG):
                    row[i] = 0.0
                c1 = cycles()
                noise_j = row_at(noise_at[r] + j * (sensors.N_Y * 8), sensors.N_Y)
                fresh_j = flags_at(fresh_at[r] + j * sensors.N_SENSORS, sensors.N_SENSORS)
                sensors.sample_into(hr, xr, hr, noise_j, fresh_j, sensors.Y_SENSOR)
                c2 = cycles()
                loop.control_step_into(
                    tau6, t, xr, hr, fresh_j, xhat[r], Pc[r], cs[r], target[r], C, Q, dt, row, W
                )
            c3 = cycles()
            loop.allocate_into(f, tau6, C, W)
            c4 = cycles()
            loop.thrusters_into(n_rps[r, 0:m], f, C, row, W)
            c5 = cycles()
            acc[0] += c1 - c0
            acc[1] += c2 - c1
            acc[2] += c3 - c2
            acc[3] += c4 - c3
            acc[4] += c5 - c4
        near = 0
        for r in range(n_runs):
            if active[r]:
                acc[ACTIVE] += 1
                land = env_row(env_at, r, pos[r])[plant.E_LAND]
                if land > 0.0 and not x[r, 2] + reach < land:
                    near += 1
        c0 = cycles()
        w = plants_into(active, same_plant, pos, x, n_rps, env_at, PS, P0, dt, work, bwork)
        spent = cycles() - c0
        acc[5] += spent
        if again and w > 0:
            c0 = cycles()
            batch_plant.rk4_block_into(P0, dt, bwork, w)
            acc[AGAIN] += cycles() - c0
        if near == 0:
            acc[FAR_STEPS] += 1
            acc[FAR_CYCLES] += spent
        else:
            acc[NEAR_STEPS] += 1
            acc[NEAR_CYCLES] += spent
            acc[NEAR_RUNS] += near
        n_cols = 0
        for r in range(n_runs):
            if not active[r]:
                continue
            c0 = cycles()
            j = pos[r]
            C = control_view(CS, r)
            log_row = scratch[r]
            env_k = env_row(env_at, r, j)
            # the observer's prediction as batch_steps makes it (its block after the loop),
            # timed apart from the row's plant columns
            in_block = observe_run(
                r, env_k, C, same_model[r], xhat, Pc, log_row, n_cols, dt, ebwork, W
            )
            c1 = cycles()
            t_next = (k0[r] + j) * dt + dt
            loop.write_plant_row(log_row, t_next, x[r], held_y[r], env_k, plant_view(PS, r), work)
            kept = row_at(log_at[r] + j * n_keep * 8, n_keep)
            for i in range(n_keep):
                kept[i] = log_row[keep[i]]
            pos[r] = j + 1
            c2 = cycles()
            if not plant.all_finite(x[r]):
                ok[r] = j
                pos[r] = length[r]
            elif in_block and j + 1 < length[r]:
                j1 = j + 1
                sense_ahead(
                    (k0[r] + j1) * dt,
                    x[r],
                    held_y[r],
                    row_at(noise_at[r] + j1 * (sensors.N_Y * 8), sensors.N_Y),
                    flags_at(fresh_at[r] + j1 * sensors.N_SENSORS, sensors.N_SENSORS),
                    C,
                    quality_view(QS, r),
                    log_row,
                    n_cols,
                    ebwork,
                    W,
                )
                sensed[r] = True
            c3 = cycles()
            if in_block:
                n_cols = end_column(xhat, Pc, n_cols, C0, dt, ebwork, scratch)
            acc[6] += c1 - c0 + cycles() - c3
            acc[7] += c2 - c1
            acc[SENSE] += c3 - c2
        if n_cols > 0:
            c0 = cycles()
            predict_block(xhat, Pc, n_cols, C0, dt, ebwork, scratch)
            acc[6] += cycles() - c0
    return h


@njit(cache=True)
def _now() -> int:
    return cycles()


def _counter_hz() -> float:
    """The time-stamp counter's rate, against the wall clock over half a second."""
    a, t0 = _now(), time.perf_counter()
    time.sleep(0.5)
    return (_now() - a) / (time.perf_counter() - t0)


def measure(runs: int, again: bool = False) -> dict:
    acc = np.zeros(N_ACC, np.int64)

    def steps(s: batch._Slots) -> int:
        return timed_steps(
            s.pos, s.length, s.ok, s.active, s.k0, s.x, s.held_y, s.xhat, s.Pc, s.cs, s.target,
            s.n_rps, s.env_at, s.noise_at, s.fresh_at, s.spring_at, s.PS, s.CS, s.QS, s.dt_s,
            s.log_at, s.work, s.W, s.same_plant, s.P0, s.bwork, s.scratch, s.keep, s.same_model,
            s.C0, s.ebwork, s.sensed, acc, again,
        )  # fmt: skip

    bb._warm(runs)
    original = batch._Slots.steps
    batch._Slots.steps = steps  # type: ignore[method-assign,assignment]
    try:
        bb.together(runs, [0, 1])  # compiles the copy (or loads it from the cache)
        acc[:] = 0
        sim_s, wall = bb.together(runs, list(range(runs)))
    finally:
        batch._Slots.steps = original  # type: ignore[method-assign]
    hz = _counter_hz()
    run_steps = int(acc[RUN_STEPS])
    per = {name: float(acc[k] / hz * 1e9 / run_steps) for k, name in enumerate(PASSES)}
    batch_steps = int(acc[FAR_STEPS] + acc[NEAR_STEPS])
    return {
        "runs": runs,
        "simulated_s": sim_s,
        "wall_s": wall,
        "us_per_run_step": wall / run_steps * 1e6,
        "ns_per_run_step": per,
        "kernel_ns_per_run_step": sum(per.values()),
        "active_runs_per_step": float(acc[ACTIVE] / batch_steps),
        "plant_pass_ns_per_batch_step_none_near": float(
            acc[FAR_CYCLES] / hz * 1e9 / max(1, acc[FAR_STEPS])
        ),
        "plant_pass_ns_per_batch_step_some_near": float(
            acc[NEAR_CYCLES] / hz * 1e9 / max(1, acc[NEAR_STEPS])
        ),
        "steps_with_runs_near": float(acc[NEAR_STEPS] / batch_steps),
        "runs_near_when_any": float(acc[NEAR_RUNS] / max(1, acc[NEAR_STEPS])),
        "counter_ghz": hz / 1e9,
        "plant_pass_ns_per_batch_step": float(acc[5] / hz * 1e9 / batch_steps),
        "plant_step_again_ns_per_batch_step": (
            float(acc[AGAIN] / hz * 1e9 / batch_steps) if again else None
        ),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=32, help="runs in the batch (default 32)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.add_argument(
        "--again",
        action="store_true",
        help="run each plant step once more at once, its data just used (see the docstring)",
    )
    args = parser.parse_args()
    if args.runs < 2:
        parser.error("--runs must be at least 2")
    out = measure(args.runs, args.again)
    if args.json:
        print(json.dumps(out, indent=2))
        return
    print(
        f"{args.runs} docking runs in one batch, {out['simulated_s']:,.0f} simulated s: "
        f"{out['us_per_run_step']:.2f} us per run-step in all (the timed copy)"
    )
    for name, ns in out["ns_per_run_step"].items():
        print(f"  {ns:7.1f} ns  {name}")
    print(f"  {out['kernel_ns_per_run_step']:7.1f} ns  the kernel's passes together")
    print(
        f"plant pass per batch step: {out['plant_pass_ns_per_batch_step_none_near'] / 1e3:.1f} us "
        f"with no run near the landing surface, "
        f"{out['plant_pass_ns_per_batch_step_some_near'] / 1e3:.1f} us with some "
        f"({out['runs_near_when_any']:.1f} runs near on average, "
        f"{100 * out['steps_with_runs_near']:.0f} % of the steps); "
        f"{out['active_runs_per_step']:.1f} runs active per step"
    )
    if args.again:
        print(
            f"plant pass {out['plant_pass_ns_per_batch_step'] / 1e3:.1f} us per batch step; its "
            f"structure-of-arrays step again at once, its data just used: "
            f"{out['plant_step_again_ns_per_batch_step'] / 1e3:.1f} us"
        )


if __name__ == "__main__":
    main()
