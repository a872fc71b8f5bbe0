"""Reference models: turn a (possibly stepping) target pose into a smooth, feasible trajectory.

The reference model sits between the mission (which commands target poses) and the controller
(which tracks the desired pose, velocity and acceleration). Thesis section 3.3: "make smooth and
feasible trajectories that is within the bandwidth of the controller".

Everything here works on 3-DOF horizontal-plane vectors ordered ``[north_m, east_m, psi_rad]``
(NED position and heading, indices ``NORTH``, ``EAST``, ``PSI``). Velocities are in m/s and
rad/s, accelerations in m/s^2 and rad/s^2, all in NED (they are time derivatives of ``eta_d``,
not body velocities).

Two models:

- First order (the thesis's model, Figure 3.5): a low-pass filter whose rate is saturated,
  ``x_dot = sat((r - x) / T, rate_max)`` per axis, discretised exactly for a target held
  constant over the step (``update_first_order``).
- Third order (the model the thesis recommends as further work): Fossen (2011) section 12.1
  first-order prefilter in cascade with a mass-damper-spring, written as three nested loops so
  that the speed and acceleration limits sit inside the loop (the "synthetic reference model"
  idea of Fernandes et al. 2012). It respects both limits exactly, does not wind up and does
  not overshoot a large step (``update_third_order``).

Headings: by default the heading error ``target - psi_d`` is wrapped with ``ssa`` so the model
turns the short way round (``HeadingMode.SHORTEST``). With ``HeadingMode.ABSOLUTE`` the target
heading is used as given, unwrapped, so a full turn can be commanded; build such a target with
``unwrap_heading_target``. The desired heading ``psi_d`` is never wrapped inside the models (it is
continuous and can go past pi); wrap it for display with ``wrap_heading``.

Each ``update`` is a pure function ``update(state, target, dt, params) -> (new_state, output)``
that never changes its arguments; parameters and states are frozen dataclasses.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "BRAKING_FRACTION",
    "EAST",
    "MAX_OMEGA_DT",
    "NORTH",
    "PSI",
    "FirstOrderParams",
    "FirstOrderState",
    "HeadingMode",
    "ReferenceOutput",
    "ReferenceTrajectory",
    "ThirdOrderParams",
    "ThirdOrderState",
    "first_order_kernel",
    "initial_state",
    "simulate_reference",
    "ssa",
    "step_response",
    "third_order_kernel",
    "unwrap_heading_target",
    "update_first_order",
    "update_third_order",
    "wrap_heading",
]

FloatArray = NDArray[np.float64]

NORTH = 0
EAST = 1
PSI = 2
N_DOF = 3

TWO_PI = 2.0 * math.pi

_NO_FEEDFORWARD = np.zeros(N_DOF)
_NO_FEEDFORWARD.setflags(write=False)

BRAKING_FRACTION = 0.5
"""Share of ``max_accel`` the third-order model plans to brake with (-).

The rest is margin for the lag between the commanded and the actual acceleration; with 0.5
a step never overshoots (checked over random steps and limits, damping >= 1), with 0.7 the
overshoot already reaches about 0.9 % for some limits.
"""

MAX_OMEGA_DT = 0.5
"""Largest ``natural_frequency_rad_s * dt`` accepted by the third-order model (-).

