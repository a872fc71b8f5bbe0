"""Extended Kalman filter on the control plant model (thesis section 3.1.1, table 3.1).

State (9): ``[north, east, psi, u, v, r, b_north, b_east, b_psi]``: the tree origin's pose
(NED), its body velocity in surge, sway and yaw, and a slowly varying bias force (NED axes)
that absorbs the current and what the model misses (eq. 2.48b).

Model (eq. 2.48):
    eta_dot = R(psi) nu
    M nu_dot + C(nu) nu + D(nu) nu + R(psi)^T K_h (p - p_eq) = tau + R(psi)^T b
    b_dot = -b / T_b + w_b

The filter predicts at the plant rate with forward Euler (eq. 3.1-3.3) and corrects with each
sensor when, and only when, that sensor delivers a fresh sample; it coasts on the model when
position fixes drop out. The ROV's measurements are first moved to the tree's origin
(eq. 3.4-3.6, see ``control.loop``). Covariance updates use the Joseph form of table 3.1.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from sim.gnc import JIT, JIT_NOALLOC, ssa_scalar

N_X = 9
NORTH, EAST, PSI, SURGE, SWAY, YAW_RATE, B_N, B_E, B_PSI = range(9)


@njit(inline="always", **JIT)
def coriolis3(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """C(nu) nu of a 3-DOF (surge, sway, yaw) mass matrix, the skew-symmetric form of m2c."""
    ax = M[0, 0] * nu[0] + M[0, 1] * nu[1] + M[0, 2] * nu[2]
    ay = M[1, 0] * nu[0] + M[1, 1] * nu[1] + M[1, 2] * nu[2]
    out = np.empty(3)
    out[0] = -ay * nu[2]
    out[1] = ax * nu[2]
    out[2] = ay * nu[0] - ax * nu[1]
    return out


@njit(**JIT)
def model_rhs(
    x: np.ndarray,
    tau: np.ndarray,
    M_inv: np.ndarray,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    T_b: np.ndarray,
) -> np.ndarray:
    """f(x, tau) of the control plant model; tau in tree axes [N, N, N m]."""
    xdot = np.empty(9)
    _model_rhs_into(xdot, x, tau, M_inv, M, D_l, D_nl, k_h, p_eq, T_b)
    return xdot


@njit(inline="always", **JIT)
def _model_rhs_into(
    xdot: np.ndarray,
    x: np.ndarray,
    tau: np.ndarray,
    M_inv: np.ndarray,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    T_b: np.ndarray,
) -> None:
    """``model_rhs`` written into ``xdot`` (9,), with scalars for the 3-vectors (the same
    operations in the same order, no temporary arrays)."""
    _model_rhs_cs_into(
        xdot, x, np.cos(x[2]), np.sin(x[2]), tau, M_inv, M, D_l, D_nl, k_h, p_eq, T_b
    )


@njit(inline="always", **JIT)
def _model_rhs_cs_into(
    xdot: np.ndarray,
    x: np.ndarray,
    c: float,
    s: float,
    tau: np.ndarray,
    M_inv: np.ndarray,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    T_b: np.ndarray,
) -> None:
    """``_model_rhs_into`` with the cosine and sine of the heading x[2] given."""
    nu0, nu1, nu2 = x[3], x[4], x[5]
    xdot[0] = c * nu0 - s * nu1
    xdot[1] = s * nu0 + c * nu1
    xdot[2] = nu2
    # NED-frame forces: wire spring and bias, rotated into the tree's axes
    fn = -k_h * (x[0] - p_eq[0]) + x[6]
    fe = -k_h * (x[1] - p_eq[1]) + x[7]
    # C(nu) nu as in coriolis3
    ax = M[0, 0] * nu0 + M[0, 1] * nu1 + M[0, 2] * nu2
    ay = M[1, 0] * nu0 + M[1, 1] * nu1 + M[1, 2] * nu2
    f0 = tau[0] + c * fn + s * fe
    f1 = tau[1] - s * fn + c * fe
    f2 = tau[2] + x[8]
    f0 -= -ay * nu2 + (D_l[0] + D_nl[0] * abs(nu0)) * nu0
    f1 -= ax * nu2 + (D_l[1] + D_nl[1] * abs(nu1)) * nu1
    f2 -= (ay * nu0 - ax * nu1) + (D_l[2] + D_nl[2] * abs(nu2)) * nu2
    for i in range(3):
        acc = 0.0
        acc += M_inv[i, 0] * f0
        acc += M_inv[i, 1] * f1
        acc += M_inv[i, 2] * f2
        xdot[3 + i] = acc
        xdot[6 + i] = -x[6 + i] / T_b[i]


@njit(inline="always", **JIT)
def predict(
    x: np.ndarray,
    P: np.ndarray,
    tau: np.ndarray,
    dt: float,
    M_inv: np.ndarray,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    T_b: np.ndarray,
    GQG: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """One prediction step (table 3.1): x+ = x + h f(x, u); P+ = Phi P Phi^T + Gamma Q Gamma^T
    with Phi = I + h df/dx (the Jacobian by hand, ``jacobian_phi_into``). Returns new arrays
    (``predict_into`` is the step in place)."""
    x_new = x.copy()
    P_new = P.copy()
    predict_into(
        x_new, P_new, tau, dt, M_inv, M, D_l, D_nl, k_h, p_eq, T_b, GQG,
        np.empty(9), np.empty((9, 9)), np.empty((9, 9)),
    )  # fmt: skip
    return x_new, P_new


@njit(inline="always", **JIT_NOALLOC)
def jacobian_phi_into(
    phi: np.ndarray,
    x: np.ndarray,
    c: float,
    s: float,
    dt: float,
    M_inv: np.ndarray,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    T_b: np.ndarray,
) -> None:
    """Phi = I + dt df/dx of ``_model_rhs_cs_into`` at x (c, s: the heading's cosine and
    sine) into ``phi`` (9, 9), differentiated by hand. Entries where f does not depend on the
    state are exactly 0 (``phi_times_into`` leaves them out). ``d|u| u / du = 2 |u|``, also
    at u = 0. Checked against central differences in ``tests/test_ekf.py``."""
    u, v, r = x[3], x[4], x[5]
    fn = -k_h * (x[0] - p_eq[0]) + x[6]
    fe = -k_h * (x[1] - p_eq[1]) + x[7]
    ax = M[0, 0] * u + M[0, 1] * v + M[0, 2] * r
    ay = M[1, 0] * u + M[1, 1] * v + M[1, 2] * r
    for i in range(9):
        for j in range(9):
            phi[i, j] = 0.0
    # eta_dot = R(psi) nu
    phi[0, PSI] = -s * u - c * v
    phi[0, SURGE] = c
    phi[0, SWAY] = -s
    phi[1, PSI] = c * u - s * v
    phi[1, SURGE] = s
    phi[1, SWAY] = c
    phi[2, YAW_RATE] = 1.0
    # g = M nu_dot (the generalised force), row k over the states j: d g_k / d x_j, kept
    # in phi's rows 6-8 for the moment (the bias rows, set last)
    g = phi[6:9]
    g[0, NORTH] = -c * k_h
    g[0, EAST] = -s * k_h
    g[0, PSI] = -s * fn + c * fe
    g[0, SURGE] = M[1, 0] * r - (D_l[0] + 2.0 * D_nl[0] * abs(u))
    g[0, SWAY] = M[1, 1] * r
    g[0, YAW_RATE] = ay + M[1, 2] * r
    g[0, B_N] = c
    g[0, B_E] = s
    g[1, NORTH] = s * k_h
    g[1, EAST] = -c * k_h
    g[1, PSI] = -c * fn - s * fe
    g[1, SURGE] = -M[0, 0] * r
    g[1, SWAY] = -M[0, 1] * r - (D_l[1] + 2.0 * D_nl[1] * abs(v))
    g[1, YAW_RATE] = -ax - M[0, 2] * r
    g[1, B_N] = -s
    g[1, B_E] = c
    # g_2 = tau_2 + b_psi - (ay u - ax v) - (D_l + D_nl |r|) r
    g[2, SURGE] = -(M[1, 0] * u + ay - M[0, 0] * v)
    g[2, SWAY] = -(M[1, 1] * u - ax - M[0, 1] * v)
    g[2, YAW_RATE] = -(M[1, 2] * u - M[0, 2] * v) - (D_l[2] + 2.0 * D_nl[2] * abs(r))
    g[2, B_PSI] = 1.0
    # nu_dot = M^-1 g
    for i in range(3):
        for j in range(9):
            phi[3 + i, j] = M_inv[i, 0] * g[0, j] + M_inv[i, 1] * g[1, j] + M_inv[i, 2] * g[2, j]
    for i in range(6):
        for j in range(9):
            phi[i, j] *= dt
    for i in range(3):
        for j in range(9):
            phi[6 + i, j] = 0.0
        phi[6 + i, 6 + i] = -dt / T_b[i]
    for i in range(9):
        phi[i, i] += 1.0


@njit(inline="always", **JIT_NOALLOC)
def phi_times_into(out: np.ndarray, phi: np.ndarray, A: np.ndarray, transposed: bool) -> None:
    """out = phi @ A (``transposed``: phi @ A.T) for phi of ``jacobian_phi_into``, leaving
    out the products with its known zeros (37 of 81 entries are not: rows 0-1 reach the
    heading and the velocities, row 2 the yaw rate, rows 3-5 everything, rows 6-8 their own
    bias), column by column."""
    for j in range(9):
        if transposed:
            a0, a1, a2, a3, a4 = A[j, 0], A[j, 1], A[j, 2], A[j, 3], A[j, 4]
            a5, a6, a7, a8 = A[j, 5], A[j, 6], A[j, 7], A[j, 8]
        else:
            a0, a1, a2, a3, a4 = A[0, j], A[1, j], A[2, j], A[3, j], A[4, j]
            a5, a6, a7, a8 = A[5, j], A[6, j], A[7, j], A[8, j]
        out[0, j] = a0 + phi[0, 2] * a2 + phi[0, 3] * a3 + phi[0, 4] * a4
        out[1, j] = a1 + phi[1, 2] * a2 + phi[1, 3] * a3 + phi[1, 4] * a4
        out[2, j] = a2 + phi[2, 5] * a5
        for i in range(3, 6):
            out[i, j] = (
                phi[i, 0] * a0
                + phi[i, 1] * a1
                + phi[i, 2] * a2
                + phi[i, 3] * a3
                + phi[i, 4] * a4
                + phi[i, 5] * a5
                + phi[i, 6] * a6
                + phi[i, 7] * a7
                + phi[i, 8] * a8
            )
        out[6, j] = phi[6, 6] * a6
        out[7, j] = phi[7, 7] * a7
        out[8, j] = phi[8, 8] * a8


@njit(inline="always", **JIT_NOALLOC)
def _symmetrise(P: np.ndarray) -> None:
    """P = (P + P^T) / 2, element by element, in place."""
    for i in range(N_X):
        for j in range(i):
            v = 0.5 * (P[i, j] + P[j, i])
            P[i, j] = v
            P[j, i] = v


@njit(inline="always", **JIT_NOALLOC)
def predict_into(
    x: np.ndarray,
    P: np.ndarray,
    tau: np.ndarray,
    dt: float,
    M_inv: np.ndarray,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    T_b: np.ndarray,
    GQG: np.ndarray,
    f0: np.ndarray,
    phi: np.ndarray,
    tmp: np.ndarray,
) -> None:
    """``predict`` in place: advances ``x`` (9,) and ``P`` (9, 9), allocating nothing. The
    work arrays ``f0`` (9,), ``phi``, ``tmp`` (9, 9) are overwritten (nothing is read from
    them before it is written)."""
    c0, s0 = np.cos(x[2]), np.sin(x[2])
    _model_rhs_cs_into(f0, x, c0, s0, tau, M_inv, M, D_l, D_nl, k_h, p_eq, T_b)
    jacobian_phi_into(phi, x, c0, s0, dt, M_inv, M, D_l, D_nl, k_h, p_eq, T_b)
    for i in range(9):
        x[i] = x[i] + dt * f0[i]
    # phi P phi^T = phi (phi P)^T (P is symmetric), each product without phi's zeros; + GQG
    # and the symmetrisation 0.5 (A + A^T) element by element, in place
    phi_times_into(tmp, phi, P, False)
    phi_times_into(P, phi, tmp, True)
    for i in range(9):
        for j in range(9):
            P[i, j] += GQG[i, j]
    _symmetrise(P)


@njit(inline="always", **JIT)
def correct(
    x: np.ndarray, P: np.ndarray, z: np.ndarray, rows: np.ndarray, r_var: np.ndarray, angle_row: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Correct with a measurement of the states ``rows`` (a selection, so H is rows of I).

    ``angle_row`` is the index within ``rows`` whose innovation is an angle (wrapped with ssa),
    or -1. Returns (x, P, normalised innovation squared per row) -- the last is what the
    operator's "observer innovation" alarm watches. New arrays; ``correct_into`` corrects in
    place."""
    m = rows.shape[0]
    if m > 2:
        raise ValueError("correct: at most 2 measured rows")
    x_new = x.copy()
    P_new = P.copy()
    nis = np.empty(m)
    z1 = z[1] if m == 2 else 0.0
    row1 = rows[1] if m == 2 else -1
    r1 = r_var[1] if m == 2 else 0.0
    n0, n1 = correct_into(
        x_new, P_new, m, z[0], z1, rows[0], row1, r_var[0], r1, angle_row,
        np.empty(N_X), np.empty(N_X), np.empty((N_X, N_X)),
    )  # fmt: skip
    nis[0] = n0
    if m == 2:
        nis[1] = n1
    return x_new, P_new, nis


