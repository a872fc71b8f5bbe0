"""Guidance-navigation-control vocabulary of Fossen (2011): one small pure function per formula.

Every function is compiled with numba so the plant and the control loop can call it from
their own compiled code; each is also an ordinary Python callable (the exception,
``quaternion_wxyz_from_rpy_radians``, is plain Python for the edges that draw and record).
Angles are radians, ``eta = [x, y, z, phi, theta, psi]`` (NED) and ``nu = [u, v, w, p, q, r]``
(BODY).
"""

from __future__ import annotations

import math
from typing import Any, Literal, TypedDict

import numpy as np
from numba import njit


# Compile options for the numeric core: no Python-style zero-division checks. No fast-math:
# reassociation and fused multiply-add depend on how the compiler inlines, so a freshly
# compiled run and one from numba's cache could differ in the last bits, and a run must be
# reproducible to the bit from its seed.
class _JitOptions(TypedDict):
    cache: bool
    error_model: Literal["python", "numpy"]


JIT: _JitOptions = {"cache": True, "error_model": "numpy"}


JIT_NOALLOC: dict[str, Any] = {"cache": True, "error_model": "numpy", "_nrt": False}
"""Options of the kernels that must not allocate (the ``*_into`` functions of the plant's
step): compiled without numba's runtime, so an array made inside one, or anything else that
needs the runtime, is a compile error, and array views cost no reference counting."""


# Named indices into eta / nu (SNAME 1950, thesis table 2.1).
X, Y, Z, PHI, THETA, PSI = 0, 1, 2, 3, 4, 5
U, V, W, P, Q, R = 0, 1, 2, 3, 4, 5


@njit(**JIT)
def ssa(angle: float) -> float:
    """Smallest signed angle: maps any angle [rad] into [-pi, pi). Branch-free, so it works on
    arrays too. (angle + pi) mod 2 pi rounds to 2 pi for angles just below -pi: folded back."""
    wrapped = (angle + np.pi) % (2.0 * np.pi)
    wrapped = wrapped - 2.0 * np.pi * (wrapped >= 2.0 * np.pi)
    return wrapped - np.pi


@njit(**JIT_NOALLOC)
def ssa_scalar(angle: float) -> float:
    """``ssa`` of one number, the same bits, for the compiled loop: an angle already within
    [-pi, pi) (almost every call) skips the floating-point remainder, a call into numba's
    helper library (``numba_fmod``, 1 % of a campaign's time): for 0 <= a + pi < 2 pi,
    (a + pi) mod 2 pi is a + pi exactly, so the rest of ``ssa`` sees the same number."""
    two_pi = 2.0 * np.pi
    wrapped = angle + np.pi
    if not (wrapped >= 0.0 and wrapped < two_pi):  # outside, or NaN: as ``ssa``
        wrapped = wrapped % two_pi
        wrapped = wrapped - two_pi * (wrapped >= two_pi)
    return wrapped - np.pi


@njit(**JIT)
def ssa_each(angles: np.ndarray) -> np.ndarray:
    """``ssa`` of every element of a 1-D array (a new array): the compiled scalar ``ssa`` per
    element, so the same numbers as ``np.array([ssa(v) for v in angles])`` without a call
    from Python per element."""
    out = np.empty(angles.shape[0])
    for i in range(angles.shape[0]):
        out[i] = ssa(angles[i])
    return out


@njit(**JIT)
def sat(x: float, limit: float) -> float:
    """Saturate x into [-limit, limit]."""
    if x > limit:
        return limit
    if x < -limit:
        return -limit
    return x


@njit(**JIT)
def Smtrx(a: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrix S(a) with S(a) b = a x b; S(a) = -S(a)^T."""
    out = np.zeros((3, 3))
    out[0, 1] = -a[2]
    out[0, 2] = a[1]
    out[1, 0] = a[2]
    out[1, 2] = -a[0]
    out[2, 0] = -a[1]
    out[2, 1] = a[0]
    return out


@njit(**JIT_NOALLOC)
def cross_into(out: np.ndarray, a: np.ndarray, b: np.ndarray) -> None:
    """out = a x b for 3-vectors (out must not alias a or b)."""
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(**JIT)
def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for 3-vectors, without allocating a matrix."""
    out = np.empty(3)
    cross_into(out, a, b)
    return out


@njit(**JIT)
def Rzyx(phi: float, theta: float, psi: float) -> np.ndarray:
    """R_nb: rotation BODY -> NED, zyx Euler angles (Fossen 2011 eq. 2.18; thesis eq. 2.3 is
    misprinted). Orthonormal with det 1; R_nb^T = R_bn."""
    out = np.empty((3, 3))
    Rzyx_into(out, np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta), np.cos(psi), np.sin(psi))
    return out


