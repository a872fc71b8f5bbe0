"""Sine and cosine from one reduction, without branches or calls, for the plant's step.

numba finds no SVML on this machine, so a loop over runs that calls ``math.sin`` stays
scalar (one libm call per element). ``sincos_poly`` computes both from one reduction,
without branches or calls, so a loop of it becomes AVX-512 code:

- **Reduction** by pi/2 in three parts (Cody-Waite, fdlibm's medium-size constants): the
  first two parts have their low bits zero, so ``n * part`` is exact for ``|n| < 2^20``,
  and the three together carry pi/2 to about 120 bits.
- **Polynomials**: fdlibm's minimax polynomials of ``__kernel_sin`` and ``__kernel_cos`` on
  [-pi/4, pi/4], evaluated on the reduced argument (without its tail).
- **Quadrant** ``n mod 4`` by two-way selects (a four-way chain of them stayed a branch
  and kept the loop scalar).

Accuracy against libm's ``sin`` and ``cos``, measured in ``tests/test_trig.py`` (dense grids
and random angles, and every angle next to a multiple of pi/2 in the range, where the
reduction cancels most): at most 1 ulp for |x| <= 200 rad, at most 2 ulp up to
``TRIG_POLY_LIMIT`` = 1.5e6 rad (the reduced argument is used without its rounding tail;
fdlibm keeps it, which costs a second ulp on rare large angles). Past the limit the
reduction is not checked (from 2^20 pi/2 = 1.65e6 rad its products stop being exact, past
about 2^51 the rounding to an integer fails outright).

``sincos`` is what the plant calls: ``sincos_poly`` with NaN for |x| beyond the limit, as a
select (a branch to libm there made the scalar plant step 20 % slower, measured). Headings
are not wrapped in the plant's state, but 1.5e6 rad is 240 000 turns (some 35 days of
spinning at 0.5 rad/s): a run that gets there has diverged, and the NaN stops it as the
plant's finiteness check stops any other. Infinity and NaN give NaN.
"""

from __future__ import annotations

import math

from numba import njit

from sim.gnc import JIT_NOALLOC

# pi/2 in three parts (the first two with their low 20 bits zero) and 2/pi: fdlibm's
# constants (e_rem_pio2.c: pio2_1, pio2_2, pio2_3 and invpio2)
PIO2_1 = 1.57079632673412561417e00
PIO2_2 = 6.07710050630396597660e-11
PIO2_3 = 2.02226624871116645580e-21
PIO2_3T = 8.47842766036889956997e-32
INV_PIO2 = 6.36619772367581382433e-01
TO_INT = 1.5 * 2.0**52
"""Adding and subtracting it rounds a double below 2^51 to the nearest integer (ties to even)."""

# fdlibm's minimax polynomials on [-pi/4, pi/4] (k_sin.c, k_cos.c)
S1, S2, S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
S4, S5, S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
C1, C2, C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
C4, C5, C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11

TRIG_POLY_LIMIT = 1.5e6
"""[rad] ``sincos_poly`` is within 2 ulp of libm for |x| up to this (1 ulp to 200 rad);
``sincos`` gives NaN beyond it."""

_QUADRANT_SAFE = 2.0**30
"""Quotients at or above this (or NaN) are given quadrant 0 before the integer conversion,
so the conversion is always defined; the result there is replaced by NaN (``sincos``)."""


@njit(**JIT_NOALLOC)
def sincos_poly(x: float) -> tuple[float, float]:
    """(sin x, cos x) without branches or calls, within 2 ulp of libm for
    |x| <= ``TRIG_POLY_LIMIT`` (1 ulp to 200 rad); meaningless outside that range
    (``sincos`` gives NaN there)."""
    n = (x * INV_PIO2 + TO_INT) - TO_INT
    y = (((x - n * PIO2_1) - n * PIO2_2) - n * PIO2_3) - n * PIO2_3T
    z = y * y
    s = y + y * z * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))))
    r = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))))
    hz = 0.5 * z
    w = 1.0 - hz
    c = w + (((1.0 - w) - hz) + z * r)
    # quadrant q = n mod 4: odd quadrants swap sine and cosine; the sine is negative in
    # quadrants 2 and 3, the cosine in 1 and 2 (two-way selects, which the compiler turns
    # into blends)
    q = int(n if abs(n) < _QUADRANT_SAFE else 0.0)
    odd = (q & 1) != 0
    sin_x = c if odd else s
    cos_x = s if odd else c
    sin_x = -sin_x if (q & 2) != 0 else sin_x
    cos_x = -cos_x if ((q + 1) & 2) != 0 else cos_x
    return sin_x, cos_x


@njit(**JIT_NOALLOC)
def sincos(x: float) -> tuple[float, float]:
    """(sin x, cos x): ``sincos_poly`` for |x| <= ``TRIG_POLY_LIMIT``, NaN beyond it and
    for infinity or NaN. Branch-free, so a loop of it vectorises."""
    s, c = sincos_poly(x)
    inside = abs(x) <= TRIG_POLY_LIMIT
    return (s if inside else math.nan), (c if inside else math.nan)
