"""Reference models: turn a (possibly stepping) target pose into a smooth, feasible trajectory.

The reference model sits between the mission (which commands target poses) and the controller
(which tracks the desired pose, velocity and acceleration). Thesis section 3.3: "make smooth and
feasible trajectories that is within the bandwidth of the controller".

Everything here works on 3-DOF horizontal-plane vectors ordered ``[north_m, east_m, psi_rad]``
(NED position and heading). Velocities are in m/s and rad/s, accelerations in m/s^2 and
rad/s^2, all in NED (they are time derivatives of ``eta_d``, not body velocities).

Two models, each a parameter set (frozen dataclass, checked) and a kernel (plain numpy
arithmetic on arrays of any common shape, which ``control.refkernel`` compiles with numba and
steps inside the control loop):

- First order (the thesis's model, Figure 3.5): a low-pass filter whose rate is saturated,
  ``x_dot = sat((r - x) / T, rate_max)`` per axis, discretised exactly for a target held
  constant over the step (``first_order_kernel``).
- Third order (the model the thesis recommends as further work): Fossen (2011) section 12.1
  first-order prefilter in cascade with a mass-damper-spring, written as three nested loops so
  that the speed and acceleration limits sit inside the loop (the "synthetic reference model"
  idea of Fernandes et al. 2012). It respects both limits exactly, does not wind up and does
  not overshoot a large step (``third_order_kernel``).

The kernels take the plain difference ``target - eta_d``: the caller chooses the heading target
(the short way round, or an unwrapped multi-turn target; ``Simulation.set_target``), and the
desired heading ``psi_d`` is never wrapped (it is continuous and can go past pi).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "BRAKING_FRACTION",
    "MAX_OMEGA_DT",
    "FirstOrderParams",
    "ThirdOrderParams",
    "first_order_kernel",
    "third_order_kernel",
]

FloatArray = NDArray[np.float64]

N_DOF = 3
"""Axes of a reference: north, east, heading."""

BRAKING_FRACTION = 0.5
"""Share of ``max_accel`` the third-order model plans to brake with (-).

The rest is margin for the lag between the commanded and the actual acceleration; with 0.5
a step never overshoots (checked over random steps and limits, damping >= 1), with 0.7 the
overshoot already reaches about 0.9 % for some limits.
"""

MAX_OMEGA_DT = 0.5
"""Largest ``natural_frequency_rad_s * dt`` to step the third-order model with (-).

The outer loops are sampled (the acceleration command is held over the step). The sampled
linear model loses stability near omega * dt = 2.9 for damping 1 and near omega * dt = 3.6 *
damping for small damping; the limit used is ``MAX_OMEGA_DT * min(1, 2 * damping)``.
"""


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
    """Largest time step to step the model with (s), derived: ``MAX_OMEGA_DT * min(1, 2 z) / w``
    (the control loop's 0.01 s is far below it for the parameter sets' bandwidths)."""

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

    Loops, per axis (``e = r - p``, ``r_dot = vel_ff`` the target's own rate, if known; the
    control loop passes zero):

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
