"""Tests of sim.environment: bounded random-walk current (thesis eq. 2.49-2.51) and linear
deep-water waves from the ITTC spectrum (eq. 2.52-2.56)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from sim import environment
from sim.environment import (
    GRAVITY_MPS2,
    OMEGA_MAX_PER_PEAK,
    OMEGA_MIN_PER_PEAK,
    CurrentParams,
    CurrentState,
    WaveField,
    WaveParams,
    advance_current,
    current_velocity_n,
    deep_water_wavenumber,
    initial_current,
    ittc_spectrum,
    make_wave_field,
    surface_elevation_m,
    wave_frequency_bands,
    wave_kinematics_n,
)

EPS = np.finfo(np.float64).eps
SEA_STATES = [(8.0, 10.0), (8.0, 20.0), (8.0, 30.0), (12.0, 30.0)]
"""(H_s [m], T_p [s]) of the four sea states of thesis table 4.1."""


# ---------------------------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------------------------


def _log_trapezoid(values_times_omega: NDArray[np.float64], omega: NDArray[np.float64]) -> float:
    """Trapezoid rule of f(omega) d omega written as f(omega) omega d ln(omega)."""
    return float(np.trapezoid(values_times_omega, np.log(omega)))


def _moment(order: int, hs: float, tp: float, n_points: int) -> float:
    """Spectral moment m_order = int omega^order S d omega over [0.05, 1000] omega_p."""
    omega_p = 2 * math.pi / tp
    omega = np.geomspace(0.05 * omega_p, 1000 * omega_p, n_points)
    return _log_trapezoid(omega ** (order + 1) * ittc_spectrum(omega, hs, tp), omega)


def _moment_and_error(order: int, hs: float, tp: float) -> tuple[float, float]:
    """Moment on a fine grid and its quadrature error bound |I_fine - I_coarse|.

    The trapezoid rule is second order, so the fine grid's error is about a quarter of the
    difference between the grids: the difference itself is a safe bound.
    """
    fine = _moment(order, hs, tp, 40_001)
    coarse = _moment(order, hs, tp, 20_001)
    return fine, abs(fine - coarse)


def _stratified_std_bound(integrand: NDArray[np.float64], widths: NDArray[np.float64]) -> float:
    """Upper bound of the std of sum_k g(omega_k) d_omega with omega_k uniform in band k.

    integrand has shape (bands, samples): g on a fine grid inside each band. Each term lies
    in [d_omega min g, d_omega max g], so its variance is at most (d_omega (max - min))^2 / 4
    (Popoviciu); the terms are independent.
    """
    ranges = integrand.max(axis=1) - integrand.min(axis=1)
    return float(math.sqrt(np.sum((widths * ranges) ** 2) / 4.0))


def _band_grid(params: WaveParams) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Fine frequency grid inside each band, shape (n, 401), and the band widths (n,)."""
    edges = wave_frequency_bands(params)
    widths = np.diff(edges)
    grid = edges[:-1, None] + widths[:, None] * np.linspace(0.0, 1.0, 401)[None, :]
    return grid, widths


def _single_component(
    period_s: float, amplitude_m: float, direction_rad: float, phase_rad: float = 0.3
) -> WaveField:
    """A one-component field: a regular deep-water wave."""
    omega = 2 * math.pi / period_s
    return WaveField(
        omega_rad_s=np.array([omega]),
        amplitude_m=np.array([amplitude_m]),
        wavenumber_rad_m=np.array([omega**2 / GRAVITY_MPS2]),
        phase_rad=np.array([phase_rad]),
        direction_rad=direction_rad,
    )


def _thesis_current(**overrides: float) -> CurrentParams:
    """Chapter 4 current: 0.1 m/s towards 225 deg, with bounds around it."""
    values = {
        "speed_mps": 0.1,
        "direction_rad": math.radians(225.0),
        "speed_min_mps": 0.0,
        "speed_max_mps": 0.5,
        "direction_min_rad": math.radians(180.0),
        "direction_max_rad": math.radians(270.0),
    }
    values.update(overrides)
    return CurrentParams(**values)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------------------------
# ITTC spectrum
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("hs", "tp"), SEA_STATES + [(1.0, 4.0)])
def test_spectrum_zeroth_moment_is_hs_squared_over_16(hs: float, tp: float) -> None:
    m0, quadrature_error = _moment_and_error(0, hs, tp)
    # Truncation at 1000 omega_p: the tail is below int A omega^-5 = A / (4 omega_b^4), i.e.
    # (5/64) H_s^2 / 1000^4; the range below 0.05 omega_p holds exp(-1.25 * 20^4) = 0.
    tail = 5.0 / 64.0 * hs**2 / 1000.0**4
    assert m0 == pytest.approx(hs**2 / 16.0, abs=tail + quadrature_error + 1e-14)