The outer loops are sampled (the acceleration command is held over the step). The sampled
linear model loses stability near omega * dt = 2.9 for damping 1 and near omega * dt = 3.6 *
damping for small damping; the limit used is ``MAX_OMEGA_DT * min(1, 2 * damping)``.
"""


class HeadingMode(Enum):
    """How the heading component of the target is compared with ``psi_d``."""

    SHORTEST = "shortest"
    """Wrap the heading error with ``ssa``: turn by at most half a turn (default)."""
    ABSOLUTE = "absolute"
    """Use ``target_psi - psi_d`` as it is: the target is an unwrapped, continuous heading."""


# --------------------------------------------------------------------------------------------
# Angles
# --------------------------------------------------------------------------------------------


@overload
def ssa(angle: float) -> float: ...
@overload
def ssa(angle: FloatArray) -> FloatArray: ...
def ssa(angle: ArrayLike) -> Any:
    """Smallest signed angle: map ``angle`` (rad) into ``[-pi, pi)``.

    ``ssa(x) = ((x + pi) mod 2 pi) - pi``, with the rounding case ``mod == 2 pi`` folded back,
    so the result is always ``>= -pi`` and ``< pi``. Property: ``ssa(x) - x`` is a whole
    multiple of ``2 pi`` (up to rounding). Works on floats (returns a float) and on arrays of
    any shape (returns an array of that shape).
    """
    if np.ndim(angle) == 0:
        shifted = math.fmod(float(angle) + math.pi, TWO_PI)
        if shifted < 0.0:
            shifted += TWO_PI
        if shifted >= TWO_PI:
            shifted -= TWO_PI
        return shifted - math.pi
    shifted_arr = np.mod(np.asarray(angle, dtype=np.float64) + np.pi, TWO_PI)
    shifted_arr = np.where(shifted_arr >= TWO_PI, shifted_arr - TWO_PI, shifted_arr)
    return shifted_arr - np.pi


def wrap_heading(psi_rad: ArrayLike) -> Any:
    """Wrap a continuous heading (rad) into ``[-pi, pi)`` for display or logging; ``ssa``."""
    return ssa(psi_rad)


def unwrap_heading_target(
    current_psi_d: float, target_psi: float, direction: int, extra_turns: int = 0
) -> float:
    """Unwrapped heading target for ``HeadingMode.ABSOLUTE`` (rad).

    Returns ``current_psi_d + delta`` where ``delta`` is congruent to
    ``target_psi - current_psi_d`` modulo ``2 pi`` and:

    - ``direction = +1`` (positive yaw, clockwise seen from above in NED):
      ``delta in [0, 2 pi) + 2 pi * extra_turns``;
    - ``direction = -1`` (counter-clockwise): ``delta in (-2 pi, 0] - 2 pi * extra_turns``;
    - ``direction = 0`` (shortest): ``delta = ssa(target_psi - current_psi_d)``;
      ``extra_turns`` must then be 0.

    A full +360 deg turn from ``psi`` is ``unwrap_heading_target(psi, psi, +1, extra_turns=1)
    == psi + 2 pi``. Compute the target once when a mission leg starts and hold it; recomputing
    it every step from the moving ``psi_d`` would keep adding turns.
    """
    if direction not in (-1, 0, 1):
        raise ValueError(f"direction must be -1, 0 or +1, got {direction!r}")
    if extra_turns < 0 or (direction == 0 and extra_turns != 0):
        raise ValueError(f"extra_turns must be >= 0 and 0 for direction 0, got {extra_turns!r}")
    if not (math.isfinite(current_psi_d) and math.isfinite(target_psi)):
        raise ValueError("current_psi_d and target_psi must be finite")
    shortest = ssa(target_psi - current_psi_d)
    if direction == 0:
        return current_psi_d + shortest
    positive = shortest + TWO_PI if shortest < 0.0 else shortest  # in [0, 2 pi)
    if direction > 0:
        return current_psi_d + positive + TWO_PI * extra_turns
    negative = positive - TWO_PI if positive > 0.0 else 0.0  # in (-2 pi, 0]
    return current_psi_d + negative - TWO_PI * extra_turns


# --------------------------------------------------------------------------------------------
# Parameters, states, outputs
# --------------------------------------------------------------------------------------------


def _positive_vector(name: str, value: ArrayLike) -> FloatArray:
    """``value`` as a read-only float array of shape (3,); ValueError naming ``name`` if not
    finite and strictly positive. A scalar is broadcast to all three axes."""
    try:
        array = np.array(np.broadcast_to(np.asarray(value, dtype=np.float64), (N_DOF,)))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a float or a vector of {N_DOF} floats") from exc
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {array}")
    if not np.all(array > 0.0):
        raise ValueError(f"{name} must be > 0 on every axis, got {array}")
    array.setflags(write=False)
    return array


def _pose_vector(name: str, value: ArrayLike) -> FloatArray:
    """``value`` as a float array of shape (3,), finite; ValueError naming ``name`` if not."""
    array = np.asarray(value, dtype=np.float64)
    if array.shape != (N_DOF,):
        raise ValueError(f"{name} must have shape ({N_DOF},), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {array}")
    return array


@dataclass(frozen=True, eq=False)
class FirstOrderParams:
    """First-order reference model with saturated rate (thesis section 3.3, Figure 3.5).

    Each field is a vector (3,) ordered [north, east, psi]; a scalar is broadcast.
    """

    time_constant_s: FloatArray
    """Low-pass time constant T (s), > 0."""
    max_rate: FloatArray
    """Largest rate of the reference, m/s for north/east and rad/s for psi, > 0 (the
    "maximum speed of the system" of section 3.3)."""

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "time_constant_s", _positive_vector("time_constant_s", self.time_constant_s)
        )
        object.__setattr__(self, "max_rate", _positive_vector("max_rate", self.max_rate))


@dataclass(frozen=True, eq=False)
class ThirdOrderParams:
    """Third-order reference model with speed and acceleration limits (Fossen 2011, 12.1).

    Each field is a vector (3,) ordered [north, east, psi]; a scalar is broadcast. The loop
    gains are derived from the natural frequency w and damping z:
    ``k_pos = w / (2 z + 1)`` (1/s), ``k_vel = w`` (1/s), ``k_acc = (2 z + 1) w`` (1/s), which
    makes the unsaturated model ``w^3 / ((s + w)(s^2 + 2 z w s + w^2))``.
    """

    natural_frequency_rad_s: FloatArray
    """Natural frequency w of the mass-damper-spring and of the prefilter (rad/s), > 0."""
    damping_ratio: FloatArray
    """Relative damping z (-), > 0; z >= 1 gives no overshoot."""
    max_speed: FloatArray
    """Largest |velocity| of the reference, m/s for north/east and rad/s for psi, > 0."""
    max_accel: FloatArray
    """Largest |acceleration| of the reference, m/s^2 for north/east and rad/s^2 for psi."""
    k_pos: FloatArray = field(init=False, repr=False)
    """Position-loop gain w / (2 z + 1) (1/s), derived."""
    k_vel: FloatArray = field(init=False, repr=False)
    """Velocity-loop gain w (1/s), derived."""
    k_acc: FloatArray = field(init=False, repr=False)
    """Acceleration-lag gain (2 z + 1) w (1/s), derived."""
    max_dt_s: float = field(init=False, repr=False)
    """Largest accepted time step (s), derived: ``MAX_OMEGA_DT * min(1, 2 z) / w``."""

    def __post_init__(self) -> None:
        for name in ("natural_frequency_rad_s", "damping_ratio", "max_speed", "max_accel"):
            object.__setattr__(self, name, _positive_vector(name, getattr(self, name)))
        omega = self.natural_frequency_rad_s
        two_zeta_plus_one = 2.0 * self.damping_ratio + 1.0
        for name, gain in (
            ("k_pos", omega / two_zeta_plus_one),
            ("k_vel", omega.copy()),
            ("k_acc", omega * two_zeta_plus_one),
        ):
            gain.setflags(write=False)
            object.__setattr__(self, name, gain)
        max_dt = MAX_OMEGA_DT * np.minimum(1.0, 2.0 * self.damping_ratio) / omega
        object.__setattr__(self, "max_dt_s", float(np.min(max_dt)))


@dataclass(frozen=True, eq=False)
class FirstOrderState:
    """State of the first-order model: the desired pose only."""

    eta_d: FloatArray
    """Desired pose (3,) [north_m, east_m, psi_rad], psi continuous (not wrapped)."""

    @classmethod
    def at_rest(cls, eta_d: ArrayLike) -> FirstOrderState:
        """State resting at pose ``eta_d`` (3,) [m, m, rad]."""
        return cls(eta_d=_pose_vector("eta_d", eta_d).copy())


@dataclass(frozen=True, eq=False)
class ThirdOrderState:
    """State of the third-order model: desired pose, velocity and acceleration (3 each)."""

    eta_d: FloatArray
    """Desired pose (3,) [north_m, east_m, psi_rad], psi continuous (not wrapped)."""
    eta_dot_d: FloatArray
    """Desired velocity (3,) in NED [m/s, m/s, rad/s]."""
    eta_ddot_d: FloatArray
    """Desired acceleration (3,) in NED [m/s^2, m/s^2, rad/s^2]."""

    @classmethod
    def at_rest(cls, eta_d: ArrayLike) -> ThirdOrderState:
        """State resting (zero velocity and acceleration) at pose ``eta_d`` (3,)."""
        return cls(
            eta_d=_pose_vector("eta_d", eta_d).copy(),
            eta_dot_d=np.zeros(N_DOF),
            eta_ddot_d=np.zeros(N_DOF),
        )


@dataclass(frozen=True, eq=False)
class ReferenceOutput:
    """What the controller tracks, at the end of the step (time t + dt)."""

    eta_d: FloatArray
    """Desired pose (3,) [north_m, east_m, psi_rad], psi continuous (not wrapped)."""
    eta_dot_d: FloatArray
    """Desired velocity (3,) in NED [m/s, m/s, rad/s]."""
    eta_ddot_d: FloatArray
    """Desired acceleration (3,) in NED [m/s^2, m/s^2, rad/s^2]."""


# --------------------------------------------------------------------------------------------
# Kernels (plain numpy ufuncs on arrays of any common shape; numba.njit compiles them as is)
# --------------------------------------------------------------------------------------------


def first_order_kernel(
    error: FloatArray, time_constant_s: FloatArray, max_rate: FloatArray, dt: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Exact step of ``x_dot = sat(e / T, r_max)``, ``e = r - x``, for ``r`` held over ``dt``.

    With ``e_lin = T r_max`` (the error below which the rate is not saturated) and
    ``t_sat = max(|e| - e_lin, 0) / r_max`` (time spent at the rate limit):

    - ``dt <= t_sat``: ``|e+| = |e| - r_max dt`` (moves at exactly the rate limit);
    - else: ``|e+| = min(|e|, e_lin) exp(-(dt - t_sat) / T)`` (exponential approach);

    and ``e+`` keeps the sign of ``e``. Returns ``(e+, x_dot+, x_ddot+)``: the error, rate and
    acceleration of the continuous solution at the end of the step, with
    ``x_dot+ = sat(e+ / T, r_max)`` and ``x_ddot+ = -x_dot+ / T`` in the linear region, 0 on the
    rate limit. Exact for any ``dt > 0``, so always stable.
    """
    abs_error = np.abs(error)
    linear_error = time_constant_s * max_rate
    saturated_time = np.maximum(abs_error - linear_error, 0.0) / max_rate
    decayed = np.minimum(abs_error, linear_error) * np.exp(
        -np.maximum(dt - saturated_time, 0.0) / time_constant_s
    )
    abs_new = np.where(dt <= saturated_time, abs_error - max_rate * dt, decayed)
    new_error = np.sign(error) * abs_new
    rate = np.sign(new_error) * np.minimum(abs_new / time_constant_s, max_rate)
    accel = np.where(abs_new < linear_error, -rate / time_constant_s, 0.0)
    return new_error, rate, accel