@njit(**JIT_NOALLOC)
def Rzyx_into(
    out: np.ndarray, cphi: float, sphi: float, cth: float, sth: float, cpsi: float, spsi: float
) -> None:
    """``Rzyx`` into ``out`` (3x3) from the cosines and sines of phi, theta and psi, so a
    caller that needs them again (``Tzyx_into``, ``gvect_into``) computes them once."""
    out[0, 0] = cpsi * cth
    out[0, 1] = -spsi * cphi + cpsi * sth * sphi
    out[0, 2] = spsi * sphi + cpsi * cphi * sth
    out[1, 0] = spsi * cth
    out[1, 1] = cpsi * cphi + sphi * sth * spsi
    out[1, 2] = -cpsi * sphi + sth * spsi * cphi
    out[2, 0] = -sth
    out[2, 1] = cth * sphi
    out[2, 2] = cth * cphi


@njit(**JIT)
def Tzyx(phi: float, theta: float) -> np.ndarray:
    """T_Theta: body angular rates -> Euler angle rates (thesis eq. 2.4).

    Singular at theta = +-90 deg."""
    out = np.empty((3, 3))
    Tzyx_into(out, np.cos(phi), np.sin(phi), np.cos(theta), np.tan(theta))
    return out


@njit(**JIT_NOALLOC)
def Tzyx_into(out: np.ndarray, cphi: float, sphi: float, cth: float, tth: float) -> None:
    """``Tzyx`` into ``out`` (3x3) from cos phi, sin phi, cos theta and tan theta."""
    out[0, 0] = 1.0
    out[0, 1] = sphi * tth
    out[0, 2] = cphi * tth
    out[1, 0] = 0.0
    out[1, 1] = cphi
    out[1, 2] = -sphi
    out[2, 0] = 0.0
    out[2, 1] = sphi / cth
    out[2, 2] = cphi / cth


@njit(**JIT)
def Hmtrx(r: np.ndarray) -> np.ndarray:
    """System transformation matrix H(r) = [[I, S(r)^T], [0, I]] (Fossen 2011 ch. 7.5).

    nu at a point displaced by r (body axes) is H(r) nu; inv(H(r)) = H(-r)."""
    out = np.eye(6)
    out[0:3, 3:6] = Smtrx(r).T
    return out


