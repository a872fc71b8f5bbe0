"""Reference models (control/reference.py) as the control loop steps them (control/refkernel.py).

Every run here goes through ``refkernel.reference_step``, the compiled step the closed loop
calls, with the parameters packed as ``control.config`` packs them.

Tolerances:
- ROUNDOFF (1e-12 relative): results that are exact in real arithmetic (exact discretisation,
  limits enforced by construction) and differ only by floating-point rounding over a few
  thousand steps.
- The third-order model holds its acceleration command over each step (sample and hold), a
  first-order-in-dt approximation of the continuous model: measured position error
  0.11-0.20 * w * dt * |step| for damping 0.7-1.5; the tests allow 0.5 * w * dt * |step| and
  check that halving dt halves the error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from control import loop, refkernel
from control.reference import (
    BRAKING_FRACTION,
    FirstOrderParams,
    ThirdOrderParams,
    first_order_kernel,
    third_order_kernel,
)
from sim.gnc import JIT

ROUNDOFF = 1e-12
_THIRD_COMPILED = njit(**JIT)(third_order_kernel)
"""The array form of the third-order kernel, compiled as the loop used to run it."""
PI = math.pi
NORTH, EAST, PSI = 0, 1, 2
"""Axes of a reference [north, east, heading]."""

FloatArray = NDArray[np.float64]
Params = FirstOrderParams | ThirdOrderParams


def first_order_params(time_constant_s: float = 5.0, max_rate: float = 0.05) -> FirstOrderParams:
    return FirstOrderParams(time_constant_s=time_constant_s, max_rate=max_rate)


def third_order_params(
    omega: float = 0.5, zeta: float = 1.0, max_speed: float = 0.05, max_accel: float = 0.01
) -> ThirdOrderParams:
    return ThirdOrderParams(
        natural_frequency_rad_s=omega, damping_ratio=zeta, max_speed=max_speed, max_accel=max_accel
    )


# --------------------------------------------------------------------------------------------
# Running the compiled step
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Run:
    """A run of the reference model: sample 0 is the start, sample k is at ``k * dt``."""

    time_s: FloatArray
    """(N+1,) [s]."""
    eta_d: FloatArray
    """(N+1, 3) desired pose [m, m, rad], psi continuous."""
    eta_dot_d: FloatArray
    """(N+1, 3) desired velocity [m/s, m/s, rad/s]."""
    eta_ddot_d: FloatArray
    """(N+1, 3) desired acceleration [m/s^2, m/s^2, rad/s^2]."""


def packed(params: Params) -> tuple[int, FloatArray]:
    """The loop's model kind and (5, 3) parameter array, as control.config builds them."""
    if isinstance(params, FirstOrderParams):
        return loop.REF_FIRST, refkernel.pack_first_order(params)
    return loop.REF_THIRD, refkernel.pack_third_order(params)


def at_rest(pose: ArrayLike) -> FloatArray:
    """Reference state (9,) resting at ``pose`` (3,): zero rate and acceleration."""
    state = np.zeros(9)
    state[0:3] = pose
    return state


def run_reference(
    params: Params, targets: ArrayLike, dt: float, start: FloatArray | None = None
) -> Run:
    """Step the compiled model over ``targets`` (N, 3), one target per step, from ``start``
    (default: at rest at the origin)."""
    kind, p = packed(params)
    targets = np.array(targets, dtype=np.float64)
    state = np.zeros(9) if start is None else np.array(start, dtype=np.float64)
    states = np.empty((targets.shape[0] + 1, 9))
    states[0] = state
    for k in range(targets.shape[0]):
        state = refkernel.reference_step(kind, state, targets[k], dt, p)
        states[k + 1] = state
    time_s = dt * np.arange(targets.shape[0] + 1)
    return Run(time_s, states[:, 0:3], states[:, 3:6], states[:, 6:9])


def step_response(
    params: Params, target: ArrayLike, dt: float, n_steps: int, start: FloatArray | None = None
) -> Run:
    """``n_steps`` steps of ``dt`` towards a constant ``target`` (3,)."""
    return run_reference(params, np.tile(np.asarray(target, float), (n_steps, 1)), dt, start)