@pytest.mark.parametrize(("hs", "tp"), SEA_STATES)
def test_spectrum_peak_lies_at_two_pi_over_tp(hs: float, tp: float) -> None:
    omega_p = 2 * math.pi / tp
    step = 1e-5 * omega_p
    omega = np.arange(0.5 * omega_p, 2.0 * omega_p, step)
    peak = omega[np.argmax(ittc_spectrum(omega, hs, tp))]
    # The maximum of a grid lies within one grid step of the true maximum.
    assert abs(peak - omega_p) <= step


def test_spectrum_periods_match_fossen_table() -> None:
    """Fossen (2011, section 8.2.1): T_z = 0.710 T_0 and T_1 = 0.772 T_0 for the ITTC form."""
    hs, tp = 8.0, 10.0
    m0, e0 = _moment_and_error(0, hs, tp)
    m1, e1 = _moment_and_error(1, hs, tp)
    m2, e2 = _moment_and_error(2, hs, tp)
    # Printed to three decimals: half a unit of the last digit. The quadrature errors and the
    # tails (m2 tail < A / (2 omega_b^2), 4e-7 relative) are four orders smaller.
    assert max(e0 / m0, e1 / m1, e2 / m2) < 1e-5
    assert 2 * math.pi * math.sqrt(m0 / m2) / tp == pytest.approx(0.710, abs=5e-4)
    assert 2 * math.pi * m0 / m1 / tp == pytest.approx(0.772, abs=5e-4)


@settings(max_examples=60, deadline=None)
@given(hs=st.floats(0.0, 20.0), tp=st.floats(2.0, 40.0), rel=st.floats(0.05, 20.0))
def test_spectrum_laws(hs: float, tp: float, rel: float) -> None:
    omega_p = 2 * math.pi / tp
    omega = np.array([rel * omega_p, omega_p])
    s = ittc_spectrum(omega, hs, tp)
    unit = ittc_spectrum(omega, 1.0, tp)
    assert np.all(s >= 0.0)
    # S is proportional to H_s^2: equal up to a few roundings of the products.
    # atol: far in the tail S is subnormal (< 2.2e-308), where floats keep no relative precision
    np.testing.assert_allclose(s, hs**2 * unit, rtol=8 * EPS, atol=1e-300)
    # omega_p is the global maximum.
    assert unit[0] <= unit[1]


def test_spectrum_is_zero_at_and_below_zero_frequency() -> None:
    s = ittc_spectrum(np.array([-1.0, 0.0, 1e-300, 1e-3]), 8.0, 10.0)
    assert np.all(np.isfinite(s))
    assert np.all(s == 0.0)  # exp(-1.25 (omega_p / 1e-3)^4) underflows to exactly 0


def test_spectrum_rejects_invalid_inputs() -> None:
    with pytest.raises(ValueError, match="significant_height_m"):
        ittc_spectrum(np.array([1.0]), -1.0, 10.0)
    with pytest.raises(ValueError, match="peak_period_s"):
        ittc_spectrum(np.array([1.0]), 1.0, 0.0)


# ---------------------------------------------------------------------------------------------
# Wave field
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("hs", "tp"), SEA_STATES)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_field_elevation_variance_is_hs_squared_over_16(hs: float, tp: float, seed: int) -> None:
    params = WaveParams(hs, tp, 0.0)
    field = make_wave_field(params, np.random.default_rng(seed))
    variance = float(np.sum(field.amplitude_m**2 / 2.0))
    grid, widths = _band_grid(params)
    sampling = _stratified_std_bound(ittc_spectrum(grid, hs, tp), widths)
    # Band truncation (closed form of the cumulative spectrum, exp(-B omega^-4)):
    # 1 - exp(-1.25 / 6^4) above, exp(-1.25 * 2^4) below; plus 4 std of the random
    # frequencies (an unbiased stratified estimate of the band integral).
    m0 = hs**2 / 16.0
    truncated = (
        1.0 - math.exp(-1.25 / OMEGA_MAX_PER_PEAK**4) + math.exp(-1.25 / OMEGA_MIN_PER_PEAK**4)
    )
    assert variance == pytest.approx(m0, abs=truncated * m0 + 4.0 * sampling)
    # The requirement 'within a few percent': 3 %, about 4 times the sampling bound above.
    assert abs(variance / m0 - 1.0) < 0.03


