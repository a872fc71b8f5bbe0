"""The twenty-sixth speed pass's comparison: one batch of docking runs
(``batch_benchmark.py``'s runs) with each run's sensors, signal checks and observer
corrections made at the start of its step and the corrections run by run
(``ekf.correct_into``), as before the pass, alternating with the kernel as it is (made at the
end of the step before, the corrections in the observers' blocks right after their
prediction: ``batchkernel.sense_ahead``, ``batch_ekf.correct_block_into``), in one process,
and whether both ways give every run the same figures.

    .venv/bin/python benchmarks/batch_pass26_ab.py [--runs 32] [--rounds 5]

"Before" is ``before_steps`` below: ``batchkernel.batch_steps`` without the sensing ahead
and without the prefetching of each run's rows (``batchkernel.prefetch_step``), every other
call the same (compiling it takes a few minutes the first time). The pass's other changes
(the checks' variance in plain loops, one ``expm1`` for the reference's axes, the block's
Joseph update in pairs) are in functions both ways call, so this compares the kernel's order
and its prefetching alone. On this noisy
2-core machine only rounds measured side by side say anything: each round runs both ways
(their order alternating) and the script prints every rate, the medians and the median of
the rounds' ratios.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from numba import njit

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
    quality_view,
    row_at,
    set_spring,
    steps_to_first_end,
)
from control.columns import N_LOG
from sim import plant, sensors


@njit(error_model="numpy", _nrt=False, cache=True)
def before_steps(
    pos, length, ok, active, k0, x, held_y, xhat, Pc, cs, target, n_rps, env_at, noise_at,
    fresh_at, spring_at, PS, CS, QS, dt, log_at, work, W, same_plant, P0, bwork, scratch, keep,
    same_model, C0, ebwork,
):  # fmt: skip
    """``batch_steps`` as before the pass: no run is sensed ahead, so every run samples,
    checks and corrects (run by run) at the start of its step, and nothing is prefetched."""
    n_runs = pos.shape[0]
    m = CS.f_lo.shape[1]
    n_keep = keep.shape[0]
    row_bytes = n_keep * 8
    n_y, n_sensors = sensors.N_Y, sensors.N_SENSORS
    tau6 = W.vec[loop.W_TAU6, 0:6]
    f = W.vec[loop.W_F, 0:m]
    h = steps_to_first_end(pos, length)
    for _ in range(h):
        for r in range(n_runs):
            active[r] = pos[r] < length[r]
            if not active[r]:
                continue
            j = pos[r]
            set_spring(CS, r, row_at(spring_at[r] + j * 24, 3))
            C = control_view(CS, r)
            Q = quality_view(QS, r)
            t = (k0[r] + j) * dt
            row = scratch[r]
            xr, hr = x[r], held_y[r]
            for i in range(N_LOG):
                row[i] = 0.0
            noise_j = row_at(noise_at[r] + j * (n_y * 8), n_y)
            fresh_j = flags_at(fresh_at[r] + j * n_sensors, n_sensors)
            sensors.sample_into(hr, xr, hr, noise_j, fresh_j, sensors.Y_SENSOR)
            loop.control_step_into(
                tau6, t, xr, hr, fresh_j, xhat[r], Pc[r], cs[r], target[r], C, Q, dt, row, W
            )
            loop.allocate_into(f, tau6, C, W)
            loop.thrusters_into(n_rps[r, 0:m], f, C, row, W)
        plants_into(active, same_plant, pos, x, n_rps, env_at, PS, P0, dt, work, bwork)
        c = 0
        for r in range(n_runs):
            if not active[r]:
                continue
            j = pos[r]
            t = (k0[r] + j) * dt
            C = control_view(CS, r)
            env_j = env_row(env_at, r, j)
            row = scratch[r]
            in_block = observe_run(r, env_j, C, same_model[r], xhat, Pc, row, c, dt, ebwork, W)
            loop.write_plant_row(row, t + dt, x[r], held_y[r], env_j, plant_view(PS, r), work)
            kept = row_at(log_at[r] + j * row_bytes, n_keep)
            for i in range(n_keep):
                kept[i] = row[keep[i]]
            pos[r] = j + 1
            if not plant.all_finite(x[r]):
                ok[r] = j
                pos[r] = length[r]
            if in_block:
                c = end_column(xhat, Pc, c, C0, dt, ebwork, scratch)
        if c > 0:
            predict_block(xhat, Pc, c, C0, dt, ebwork, scratch)
    return h


def _steps_before(s: batch._Slots) -> int:
    return before_steps(
        s.pos, s.length, s.ok, s.active, s.k0, s.x, s.held_y, s.xhat, s.Pc, s.cs, s.target,
        s.n_rps, s.env_at, s.noise_at, s.fresh_at, s.spring_at, s.PS, s.CS, s.QS, s.dt_s,
        s.log_at, s.work, s.W, s.same_plant, s.P0, s.bwork, s.scratch, s.keep, s.same_model,
        s.C0, s.ebwork,
    )  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=32)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    bb._warm(args.runs)
    after = batch._Slots.steps
    batch._Slots.steps = _steps_before  # type: ignore[method-assign,assignment]
    try:
        bb.together(args.runs, [0, 1])  # compiles "before" (or loads it) before any timing
    finally:
        batch._Slots.steps = after  # type: ignore[method-assign]
    bb.compare_ways("sense-ahead", batch._Slots, "steps", _steps_before, args.runs, args.rounds)


if __name__ == "__main__":
    main()
