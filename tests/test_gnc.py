"""Laws of the kinematic vocabulary (sim.gnc), checked as properties and against scipy."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit
from scipy.spatial.transform import Rotation

from sim.gnc import (
    Hmtrx,
    Rzyx,
    Smtrx,
    Tzyx,
    coriolis_force,
    cross,
    euler_from_rotation,
    m2c,
    quaternion_wxyz_from_rpy_radians,
    ssa,
    ssa_each,
    ssa_scalar,
)

angle = st.floats(-10.0, 10.0, allow_nan=False)
small_pitch = st.floats(-1.4, 1.4, allow_nan=False)  # away from the +-90 deg singularity
vec3 = st.lists(st.floats(-100, 100, allow_nan=False), min_size=3, max_size=3).map(np.array)
vec6 = st.lists(st.floats(-10, 10, allow_nan=False), min_size=6, max_size=6).map(np.array)


@given(angle, angle, angle)
def test_rotation_is_orthonormal_with_unit_determinant(phi, theta, psi):
    R = Rzyx(phi, theta, psi)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)  # round-off of 3x3 products
    assert math.isclose(np.linalg.det(R), 1.0, abs_tol=1e-12)


@given(angle, small_pitch, angle)
def test_rotation_matches_scipy_intrinsic_zyx(phi, theta, psi):
    """Independent library: scipy's intrinsic Z-Y-X Euler rotation is R_nb."""
    expected = Rotation.from_euler("ZYX", [psi, theta, phi]).as_matrix()
    np.testing.assert_allclose(Rzyx(phi, theta, psi), expected, atol=1e-12)


def rotation_of_quaternion(w: float, x: float, y: float, z: float) -> np.ndarray:
    """The rotation matrix of a unit quaternion [w, x, y, z], written out (independent of
    sim.gnc)."""
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


@given(angle, angle, angle)
def test_quaternion_is_the_zyx_rotation(phi, theta, psi):
    """Law: the quaternion of (phi, theta, psi) has unit norm and rotates as Rzyx, at any
    angles (no singularity); 1e-12 is the round-off of a few products of sines and cosines."""
    q = quaternion_wxyz_from_rpy_radians(phi, theta, psi)
    assert q.shape == (4,)
    assert math.isclose(float(q @ q), 1.0, abs_tol=1e-12)
    np.testing.assert_allclose(rotation_of_quaternion(*q), Rzyx(phi, theta, psi), atol=1e-12)


@given(st.floats(-3.0, 3.0), st.floats(-1.4, 1.4), st.floats(-3.0, 3.0))
def test_euler_round_trip(phi, theta, psi):
    np.testing.assert_allclose(
        euler_from_rotation(Rzyx(phi, theta, psi)), [phi, theta, psi], atol=1e-9
    )


@given(st.floats(-1e6, 1e6, allow_nan=False))
def test_ssa_lands_in_half_open_interval(a):
    out = ssa(a)
    assert -math.pi <= out < math.pi
    # same angle: differs by a whole number of turns
    turns = (a - out) / (2 * math.pi)
    assert abs(turns - round(turns)) < 1e-6 * max(1.0, abs(a))


def test_ssa_folds_the_rounding_edge_below_minus_pi():
    """(a + pi) mod 2 pi rounds to exactly 2 pi for a just below -pi; the result must still be
    in [-pi, pi), and the same for arrays."""
    edge = np.nextafter(-math.pi, -4.0)
    assert -math.pi <= ssa(edge) < math.pi
    out = ssa(np.array([edge, -math.pi, math.pi, 3 * math.pi]))
    assert np.all(out >= -math.pi) and np.all(out < math.pi)


@given(vec3, vec3)
def test_skew_matrix_is_cross_product(a, b):
    np.testing.assert_allclose(Smtrx(a) @ b, np.cross(a, b), atol=1e-9)
    np.testing.assert_allclose(cross(a, b), np.cross(a, b), atol=1e-9)
    np.testing.assert_allclose(Smtrx(a), -Smtrx(a).T)