@pytest.mark.parametrize(("hs", "tp"), SEA_STATES)
@pytest.mark.parametrize("depth_m", [0.0, 20.0, 100.0])
def test_field_velocity_variance_matches_spectrum_integral(
    hs: float, tp: float, depth_m: float
) -> None:
    params = WaveParams(hs, tp, 0.0)
    field = make_wave_field(params, np.random.default_rng(7))
    decay = np.exp(-field.wavenumber_rad_m * depth_m)
    field_sum = float(np.sum((field.omega_rad_s * field.amplitude_m * decay) ** 2 / 2.0))

    def integrand(omega: NDArray[np.float64]) -> NDArray[np.float64]:
        """omega^2 S(omega) exp(-2 k z): horizontal velocity spectrum at depth z."""
        k = omega**2 / GRAVITY_MPS2
        return omega**2 * ittc_spectrum(omega, hs, tp) * np.exp(-2.0 * k * depth_m)

    omega_p = 2 * math.pi / tp
    lower, upper = OMEGA_MIN_PER_PEAK * omega_p, OMEGA_MAX_PER_PEAK * omega_p
    omega = np.geomspace(0.05 * omega_p, 1000 * omega_p, 40_001)
    full = _log_trapezoid(omega * integrand(omega), omega)
    outside = omega[(omega < lower) | (omega > upper)]
    # Spectrum outside the bands, integrated piecewise on the same grid (both pieces).
    below, above = omega[omega < lower], omega[omega > upper]
    tail = _log_trapezoid(below * integrand(below), below) + _log_trapezoid(
        above * integrand(above), above
    )
    assert outside.size > 0
    grid, widths = _band_grid(params)
    sampling = _stratified_std_bound(integrand(grid), widths)
    # Field sum is an unbiased estimate of the in-band integral, full - tail: 4 std of the
    # random frequencies, plus the lost tail (3.5 % at the surface, < 1e-4 at 20 m), plus
    # the quadrature error of the log-grid (below 1e-5 relative, see the moment tests).
    assert field_sum == pytest.approx(full, abs=tail + 4.0 * sampling + 1e-5 * full)
    assert field_sum == pytest.approx(full - tail, abs=4.0 * sampling + 1e-5 * full)


def test_time_record_velocity_variance_matches_field_sum() -> None:
    params = WaveParams(8.0, 20.0, 0.4)
    field = make_wave_field(params, np.random.default_rng(11))
    depth_m = 50.0
    t = np.arange(0.0, 7200.0, 0.5)
    velocity = wave_kinematics_n(field, t, depth_m).velocity_n
    speed_amp = field.omega_rad_s * field.amplitude_m * np.exp(-field.wavenumber_rad_m * depth_m)
    variances = speed_amp**2 / 2.0
    expected = float(np.sum(variances))
    horizontal = float(np.mean(velocity[:, 0] ** 2 + velocity[:, 1] ** 2))
    vertical = float(np.mean(velocity[:, 2] ** 2))
    # Variance from a record of length T of a Gaussian process with one-sided spectrum S:
    # relative std sqrt(2 pi int S^2 d omega / T) / m0 (Bendat & Piersol), with the discrete
    # spectrum S(omega_k) = variance_k / d omega. Allow 4 std.
    d_omega = float(np.diff(wave_frequency_bands(params))[0])
    relative_std = math.sqrt(2 * math.pi * np.sum(variances**2) / d_omega / t[-1]) / expected
    assert horizontal == pytest.approx(expected, rel=4.0 * relative_std)
    # Deep-water orbits are circles: the vertical component has the same variance.
    assert vertical == pytest.approx(expected, rel=4.0 * relative_std)


def test_single_component_decays_as_exp_minus_kz() -> None:
    """T = 10 s at 100 m depth: variance ratio exp(-2 k_p 100) = exp(-8.05) = 3.2e-4."""
    period = 10.0
    field = _single_component(period, 1.0, 0.0)
    k = float(field.wavenumber_rad_m[0])
    t = np.arange(400) * period / 40.0  # ten whole periods, 40 samples each
    rms = {}
    for depth in (0.0, 100.0):
        velocity = wave_kinematics_n(field, t, depth).velocity_n
        rms[depth] = math.sqrt(float(np.mean(velocity[:, 0] ** 2)))
    omega = 2 * math.pi / period
    # Mean of sin^2 over whole periods sampled more than twice per period is exactly 1/2:
    # only round-off differs (a few hundred operations, 1e-12).
    assert rms[0.0] == pytest.approx(omega / math.sqrt(2.0), rel=1e-12)
    assert rms[100.0] / rms[0.0] == pytest.approx(math.exp(-k * 100.0), rel=1e-12)
    # The closed form itself: k_p = (2 pi / 10)^2 / 9.81 = 0.04024 rad/m (4 digits printed).
    assert (rms[100.0] / rms[0.0]) ** 2 == pytest.approx(math.exp(-2 * 0.04024 * 100), rel=1e-3)


