"""Compiled reference-model steps used inside the closed-loop kernel.

State per axis [north, east, psi]: position, velocity, acceleration (9 numbers, laid out as
pos (3), vel (3), acc (3)). Parameters ``params`` (4, 3): rows

    0: omega [1/s]   bandwidth (first order: 1 / time constant)
    1: v_max         speed limit [m/s, rad/s]
    2: a_max         acceleration limit [m/s^2, rad/s^2] (third order only)
    3: t_acc [s]     time constant of the acceleration (third order only)

First order (thesis section 3.3, fig. 3.5): pos_dot = sat(omega (target - pos), v_max).

Third order (the better choice the thesis names, after Fernandes et al. 2012): a velocity
planner with the speed limit and a braking curve, an acceleration loop with its limit, and a
first-order lag on the acceleration (so the jerk is finite):

    v_cmd = sign(e) min(v_max, omega |e|, 0.8 sqrt(2 a_max |e|)),   e = target - pos
    a_cmd = sat(omega_v (v_cmd - vel), a_max),                      omega_v = 2 omega ... 4 omega
    acc_dot = (a_cmd - acc) / t_acc

The braking curve lets the reference stop at the target from full speed without overshoot;
for small steps the model is linear and third order. Headings arrive already unwrapped as the
target (the caller chooses the short way or an absolute, multi-turn target).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from sim.gnc import JIT


@njit(**JIT)
def first_order_step(state: np.ndarray, target: np.ndarray, dt: float,
                     params: np.ndarray) -> np.ndarray:
    """One step of the saturated first-order reference (exact for the linear part)."""
    out = np.zeros(9)
    for i in range(3):
        e = target[i] - state[i]
        omega = params[0, i]
        vmax = params[1, i]
        rate = omega * e
        if abs(rate) <= vmax:
            # exact exponential decay over the step
            new = target[i] - e * np.exp(-omega * dt)
            out[3 + i] = (new - state[i]) / dt
        else:
            step = vmax * dt if e > 0 else -vmax * dt
            new = state[i] + step if abs(step) < abs(e) else target[i]
            out[3 + i] = (new - state[i]) / dt
        out[i] = new
    return out


@njit(**JIT)
def third_order_step(state: np.ndarray, target: np.ndarray, dt: float,
                     params: np.ndarray) -> np.ndarray:
    """One step of the speed- and acceleration-limited third-order reference."""
    out = np.empty(9)
    for i in range(3):
        pos, vel, acc = state[i], state[3 + i], state[6 + i]
        omega, vmax, amax, tacc = params[0, i], params[1, i], params[2, i], params[3, i]
        e = target[i] - pos
        mag = min(vmax, omega * abs(e), 0.8 * np.sqrt(2.0 * amax * abs(e)))
        v_cmd = mag if e >= 0 else -mag
        a_cmd = 3.0 * omega * (v_cmd - vel)
        a_cmd = min(max(a_cmd, -amax), amax)
        acc_new = acc + dt * (a_cmd - acc) / tacc if tacc > dt else a_cmd
        acc_new = min(max(acc_new, -amax), amax)
        vel_new = min(max(vel + dt * acc_new, -vmax), vmax)
        out[i] = pos + dt * vel_new
        out[3 + i] = vel_new
        out[6 + i] = acc_new
    return out


@njit(**JIT)
def reference_step(kind: int, state: np.ndarray, target: np.ndarray, dt: float,
                   params: np.ndarray) -> np.ndarray:
    """Dispatch on the model kind (0 first order, 1 third order)."""
    if kind == 0:
        return first_order_step(state, target, dt, params)
    return third_order_step(state, target, dt, params)
