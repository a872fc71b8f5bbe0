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

from sim.gnc import JIT, JIT_NOALLOC, dot_into, ssa

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
    with Phi = I + h df/dx (forward-difference Jacobian, step 1e-6 scaled to each state).
    Returns new arrays (``predict_into`` is the step in place)."""
    x_new = x.copy()
    P_new = P.copy()
    predict_into(
        x_new, P_new, tau, dt, M_inv, M, D_l, D_nl, k_h, p_eq, T_b, GQG,
        np.empty(9), np.empty(9), np.empty(9), np.empty((9, 9)), np.empty((9, 9)),
    )  # fmt: skip
    return x_new, P_new


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
    fj: np.ndarray,
    xp: np.ndarray,
    phi: np.ndarray,
    tmp: np.ndarray,
) -> None:
    """``predict`` in place: advances ``x`` (9,) and ``P`` (9, 9), allocating nothing. The
    work arrays ``f0``, ``fj``, ``xp`` (9,), ``phi``, ``tmp`` (9, 9) are overwritten (nothing is
    read from them before it is written)."""
    # the heading's cosine and sine once: only the heading's own column perturbs it
    c0, s0 = np.cos(x[2]), np.sin(x[2])
    _model_rhs_cs_into(f0, x, c0, s0, tau, M_inv, M, D_l, D_nl, k_h, p_eq, T_b)
    for i in range(9):
        for j in range(9):
            phi[i, j] = 1.0 if i == j else 0.0
        xp[i] = x[i]  # one work copy: each column perturbs one state and puts it back
    for j in range(9):
        eps = 1e-6 * max(1.0, abs(x[j]))
        xp[j] = x[j] + eps
        if j == PSI:
            _model_rhs_into(fj, xp, tau, M_inv, M, D_l, D_nl, k_h, p_eq, T_b)
        else:
            _model_rhs_cs_into(fj, xp, c0, s0, tau, M_inv, M, D_l, D_nl, k_h, p_eq, T_b)
        xp[j] = x[j]
        for i in range(9):
            phi[i, j] += dt * (fj[i] - f0[i]) / eps
    for i in range(9):
        x[i] = x[i] + dt * f0[i]
    # phi P phi^T by the same two BLAS products as ``phi @ P @ phi.T``; + GQG and the
    # symmetrisation 0.5 (A + A^T) element by element, in place
    dot_into(phi, P, tmp)
    dot_into(tmp, phi.T, P)
    for i in range(9):
        for j in range(9):
            P[i, j] += GQG[i, j]
    for i in range(9):
        for j in range(i):
            v = 0.5 * (P[i, j] + P[j, i])
            P[i, j] = v
            P[j, i] = v


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
    e0 = z0 - x[row0]
    e1 = z1 - x[row1] if m == 2 else 0.0
    if angle_row == 0:
        e0 = ssa(e0)
    elif angle_row == 1:
        e1 = ssa(e1)
    # innovation covariance and its inverse
    s00 = P[row0, row0] + r0
    if m == 1:
        i00, i01, i10, i11 = 1.0 / s00, 0.0, 0.0, 0.0
        s11 = 1.0
    else:
        s01 = P[row0, row1]
        s10 = P[row1, row0]
        s11 = P[row1, row1] + r1
        det = s00 * s11 - s01 * s10
        i00, i01, i10, i11 = s11 / det, -s01 / det, -s10 / det, s00 / det
    # gain K (9, m), as two columns
    for i in range(N_X):
        if m == 1:
            k0[i] = P[i, row0] * i00
            k1[i] = 0.0
        else:
            k0[i] = P[i, row0] * i00 + P[i, row1] * i10
            k1[i] = P[i, row0] * i01 + P[i, row1] * i11
    for i in range(N_X):
        x[i] = x[i] + (k0[i] * e0 + k1[i] * e1)
    # Joseph form: A = (I - K H) P, then P+ = A (I - K H)^T + K R K^T (A is all of the old P
    # that P+ needs, so P+ is written over P)
    rr1 = r1 if m == 2 else 0.0
    c1 = row1 if m == 2 else row0
    for i in range(N_X):
        for j in range(N_X):
            A[i, j] = P[i, j] - (k0[i] * P[row0, j] + k1[i] * P[c1, j])
    for i in range(N_X):
        for j in range(N_X):
            P[i, j] = (
                A[i, j]
                - (A[i, row0] * k0[j] + A[i, c1] * k1[j])
                + (k0[i] * r0 * k0[j] + k1[i] * rr1 * k1[j])
            )
    for i in range(N_X):
        for j in range(i):
            v = 0.5 * (P[i, j] + P[j, i])
            P[i, j] = v
            P[j, i] = v
    nis1 = e1 * e1 / s11 if m == 2 else 0.0
    return e0 * e0 / s00, nis1