def test_single_component_orbit_is_circular_and_in_phase_with_elevation() -> None:
    period, amplitude, depth = 12.0, 2.0, 30.0
    field = _single_component(period, amplitude, 0.7)
    omega = 2 * math.pi / period
    t = np.linspace(0.0, 3 * period, 301)
    velocity = wave_kinematics_n(field, t, depth).velocity_n
    horizontal = velocity[:, 0] * math.cos(0.7) + velocity[:, 1] * math.sin(0.7)
    radius = omega * amplitude * math.exp(-float(field.wavenumber_rad_m[0]) * depth)
    # u^2 + w^2 = (omega A e^{-kz})^2 at every instant (90 deg phase shift); round-off only.
    np.testing.assert_allclose(horizontal**2 + velocity[:, 2] ** 2, radius**2, rtol=1e-12)
    # At the surface the horizontal velocity is omega * zeta (eq. 2.53 phase convention) and
    # the vertical velocity is up (negative NED z) while the surface rises.
    surface = wave_kinematics_n(field, t, 0.0).velocity_n
    zeta = surface_elevation_m(field, t)
    surface_u = surface[:, 0] * math.cos(0.7) + surface[:, 1] * math.sin(0.7)
    np.testing.assert_allclose(surface_u, omega * zeta, atol=1e-12 * omega * amplitude)
    np.testing.assert_allclose(-surface[:, 2], np.gradient(zeta, t), atol=0.01 * omega * amplitude)


def test_single_component_is_periodic_in_space_and_uniform_crosswise() -> None:
    period, direction = 8.0, math.radians(30.0)
    field = _single_component(period, 1.5, direction)
    wavelength = 2 * math.pi / float(field.wavenumber_rad_m[0])
    t = np.linspace(0.0, 20.0, 81)
    base = wave_kinematics_n(field, t, 5.0).velocity_n
    along = wave_kinematics_n(
        field,
        t,
        5.0,
        north_m=wavelength * math.cos(direction),
        east_m=wavelength * math.sin(direction),
    ).velocity_n
    across = wave_kinematics_n(
        field, t, 5.0, north_m=-37.0 * math.sin(direction), east_m=37.0 * math.cos(direction)
    ).velocity_n
    half = wave_kinematics_n(
        field,
        t,
        5.0,
        north_m=0.5 * wavelength * math.cos(direction),
        east_m=0.5 * wavelength * math.sin(direction),
    ).velocity_n
    # Phase errors of order eps * k * x (k x ~ 2 pi): absolute 1e-12 of the speed amplitude.
    scale = 1e-12 * 2 * math.pi / period * 1.5
    np.testing.assert_allclose(along, base, atol=scale)
    np.testing.assert_allclose(across, base, atol=scale)
    np.testing.assert_allclose(half, -base, atol=scale)  # half a wavelength: opposite phase


@pytest.mark.parametrize("depth_m", [0.0, 35.0, 100.0])
def test_acceleration_is_time_derivative_of_velocity(depth_m: float) -> None:
    field = make_wave_field(WaveParams(8.0, 10.0, 1.1), np.random.default_rng(3))
    h = 1e-3
    t = np.linspace(10.0, 200.0, 501)
    accel = wave_kinematics_n(field, t, depth_m).accel_n
    forward = wave_kinematics_n(field, t + h, depth_m).velocity_n
    backward = wave_kinematics_n(field, t - h, depth_m).velocity_n
    central = (forward - backward) / (2 * h)
    speed_amp = field.omega_rad_s * field.amplitude_m * np.exp(-field.wavenumber_rad_m * depth_m)
    # Central difference error <= h^2 / 6 max|v'''| <= h^2 / 6 sum omega^3 c_k, plus round-off
    # of the two velocities (a few eps * omega t per phase) divided by 2 h.
    truncation = h**2 / 6.0 * float(np.sum(field.omega_rad_s**2 * speed_amp))
    round_off = 100 * EPS * float(np.sum(speed_amp * (1 + field.omega_rad_s * t[-1]))) / h
    np.testing.assert_allclose(accel, central, rtol=0.0, atol=truncation + round_off)
    assert np.max(np.abs(accel)) > 100 * (truncation + round_off)  # the check has teeth