@njit(**JIT)
def m2c(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Coriolis-centripetal matrix C(nu) from a 6x6 mass matrix M (Fossen 2011 eq. 3.46).

    Skew-symmetric parametrisation, so nu^T C(nu) nu = 0 for any nu."""
    Ms = 0.5 * (M + M.T)
    M11, M12 = Ms[0:3, 0:3], Ms[0:3, 3:6]
    M21, M22 = Ms[3:6, 0:3], Ms[3:6, 3:6]
    nu1 = np.ascontiguousarray(nu[0:3])
    nu2 = np.ascontiguousarray(nu[3:6])
    a = M11 @ nu1 + M12 @ nu2
    b = M21 @ nu1 + M22 @ nu2
    C = np.zeros((6, 6))
    C[0:3, 3:6] = -Smtrx(a)
    C[3:6, 0:3] = -Smtrx(a)
    C[3:6, 3:6] = -Smtrx(b)
    return C


@njit(**JIT)
def coriolis_force(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """C(nu) nu for the parametrisation of m2c, computed without building C (cheaper).
    M must be symmetric (every mass matrix of the plant is, checked on load)."""
    out = np.empty(6)
    coriolis_force_into(out, M, nu)
    return out


@njit(**JIT_NOALLOC)
def _row_dot(M: np.ndarray, i: int, nu: np.ndarray) -> float:
    """sum_j M[i, j] nu[j], summed from 0.0 in the order of j."""
    s = 0.0
    for j in range(nu.shape[0]):
        s += M[i, j] * nu[j]
    return s


@njit(**JIT_NOALLOC)
def coriolis_force_into(out: np.ndarray, M: np.ndarray, nu: np.ndarray) -> None:
    """``coriolis_force`` into ``out`` (6,), with the momenta a, b as scalars (no array)."""
    a0, a1, a2 = _row_dot(M, 0, nu), _row_dot(M, 1, nu), _row_dot(M, 2, nu)
    b0, b1, b2 = _row_dot(M, 3, nu), _row_dot(M, 4, nu), _row_dot(M, 5, nu)
    out[0] = -(a1 * nu[5] - a2 * nu[4])
    out[1] = -(a2 * nu[3] - a0 * nu[5])
    out[2] = -(a0 * nu[4] - a1 * nu[3])
    out[3] = -(a1 * nu[2] - a2 * nu[1]) - (b1 * nu[5] - b2 * nu[4])
    out[4] = -(a2 * nu[0] - a0 * nu[2]) - (b2 * nu[3] - b0 * nu[5])
    out[5] = -(a0 * nu[1] - a1 * nu[0]) - (b0 * nu[4] - b1 * nu[3])


@njit(**JIT)
def gvect(
    W: float, B: float, theta: float, phi: float, r_bg: np.ndarray, r_bb: np.ndarray
) -> np.ndarray:
    """Restoring vector g(eta) of weight W at r_bg and buoyancy B at r_bb, both in body axes
    (Fossen 2011 eq. 4.6, the 6-row form; thesis eq. 2.9 is printed with 7 rows)."""
    g = np.empty(6)
    gvect_into(g, W, B, np.sin(theta), np.cos(theta), np.sin(phi), np.cos(phi), r_bg, r_bb)
    return g


@njit(**JIT_NOALLOC)
def gvect_into(
    g: np.ndarray,
    W: float,
    B: float,
    sth: float,
    cth: float,
    sphi: float,
    cphi: float,
    r_bg: np.ndarray,
    r_bb: np.ndarray,
) -> None:
    """``gvect`` into ``g`` (6,) from the sines and cosines of theta and phi."""
    g[0] = (W - B) * sth
    g[1] = -(W - B) * cth * sphi
    g[2] = -(W - B) * cth * cphi
    g[3] = -(r_bg[1] * W - r_bb[1] * B) * cth * cphi + (r_bg[2] * W - r_bb[2] * B) * cth * sphi
    g[4] = (r_bg[2] * W - r_bb[2] * B) * sth + (r_bg[0] * W - r_bb[0] * B) * cth * cphi
    g[5] = -(r_bg[0] * W - r_bb[0] * B) * cth * sphi - (r_bg[1] * W - r_bb[1] * B) * sth


@njit(**JIT)
def rotation_to_vector(Rm: np.ndarray) -> np.ndarray:
    """Small-angle rotation vector of a rotation matrix: vee((R - R^T)/2) = sin(angle) * axis."""
    out = np.empty(3)
    rotation_to_vector_into(out, Rm)
    return out


@njit(**JIT_NOALLOC)
def rotation_to_vector_into(out: np.ndarray, Rm: np.ndarray) -> None:
    """``rotation_to_vector`` into ``out`` (3,)."""
    out[0] = 0.5 * (Rm[2, 1] - Rm[1, 2])
    out[1] = 0.5 * (Rm[0, 2] - Rm[2, 0])
    out[2] = 0.5 * (Rm[1, 0] - Rm[0, 1])


@njit(**JIT)
def euler_from_rotation(Rm: np.ndarray) -> np.ndarray:
    """zyx Euler angles [phi, theta, psi] of R_nb (inverse of Rzyx away from theta = +-90 deg)."""
    out = np.empty(3)
    out[0] = np.arctan2(Rm[2, 1], Rm[2, 2])
    out[1] = -np.arcsin(min(1.0, max(-1.0, Rm[2, 0])))
    out[2] = np.arctan2(Rm[1, 0], Rm[0, 0])
    return out


@njit(**JIT)
def mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """A @ x with explicit loops: for the small matrices of the plant this is several times
    faster in compiled code than a BLAS call."""
    out = np.zeros(A.shape[0])
    mv_into(out, A, x)
    return out


@njit(**JIT_NOALLOC)
def mv_into(out: np.ndarray, A: np.ndarray, x: np.ndarray) -> None:
    """out = A @ x, each element summed from 0.0 in the order of the columns (out must not
    alias x)."""
    n, m = A.shape
    for i in range(n):
        s = 0.0
        for j in range(m):
            s += A[i, j] * x[j]
        out[i] = s


@njit(**JIT_NOALLOC)
def mv3_into(out: np.ndarray, A: np.ndarray, x: np.ndarray) -> None:
    """``mv_into`` for a 3x3 A: the same sums, with loop bounds the compiler sees (and
    inlined where it is called, so no call per product)."""
    for i in range(3):
        s = 0.0
        for j in range(3):
            s += A[i, j] * x[j]
        out[i] = s


@njit(**JIT_NOALLOC)
def mv6_into(out: np.ndarray, A: np.ndarray, x: np.ndarray) -> None:
    """``mv_into`` for a 6x6 A (see ``mv3_into``)."""
    for i in range(6):
        s = 0.0
        for j in range(6):
            s += A[i, j] * x[j]
        out[i] = s


@njit(**JIT_NOALLOC)
def mtv3_into(out: np.ndarray, A: np.ndarray, x: np.ndarray) -> None:
    """``mtv_into`` for a 3x3 A (see ``mv3_into``)."""
    for j in range(3):
        s = 0.0
        for i in range(3):
            s += A[i, j] * x[i]
        out[j] = s


@njit(**JIT)
def mtv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """A^T @ x with explicit loops."""
    out = np.zeros(A.shape[1])
    mtv_into(out, A, x)
    return out


@njit(**JIT_NOALLOC)
def mtv_into(out: np.ndarray, A: np.ndarray, x: np.ndarray) -> None:
    """out = A^T @ x, summed like ``mv_into`` (out must not alias x)."""
    n, m = A.shape
    for j in range(m):
        s = 0.0
        for i in range(n):
            s += A[i, j] * x[i]
        out[j] = s


@njit(**JIT)
def mtm(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A^T @ B for 3x3 matrices with explicit loops."""
    out = np.zeros((3, 3))
    mtm_into(out, A, B)
    return out


@njit(**JIT_NOALLOC)
def mtm_into(out: np.ndarray, A: np.ndarray, B: np.ndarray) -> None:
    """out = A^T @ B for 3x3 matrices (out must not alias A or B)."""
    for i in range(3):
        for j in range(3):
            s = 0.0
            for k in range(3):
                s += A[k, i] * B[k, j]
            out[i, j] = s


@njit(**JIT)
def mm(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A @ B for 3x3 matrices with explicit loops."""
    out = np.zeros((3, 3))
    mm_into(out, A, B)
    return out


@njit(**JIT_NOALLOC)
def mm_into(out: np.ndarray, A: np.ndarray, B: np.ndarray) -> None:
    """out = A @ B for 3x3 matrices (out must not alias A or B)."""
    for i in range(3):
        for j in range(3):
            s = 0.0
            for k in range(3):
                s += A[i, k] * B[k, j]
            out[i, j] = s


def quaternion_wxyz_from_rpy_radians(phi: float, theta: float, psi: float) -> np.ndarray:
    """Unit quaternion [w, x, y, z] of R_nb = Rzyx(phi, theta, psi) = Rz(psi) Ry(theta) Rx(phi)
    (Fossen 2011 eq. 2.18): q = qz(psi) qy(theta) qx(phi), so its rotation matrix is Rzyx and
    its norm is 1. Plain Python (not compiled): for the edges that draw and record poses."""
    cr, sr = math.cos(phi / 2.0), math.sin(phi / 2.0)
    cp, sp = math.cos(theta / 2.0), math.sin(theta / 2.0)
    cy, sy = math.cos(psi / 2.0), math.sin(psi / 2.0)
    return np.array(
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    )