def third_order_kernel(
    error: FloatArray,
    vel: FloatArray,
    acc: FloatArray,
    vel_ff: FloatArray,
    k_pos: FloatArray,
    k_vel: FloatArray,
    k_acc: FloatArray,
    max_speed: FloatArray,
    max_accel: FloatArray,
    dt: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """One step of the saturated third-order model; returns ``(delta_pos, vel+, acc+)``.

    Loops, per axis (``e = r - p``, ``r_dot`` the optional target-rate feedforward):

    - speed command ``v_c = sat_vmax(r_dot + sign(e) min(k_pos |e|, sqrt(2 b a_max |e|)))``,
      the square root being the braking curve at ``b a_max`` (``b = BRAKING_FRACTION``);
    - acceleration command ``a_c = sat_amax(k_vel (v_c - v))``, further limited so that the
      "settled speed" ``v_s = v + a / k_acc`` stays in ``[-v_max, v_max]``;
    - jerk ``a_dot = k_acc (a_c - a)``, ``v_dot = a``, ``p_dot = v``.

    Without saturation this is ``p''' = w^3 (r - p) + (2z+1) w^2 (r_dot - v) - (2z+1) w a``.
    ``a_c`` is held over the step and the chain is integrated exactly (``E = exp(-k_acc dt)``,
    ``phi = (1 - E) / k_acc``, ``d = a - a_c``):
    ``a+ = a_c + d E``, ``v+ = v + a_c dt + d phi``, ``p+ = p + v dt + a_c dt^2 / 2 +
    d (dt - phi) / k_acc``. Since ``v_s_dot = a_c`` exactly, ``|v_s| <= v_max``; ``v`` is a
    first-order lag of ``v_s`` and ``a`` of ``a_c``, so ``|v| <= v_max`` and ``|a| <= a_max``.
    """
    abs_error = np.abs(error)
    pull = np.minimum(k_pos * abs_error, np.sqrt((2.0 * BRAKING_FRACTION) * max_accel * abs_error))
    speed_cmd = np.minimum(np.maximum(vel_ff + np.copysign(pull, error), -max_speed), max_speed)
    settled_speed = vel + acc / k_acc
    accel_cmd = k_vel * (speed_cmd - vel)
    accel_cmd = np.minimum(
        np.maximum(accel_cmd, (-max_speed - settled_speed) / dt), (max_speed - settled_speed) / dt
    )
    accel_cmd = np.minimum(np.maximum(accel_cmd, -max_accel), max_accel)
    decay_m1 = np.expm1(k_acc * -dt)  # E - 1, accurate when k_acc dt is small
    decay = decay_m1 + 1.0
    phi = -decay_m1 / k_acc
    acc_gap = acc - accel_cmd
    acc_new = accel_cmd + acc_gap * decay
    vel_new = vel + accel_cmd * dt + acc_gap * phi
    delta_pos = vel * dt + 0.5 * accel_cmd * dt * dt + acc_gap * (dt - phi) / k_acc
    return delta_pos, vel_new, acc_new


# --------------------------------------------------------------------------------------------
# Updates
# --------------------------------------------------------------------------------------------


def _pose_error(target: ArrayLike, eta_d: FloatArray, heading_mode: HeadingMode) -> FloatArray:
    """``target - eta_d`` (3,), heading component wrapped with ``ssa`` in SHORTEST mode."""
    target_array = np.asarray(target, dtype=np.float64)
    if target_array.shape != (N_DOF,) or not np.isfinite(target_array).all():
        raise ValueError(f"target must be a finite vector of shape ({N_DOF},), got {target}")
    error = target_array - eta_d
    if heading_mode is HeadingMode.SHORTEST:
        error[PSI] = ssa(error[PSI])
    return error


def _check_dt(dt: float, max_dt: float) -> None:
    """ValueError unless ``0 < dt <= max_dt``."""
    if not 0.0 < dt <= max_dt:
        raise ValueError(f"dt must be > 0 and <= {max_dt:.6g} s, got {dt!r}")


def update_first_order(
    state: FirstOrderState,
    target: ArrayLike,
    dt: float,
    params: FirstOrderParams,
    heading_mode: HeadingMode = HeadingMode.SHORTEST,
) -> tuple[FirstOrderState, ReferenceOutput]:
    """Advance the first-order model by ``dt`` (s) towards ``target`` (3,) [m, m, rad].

    ``eta_d_dot = sat((target - eta_d) / T, max_rate)`` per axis, solved exactly for the target
    held over the step (``first_order_kernel``), so any ``dt > 0`` is stable. The output
    velocity is the model's rate at the end of the step; the output acceleration is its
    derivative, ``-eta_dot_d / T`` when the rate is not saturated and 0 on the rate limit (it
    jumps when the target steps: this model gives no acceleration limit).

    For a ramp target of rate ``r_dot`` (``|r_dot| < max_rate``) the model lags in steady state
    by ``T r_dot``.
    """
    _check_dt(dt, math.inf)
    error = _pose_error(target, state.eta_d, heading_mode)
    new_error, rate, accel = first_order_kernel(error, params.time_constant_s, params.max_rate, dt)
    eta_d = state.eta_d + (error - new_error)
    return FirstOrderState(eta_d=eta_d), ReferenceOutput(eta_d, rate, accel)


def update_third_order(
    state: ThirdOrderState,
    target: ArrayLike,
    dt: float,
    params: ThirdOrderParams,
    heading_mode: HeadingMode = HeadingMode.SHORTEST,
    target_rate: ArrayLike | None = None,
) -> tuple[ThirdOrderState, ReferenceOutput]:
    """Advance the third-order model by ``dt`` (s) towards ``target`` (3,) [m, m, rad].

    Unsaturated, per axis: ``eta_d''' + (2z+1) w eta_d'' + (2z+1) w^2 eta_d' + w^3 eta_d =
    w^3 r + (2z+1) w^2 r_dot`` (Fossen 2011, section 12.1, plus a velocity feedforward), i.e. a
    prefilter ``w / (s + w)`` in cascade with ``w^2 / (s^2 + 2 z w s + w^2)`` for steps.
    Saturated: see ``third_order_kernel``; ``|eta_dot_d| <= max_speed`` and
    ``|eta_ddot_d| <= max_accel`` always hold, and a step does not overshoot for ``z >= 1``.

    ``target_rate`` (3,) [m/s, m/s, rad/s] is the target's own rate, if known (a ramp). With it
    a ramp slower than ``max_speed`` is followed with no steady-state position error. Without it
    (``None``, zero) the model is type 1 and lags a ramp of rate ``r_dot`` by
    ``(2 z + 1) r_dot / w`` (the sum of the time constants), or by ``r_dot^2 / (2 b max_accel)``
    if that is larger (braking curve, ``b = BRAKING_FRACTION``).

    ``dt`` must satisfy ``0 < dt <= params.max_dt_s`` (see ``MAX_OMEGA_DT``).
    """
    _check_dt(dt, params.max_dt_s)
    error = _pose_error(target, state.eta_d, heading_mode)
    vel_ff = _NO_FEEDFORWARD if target_rate is None else _pose_vector("target_rate", target_rate)
    delta_pos, vel, acc = third_order_kernel(
        error,
        state.eta_dot_d,
        state.eta_ddot_d,
        vel_ff,
        params.k_pos,
        params.k_vel,
        params.k_acc,
        params.max_speed,
        params.max_accel,
        dt,
    )
    eta_d = state.eta_d + delta_pos
    return ThirdOrderState(eta_d, vel, acc), ReferenceOutput(eta_d, vel, acc)


# --------------------------------------------------------------------------------------------
# Runs over many steps (tests, plots)
# --------------------------------------------------------------------------------------------

ReferenceParams = FirstOrderParams | ThirdOrderParams
ReferenceState = FirstOrderState | ThirdOrderState

_MODELS: dict[type, tuple[Callable[..., Any], Callable[[ArrayLike], Any]]] = {
    FirstOrderParams: (update_first_order, FirstOrderState.at_rest),
    ThirdOrderParams: (update_third_order, ThirdOrderState.at_rest),
}


@dataclass(frozen=True, eq=False)
class ReferenceTrajectory:
    """A reference model run: sample 0 is the initial state, sample k is at ``k * dt``."""

    time_s: FloatArray
    """Time (N+1,) (s)."""
    eta_d: FloatArray
    """Desired pose (N+1, 3) [m, m, rad], psi continuous."""
    eta_dot_d: FloatArray
    """Desired velocity (N+1, 3) [m/s, m/s, rad/s]."""
    eta_ddot_d: FloatArray
    """Desired acceleration (N+1, 3) [m/s^2, m/s^2, rad/s^2]."""


def initial_state(params: ReferenceParams, eta_d: ArrayLike) -> ReferenceState:
    """The model's state resting at pose ``eta_d`` (3,), the model chosen by ``params``."""
    return _MODELS[type(params)][1](eta_d)


def simulate_reference(
    params: ReferenceParams,
    targets: ArrayLike,
    dt: float,
    state: ReferenceState | None = None,
    heading_mode: HeadingMode = HeadingMode.SHORTEST,
    target_rates: ArrayLike | None = None,
) -> ReferenceTrajectory:
    """Run the model chosen by ``params`` over ``targets`` (N, 3), one target per step.

    ``state`` defaults to rest at the origin. ``target_rates`` (N, 3) is passed to the
    third-order model as ``target_rate`` (the first-order model takes none).
    """
    update = _MODELS[type(params)][0]
    target_array = np.asarray(targets, dtype=np.float64)
    if target_array.ndim != 2 or target_array.shape[1] != N_DOF:
        raise ValueError(f"targets must have shape (N, {N_DOF}), got {target_array.shape}")
    n_steps = target_array.shape[0]
    rates = None if target_rates is None else np.broadcast_to(target_rates, target_array.shape)
    current = initial_state(params, np.zeros(N_DOF)) if state is None else state
    eta = np.empty((n_steps + 1, N_DOF))
    eta_dot = np.zeros((n_steps + 1, N_DOF))
    eta_ddot = np.zeros((n_steps + 1, N_DOF))
    eta[0] = current.eta_d
    if isinstance(current, ThirdOrderState):
        eta_dot[0], eta_ddot[0] = current.eta_dot_d, current.eta_ddot_d
    options: dict[str, Any] = {"heading_mode": heading_mode}
    for k in range(n_steps):
        if rates is not None:
            options["target_rate"] = rates[k]
        current, out = update(current, target_array[k], dt, params, **options)
        eta[k + 1], eta_dot[k + 1], eta_ddot[k + 1] = out.eta_d, out.eta_dot_d, out.eta_ddot_d
    time_s = dt * np.arange(n_steps + 1)
    return ReferenceTrajectory(time_s, eta, eta_dot, eta_ddot)


def step_response(
    params: ReferenceParams,
    target: ArrayLike,
    dt: float,
    n_steps: int,
    state: ReferenceState | None = None,
    heading_mode: HeadingMode = HeadingMode.SHORTEST,
) -> ReferenceTrajectory:
    """Run the model for ``n_steps`` steps of ``dt`` (s) towards a constant ``target`` (3,).

    ``state`` defaults to rest at the origin, so the target is the step size.
    """
    targets = np.broadcast_to(_pose_vector("target", target), (n_steps, N_DOF))
    return simulate_reference(params, targets, dt, state, heading_mode)