@settings(max_examples=40, deadline=None)
@given(
    direction=st.floats(-2 * math.pi, 2 * math.pi),
    seed=st.integers(0, 2**32 - 1),
    north=st.floats(-500.0, 500.0),
    east=st.floats(-500.0, 500.0),
)
def test_horizontal_velocity_is_along_wave_direction(
    direction: float, seed: int, north: float, east: float
) -> None:
    field = make_wave_field(WaveParams(4.0, 12.0, direction, 50), np.random.default_rng(seed))
    t = np.linspace(0.0, 60.0, 61)
    kinematics = wave_kinematics_n(field, t, 10.0, north, east)
    for vector in (kinematics.velocity_n, kinematics.accel_n):
        horizontal = vector[:, :2]
        across = horizontal[:, 0] * -math.sin(direction) + horizontal[:, 1] * math.cos(direction)
        # Exactly zero but for the rounding of u cos(b), u sin(b): a few eps of |u|.
        assert np.all(np.abs(across) <= 4 * EPS * np.linalg.norm(horizontal, axis=1) + 1e-300)


def test_same_seed_same_field_different_seed_different_field() -> None:
    params = WaveParams(8.0, 20.0, 0.2)
    first = make_wave_field(params, np.random.default_rng(42))
    again = make_wave_field(params, np.random.default_rng(42))
    other = make_wave_field(params, np.random.default_rng(43))
    t = np.linspace(0.0, 100.0, 201)
    for name in ("omega_rad_s", "amplitude_m", "wavenumber_rad_m", "phase_rad"):
        assert np.array_equal(getattr(first, name), getattr(again, name))
        assert not np.array_equal(getattr(first, name), getattr(other, name))
    assert np.array_equal(
        wave_kinematics_n(first, t, 50.0).velocity_n, wave_kinematics_n(again, t, 50.0).velocity_n
    )
    assert not np.array_equal(
        wave_kinematics_n(first, t, 50.0).velocity_n, wave_kinematics_n(other, t, 50.0).velocity_n
    )


def test_zero_height_gives_still_water() -> None:
    field = make_wave_field(WaveParams(0.0, 10.0, 0.0), np.random.default_rng(0))
    assert np.all(field.amplitude_m == 0.0)
    kinematics = wave_kinematics_n(field, np.linspace(0.0, 10.0, 11), 0.0)
    assert np.all(kinematics.velocity_n == 0.0)
    assert np.all(kinematics.accel_n == 0.0)


def test_frequencies_lie_in_their_bands_and_follow_dispersion() -> None:
    params = WaveParams(8.0, 10.0, 0.0, 300)
    field = make_wave_field(params, np.random.default_rng(5))
    edges = wave_frequency_bands(params)
    assert edges.shape == (301,)
    assert np.all(field.omega_rad_s >= edges[:-1]) and np.all(field.omega_rad_s < edges[1:])
    np.testing.assert_array_equal(field.wavenumber_rad_m, field.omega_rad_s**2 / GRAVITY_MPS2)
    np.testing.assert_array_equal(deep_water_wavenumber(2.0), 4.0 / 9.81)
    # Random frequencies: irregular spacing. A fixed grid (constant spacing d_omega) would
    # repeat the whole sea after 2 pi / d_omega = 9 min; uniform positions in each band give
    # spacings with std d_omega / sqrt(6) = 0.41 d_omega, far above the 0.1 checked here.
    spacing = np.diff(field.omega_rad_s)
    assert np.std(spacing) > 0.1 * np.mean(spacing)


def test_wave_functions_do_not_modify_arguments_and_field_is_read_only() -> None:
    field = make_wave_field(WaveParams(8.0, 10.0, 0.0), np.random.default_rng(0))
    t = np.linspace(0.0, 5.0, 6)
    t_copy = t.copy()
    omega_copy = field.omega_rad_s.copy()
    wave_kinematics_n(field, t, 10.0)
    assert np.array_equal(t, t_copy) and np.array_equal(field.omega_rad_s, omega_copy)
    with pytest.raises(ValueError):
        field.omega_rad_s[0] = 1.0


def test_long_record_is_computed_in_blocks_without_seams(monkeypatch: pytest.MonkeyPatch) -> None:
    field = make_wave_field(WaveParams(8.0, 10.0, 0.0), np.random.default_rng(9))
    t = np.linspace(0.0, 100.0, 1001)
    whole = wave_kinematics_n(field, t, 10.0).velocity_n
    # Blocks of 7 time rows (200 components): 143 blocks, the last one short.
    monkeypatch.setattr(environment, "_BLOCK_ELEMENTS", 7 * 200 + 13)
    blocked = wave_kinematics_n(field, t, 10.0).velocity_n
    speed_amp = field.omega_rad_s * field.amplitude_m * np.exp(-field.wavenumber_rad_m * 10.0)
    # Blocks of different sizes only change the summation order inside the matrix product:
    # the classic bound n eps sum|c_k| (n = 200 terms). A seam (a block shifted or skipped)
    # would be an error of the order of the velocity itself, 1e10 times larger.
    bound = speed_amp.size * EPS * float(np.sum(speed_amp))
    np.testing.assert_allclose(blocked, whole, rtol=0.0, atol=bound)
    assert np.max(np.abs(whole)) > 1e6 * bound