@njit(inline="always", **JIT_NOALLOC)
def correct_into(
    x: np.ndarray,
    P: np.ndarray,
    m: int,
    z0: float,
    z1: float,
    row0: int,
    row1: int,
    r0: float,
    r1: float,
    angle_row: int,
    k0: np.ndarray,
    k1: np.ndarray,
    A: np.ndarray,
) -> tuple[float, float]:
    """``correct`` in place, for m = 1 (``z0`` of state ``row0``, variance ``r0``) or m = 2
    measured rows (and ``z1``, ``row1``, ``r1``): updates ``x`` (9,) and ``P`` (9, 9),
    allocating nothing; ``k0``, ``k1`` (9,) and ``A`` (9, 9) are work arrays. Returns the
    normalised innovations squared (the second 0.0 when m = 1).

    Table 3.1 written for H = rows of the identity, with m <= 2 (the loop's sensors):
    S = P[rows, rows] + R, K = P[:, rows] S^-1 (S^-1 in closed form), and the Joseph form
    (I - K H) P (I - K H)^T + K R K^T as rank-m updates. The same algebra as the dense
    products, in a different summation order (the last bits differ)."""
    if m == 1:
        return _correct_one_into(x, P, z0, row0, r0, angle_row == 0, k0, A), 0.0
    e0 = z0 - x[row0]
    e1 = z1 - x[row1]
    if angle_row == 0:
        e0 = ssa_scalar(e0)
    elif angle_row == 1:
        e1 = ssa_scalar(e1)
    # innovation covariance and its inverse
    s00 = P[row0, row0] + r0
    s01 = P[row0, row1]
    s10 = P[row1, row0]
    s11 = P[row1, row1] + r1
    det = s00 * s11 - s01 * s10
    i00, i01, i10, i11 = s11 / det, -s01 / det, -s10 / det, s00 / det
    # gain K (9, 2), as two columns
    for i in range(N_X):
        k0[i] = P[i, row0] * i00 + P[i, row1] * i10
        k1[i] = P[i, row0] * i01 + P[i, row1] * i11
    for i in range(N_X):
        x[i] = x[i] + (k0[i] * e0 + k1[i] * e1)
    # Joseph form: A = (I - K H) P, then P+ = A (I - K H)^T + K R K^T (A is all of the old P
    # that P+ needs, so P+ is written over P)
    for i in range(N_X):
        for j in range(N_X):
            A[i, j] = P[i, j] - (k0[i] * P[row0, j] + k1[i] * P[row1, j])
    for i in range(N_X):
        for j in range(N_X):
            P[i, j] = (
                A[i, j]
                - (A[i, row0] * k0[j] + A[i, row1] * k1[j])
                + (k0[i] * r0 * k0[j] + k1[i] * r1 * k1[j])
            )
    _symmetrise(P)
    return e0 * e0 / s00, e1 * e1 / s11