@given(vec3)
def test_H_inverse_is_H_of_minus_r(r):
    np.testing.assert_allclose(Hmtrx(r) @ Hmtrx(-r), np.eye(6), atol=1e-9)


def _random_spd(rng):
    a = rng.standard_normal((6, 6))
    return a @ a.T + 6 * np.eye(6)


@settings(max_examples=50)
@given(vec6, st.integers(0, 2**31 - 1))
def test_coriolis_does_no_work(nu, seed):
    """nu^T C(nu) nu = 0 for the skew-symmetric parametrisation (Fossen 2011, property 3.2)."""
    M = _random_spd(np.random.default_rng(seed))
    C = m2c(M, nu)
    assert abs(nu @ C @ nu) < 1e-9 * (1 + np.abs(M).max() * (nu @ nu))
    np.testing.assert_allclose(C @ nu, coriolis_force(M, nu), atol=1e-9)


@given(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), vec3)
def test_euler_rates_match_finite_difference_of_rotation(phi, theta, w):
    """T_Theta maps body rates to Euler-angle rates: rotating by w for dt and re-reading the
    angles must agree with T_Theta w (first-order, dt = 1e-7)."""
    dt = 1e-7
    psi = 0.3
    R0 = Rzyx(phi, theta, psi)
    R1 = R0 @ Rotation.from_rotvec(w * dt).as_matrix()
    rates = (euler_from_rotation(R1) - np.array([phi, theta, psi])) / dt
    np.testing.assert_allclose(rates, Tzyx(phi, theta) @ w, atol=1e-4 * (1 + np.abs(w).max()))


def test_ssa_each_is_ssa_of_every_element_to_the_bit() -> None:
    """The scores' heading errors go through ``ssa_each``: the compiled scalar ``ssa`` of each
    element, the same bits as calling it per element, just below -pi and at odd multiples of
    pi included."""
    rng = np.random.default_rng(4)
    angles = np.concatenate(
        [
            rng.uniform(-20.0, 20.0, 2000),
            [-math.pi, math.pi, 3.0 * math.pi, np.nextafter(-math.pi, -4.0), 0.0, -0.0],
        ]
    )
    want = np.array([ssa(float(v)) for v in angles])
    got = ssa_each(angles)
    assert got.tobytes() == want.tobytes()
    assert np.all((got >= -math.pi) & (got < math.pi))


@njit(cache=False, error_model="numpy")
def _ssa_scalar_each(angles):  # type: ignore[no-untyped-def]
    out = np.empty(angles.shape[0])
    for i in range(angles.shape[0]):
        out[i] = ssa_scalar(angles[i])
    return out


def test_ssa_scalar_is_ssa_to_the_bit() -> None:
    """The kernels' ``ssa_scalar`` skips the remainder for angles already in [-pi, pi): the
    same bits as ``ssa`` there, beyond it, at its edges (just below -pi, +-pi, odd multiples
    of pi, +-0, the largest double below pi) and for NaN and infinities."""
    rng = np.random.default_rng(6)
    edges = [-math.pi, math.pi, 3.0 * math.pi, -3.0 * math.pi, np.nextafter(-math.pi, -4.0)]
    edges += [np.nextafter(math.pi, 0.0), 0.0, -0.0, 1e-300, -1e-300, 1e17, -1e17]
    angles = np.concatenate([rng.uniform(-4.0, 4.0, 20000), rng.uniform(-1e4, 1e4, 2000), edges])
    want = np.array([ssa(float(v)) for v in angles])
    got = _ssa_scalar_each(angles)
    assert got.tobytes() == want.tobytes()
    special = np.array([math.nan, math.inf, -math.inf])
    assert np.all(np.isnan(_ssa_scalar_each(special)))
    assert np.all(np.isnan([ssa(float(v)) for v in special]))
