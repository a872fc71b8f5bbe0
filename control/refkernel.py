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
from sim.gnc import JIT, JIT_NOALLOC

_first_kernel = njit(**JIT)(reference.first_order_kernel)


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
    out = np.empty(9)
    first_order_step_into(out, state, target, dt, params)
    return out


@njit(inline="always", **JIT_NOALLOC)
def _first_order_axis(
    e: float, time_constant_s: float, max_rate: float, dt: float
) -> tuple[float, float, float]:
    """``reference.first_order_kernel`` for one axis, on scalars: the same operations in the
    same order (numpy's abs, maximum, minimum, exp and sign on scalars, ``np.where`` as a
    branch). Returns (e+, rate+, acc+)."""
    abs_error = np.abs(e)
    linear_error = time_constant_s * max_rate
    saturated_time = np.maximum(abs_error - linear_error, 0.0) / max_rate
    decayed = np.minimum(abs_error, linear_error) * np.exp(
        -np.maximum(dt - saturated_time, 0.0) / time_constant_s
    )
    abs_new = abs_error - max_rate * dt if dt <= saturated_time else decayed
    new_error = np.sign(e) * abs_new
    rate = np.sign(new_error) * np.minimum(abs_new / time_constant_s, max_rate)
    accel = -rate / time_constant_s if abs_new < linear_error else 0.0
    return new_error, rate, accel


@njit(inline="always", **JIT_NOALLOC)
def first_order_step_into(
    out: np.ndarray, state: np.ndarray, target: np.ndarray, dt: float, params: np.ndarray
) -> None:
    """``first_order_step`` into ``out`` (9,), which may be ``state`` itself."""
    for i in range(3):
        new_error, rate, accel = _first_order_axis(
            target[i] - state[i], 1.0 / params[0, i], params[3, i], dt
        )
        out[i] = target[i] - new_error
        out[3 + i] = rate
        out[6 + i] = accel


@njit(inline="always", **JIT_NOALLOC)
def _third_order_axis(
    e: float,
    v: float,
    a: float,
    v_ff: float,
    k_pos: float,
    k_vel: float,
    k_acc: float,
    max_speed: float,
    max_accel: float,
    dt: float,
    decay_m1: float,
) -> tuple[float, float, float]:
    """``reference.third_order_kernel`` for one axis, on scalars: the same operations in the
    same order (numpy's minimum, maximum, copysign and expm1 on scalars are the kernels its
    array form applies element by element), so the same bits, without its ~30 temporary
    3-vectors. ``decay_m1`` is the acceleration's decay over the step less one,
    ``np.expm1(k_acc * -dt)`` (``third_order_step_into`` works it out once for axes of one
    k_acc). Returns (delta_pos, vel+, acc+)."""
    abs_error = np.abs(e)
    pull = np.minimum(
        k_pos * abs_error, np.sqrt((2.0 * reference.BRAKING_FRACTION) * max_accel * abs_error)
    )
    speed_cmd = np.minimum(np.maximum(v_ff + np.copysign(pull, e), -max_speed), max_speed)
    settled_speed = v + a / k_acc
    accel_cmd = k_vel * (speed_cmd - v)
    accel_cmd = np.minimum(
        np.maximum(accel_cmd, (-max_speed - settled_speed) / dt), (max_speed - settled_speed) / dt
    )
    accel_cmd = np.minimum(np.maximum(accel_cmd, -max_accel), max_accel)
    decay = decay_m1 + 1.0
    phi = -decay_m1 / k_acc
    acc_gap = a - accel_cmd
    acc_new = accel_cmd + acc_gap * decay
    vel_new = v + accel_cmd * dt + acc_gap * phi
    delta_pos = v * dt + 0.5 * accel_cmd * dt * dt + acc_gap * (dt - phi) / k_acc
    return delta_pos, vel_new, acc_new