# --------------------------------------------------------------------------------------------
# Headings: the kernels take the plain difference and never wrap psi_d
# --------------------------------------------------------------------------------------------

HEADING_MODELS = [
    pytest.param(FirstOrderParams(time_constant_s=2.0, max_rate=math.radians(5)), id="first"),
    pytest.param(third_order_params(0.8, 1.0, math.radians(5), math.radians(2)), id="third"),
]


@pytest.mark.parametrize("params", HEADING_MODELS)
def test_heading_stays_continuous_across_pi(params: Params) -> None:
    # From 170 deg to -170 deg the short way is +20 deg: Simulation.set_target makes the
    # target 190 deg, and psi_d goes there without being wrapped.
    run = step_response(
        params,
        [0.0, 0.0, math.radians(190)],
        0.05,
        1200,
        start=at_rest([0.0, 0.0, math.radians(170)]),
    )
    psi = run.eta_d[:, PSI]
    assert psi[-1] == pytest.approx(math.radians(190), abs=1e-6)
    assert np.all(np.diff(psi) >= -ROUNDOFF)


@pytest.mark.parametrize("params", HEADING_MODELS)
def test_full_circle_target_turns_a_full_circle_and_back(params: Params) -> None:
    psi0 = 0.3
    n_steps = 3000  # 150 s: 360 deg at 5 deg/s is 72 s, plus accel, decel and settling
    run = step_response(
        params, [1.0, 1.0, psi0 + 2 * PI], 0.05, n_steps, start=at_rest([1.0, 1.0, psi0])
    )
    psi = run.eta_d[:, PSI]
    assert psi[-1] == pytest.approx(psi0 + 2 * PI, abs=1e-6)
    assert np.all(np.diff(psi) >= -ROUNDOFF)
    assert np.all(run.eta_d[:, 0:2] == 1.0)  # position untouched
    back = step_response(params, [1.0, 1.0, psi0], 0.05, n_steps, start=at_rest(run.eta_d[-1]))
    assert back.eta_d[-1, PSI] == pytest.approx(psi0, abs=1e-6)
    assert np.all(np.diff(back.eta_d[:, PSI]) <= ROUNDOFF)


# --------------------------------------------------------------------------------------------
# First-order model
# --------------------------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    time_constant=st.floats(min_value=0.05, max_value=50),
    max_rate=st.floats(min_value=1e-3, max_value=2),
    step=st.lists(st.floats(min_value=-100, max_value=100), min_size=3, max_size=3),
    dt=st.floats(min_value=1e-3, max_value=2.0),
)
def test_first_order_rate_never_exceeds_max_rate(
    time_constant: float, max_rate: float, step: list[float], dt: float
) -> None:
    params = first_order_params(time_constant, max_rate)
    run = step_response(params, step, dt, 200)
    limit = max_rate * (1 + ROUNDOFF)
    assert np.all(np.abs(run.eta_dot_d) <= limit)
    # Positions up to 100 carry ~1e-14 of rounding, large next to max_rate * dt (>= 1e-6).
    position_roundoff = 1e-13 * (1.0 + np.abs(step).max())
    assert np.all(np.abs(np.diff(run.eta_d, axis=0)) <= limit * dt + position_roundoff)
    # It moves towards the target and never past it (the pose is target - error: rounding
    # of the size of the target's last bit).
    assert np.all(np.abs(step - run.eta_d) <= np.abs(step) * (1 + ROUNDOFF) + position_roundoff)


def test_first_order_small_step_is_exponential() -> None:
    time_constant, dt = 4.0, 0.01
    params = first_order_params(time_constant, max_rate=1.0)
    step = np.array([0.5, -0.2, 0.1])  # all below T * max_rate = 4: never rate limited
    run = step_response(params, step, dt, 2000)
    decay = np.exp(-run.time_s / time_constant)[:, None]
    # Exact discretisation: only rounding separates it from the closed form.
    np.testing.assert_allclose(run.eta_d, step * (1 - decay), rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.eta_dot_d[1:], (step * decay / time_constant)[1:], atol=1e-12)
    np.testing.assert_allclose(
        run.eta_ddot_d[1:], (-step * decay / time_constant**2)[1:], atol=1e-12
    )