@pytest.mark.parametrize(
    ("kwargs", "field_name"),
    [
        ({"significant_height_m": -0.1}, "significant_height_m"),
        ({"significant_height_m": math.nan}, "significant_height_m"),
        ({"peak_period_s": 0.0}, "peak_period_s"),
        ({"peak_period_s": math.inf}, "peak_period_s"),
        ({"direction_rad": math.nan}, "direction_rad"),
        ({"n_components": 9}, "n_components"),
        ({"n_components": 5001}, "n_components"),
    ],
)
def test_invalid_wave_params_raise_naming_the_field(
    kwargs: dict[str, float], field_name: str
) -> None:
    values: dict[str, float] = {
        "significant_height_m": 8.0,
        "peak_period_s": 10.0,
        "direction_rad": 0.0,
    }
    values.update(kwargs)
    with pytest.raises(ValueError, match=rf"^{field_name} "):
        WaveParams(**values)  # type: ignore[arg-type]


def test_kinematics_rejects_negative_depth() -> None:
    field = _single_component(10.0, 1.0, 0.0)
    with pytest.raises(ValueError, match="depth_m"):
        wave_kinematics_n(field, np.zeros(3), -1.0)


# ---------------------------------------------------------------------------------------------
# Current
# ---------------------------------------------------------------------------------------------


def test_thesis_current_velocity_is_minus_0_0707_north_and_east() -> None:
    """Chapter 4: uniform 0.1 m/s towards 225 deg (south-west)."""
    velocity = current_velocity_n(0.1, math.radians(225.0))
    # Expected values printed to four decimals: half a unit of the last digit.
    np.testing.assert_allclose(velocity, [-0.0707, -0.0707, 0.0], rtol=0.0, atol=5e-5)


def test_current_velocity_shapes_and_broadcasting() -> None:
    speeds = np.array([0.1, 0.2, 0.3])
    velocity = current_velocity_n(speeds, 0.0)
    assert velocity.shape == (3, 3)
    np.testing.assert_array_equal(velocity[:, 0], speeds)  # cos(0) = 1, sin(0) = 0 exactly
    np.testing.assert_array_equal(velocity[:, 1:], 0.0)
    east = current_velocity_n(0.2, math.pi / 2)
    np.testing.assert_allclose(east, [0.0, 0.2, 0.0], atol=0.2 * EPS)


def test_zero_intensity_keeps_current_exactly_constant() -> None:
    params = _thesis_current()
    state = initial_current(params)
    chunk = advance_current(state, params, 0.01, 1000, np.random.default_rng(0))
    assert np.all(chunk.speeds_mps == 0.1)
    assert np.all(chunk.directions_rad == math.radians(225.0))
    assert chunk.state.speed_mps == 0.1
    assert chunk.state.direction_rad == math.radians(225.0)
    assert chunk.speeds_mps.shape == chunk.directions_rad.shape == (1000,)


def test_first_sample_is_the_input_state_and_last_state_continues() -> None:
    params = _thesis_current(speed_walk_mps_per_sqrt_s=0.01, direction_walk_rad_per_sqrt_s=0.02)
    state = CurrentState(0.2, 4.0)
    chunk = advance_current(state, params, 0.01, 50, np.random.default_rng(1))
    assert chunk.speeds_mps[0] == 0.2 and chunk.directions_rad[0] == 4.0
    assert chunk.speeds_mps[1] != 0.2  # the walk moves
    empty = advance_current(state, params, 0.01, 0, np.random.default_rng(1))
    assert empty.speeds_mps.shape == (0,) and empty.state == state


def test_rng_consumption_does_not_depend_on_intensity() -> None:
    still, moving = _thesis_current(), _thesis_current(speed_walk_mps_per_sqrt_s=0.01)
    rng_still, rng_moving = np.random.default_rng(5), np.random.default_rng(5)
    advance_current(initial_current(still), still, 0.01, 100, rng_still)
    advance_current(initial_current(moving), moving, 0.01, 100, rng_moving)
    assert rng_still.random() == rng_moving.random()


def test_current_is_deterministic_per_seed() -> None:
    params = _thesis_current(speed_walk_mps_per_sqrt_s=0.01, direction_walk_rad_per_sqrt_s=0.01)
    runs = [
        advance_current(initial_current(params), params, 0.01, 500, np.random.default_rng(seed))
        for seed in (3, 3, 4)
    ]
    assert np.array_equal(runs[0].speeds_mps, runs[1].speeds_mps)
    assert np.array_equal(runs[0].directions_rad, runs[1].directions_rad)
    assert not np.array_equal(runs[0].speeds_mps, runs[2].speeds_mps)


