"""Speed of the closed loop: plant, sensors, signal checks, EKF, reference, controller and
allocation at 100 Hz, model scale with sensor feedback (the most expensive configuration).

Prints the real-time factor and steps per second of the whole loop (best of several repeats),
then the cost of each component measured alone in compiled code, so one can see what
dominates."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import machine
from control import ekf, loop, pid, refkernel
from control.config import ControlSettings
from control.simulation import Simulation
from sim import environment as envmod
from sim import params, plant, sensors


def thesis_current() -> envmod.CurrentParams:
    d = math.radians(225.0)
    return envmod.CurrentParams(
        speed_mps=0.1,
        direction_rad=d,
        speed_min_mps=0.1,
        speed_max_mps=0.1,
        direction_min_rad=d,
        direction_max_rad=d,
    )


# The plant's pieces are timed from loops compiled without numba's runtime, as the chunk
# kernels call them (a loop with the runtime would add the reference counting of every array
# in PlantArrays to each call, which the chunks do not pay).
_NO_NRT = {"cache": True, "error_model": "numpy", "_nrt": False}


@njit(**_NO_NRT)
def _plant_steps(x, n, env, P, dt, work, reps):
    for _ in range(reps):
        plant.rk4_step_into(x, x, n, env, P, dt, work)


@njit(cache=True)
def _time_plant(x, n, env, P, dt, reps):
    """The RK4 step as the loops run it: inlined, into the state, with one work space."""
    x = x.copy()
    _plant_steps(x, n, env, P, dt, plant.make_work(n.shape[0]), reps)
    return x


@njit(**_NO_NRT)
def _rhs_calls(xdot, x, thrust_b, env, P, work, reps):
    s = 0.0
    for _ in range(reps):
        plant.rhs_into(xdot, x, thrust_b, env, P, work)
        s += xdot[0]
    return s


@njit(cache=True)
def _time_rhs(x, n, env, P, reps):
    """One right-hand side (the thrusters' wrench computed once, as in the RK4 step)."""
    work = plant.make_work(n.shape[0])
    thrust_b = np.zeros(6)
    plant.thruster_wrench_into(thrust_b, n, P, work)
    return _rhs_calls(np.zeros(plant.N_STATE), x, thrust_b, env, P, work, reps)


@njit(cache=True)
def _time_open_step(x, y, n, env, P, reps):
    """The plant-alone step as the open-loop chunk kernel runs it (RK4, sensors, log row), in
    chunks of 100 steps as ``Simulation`` runs it, the environment row held."""
    chunk = min(reps, 100)
    env_rows = np.empty((chunk, env.shape[0]))
    for k in range(chunk):
        env_rows[k] = env
    noise = np.zeros((chunk, y.shape[0]))
    fresh = np.ones((chunk, 5), dtype=np.bool_)
    done = 0
    # the first step's index as a typed int, as ``Simulation`` passes it: a literal 0 here
    # had numba compile the open loop's chunk kernel again for ``Literal[int](0)``, minutes
    # of the benchmark's first run after a fresh set-up
    k0 = np.int64(0)
    for _ in range(reps // chunk):
        done += loop.run_open_chunk(k0, x, y, n, env_rows, noise, fresh, P, 0.01)[3]
    return done


# The control system's pieces likewise: their in-place kernels, with one work space, from
# loops without the runtime, as ``control.loop._closed_steps`` runs them.
@njit(**_NO_NRT)
def _control_steps(x, y, fresh, xhat, Pc, cs, target, C, Q, row, W, reps):
    tau = W.vec[loop.W_TAU6, 0:6]
    for k in range(reps):
        loop.control_step_into(tau, k * 0.01, x, y, fresh, xhat, Pc, cs, target, C, Q, 0.01, row, W)
    return tau[0]


@njit(cache=True)
def _time_control_step(x, y, xhat, Pc, cs, target, C, Q, reps):
    fresh = np.zeros(5, dtype=np.bool_)  # no fresh sample: EKF corrections timed apart
    W = loop.make_control_work()
    row = np.zeros(loop.N_LOG)
    return _control_steps(
        x, y, fresh, xhat.copy(), Pc.copy(), cs.copy(), target, C, Q, row, W, reps
    )


@njit(cache=True)
def _time_sensors(x, held, noise, fresh, reps):
    held = held.copy()
    for _ in range(reps):
        sensors.sample_into(held, x, held, noise, fresh, sensors.Y_SENSOR)
    return held


@njit(**_NO_NRT)
def _predicts(xh, Pc, tau, C, dt, W, reps):
    for _ in range(reps):
        ekf.predict_into(
            xh, Pc, tau, dt, C.M_inv, C.M, C.D_l, C.D_nl, C.k_h, C.p_eq, C.T_b, C.GQG,
            W.vec[loop.W_F0, 0:9],
            W.mat[loop.MW_PHI], W.mat[loop.MW_TMP],
        )  # fmt: skip
    return xh[0]


@njit(cache=True)
def _time_ekf(xh, Pc, C, dt, reps):
    return _predicts(xh.copy(), Pc.copy(), np.zeros(3), C, dt, loop.make_control_work(), reps)


@njit(**_NO_NRT)
def _corrections(xh, Pc, z0, z1, W, reps):
    s = 0.0
    for _ in range(reps):
        n0, _n1 = ekf.correct_into(
            xh, Pc, 2, z0, z1, 0, 1, 0.01, 0.01, -1,
            W.vec[loop.W_K0, 0:9], W.vec[loop.W_K1, 0:9], W.mat[loop.MW_A],
        )  # fmt: skip
        s += n0
    return s


@njit(cache=True)
def _time_ekf_correct(xh, Pc, reps):
    return _corrections(xh.copy(), Pc.copy(), xh[0], xh[1], loop.make_control_work(), reps)


@njit(**_NO_NRT)
def _references(state, target, params_, reps):
    for _ in range(reps):
        refkernel.reference_step_into(state, loop.REF_THIRD, state, target, 0.01, params_)
    return state[0]


@njit(cache=True)
def _time_reference(state, target, params_, reps):
    return _references(state.copy(), target, params_, reps)


@njit(**_NO_NRT)
def _controllers(C, eta, z, out, terms, work, reps):
    for _ in range(reps):
        pid.tree_pid_into(
            out[0], out[1], terms, out[2], out[3], eta, z, z, z, z, out[1], C.Kp, C.Ki, C.Kd,
            True, C.M, C.D_l, C.D_nl, C.k_h, C.p_eq, loop.EYE3, loop.EYE3, C.i_limit, 0.01,
            work,
        )  # fmt: skip
    return out[1, 0]


@njit(cache=True)
def _time_controller(C, reps):
    eta = np.array([0.1, 0.2, 0.3])
    return _controllers(C, eta, np.zeros(3), np.zeros((4, 3)), np.zeros((4, 3)),
                        np.zeros((5, 3)), reps)  # fmt: skip


@njit(**_NO_NRT)
def _allocations(C, tau, f, W, reps):
    for _ in range(reps):
        loop.allocate_into(f, tau, C, W)
    return f[0]


@njit(cache=True)
def _time_allocation(C, reps):
    tau = np.array([30.0, -20.0, 0.0, 0.0, 0.0, 15.0])
    return _allocations(C, tau, np.zeros(C.f_lo.shape[0]), loop.make_control_work(), reps)


def _per_call(fn, *args, reps: int = 20000, repeats: int = 5) -> float:
    """Microseconds per call, the best of ``repeats`` timings of ``reps`` calls."""
    fn(*args, 10)
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(*args, reps)
        best = min(best, time.perf_counter() - t0)
    return best / reps * 1e6


def figures(steps: int, simulated_s: float, wall_s: float, cost: dict[str, float]) -> dict:
    """The benchmark's figures as one JSON-ready dict (``--json``)."""
    return {
        "steps": steps,
        "simulated_s": simulated_s,
        "wall_s": wall_s,
        "steps_per_s": steps / wall_s,
        "real_time_factor": simulated_s / wall_s,
        "us_per_step": wall_s / steps * 1e6,
        "per_call_us": cost,
        "load_average": [round(v, 2) for v in os.getloadavg()],
        "machine": machine.describe(),
    }


def plant_costs(sim: Simulation) -> dict[str, float]:
    """Microseconds per call of the plant's pieces at the simulation's present state."""
    env = sim._environment_chunk(1)[0]
    n = np.zeros(sim.n_thrusters)
    x = sim.plant_state
    return {
        "plant RK4 step (4 rhs)": _per_call(_time_plant, x, n, env, sim.arrays, 0.01),
        "plant right-hand side": _per_call(_time_rhs, x, n, env, sim.arrays),
        "sensor sampling": _per_call(
            _time_sensors, x, sim.held_y, np.zeros(11), np.ones(5, dtype=np.bool_)
        ),
    }


def load_text() -> str:
    """The machine's load average (1, 5, 15 min): timings under load are upper bounds."""
    return "load average {:.2f} {:.2f} {:.2f}; ".format(*os.getloadavg()) + machine.text(
        machine.describe()
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--duration", type=float, default=300.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    out = sys.stderr if args.json else sys.stdout  # --json: only the JSON on stdout
    ps = params.load("model-scale")
    settings = ControlSettings(feedback="ekf", allocation="priority", feedforward=True)
    Simulation(ps, tree_depth_m=400.0, current=thesis_current(), settings=settings).run_for(1.0)
    best = math.inf
    steps = 0
    for _ in range(args.repeats):
        sim = Simulation(ps, tree_depth_m=400.0, current=thesis_current(), settings=settings)
        sim.set_target(2.0, 2.0, 0.5)
        t0 = time.perf_counter()
        steps = len(sim.run_for(args.duration))
        best = min(best, time.perf_counter() - t0)
    print(
        f"closed loop (model scale, EKF, priority allocation, feedforward): "
        f"{args.duration:.0f} s simulated in {best:.3f} s",
        file=out,
    )
    print(
        f"  {steps / best:,.0f} steps/s, real-time factor {args.duration / best:,.0f}x, "
        f"{best / steps * 1e6:.1f} us per step ({load_text()})",
        file=out,
    )
    C = sim.C
    x = sim.plant_state
    cost = {
        **plant_costs(sim),
        "EKF predict": _per_call(_time_ekf, sim.xhat, sim.P_cov, C, 0.01),
        "EKF correct (position)": _per_call(_time_ekf_correct, sim.xhat, sim.P_cov),
        "reference (3rd order)": _per_call(_time_reference, np.zeros(9), np.ones(3), C.ref_params),
        "controller (PID + FF)": _per_call(_time_controller, C),
        "allocation (priority)": _per_call(_time_allocation, C),
        "control step, no new sample": _per_call(
            _time_control_step,
            x,
            sim.held_y,
            sim.xhat,
            sim.P_cov,
            sim.cs,
            np.array([2.0, 2.0, 0.5]),
            C,
            sim.Q,
        ),
    }
    if args.json:
        print(json.dumps(figures(steps, args.duration, best, cost), indent=1))
        return
    print(f"cost per call, measured alone, best of 5 (us; {load_text()}):")
    for name, us in cost.items():
        print(f"  {name:38s} {us:7.2f}")


if __name__ == "__main__":
    main()