@njit(inline="always", **JIT)
def third_order_step(
    state: np.ndarray, target: np.ndarray, dt: float, params: np.ndarray
) -> np.ndarray:
    """One step of the speed- and acceleration-limited third-order model (per axis, see
    ``_third_order_axis``)."""
    out = np.empty(9)
    third_order_step_into(out, state, target, dt, params)
    return out


@njit(inline="always", **JIT_NOALLOC)
def third_order_step_into(
    out: np.ndarray, state: np.ndarray, target: np.ndarray, dt: float, params: np.ndarray
) -> None:
    """``third_order_step`` into ``out`` (9,), which may be ``state`` itself. An axis whose
    k_acc is the one before's (the parameter sets give the three axes one bandwidth and one
    damping) takes that axis's decay, the same number, not a second libm ``expm1``."""
    k_prev = np.nan
    decay_m1 = np.nan
    for i in range(3):
        k_acc = params[2, i]
        if not k_acc == k_prev or k_acc == 0.0:  # (NaN never equal; +-0 not the same)
            decay_m1 = np.expm1(k_acc * -dt)
            k_prev = k_acc
        delta, vel, acc = _third_order_axis(
            target[i] - state[i],
            state[3 + i],
            state[6 + i],
            0.0,
            params[0, i],
            params[1, i],
            params[2, i],
            params[3, i],
            params[4, i],
            dt,
            decay_m1,
        )
        out[i] = state[i] + delta
        out[3 + i] = vel
        out[6 + i] = acc


@njit(inline="always", **JIT)
def reference_step(
    kind: int, state: np.ndarray, target: np.ndarray, dt: float, params: np.ndarray
) -> np.ndarray:
    """Dispatch on the model kind (0 first order, 1 third order)."""
    out = np.empty(9)
    reference_step_into(out, kind, state, target, dt, params)
    return out


@njit(inline="always", **JIT_NOALLOC)
def reference_step_into(
    out: np.ndarray, kind: int, state: np.ndarray, target: np.ndarray, dt: float, params: np.ndarray
) -> None:
    """``reference_step`` into ``out`` (9,), which may be ``state`` itself; allocates nothing."""
    if kind == 0:
        first_order_step_into(out, state, target, dt, params)
    else:
        third_order_step_into(out, state, target, dt, params)


@njit(**JIT_NOALLOC)
def polls_still_away(
    kind: int,
    state: np.ndarray,
    target: np.ndarray,
    dt: float,
    params: np.ndarray,
    goal: np.ndarray,
    tol: np.ndarray,
    steps_per_poll: int,
    max_polls: int,
    scratch: np.ndarray,
) -> int:
    """How many polls of ``steps_per_poll`` steps, one after another from ``state``, end with
    the reference certainly away from ``goal``: the count of polls from the first whose end
    state has some entry i of the first six (pose, rate) with |state[i] - goal[i]| above
    ``tol[i]`` by a margin (a millionth of it, and 1e-9), up to ``max_polls``. The reference
    steps towards ``target`` with ``reference_step_into``, as the closed-loop kernel steps it;
    ``scratch`` (9,) holds the state as it goes (nothing else is changed).

    A caller that would stop when every |state[i] - goal[i]| < tol[i] may skip the checks at
    the ends of these polls: they would all have said no. The same arithmetic compiled in
    another function could differ in the last bits (some 1e-14 m at a pose of 100 m; the model
    is contracting, so such differences do not grow): the margin is far above that and far
    below the tolerances (1e-5 and more), so it costs at most the one poll whose end lands
    within it. (Twice the tolerance would cost nine polls of a reference with a 10-s time
    constant: ln 2 of its exponential tail.)"""
    for i in range(9):
        scratch[i] = state[i]
    for p in range(max_polls):
        for _ in range(steps_per_poll):
            reference_step_into(scratch, kind, scratch, target, dt, params)
        away = False
        for i in range(6):
            if abs(scratch[i] - goal[i]) > tol[i] * (1.0 + 1e-6) + 1e-9:
                away = True
        if not away:
            return p
    return max_polls