@pytest.mark.parametrize("column", ["speed", "direction"])
def test_increment_std_is_sigma_sqrt_dt(column: str) -> None:
    sigma, dt, n = 0.05, 0.01, 100_000
    # Bands 100 units wide around the start: the walk spreads sigma sqrt(n dt) = 1.6, so it
    # never reaches a bound and every increment is a free one.
    params = CurrentParams(50.0, 50.0, 0.0, 100.0, 0.0, 100.0, sigma, sigma)
    chunk = advance_current(initial_current(params), params, dt, n, np.random.default_rng(8))
    samples = chunk.speeds_mps if column == "speed" else chunk.directions_rad
    increments = np.diff(samples)
    # Relative standard error of a sample std from m normal values: 1 / sqrt(2 (m - 1)) =
    # 0.22 %; allow 5 of them.
    tolerance = 5.0 / math.sqrt(2.0 * (increments.size - 1))
    assert np.std(increments) == pytest.approx(sigma * math.sqrt(dt), rel=tolerance)
    assert abs(np.mean(increments)) < 5.0 * sigma * math.sqrt(dt) / math.sqrt(increments.size)


def test_walk_reflects_at_bounds_rather_than_sticking() -> None:
    # Spread sigma sqrt(T) = 1.6 m/s against a 0.1 m/s band: many reflections.
    params = CurrentParams(0.1, 1.0, 0.05, 0.15, 0.9, 1.1, 0.05, 0.05)
    chunk = advance_current(
        initial_current(params), params, 0.01, 100_000, np.random.default_rng(2)
    )
    for samples, lo, hi in ((chunk.speeds_mps, 0.05, 0.15), (chunk.directions_rad, 0.9, 1.1)):
        assert np.all((samples >= lo) & (samples <= hi))
        # Clipping would pile samples exactly on the bounds; reflection never lands on them.
        assert not np.any((samples == lo) | (samples == hi))
        # ... yet the walk visits both ends of the band (within 1 % of its width).
        assert samples.min() < lo + 0.01 * (hi - lo) and samples.max() > hi - 0.01 * (hi - lo)


bounded_currents = st.builds(
    lambda lo, width, start, direction_lo, direction_width, direction_start, sigma, dsigma: (
        CurrentParams(
            lo + start * width,
            direction_lo + direction_start * direction_width,
            lo,
            lo + width,
            direction_lo,
            direction_lo + direction_width,
            sigma,
            dsigma,
        )
    ),
    lo=st.floats(0.0, 2.0),
    width=st.floats(0.0, 1.0),
    start=st.floats(0.0, 1.0),
    direction_lo=st.floats(-7.0, 7.0),
    direction_width=st.floats(0.0, 7.0),
    direction_start=st.floats(0.0, 1.0),
    sigma=st.floats(0.0, 2.0),
    dsigma=st.floats(0.0, 2.0),
)


@settings(max_examples=150, deadline=None)
@given(
    params=bounded_currents,
    dt=st.floats(1e-3, 1.0),
    n_steps=st.integers(0, 3000),
    seed=st.integers(0, 2**32 - 1),
)
def test_walk_stays_inside_bounds(
    params: CurrentParams, dt: float, n_steps: int, seed: int
) -> None:
    state = initial_current(params)
    rng = np.random.default_rng(seed)
    for _ in range(3):  # several chunks, carrying the state
        state, speeds, directions = advance_current(state, params, dt, n_steps, rng)
        assert np.all((speeds >= params.speed_min_mps) & (speeds <= params.speed_max_mps))
        assert np.all(
            (directions >= params.direction_min_rad) & (directions <= params.direction_max_rad)
        )
        assert params.speed_min_mps <= state.speed_mps <= params.speed_max_mps
        assert params.direction_min_rad <= state.direction_rad <= params.direction_max_rad


@settings(max_examples=100, deadline=None)
@given(
    params=bounded_currents,
    dt=st.floats(1e-3, 1.0),
    first=st.integers(0, 1500),
    second=st.integers(0, 1500),
    seed=st.integers(0, 2**32 - 1),
)
def test_chunked_run_equals_one_run(
    params: CurrentParams, dt: float, first: int, second: int, seed: int
) -> None:
    whole = advance_current(
        initial_current(params), params, dt, first + second, np.random.default_rng(seed)
    )
    rng = np.random.default_rng(seed)
    head = advance_current(initial_current(params), params, dt, first, rng)
    tail = advance_current(head.state, params, dt, second, rng)
    # each value from the one before, its normal and the fold sign alone: bit for bit
    assert np.array_equal(np.concatenate([head.speeds_mps, tail.speeds_mps]), whole.speeds_mps)
    assert np.array_equal(
        np.concatenate([head.directions_rad, tail.directions_rad]), whole.directions_rad
    )
    assert tail.state == whole.state