def test_first_order_large_step_moves_at_max_rate_until_close() -> None:
    time_constant, max_rate, dt, step = 5.0, 0.05, 0.01, 2.0
    params = first_order_params(time_constant, max_rate)
    run = step_response(params, [step, -step, 0.0], dt, 10000)
    north = run.eta_d[:, NORTH]
    t_sat = (step - time_constant * max_rate) / max_rate  # 35 s at the rate limit
    on_limit = run.time_s <= t_sat - dt
    np.testing.assert_allclose(np.diff(north)[on_limit[1:]], max_rate * dt, rtol=1e-9)
    np.testing.assert_allclose(run.eta_dot_d[1:, NORTH][on_limit[1:]], max_rate, rtol=1e-12)
    np.testing.assert_allclose(run.eta_ddot_d[1:, NORTH][on_limit[1:]], 0.0, atol=0)
    # After that, exponential approach from T * max_rate away (closed form, exact).
    tail = np.where(
        run.time_s <= t_sat,
        max_rate * run.time_s,
        step - time_constant * max_rate * np.exp(-(run.time_s - t_sat) / time_constant),
    )
    np.testing.assert_allclose(north, tail, atol=1e-9)
    np.testing.assert_allclose(run.eta_d[:, EAST], -tail, atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    time_constant=st.floats(min_value=0.05, max_value=50),
    max_rate=st.floats(min_value=1e-3, max_value=2),
    error=st.floats(min_value=-100, max_value=100),
    dt=st.floats(min_value=1e-3, max_value=5.0),
)
def test_first_order_two_half_steps_equal_one_step(
    time_constant: float, max_rate: float, error: float, dt: float
) -> None:
    # Exact discretisation is a semigroup: x(2 dt) from x(0) == x(dt) from x(dt).
    params = first_order_params(time_constant, max_rate)
    target = [error, -error, 0.5 * error]
    one = step_response(params, target, 2 * dt, 1)
    two = step_response(params, target, dt, 2)
    np.testing.assert_allclose(two.eta_d[-1], one.eta_d[-1], rtol=1e-9, atol=1e-12)


def test_first_order_ramp_lags_by_time_constant_times_rate() -> None:
    time_constant, dt, rate = 2.0, 0.01, 0.01
    params = first_order_params(time_constant, max_rate=0.05)  # lag 0.02 < T * max_rate = 0.1
    times = dt * np.arange(6000)
    targets = np.column_stack([rate * times, np.zeros_like(times), np.zeros_like(times)])
    run = run_reference(params, targets, dt)
    lag = targets[-1, NORTH] - run.eta_d[-2, NORTH]  # target and pose at the same instant, 30 T
    # Sampled ramp: lag = rate * dt / (1 - exp(-dt / T)) = rate * (T + dt / 2) + O(dt^2).
    assert lag == pytest.approx(rate * dt / -math.expm1(-dt / time_constant), rel=1e-9)
    assert lag == pytest.approx(rate * time_constant, abs=rate * dt)


# --------------------------------------------------------------------------------------------
# Third-order model
# --------------------------------------------------------------------------------------------

axis_params = st.tuples(
    st.floats(min_value=0.1, max_value=2.0),  # natural frequency (rad/s)
    st.floats(min_value=0.3, max_value=3.0),  # damping ratio
    st.floats(min_value=0.01, max_value=1.0),  # max speed
    st.floats(min_value=1e-3, max_value=1.0),  # max accel
)


def params_from_axes(axes: list[tuple[float, float, float, float]]) -> ThirdOrderParams:
    omega, zeta, speed, accel = (np.array(column) for column in zip(*axes, strict=True))
    return ThirdOrderParams(omega, zeta, speed, accel)


