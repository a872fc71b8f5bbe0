"""Compiled reference-model steps used inside the closed-loop kernel.

The models themselves (equations, limits and why the limits hold) are in ``control.reference``;
this module compiles their kernels with numba, packs their parameters into one array so the
loop can carry them, and steps them: ``reference_step(kind, state, target, dt, params)`` returns
the new state and changes none of its arguments (tests: tests/test_reference.py).

State (9): reference position, velocity, acceleration per axis [north, east, psi]. Parameters
``params`` (5, 3), rows:

    0: k_pos (third order) or 1 / T (first order)   [1/s]
    1: k_vel (third order)                           [1/s]
    2: k_acc (third order)                           [1/s]
    3: max speed (third order) or max rate (first)   [m/s, rad/s]
    4: max acceleration (third order)                [m/s^2, rad/s^2]

The target's heading arrives already chosen by the caller (the short way round, or an
absolute multi-turn target), so the kernels take the plain difference.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from control import reference
from sim.gnc import JIT

_first_kernel = njit(**JIT)(reference.first_order_kernel)
_third_kernel = njit(**JIT)(reference.third_order_kernel)
_ZERO3 = np.zeros(3)


def pack_first_order(p: reference.FirstOrderParams) -> np.ndarray:
    """The (5, 3) ``params`` of the first-order model."""
    out = np.zeros((5, 3))
    out[0] = 1.0 / p.time_constant_s
    out[3] = p.max_rate
    return out


def pack_third_order(p: reference.ThirdOrderParams) -> np.ndarray:
    """The (5, 3) ``params`` of the third-order model."""
    return np.vstack([p.k_pos, p.k_vel, p.k_acc, p.max_speed, p.max_accel])


@njit(inline="always", **JIT)
def first_order_step(
    state: np.ndarray, target: np.ndarray, dt: float, params: np.ndarray
) -> np.ndarray:
    """One exact step of the saturated first-order model (thesis section 3.3)."""
    error = target - state[0:3]
    new_error, rate, accel = _first_kernel(error, 1.0 / params[0], params[3], dt)
    out = np.empty(9)
    out[0:3] = target - new_error
    out[3:6] = rate
    out[6:9] = accel
    return out


@njit(inline="always", **JIT)
def third_order_step(
    state: np.ndarray, target: np.ndarray, dt: float, params: np.ndarray
) -> np.ndarray:
    """One step of the speed- and acceleration-limited third-order model."""
    error = target - state[0:3]
    delta, vel, acc = _third_kernel(
        error,
        state[3:6].copy(),
        state[6:9].copy(),
        _ZERO3,
        params[0],
        params[1],
        params[2],
        params[3],
        params[4],
        dt,
    )
    out = np.empty(9)
    out[0:3] = state[0:3] + delta
    out[3:6] = vel
    out[6:9] = acc
    return out


@njit(inline="always", **JIT)
def reference_step(
    kind: int, state: np.ndarray, target: np.ndarray, dt: float, params: np.ndarray
) -> np.ndarray:
    """Dispatch on the model kind (0 first order, 1 third order)."""
    if kind == 0:
        return first_order_step(state, target, dt, params)
    return third_order_step(state, target, dt, params)