@pytest.mark.parametrize(
    ("overrides", "field_name"),
    [
        ({"speed_min_mps": -0.1}, "speed_min_mps"),
        ({"speed_max_mps": 0.05, "speed_mps": 0.05, "speed_min_mps": 0.1}, "speed_max_mps"),
        ({"speed_mps": 0.6}, "speed_mps"),
        ({"speed_mps": math.nan}, "speed_mps"),
        ({"direction_min_rad": math.inf}, "direction_min_rad"),
        ({"direction_max_rad": 3.0}, "direction_max_rad"),
        ({"direction_rad": 5.0}, "direction_rad"),
        ({"speed_walk_mps_per_sqrt_s": -1e-3}, "speed_walk_mps_per_sqrt_s"),
        ({"direction_walk_rad_per_sqrt_s": math.nan}, "direction_walk_rad_per_sqrt_s"),
    ],
)
def test_invalid_current_params_raise_naming_the_field(
    overrides: dict[str, float], field_name: str
) -> None:
    with pytest.raises(ValueError, match=rf"^{field_name} must") as info:
        _thesis_current(**overrides)
    assert " must lie in " in str(info.value)  # the allowed range is stated


def test_advance_current_rejects_bad_step_and_state() -> None:
    params = _thesis_current()
    state = initial_current(params)
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="dt_s"):
        advance_current(state, params, 0.0, 10, rng)
    with pytest.raises(ValueError, match="n_steps"):
        advance_current(state, params, 0.01, -1, rng)
    with pytest.raises(ValueError, match="state.speed_mps"):
        advance_current(CurrentState(0.7, 4.0), params, 0.01, 10, rng)
    with pytest.raises(ValueError, match="speed_fold_sign"):
        CurrentState(0.1, 4.0, speed_fold_sign=0)


@pytest.mark.parametrize(
    "params",
    [
        CurrentParams(0.3, 0.5, 0.1, 0.5, -1.0, 2.0, 0.02, 0.01),  # inside its band
        CurrentParams(0.1, 1.0, 0.05, 0.15, 0.9, 1.1, 0.05, 0.05),  # folds many times
    ],
    ids=["inside", "folding"],
)
def test_current_walk_is_the_step_by_step_form_bit_for_bit(params: CurrentParams) -> None:
    """Both walks go in one compiled call; the numbers are those of the walk written a step
    at a time in Python: the increment ``sigma sqrt(dt) * normal`` added with the fold sign,
    the sum reflected into the band (a triangle wave of period 2 w) where it leaves it, the
    sign turned over where the reflection mirrors. The folding case does fold."""
    state = CurrentState(params.speed_mps, params.direction_rad, -1, 1)
    got = advance_current(state, params, 0.01, 500, np.random.default_rng(5))
    normals = np.random.default_rng(5).standard_normal((500, 2))
    walks = (
        (params.speed_walk_mps_per_sqrt_s, state.speed_mps, -1, got.state.speed_fold_sign),
        (
            params.direction_walk_rad_per_sqrt_s,
            state.direction_rad,
            1,
            got.state.direction_fold_sign,
        ),
    )
    bands = (
        (params.speed_min_mps, params.speed_max_mps),
        (params.direction_min_rad, params.direction_max_rad),
    )
    samples = (got.speeds_mps, got.directions_rad)
    ends = (got.state.speed_mps, got.state.direction_rad)
    folds = 0
    for k in range(2):
        sigma, v, sign, end_sign = walks[k]
        lo, hi = bands[k]
        w = hi - lo
        path = [v]
        for i in range(500):
            x = v + sign * (sigma * math.sqrt(0.01) * normals[i, k])
            if lo <= x <= hi:
                v = x
            else:
                folds += 1
                m = (x - lo) % (2.0 * w)
                if m > w:
                    v, sign = min(max(lo + (2.0 * w - m), lo), hi), -sign
                else:
                    v = min(max(lo + m, lo), hi)
            path.append(v)
        ref = np.array(path)
        assert np.array_equal(samples[k].view(np.int64), ref[:-1].view(np.int64))
        assert ends[k] == ref[-1] and end_sign == sign
    assert (folds > 0) == (params.speed_max_mps - params.speed_min_mps < 0.2)
