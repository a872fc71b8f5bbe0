"""Tests of control/reference.py: angle helpers, first-order and third-order reference models.

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

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal

from control.reference import (
    BRAKING_FRACTION,
    EAST,
    NORTH,
    PSI,
    FirstOrderParams,
    FirstOrderState,
    HeadingMode,
    ReferenceOutput,
    ThirdOrderParams,
    ThirdOrderState,
    first_order_kernel,
    initial_state,
    simulate_reference,
    ssa,
    step_response,
    third_order_kernel,
    unwrap_heading_target,
    update_first_order,
    update_third_order,
    wrap_heading,
)

ROUNDOFF = 1e-12
PI = math.pi

positive = st.floats(min_value=1e-3, max_value=1e3)
angles = st.floats(min_value=-1e4, max_value=1e4, allow_nan=False)


def first_order_params(time_constant_s: float = 5.0, max_rate: float = 0.05) -> FirstOrderParams:
    return FirstOrderParams(time_constant_s=time_constant_s, max_rate=max_rate)


def third_order_params(
    omega: float = 0.5, zeta: float = 1.0, max_speed: float = 0.05, max_accel: float = 0.01
) -> ThirdOrderParams:
    return ThirdOrderParams(
        natural_frequency_rad_s=omega, damping_ratio=zeta, max_speed=max_speed, max_accel=max_accel
    )


# --------------------------------------------------------------------------------------------
# Angles
# --------------------------------------------------------------------------------------------


@given(angles)
def test_ssa_scalar_in_range_and_congruent(angle: float) -> None:
    wrapped = ssa(angle)
    assert -PI <= wrapped < PI
    turns = (angle - wrapped) / (2 * PI)
    # 1e4 rad carries about 2e-12 rad of rounding; 1e-9 turn is far above it.
    assert abs(turns - round(turns)) < 1e-9


@given(st.lists(angles, min_size=1, max_size=20))
def test_ssa_array_matches_scalar(values: list[float]) -> None:
    wrapped = ssa(np.array(values))
    assert np.all(wrapped >= -PI) and np.all(wrapped < PI)
    np.testing.assert_allclose(wrapped, [ssa(v) for v in values], rtol=0, atol=ROUNDOFF)


@pytest.mark.parametrize(
    "angle", [PI, -PI, 3 * PI, -3 * PI, np.nextafter(PI, 0.0), np.nextafter(-PI, -4.0), -1e-300]
)
def test_ssa_edges_stay_in_half_open_interval(angle: float) -> None:
    for wrapped in (ssa(angle), float(ssa(np.array([angle]))[0]), wrap_heading(angle)):
        assert -PI <= wrapped < PI


def test_ssa_pi_maps_to_minus_pi() -> None:
    assert ssa(PI) == -PI
    assert wrap_heading(3 * PI) == pytest.approx(-PI, abs=ROUNDOFF)


@given(
    st.floats(min_value=-20, max_value=20),
    st.floats(min_value=-20, max_value=20),
    st.sampled_from([-1, 0, 1]),
)
def test_unwrap_heading_target_laws(current: float, target: float, direction: int) -> None:
    unwrapped = unwrap_heading_target(current, target, direction)
    delta = unwrapped - current
    assert abs(ssa(unwrapped - target)) < 1e-9  # same heading as the target
    if direction > 0:
        assert 0.0 <= delta < 2 * PI
    elif direction < 0:
        assert -2 * PI < delta <= 0.0
    else:
        assert -PI <= delta < PI


def test_unwrap_heading_target_full_turns() -> None:
    psi = 0.3
    assert unwrap_heading_target(psi, psi, +1, extra_turns=1) == pytest.approx(psi + 2 * PI)
    assert unwrap_heading_target(psi, psi, -1, extra_turns=1) == pytest.approx(psi - 2 * PI)
    # 10 deg -> 350 deg clockwise is +340 deg, counter-clockwise -20 deg.
    start, goal = math.radians(10), math.radians(350)
    assert unwrap_heading_target(start, goal, +1) == pytest.approx(math.radians(350))
    assert unwrap_heading_target(start, goal, -1) == pytest.approx(math.radians(-10))
    assert unwrap_heading_target(start, goal, 0) == pytest.approx(math.radians(-10))


@pytest.mark.parametrize(("direction", "extra_turns"), [(2, 0), (-2, 0), (0, 1), (1, -1)])
def test_unwrap_heading_target_rejects_bad_arguments(direction: int, extra_turns: int) -> None:
    with pytest.raises(ValueError, match="direction|extra_turns"):
        unwrap_heading_target(0.0, 1.0, direction, extra_turns)


# --------------------------------------------------------------------------------------------
# Headings in both models
# --------------------------------------------------------------------------------------------

HEADING_MODELS = [
    pytest.param(FirstOrderParams(time_constant_s=2.0, max_rate=math.radians(5)), id="first"),
    pytest.param(third_order_params(0.8, 1.0, math.radians(5), math.radians(2)), id="third"),
]


@pytest.mark.parametrize("params", HEADING_MODELS)
def test_heading_takes_the_short_way(params: FirstOrderParams | ThirdOrderParams) -> None:
    start = initial_state(params, [0.0, 0.0, math.radians(10)])
    run = step_response(params, [0.0, 0.0, math.radians(350)], 0.05, 1200, state=start)
    psi = run.eta_d[:, PSI]
    # Short way: -20 deg, ending at psi_d = -10 deg (not +340 deg).
    assert psi[-1] == pytest.approx(math.radians(-10), abs=1e-6)
    assert np.all(np.diff(psi) <= ROUNDOFF)
    assert psi.max() <= math.radians(10) + ROUNDOFF


@pytest.mark.parametrize("params", HEADING_MODELS)
def test_heading_stays_continuous_across_pi(params: FirstOrderParams | ThirdOrderParams) -> None:
    start = initial_state(params, [0.0, 0.0, math.radians(170)])
    run = step_response(params, [0.0, 0.0, math.radians(-170)], 0.05, 1200, state=start)
    # +20 deg the short way; psi_d is not wrapped, it ends at 190 deg > pi.
    assert run.eta_d[-1, PSI] == pytest.approx(math.radians(190), abs=1e-6)
    assert wrap_heading(run.eta_d[-1, PSI]) == pytest.approx(math.radians(-170), abs=1e-6)


@pytest.mark.parametrize("params", HEADING_MODELS)
def test_absolute_mode_turns_a_full_circle_and_back(
    params: FirstOrderParams | ThirdOrderParams,
) -> None:
    psi0 = 0.3
    full_turn = unwrap_heading_target(psi0, psi0, +1, extra_turns=1)
    start = initial_state(params, [1.0, 1.0, psi0])
    n_steps = 3000  # 150 s: 360 deg at 5 deg/s is 72 s, plus accel, decel and settling
    run = step_response(
        params,
        [1.0, 1.0, full_turn],
        0.05,
        n_steps,
        state=start,
        heading_mode=HeadingMode.ABSOLUTE,
    )
    psi = run.eta_d[:, PSI]
    assert psi[-1] == pytest.approx(psi0 + 2 * PI, abs=1e-6)
    assert np.all(np.diff(psi) >= -ROUNDOFF)
    # The same numeric target in the default mode is "already there": no motion at all.
    still = step_response(params, [1.0, 1.0, full_turn], 0.05, 100, state=start)
    np.testing.assert_allclose(still.eta_d[:, PSI], psi0, atol=1e-9)
    # And back counter-clockwise from psi0 + 2 pi to psi0.
    back_target = unwrap_heading_target(psi[-1], psi[-1], -1, extra_turns=1)
    assert back_target == pytest.approx(psi0, abs=1e-6)
    back = step_response(
        params,
        [1.0, 1.0, back_target],
        0.05,
        n_steps,
        state=initial_state(params, run.eta_d[-1]),
        heading_mode=HeadingMode.ABSOLUTE,
    )
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
    run = step_response(params, step, dt, 200, heading_mode=HeadingMode.ABSOLUTE)
    limit = max_rate * (1 + ROUNDOFF)
    assert np.all(np.abs(run.eta_dot_d) <= limit)
    # Positions up to 100 carry ~1e-14 of rounding, large next to max_rate * dt (>= 1e-6).
    position_roundoff = 1e-13 * (1.0 + np.abs(step).max())
    assert np.all(np.abs(np.diff(run.eta_d, axis=0)) <= limit * dt + position_roundoff)
    # It moves towards the target and never past it.
    assert np.all(np.abs(step - run.eta_d) <= np.abs(step) * (1 + ROUNDOFF))


def test_first_order_small_step_is_exponential() -> None:
    time_constant, dt = 4.0, 0.01
    params = first_order_params(time_constant, max_rate=1.0)
    step = np.array([0.5, -0.2, 0.1])  # all below T * max_rate = 4: never rate limited
    run = step_response(params, step, dt, 2000, heading_mode=HeadingMode.ABSOLUTE)
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
    run = step_response(params, [step, -step, 0.0], dt, 10000, heading_mode=HeadingMode.ABSOLUTE)
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
    target = np.array([error, -error, 0.5 * error])
    start = FirstOrderState.at_rest(np.zeros(3))
    mode = HeadingMode.ABSOLUTE
    one, _ = update_first_order(start, target, 2 * dt, params, mode)
    half, _ = update_first_order(start, target, dt, params, mode)
    two, _ = update_first_order(half, target, dt, params, mode)
    np.testing.assert_allclose(two.eta_d, one.eta_d, rtol=1e-9, atol=1e-12)


def test_first_order_ramp_lags_by_time_constant_times_rate() -> None:
    time_constant, dt, rate = 2.0, 0.01, 0.01
    params = first_order_params(time_constant, max_rate=0.05)  # lag 0.02 < T * max_rate = 0.1
    times = dt * np.arange(6000)
    targets = np.column_stack([rate * times, np.zeros_like(times), np.zeros_like(times)])
    run = simulate_reference(params, targets, dt)
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
    rates=st.lists(st.floats(min_value=-2, max_value=2), min_size=3, max_size=3),
    use_rates=st.booleans(),
)
def test_third_order_never_exceeds_speed_or_accel(
    axes: list[tuple[float, float, float, float]],
    targets: list[list[float]],
    rates: list[float],
    use_rates: bool,
) -> None:
    params = params_from_axes(axes)
    dt = min(0.05, params.max_dt_s)
    n_steps = 1600
    # Piecewise-constant target that jumps while the model is moving (windup check).
    schedule = np.repeat(np.array(targets), -(-n_steps // len(targets)), axis=0)[:n_steps]
    run = simulate_reference(
        params,
        schedule,
        dt,
        heading_mode=HeadingMode.ABSOLUTE,
        target_rates=np.array(rates) if use_rates else None,
    )
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
    run = step_response(params, step, dt, int(duration / dt), heading_mode=HeadingMode.ABSOLUTE)
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


def test_third_order_ramp_with_feedforward_has_no_steady_state_error() -> None:
    omega, zeta, dt, rate = 0.5, 1.0, 0.01, 0.02
    params = third_order_params(omega, zeta, max_speed=0.05, max_accel=0.01)
    times = dt * np.arange(8000)
    targets = np.column_stack([rate * times, -rate * times, 0.5 * rate * times])
    rates = np.array([rate, -rate, 0.5 * rate])
    with_ff = simulate_reference(params, targets, dt, target_rates=rates)
    np.testing.assert_allclose(with_ff.eta_d[-1], targets[-1] + rates * dt, atol=1e-9)
    np.testing.assert_allclose(with_ff.eta_dot_d[-1], rates, atol=1e-12)
    # Without the feedforward the model is type 1: lag (2 z + 1) r_dot / w = 0.12 m.
    without = simulate_reference(params, targets, dt)
    lag = targets[-1] - without.eta_d[-2]
    np.testing.assert_allclose(lag, (2 * zeta + 1) * rates / omega, rtol=1e-6)


# --------------------------------------------------------------------------------------------
# Validation, purity, helpers
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


@pytest.mark.parametrize("dt", [0.0, -0.01, math.nan, 10.0])
def test_third_order_rejects_bad_dt(dt: float) -> None:
    with pytest.raises(ValueError, match="dt"):
        update_third_order(
            ThirdOrderState.at_rest(np.zeros(3)), np.ones(3), dt, ThirdOrderParams(**GOOD_THIRD)
        )


@pytest.mark.parametrize("dt", [0.0, -0.01, math.nan])
def test_first_order_rejects_bad_dt(dt: float) -> None:
    with pytest.raises(ValueError, match="dt"):
        update_first_order(
            FirstOrderState.at_rest(np.zeros(3)), np.ones(3), dt, FirstOrderParams(**GOOD_FIRST)
        )


@pytest.mark.parametrize("target", [[1.0, math.nan, 0.0], [1.0, 2.0], [0.0, 0.0, math.inf]])
def test_updates_reject_bad_targets(target: list[float]) -> None:
    with pytest.raises(ValueError, match="target"):
        update_first_order(
            FirstOrderState.at_rest(np.zeros(3)), target, 0.01, FirstOrderParams(**GOOD_FIRST)
        )
    with pytest.raises(ValueError, match="target"):
        update_third_order(
            ThirdOrderState.at_rest(np.zeros(3)), target, 0.01, ThirdOrderParams(**GOOD_THIRD)
        )


def test_updates_do_not_change_their_arguments() -> None:
    target = np.array([3.0, -2.0, 4.0])
    target_copy = target.copy()
    first = FirstOrderState(eta_d=np.array([0.1, 0.2, 0.3]))
    first_copy = first.eta_d.copy()
    new_first, out_first = update_first_order(first, target, 0.1, FirstOrderParams(**GOOD_FIRST))
    third = ThirdOrderState(
        np.array([0.1, 0.2, 0.3]), np.array([0.01, 0.0, -0.01]), np.array([0.001, 0.0, 0.0])
    )
    third_copies = [third.eta_d.copy(), third.eta_dot_d.copy(), third.eta_ddot_d.copy()]
    new_third, out_third = update_third_order(third, target, 0.1, ThirdOrderParams(**GOOD_THIRD))
    np.testing.assert_array_equal(target, target_copy)
    np.testing.assert_array_equal(first.eta_d, first_copy)
    for array, copy in zip(
        (third.eta_d, third.eta_dot_d, third.eta_ddot_d), third_copies, strict=True
    ):
        np.testing.assert_array_equal(array, copy)
    assert isinstance(out_first, ReferenceOutput) and isinstance(out_third, ReferenceOutput)
    assert not np.array_equal(new_first.eta_d, first.eta_d)
    assert not np.array_equal(new_third.eta_d, third.eta_d)
    np.testing.assert_array_equal(out_third.eta_d, new_third.eta_d)


def test_runs_are_deterministic_and_well_shaped() -> None:
    params = ThirdOrderParams(**GOOD_THIRD)
    start = ThirdOrderState.at_rest([1.0, 2.0, 3.0])
    first = step_response(params, [2.0, 1.0, -3.0], 0.05, 300, state=start)
    second = step_response(params, [2.0, 1.0, -3.0], 0.05, 300, state=start)
    assert first.time_s.shape == (301,)
    assert first.eta_d.shape == first.eta_dot_d.shape == first.eta_ddot_d.shape == (301, 3)
    assert first.time_s[-1] == pytest.approx(15.0)
    np.testing.assert_array_equal(first.eta_d[0], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(first.eta_dot_d[0], 0.0)
    np.testing.assert_array_equal(first.eta_d, second.eta_d)
    with pytest.raises(ValueError, match="targets"):
        simulate_reference(params, np.zeros((10, 2)), 0.05)


@pytest.mark.slow
def test_kernels_compile_with_numba(request: pytest.FixtureRequest) -> None:
    if "slow" not in (request.config.option.markexpr or ""):
        pytest.skip("compiles with numba (about 3 s): run with -m slow")
    numba = pytest.importorskip("numba")
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
    for kernel, args in ((first_order_kernel, first_args), (third_order_kernel, third_args)):
        for jitted, plain in zip(numba.njit(kernel)(*args), kernel(*args), strict=True):
            np.testing.assert_allclose(jitted, plain, rtol=1e-14, atol=1e-15)
