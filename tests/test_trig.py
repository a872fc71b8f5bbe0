"""``sim.trig``: the plant's sine and cosine against libm's (``math.sin``, ``math.cos``).

The bounds are what was measured: at most 1 ulp of libm's
answer for |x| <= 200 rad, 2 ulp up to ``TRIG_POLY_LIMIT`` (the reduced argument is used
without its rounding tail, which costs the second ulp on rare angles past a few hundred rad).
Angles next to the multiples of pi/2 are where the reduction cancels most; without the fourth
part of pi/2 they were 1e5 ulp off, so they are checked one by one (every multiple to 1e5 rad,
a random sample of them beyond).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from sim.gnc import JIT_NOALLOC
from sim.trig import TRIG_POLY_LIMIT, sincos, sincos_poly


@njit(**JIT_NOALLOC)
def _poly_each(x: np.ndarray, s: np.ndarray, c: np.ndarray) -> None:
    for i in range(x.shape[0]):
        s[i], c[i] = sincos_poly(x[i])


@njit(**JIT_NOALLOC)
def _full_each(x: np.ndarray, s: np.ndarray, c: np.ndarray) -> None:
    for i in range(x.shape[0]):
        s[i], c[i] = sincos(x[i])


def _ulp_errors(x: np.ndarray, fn=_poly_each) -> tuple[float, float]:
    """Largest error of (sin, cos) over ``x`` in units in the last place of libm's answer."""
    s = np.empty_like(x)
    c = np.empty_like(x)
    fn(x, s, c)
    ref_s = np.array([math.sin(v) for v in x])
    ref_c = np.array([math.cos(v) for v in x])
    err_s = np.abs(s - ref_s) / np.spacing(np.abs(ref_s))
    err_c = np.abs(c - ref_c) / np.spacing(np.abs(ref_c))
    return float(err_s.max()), float(err_c.max())


def test_within_one_ulp_over_the_plants_angles() -> None:
    # roll, pitch and the headings of every mission stay well inside 200 rad
    grid = np.linspace(-200.0, 200.0, 400_001)
    rand = np.random.default_rng(3).uniform(-200.0, 200.0, 400_000)
    assert _ulp_errors(grid) <= (1.0, 1.0)
    assert _ulp_errors(rand) <= (1.0, 1.0)


def test_within_two_ulp_up_to_the_limit() -> None:
    rand = np.random.default_rng(4).uniform(-TRIG_POLY_LIMIT, TRIG_POLY_LIMIT, 400_000)
    assert _ulp_errors(rand) <= (2.0, 2.0)


def test_next_to_multiples_of_half_pi() -> None:
    k = np.arange(-63_000, 63_001)
    far = np.random.default_rng(6).integers(63_000, int(TRIG_POLY_LIMIT / (math.pi / 2.0)), 60_000)
    k = np.concatenate([k, far, -far])
    xm = k * (math.pi / 2.0)
    x = np.concatenate([xm, np.nextafter(xm, math.inf), np.nextafter(xm, -math.inf)])
    assert np.all(np.abs(x) <= TRIG_POLY_LIMIT)
    assert _ulp_errors(x) <= (1.0, 1.0)


def test_tiny_angles_exact() -> None:
    # sin x = x and cos x = 1 to the last bit below 1e-9 rad, as libm
    x = np.concatenate(
        [10.0 ** -np.arange(9.0, 300.0, 0.5), -(10.0 ** -np.arange(9.0, 300.0, 0.5))]
    )
    s = np.empty_like(x)
    c = np.empty_like(x)
    _poly_each(x, s, c)
    assert np.array_equal(s, x)
    assert np.all(c == 1.0)


def test_zero_and_quadrant_signs() -> None:
    s = np.empty(1)
    c = np.empty(1)
    _poly_each(np.array([0.0]), s, c)
    assert (s[0], c[0]) == (0.0, 1.0)
    assert not math.copysign(1.0, s[0]) < 0.0
    _poly_each(np.array([-0.0]), s, c)
    # sin(-0) is +0 here (libm: -0): the polynomial's y + (y z) P adds +0 to -0
    assert (s[0], c[0]) == (0.0, 1.0)
    # the middle of each quadrant, over several turns both ways: signs (+,+), (+,-), (-,-),
    # (-,+) for quadrants 0..3 of the angle's turn
    signs = [(1, 1), (1, -1), (-1, -1), (-1, 1)]
    turns = np.arange(-5, 6)
    for q, (ss, cs) in enumerate(signs):
        x = 2.0 * math.pi * turns + (q + 0.5) * math.pi / 2.0
        sv = np.empty_like(x)
        cv = np.empty_like(x)
        _poly_each(x, sv, cv)
        assert np.all(np.sign(sv) == ss), (q, sv)
        assert np.all(np.sign(cv) == cs), (q, cv)
    # exact quarter turns as libm gives them (cos(pi/2) = 6.1e-17, not 0)
    x = np.array([math.pi / 2.0, math.pi, 1.5 * math.pi, -math.pi / 2.0, -math.pi])
    sv = np.empty_like(x)
    cv = np.empty_like(x)
    _poly_each(x, sv, cv)
    np.testing.assert_array_equal(sv, [math.sin(v) for v in x])
    np.testing.assert_array_equal(cv, [math.cos(v) for v in x])


@pytest.mark.parametrize("x", [TRIG_POLY_LIMIT * (1.0 + 2.0**-52), -3.0e6, 1.0e12, 1.0e300])
def test_beyond_the_limit_is_nan(x: float) -> None:
    s = np.empty(1)
    c = np.empty(1)
    _full_each(np.array([x]), s, c)
    assert math.isnan(s[0]) and math.isnan(c[0])
    _full_each(np.array([TRIG_POLY_LIMIT]), s, c)  # the limit itself is inside
    assert (s[0], c[0]) == pytest.approx((math.sin(TRIG_POLY_LIMIT), math.cos(TRIG_POLY_LIMIT)))


def test_inside_the_limit_is_the_polynomial() -> None:
    x = np.random.default_rng(5).uniform(-TRIG_POLY_LIMIT, TRIG_POLY_LIMIT, 10_000)
    s1, c1, s2, c2 = (np.empty_like(x) for _ in range(4))
    _full_each(x, s1, c1)
    _poly_each(x, s2, c2)
    assert np.array_equal(s1, s2) and np.array_equal(c1, c2)


@pytest.mark.parametrize("x", [math.inf, -math.inf, math.nan])
def test_non_finite_gives_nan(x: float) -> None:
    s = np.empty(1)
    c = np.empty(1)
    _full_each(np.array([x]), s, c)
    assert math.isnan(s[0]) and math.isnan(c[0])
    _poly_each(np.array([x]), s, c)
    assert math.isnan(s[0]) and math.isnan(c[0])
