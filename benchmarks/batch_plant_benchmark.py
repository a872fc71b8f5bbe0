"""Speed of the batch plant (``sim.batch_plant.rk4_batch_into``) against the scalar plant
step (``sim.plant.rk4_step_into``) run after run, full-scale docking configuration.

The plant arrays, a state and an environment row come from the library's
``full-docking-current-0.3`` mission after 2 s (gripping, quasi-static wire, the landing
surface on, the tree hanging far above the frame); each run's state is perturbed a little
(positions by 0.1 m, velocities by 0.02 m/s), its propeller speeds drawn at random. With
``--landing`` every run sits on the frame instead (corners and posts in contact, the scalar
contact code run by run). Each figure is the best of ``--repeats`` timings of ``--steps``
steps, compiled code calling the step in a loop (no Python between steps).

    .venv/bin/python benchmarks/batch_plant_benchmark.py [--landing] [--sizes 8,32] [--json]

Prints ns per run and step, the real-time factor (simulated time over wall time) of one run
and of the whole batch, and the speed-up over the scalar step; ``--asm`` also counts the
AVX-512 (zmm) instructions and <8 x double> operations in the compiled batch step.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from missions import schema
from missions.setup import build_simulation
from sim import plant
from sim.batch_plant import BatchWork, make_batch_work, rhs_batch_into, rk4_batch_into
from sim.gnc import JIT_NOALLOC

BATCH_SIZES = (1, 8, 64, 256)


@njit(**JIT_NOALLOC)
def _scalar_steps(
    x_rs: np.ndarray,
    n_rps: np.ndarray,
    env: np.ndarray,
    P: plant.PlantArrays,
    dt: float,
    steps: int,
    work: plant.PlantWork,
) -> None:
    """``steps`` steps of every run (rows of ``x_rs``), one run after the other."""
    for _ in range(steps):
        for r in range(x_rs.shape[0]):
            plant.rk4_step_into(x_rs[r], x_rs[r], n_rps[r], env[r], P, dt, work)


@njit(**JIT_NOALLOC)
def _batch_steps(
    x_sb: np.ndarray,
    n_rps: np.ndarray,
    env: np.ndarray,
    P: plant.PlantArrays,
    dt: float,
    steps: int,
    work: BatchWork,
) -> None:
    for _ in range(steps):
        rk4_batch_into(x_sb, n_rps, env, P, dt, work)


def docking_inputs(n: int, landing: bool, seed: int = 1):
    """(PlantArrays, dt, states (N_STATE, n), propeller speeds (m, n), env rows (N_ENV, n))."""
    sim = build_simulation(schema.load_mission("full-docking-current-0.3"))
    sim.step(200)
    env_rows, _ = sim._chunk_inputs(1)
    P, x0, env0, dt = sim.arrays, sim.x.copy(), env_rows[0].copy(), sim.dt_s
    rng = np.random.default_rng(seed)
    x = np.repeat(x0[:, None], n, axis=1)
    x[0:3] += rng.uniform(-0.1, 0.1, (3, n))
    x[6:9] += rng.uniform(-0.02, 0.02, (3, n))
    x[12:15] += rng.uniform(-0.1, 0.1, (3, n))
    env = np.repeat(env0[:, None], n, axis=1)
    if landing:
        env[plant.E_LAND] = x[2] + P.tree_half_height - 0.03
        env[plant.E_FRAME : plant.E_FRAME + 2] = x[0:2] + rng.uniform(-0.03, 0.03, (2, n))
        env[plant.E_FRAME_PSI] = x[5]
    m = P.thr_T.shape[1]
    n_rps = rng.uniform(-0.3, 0.3, (m, n)) * P.thr_n_max[:, None]
    return P, dt, x, n_rps, env


def _best(fn, reset, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        reset()
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def measure(n: int, landing: bool, run_steps: int, repeats: int) -> dict:
    P, dt, x, n_rps, env = docking_inputs(n, landing)
    steps = max(4, run_steps // n)
    x_sb = x.copy()
    # copies, run index first (np.ascontiguousarray(x.T) of one run would be x itself)
    x_rs = np.array(x.T, order="C")
    n_rs, env_rs = np.array(n_rps.T, order="C"), np.array(env.T, order="C")
    m = n_rps.shape[0]
    bwork = make_batch_work(m)
    swork = plant.make_work(m)

    def reset_b() -> None:
        x_sb[:] = x

    def reset_s() -> None:
        x_rs[:] = x.T

    _batch_steps(x_sb, n_rps, env, P, dt, 1, bwork)  # compile or load
    _scalar_steps(x_rs, n_rs, env_rs, P, dt, 1, swork)
    t_b = _best(lambda: _batch_steps(x_sb, n_rps, env, P, dt, steps, bwork), reset_b, repeats)
    t_s = _best(lambda: _scalar_steps(x_rs, n_rs, env_rs, P, dt, steps, swork), reset_s, repeats)
    same = bool(np.array_equal(x_sb, x_rs.T))
    batch_step_s = t_b / steps
    scalar_step_s = t_s / (steps * n)
    return {
        "runs": n,
        "steps": steps,
        "batch_ns_per_run_step": batch_step_s / n * 1e9,
        "scalar_ns_per_run_step": scalar_step_s * 1e9,
        "speedup": scalar_step_s * n / batch_step_s,
        "batch_rtf_per_run": dt / batch_step_s,
        "batch_rtf_aggregate": n * dt / batch_step_s,
        "scalar_rtf": dt / scalar_step_s,
        "bit_identical": same,
    }


def vector_counts(landing: bool) -> dict:
    """AVX-512 use in the batch step, compiled afresh (numba shows no assembly of a kernel
    loaded from its cache): lines of assembly with a zmm register, <8 x double> in the IR,
    of the step and of a stage's right-hand side (``rhs_batch_into``, a function of its own
    that the step calls four times)."""
    P, dt, x, n_rps, env = docking_inputs(8, landing)
    work = make_batch_work(n_rps.shape[0])
    step = njit(error_model="numpy", _nrt=False)(rk4_batch_into.py_func)
    step(x, n_rps, env, P, dt, work)  # also leaves the block's states in work.x0, work.env
    rhs = njit(error_model="numpy", _nrt=False)(rhs_batch_into.py_func)
    rhs(work.k[0], work.x0, work.env, P, work, 8)
    asm = "\n".join(f.inspect_asm(f.signatures[0]) for f in (step, rhs))
    ir = "\n".join(f.inspect_llvm(f.signatures[0]) for f in (step, rhs))
    lines = asm.splitlines()
    return {
        "asm_lines": len(lines),
        "asm_lines_with_zmm": sum("zmm" in line for line in lines),
        "llvm_ir_8_x_double": ir.count("<8 x double>"),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--landing", action="store_true", help="every run on the frame")
    parser.add_argument("--run-steps", type=int, default=100_000, help="run-steps a timing")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--asm", action="store_true", help="count zmm / <8 x double> too")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--sizes",
        default=",".join(str(n) for n in BATCH_SIZES),
        help="runs a batch, comma-separated (default %(default)s)",
    )
    args = parser.parse_args()
    sizes = [int(v) for v in args.sizes.split(",")]
    rows = [measure(n, args.landing, args.run_steps, args.repeats) for n in sizes]
    res: dict = {
        "configuration": "full-docking-current-0.3, " + ("landing" if args.landing else "hanging"),
        "batches": rows,
        "load_average": list(os.getloadavg()),
    }
    if args.asm:
        res["vector_code"] = vector_counts(args.landing)
    if args.json:
        print(json.dumps(res, indent=1))
        return
    print(f"{res['configuration']}, load average {res['load_average']}")
    print(
        f"{'runs':>5} {'batch ns/run-step':>18} {'scalar ns/run-step':>19} {'speed-up':>9} "
        f"{'RTF per run':>12} {'RTF batch':>11} {'RTF scalar':>11} {'same bits':>9}"
    )
    for r in rows:
        print(
            f"{r['runs']:>5} {r['batch_ns_per_run_step']:>18.0f} "
            f"{r['scalar_ns_per_run_step']:>19.0f} {r['speedup']:>9.2f} "
            f"{r['batch_rtf_per_run']:>12,.0f} {r['batch_rtf_aggregate']:>11,.0f} "
            f"{r['scalar_rtf']:>11,.0f} {r['bit_identical']!s:>9}"
        )
    if args.asm:
        v = res["vector_code"]
        print(
            f"batch step: {v['asm_lines_with_zmm']} of {v['asm_lines']} assembly lines use zmm "
            f"registers, {v['llvm_ir_8_x_double']} <8 x double> in the LLVM IR"
        )


if __name__ == "__main__":
    main()