@settings(max_examples=40, deadline=None)
@given(
    axes=st.lists(axis_params, min_size=3, max_size=3),
    targets=st.lists(
        st.lists(st.floats(min_value=-50, max_value=50), min_size=3, max_size=3),
        min_size=1,
        max_size=4,
    ),
)
def test_third_order_never_exceeds_speed_or_accel(
    axes: list[tuple[float, float, float, float]],
    targets: list[list[float]],
) -> None:
    params = params_from_axes(axes)
    dt = min(0.05, params.max_dt_s)
    n_steps = 1600
    # Piecewise-constant target that jumps while the model is moving (windup check).
    schedule = np.repeat(np.array(targets), -(-n_steps // len(targets)), axis=0)[:n_steps]
    run = run_reference(params, schedule, dt)
    # Limits hold by construction; only rounding can exceed them.
    assert np.all(np.abs(run.eta_dot_d) <= params.max_speed * (1 + ROUNDOFF))
    assert np.all(np.abs(run.eta_ddot_d) <= params.max_accel * (1 + ROUNDOFF))
    assert np.all(np.isfinite(run.eta_d))


settling_axis = st.tuples(
    st.floats(min_value=0.5, max_value=2.0),  # natural frequency (rad/s)
    st.floats(min_value=1.0, max_value=2.0),  # damping ratio
    st.floats(min_value=0.02, max_value=1.0),  # max speed
    st.floats(min_value=0.1, max_value=10.0),  # time to reach max speed at max accel (s)
)


@settings(max_examples=12, deadline=None)
@given(
    axes=st.lists(settling_axis, min_size=3, max_size=3),
    step_over_speed_s=st.lists(st.floats(min_value=0.05, max_value=40), min_size=3, max_size=3),
    signs=st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3),
)
def test_third_order_step_settles_without_overshoot(
    axes: list[tuple[float, float, float, float]],
    step_over_speed_s: list[float],
    signs: list[float],
) -> None:
    params = params_from_axes([(w, z, v, v / ramp) for w, z, v, ramp in axes])
    step = np.array(signs) * np.array(step_over_speed_s) * params.max_speed
    omega, zeta = params.natural_frequency_rad_s, params.damping_ratio
    # Cruise + accel/decel time + 14 time constants of the slowest linear pole w(z - sqrt(z^2-1)).
    cruise = np.abs(step) / params.max_speed
    ramps = params.max_speed / params.max_accel * (1 + 1 / BRAKING_FRACTION)
    slowest_pole = omega * (zeta - np.sqrt(zeta**2 - 1))
    duration = float(np.max(cruise + ramps + 14 / slowest_pole))
    dt = 0.05
    run = step_response(params, step, dt, int(duration / dt))
    progress = run.eta_d / step  # 0 at the start, 1 at the target
    assert np.all(progress.max(axis=0) < 1.01)  # overshoot below 1 % of the step
    assert np.all(progress.min(axis=0) > -0.01)  # and no initial swing the wrong way
    np.testing.assert_allclose(run.eta_d[-1], step, rtol=1e-3)


def linear_third_order(omega: float, zeta: float, times: np.ndarray, step: float) -> np.ndarray:
    """Step response (position, velocity, acceleration) of w^3 / ((s + w)(s^2 + 2 z w s + w^2))."""
    den = np.polymul([1.0, omega], [1.0, 2 * zeta * omega, omega**2])
    outputs = []
    for num in ([omega**3], [omega**3, 0.0], [omega**3, 0.0, 0.0]):
        _, y, _ = signal.lsim(signal.lti(num, den), np.full_like(times, step), times)
        outputs.append(y)
    return np.array(outputs)


def third_order_error(omega: float, zeta: float, dt: float, step: float) -> np.ndarray:
    """Max |model - linear closed form| for position, velocity, acceleration."""
    params = third_order_params(omega, zeta, max_speed=1.0, max_accel=1.0)
    run = step_response(params, [step, step, step], dt, int(40 / dt))
    assert np.abs(run.eta_dot_d).max() < 0.1 and np.abs(run.eta_ddot_d).max() < 0.1  # unsaturated
    expected = linear_third_order(omega, zeta, run.time_s, step)
    actual = np.array([run.eta_d[:, PSI], run.eta_dot_d[:, PSI], run.eta_ddot_d[:, PSI]])
    np.testing.assert_allclose(run.eta_d[:, NORTH], run.eta_d[:, PSI], atol=1e-15)  # same axes
    return np.abs(actual - expected).max(axis=1)


def test_third_order_small_step_matches_critically_damped_closed_form() -> None:
    omega, dt, step = 0.5, 0.01, 0.1
    params = third_order_params(omega, 1.0, max_speed=1.0, max_accel=1.0)
    run = step_response(params, [step, 0.0, 0.0], dt, 4000)
    x = omega * run.time_s
    # Triple pole at -w: y = 1 - e^-x (1 + x + x^2 / 2), y' = w e^-x x^2 / 2,
    # y'' = w^2 e^-x (x - x^2 / 2).
    pos = step * (1 - np.exp(-x) * (1 + x + x**2 / 2))
    vel = step * omega * np.exp(-x) * x**2 / 2
    acc = step * omega**2 * np.exp(-x) * (x - x**2 / 2)
    tol = 0.5 * omega * dt * step  # sample-and-hold error, see module docstring
    np.testing.assert_allclose(run.eta_d[:, NORTH], pos, atol=tol)
    np.testing.assert_allclose(run.eta_dot_d[:, NORTH], vel, atol=tol * omega)
    np.testing.assert_allclose(run.eta_ddot_d[:, NORTH], acc, atol=tol * omega**2)


@pytest.mark.parametrize("zeta", [0.7, 1.5])
def test_third_order_small_step_matches_lsim_and_converges(zeta: float) -> None:
    omega, step = 0.5, 0.1
    coarse = third_order_error(omega, zeta, 0.02, step)
    fine = third_order_error(omega, zeta, 0.01, step)
    assert fine[0] < 0.5 * omega * 0.01 * step
    assert fine[1] < 0.5 * omega**2 * 0.01 * step
    assert fine[2] < 0.5 * omega**3 * 0.01 * step
    # First-order convergence in dt: the gap is discretisation, not a model error.
    np.testing.assert_allclose(coarse / fine, 2.0, rtol=0.1)


def test_third_order_two_metre_step_takes_cruise_plus_ramps() -> None:
    speed, accel, dt, step = 0.05, 0.01, 0.01, 2.0
    params = third_order_params(0.5, 1.0, speed, accel)
    run = step_response(params, [step, 0.0, 0.0], dt, 7000)
    arrived = run.time_s[np.argmax(np.abs(step - run.eta_d[:, NORTH]) < 0.01 * step)]
    # Fastest possible with |v| <= v_max, |a| <= a_max: trapezoid, 2 / 0.05 + 0.05 / 0.01 = 45 s.
    assert arrived >= step / speed + speed / accel
    # This model accelerates at a_max and plans to brake at BRAKING_FRACTION * a_max: 47.5 s,
    # plus the lags of the acceleration loop (3 / k_acc = 2 s).
    trapezoid = step / speed + speed / (2 * accel) + speed / (2 * BRAKING_FRACTION * accel)
    assert arrived <= trapezoid + 3 / params.k_acc[NORTH]
    # Most of the way at max speed: the trapezoid cruises for 40 - 2.5 - 5 = 32.5 s, less about
    # ln(100) / k_acc = 3 s for the speed to come within 1 % (measured 30.6 s).
    cruising = run.eta_dot_d[:, NORTH] >= 0.99 * speed
    assert cruising.sum() * dt > 28.0


def _third_order_ramp(
    params: ThirdOrderParams, targets: FloatArray, rates: FloatArray, dt: float
) -> tuple[FloatArray, FloatArray]:
    """Final pose and velocity (3,) of the third-order kernel following ``targets`` (N, 3) with
    the target rate ``rates`` (3,) fed forward (the kernel's ``vel_ff``; the control loop
    passes zero)."""
    pose, vel, acc = np.zeros(3), np.zeros(3), np.zeros(3)
    for target in targets:
        delta, vel, acc = third_order_kernel(
            target - pose,
            vel,
            acc,
            rates,
            params.k_pos,
            params.k_vel,
            params.k_acc,
            params.max_speed,
            params.max_accel,
            dt,
        )
        pose = pose + delta
    return pose, vel


def test_third_order_ramp_with_feedforward_has_no_steady_state_error() -> None:
    omega, zeta, dt, rate = 0.5, 1.0, 0.01, 0.02
    params = third_order_params(omega, zeta, max_speed=0.05, max_accel=0.01)
    times = dt * np.arange(8000)
    targets = np.column_stack([rate * times, -rate * times, 0.5 * rate * times])
    rates = np.array([rate, -rate, 0.5 * rate])
    pose, vel = _third_order_ramp(params, targets, rates, dt)
    np.testing.assert_allclose(pose, targets[-1] + rates * dt, atol=1e-9)
    np.testing.assert_allclose(vel, rates, atol=1e-12)
    # Without the feedforward (the control loop's case) the model is type 1: it lags by
    # (2 z + 1) r_dot / w = 0.12 m.
    without = run_reference(params, targets, dt)
    lag = targets[-1] - without.eta_d[-2]
    np.testing.assert_allclose(lag, (2 * zeta + 1) * rates / omega, rtol=1e-6)


# --------------------------------------------------------------------------------------------
# Parameters, purity, compilation
# --------------------------------------------------------------------------------------------

GOOD_FIRST = {"time_constant_s": 5.0, "max_rate": [0.05, 0.05, 0.05]}
GOOD_THIRD = {
    "natural_frequency_rad_s": 0.5,
    "damping_ratio": 1.0,
    "max_speed": 0.05,
    "max_accel": 0.01,
}
BAD_VALUES = [0.0, -1.0, math.nan, math.inf, [0.1, 0.0, 0.1], [0.1, math.nan, 0.1], [1.0, 2.0]]


@pytest.mark.parametrize("bad", BAD_VALUES)
@pytest.mark.parametrize(
    ("cls", "good", "name"),
    [(FirstOrderParams, GOOD_FIRST, name) for name in GOOD_FIRST]
    + [(ThirdOrderParams, GOOD_THIRD, name) for name in GOOD_THIRD],
)
def test_invalid_params_name_the_field(cls: type, good: dict, name: str, bad: object) -> None:
    with pytest.raises(ValueError, match=name):
        cls(**{**good, name: bad})


def test_params_are_read_only() -> None:
    params = ThirdOrderParams(**GOOD_THIRD)
    with pytest.raises(ValueError):
        params.max_speed[0] = 10.0
    with pytest.raises(AttributeError):
        params.max_speed = np.ones(3)  # type: ignore[misc]


def test_packed_params_are_the_loop_gains_and_limits() -> None:
    """The rows control.refkernel documents: [k_pos or 1/T, k_vel, k_acc, max speed or rate,
    max accel]; for w = 0.5, z = 1: k_pos = w / 3, k_vel = w, k_acc = 3 w."""
    third = refkernel.pack_third_order(ThirdOrderParams(**GOOD_THIRD))
    np.testing.assert_allclose(third[:, 0], [0.5 / 3, 0.5, 1.5, 0.05, 0.01], rtol=1e-15)
    first = refkernel.pack_first_order(FirstOrderParams(**GOOD_FIRST))
    np.testing.assert_allclose(first[:, 0], [0.2, 0.0, 0.0, 0.05, 0.0], rtol=1e-15)


@pytest.mark.parametrize(
    "params",
    [FirstOrderParams(**GOOD_FIRST), ThirdOrderParams(**GOOD_THIRD)],
    ids=["first", "third"],
)
def test_step_does_not_change_its_arguments_and_is_deterministic(params: Params) -> None:
    kind, p = packed(params)
    state = np.array([0.1, 0.2, 0.3, 0.01, 0.0, -0.01, 0.001, 0.0, 0.0])
    target = np.array([3.0, -2.0, 4.0])
    copies = state.copy(), target.copy(), p.copy()
    new = refkernel.reference_step(kind, state, target, 0.1, p)
    again = refkernel.reference_step(kind, state, target, 0.1, p)
    for array, copy in zip((state, target, p), copies, strict=True):
        np.testing.assert_array_equal(array, copy)
    np.testing.assert_array_equal(new, again)
    assert new.shape == (9,)
    assert not np.array_equal(new[0:3], state[0:3])


def test_compiled_kernels_do_the_numpy_arithmetic() -> None:
    """control.refkernel compiles the kernels of control.reference as they stand: the same
    numbers to the last bits (1e-14 relative allows for numba's own exp and sqrt)."""
    error = np.array([2.0, -0.01, 0.3])
    first_args = (error, np.full(3, 5.0), np.full(3, 0.05), 0.01)
    params = ThirdOrderParams(**GOOD_THIRD)
    third_args = (
        error,
        np.full(3, 0.01),
        np.full(3, -0.001),
        np.zeros(3),
        params.k_pos,
        params.k_vel,
        params.k_acc,
        params.max_speed,
        params.max_accel,
        0.01,
    )
    pairs = (
        (refkernel._first_kernel, first_order_kernel, first_args),
        (_THIRD_COMPILED, third_order_kernel, third_args),
    )
    for jitted, plain, args in pairs:
        for a, b in zip(jitted(*args), plain(*args), strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("frequencies", [0.5, [0.5, 0.7, 0.5], [0.4, 0.4, 0.9]])
def test_the_loops_third_order_step_is_the_array_kernel_to_the_bit(frequencies) -> None:
    """refkernel.third_order_step runs the kernel per axis on scalars (no temporary arrays):
    the same operations in the same order as the compiled array form, so the same bits, over
    states inside and outside the speed and acceleration limits; with one k_acc for the
    three axes (one decay for all) and with axes of their own."""
    rng = np.random.default_rng(11)
    params = ThirdOrderParams(**{**GOOD_THIRD, "natural_frequency_rad_s": frequencies})
    packed = refkernel.pack_third_order(params)
    for _ in range(500):
        state = rng.normal(0.0, 1.0, 9) * np.repeat([3.0, 0.3, 0.05], 3)
        target = rng.normal(0.0, 3.0, 3)
        dt = float(rng.choice([0.01, 0.05, 0.2]))
        got = refkernel.third_order_step(state, target, dt, packed)
        delta, vel, acc = _THIRD_COMPILED(
            target - state[0:3],
            state[3:6].copy(),
            state[6:9].copy(),
            np.zeros(3),
            params.k_pos,
            params.k_vel,
            params.k_acc,
            params.max_speed,
            params.max_accel,
            dt,
        )
        want = np.concatenate([state[0:3] + delta, vel, acc])
        assert np.array_equal(got, want), (state, target, dt)


def test_the_loops_first_order_step_is_the_array_kernel_to_the_bit() -> None:
    """refkernel.first_order_step runs the kernel per axis on scalars (no temporary arrays, as
    the closed loop's step must allocate nothing): the same bits as the compiled array form of
    ``first_order_kernel``, on the rate limit, on the exponential approach and across the
    switch between them, and into the state's own array."""
    rng = np.random.default_rng(12)
    packed = refkernel.pack_first_order(FirstOrderParams(**GOOD_FIRST))
    time_constant = 1.0 / packed[0]
    for _ in range(500):
        state = rng.normal(0.0, 1.0, 9) * np.repeat([1.0, 0.05, 0.01], 3)
        target = state[0:3] + rng.normal(0.0, 1.0, 3) * rng.choice([0.01, 0.25, 3.0])
        dt = float(rng.choice([0.01, 0.05, 2.0]))
        got = refkernel.first_order_step(state, target, dt, packed)
        new_error, rate, accel = refkernel._first_kernel(
            target - state[0:3], time_constant, packed[3].copy(), dt
        )
        want = np.concatenate([target - new_error, rate, accel])
        assert np.array_equal(got, want), (state, target, dt)
        in_place = state.copy()
        refkernel.reference_step_into(in_place, loop.REF_FIRST, in_place, target, dt, packed)
        assert np.array_equal(in_place, want)