@njit(inline="always", **JIT_NOALLOC)
def _correct_one_into(
    x: np.ndarray,
    P: np.ndarray,
    z0: float,
    row0: int,
    r0: float,
    angle: bool,
    k: np.ndarray,
    A: np.ndarray,
) -> float:
    """``correct_into`` for one measured row (the gyro's yaw rate every step, the compass):
    the same operations in the same order without the second row's terms, which for m = 1
    are products with an exact zero gain (x + 0 y = x for finite y: the same bits, checked
    against the two-row form in ``tests/test_ekf_correct.py``). About half the arithmetic.
    Returns the normalised innovation squared."""
    e0 = z0 - x[row0]
    if angle:
        e0 = ssa_scalar(e0)
    s00 = P[row0, row0] + r0
    i00 = 1.0 / s00
    for i in range(N_X):
        k[i] = P[i, row0] * i00
    for i in range(N_X):
        x[i] = x[i] + k[i] * e0
    for i in range(N_X):
        ki = k[i]
        for j in range(N_X):
            A[i, j] = P[i, j] - ki * P[row0, j]
    for i in range(N_X):
        a_ir = A[i, row0]
        kr = k[i] * r0
        for j in range(N_X):
            P[i, j] = A[i, j] - a_ir * k[j] + kr * k[j]
    _symmetrise(P)
    return e0 * e0 / s00
