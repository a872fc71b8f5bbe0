"""The observer's prediction (``control.ekf.predict_into``) and corrections (``correct_into``
in ``control.loop._observe_into``'s order) of a block of runs at once, laid out so the
compiler vectorises over the runs (the run index last), for the batch kernel.

A run's prediction is a 9-state Euler step of the control plant model and the covariance
update Phi P Phi^T + GQG with its 9x9 Jacobian. Run by run (``predict_into``, each run's P
contiguous) it took some 320 ns a run-step of a docking batch on this project's Zen 4, the
second largest of the batch kernel's passes (``benchmarks/kernel_passes.py``). Here the runs
under way are loaded into the columns of one flat work array (``load_run``), every quantity
a row of ``BLOCK`` runs, row k of run r at ``k * BLOCK + r`` (``_at``: one array and a
distance between rows that the compiler sees, so it needs no check at run time that a row
written is not a row read, the layout of ``sim.batch_plant``), stepped in a few loops over
the runs (``predict_block_into``) and stored back (``store_run``).

Every run's numbers are ``predict_into``'s bit for bit: each quantity is computed with the
scalar code's operations in the scalar code's order (numba compiles without fast-math or
contraction into fused multiply-adds), the Jacobian's known zeros are left out of the
products where ``ekf.phi_times_into`` leaves them out and kept where it keeps them (the
signs of zeros follow), the heading's cosine and sine are libm's as there (a loop of their
own, which does not vectorise). ``tests/test_batch_ekf.py`` checks the bits.

The corrections (``correct_block_into``) follow the prediction with the samples of each
run's next step (``load_samples``, made by ``control.batchkernel.sense_ahead``): a
correction no column accepts is skipped, and a column that does not accept one keeps its
numbers by a select (a scratch timing put the gyro's correction of every step at 120 ns a
run by itself; in the block all the corrections add some 30-40 ns a run-step to the
prediction, ``kernel_passes.py``).

The control model (M, its inverse, the damping, the bias time constants, GQG) is one for the
block: the caller puts only runs whose model is the one it passes (``control.batch``'s
``same_model``); each run's wire spring (k_h, p_eq) and input wrench are its own, as are
its samples' variances and its ROV's mounting vector.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from sim.gnc import JIT, JIT_NOALLOC, ssa_scalar

LANES = 8
"""The doubles in an AVX-512 register: ``pad_block`` pads a block's width to a multiple of
this, so the loops over the runs have no scalar remainder."""

BLOCK = 32
"""Runs a block (a batch task has at most 32; more go in several blocks). Row k of run r is
element ``k * BLOCK + r`` of the work array."""

# row groups of the flat work array
R_X = 0  # (9) the state estimate
R_P = 9  # (81) its covariance, row-major: P[i, j] in row R_P + 9 i + j
R_TMP = 90  # (81) Phi P
R_PHI = 171  # (81) Phi, row-major; only the 37 entries phi_times_into reads are written
R_TAU = 252  # (3) the input wrench in the tree's axes [N, N, N m]
R_SPRING = 255  # (3) the control model's wire spring: k_h [N/m], p_eq north, east [m]
R_CS = 258  # (2) the heading's cosine and sine
# the corrections with the next step's samples (``correct_block_into``)
R_ACC = 260  # (4) 1.0 where the sample is accepted: A_COMPASS, A_POSITION, A_GYRO, A_DVL
R_Z = 264  # (6) the measurements: Z_PSI, Z_NORTH, Z_EAST (the fix's), Z_RATE, Z_U, Z_V
R_MOUNT = 270  # (2) the ROV's mounting vector on the tree [m] (ControlArrays.r_mount)
R_RVAR = 272  # (4) the measurement variances, in A_* order
R_NIS = 276  # (3) normalised innovations squared: the compass's, the fix's two
R_K = 279  # (18) the gain's two columns
R_PROW = 297  # (18) the measured rows of P before the update
R_ACOL = 315  # (18) the measured columns of the Joseph form's A
R_E = 333  # (2) the innovations
N_ROWS = 335

A_COMPASS, A_POSITION, A_GYRO, A_DVL = 0, 1, 2, 3
Z_PSI, Z_NORTH, Z_EAST, Z_RATE, Z_U, Z_V = 0, 1, 2, 3, 4, 5


class EkfBlock(NamedTuple):
    """The block's work space (``make_ekf_block``), reused for every step."""

    a: np.ndarray  # (N_ROWS * BLOCK,) the rows (R_*), flat
    runs: np.ndarray  # (BLOCK,) int64: which run a column holds (for the caller)


@njit(**JIT)
def make_ekf_block() -> EkfBlock:
    """A fresh work space for one block of runs."""
    return EkfBlock(np.zeros(N_ROWS * BLOCK), np.zeros(BLOCK, np.int64))


@njit(inline="always", **JIT_NOALLOC)
def _at(k: int, r: int) -> np.uint64:
    """Where row k of run r is in the flat work array (unsigned: no wrap-around of negative
    indices, which would hide the rows' constant distance from the compiler)."""
    return np.uint64(k * BLOCK + r)


@njit(inline="always", **JIT_NOALLOC)
def load_run(
    wb: EkfBlock,
    c: int,
    xhat: np.ndarray,
    P: np.ndarray,
    tau: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
) -> None:
    """Run state ``xhat`` (9,), covariance ``P`` (9, 9), input wrench ``tau`` (3,) and wire
    spring (``k_h``, ``p_eq`` (2,)) into column ``c``."""
    a = wb.a
    for i in range(9):
        a[_at(R_X + i, c)] = xhat[i]
    for i in range(9):
        for j in range(9):
            a[_at(R_P + 9 * i + j, c)] = P[i, j]
    for i in range(3):
        a[_at(R_TAU + i, c)] = tau[i]
    a[_at(R_SPRING, c)] = k_h
    a[_at(R_SPRING + 1, c)] = p_eq[0]
    a[_at(R_SPRING + 2, c)] = p_eq[1]
    for i in range(4):
        a[_at(R_ACC + i, c)] = 0.0  # no samples unless ``load_samples`` brings them


@njit(inline="always", **JIT_NOALLOC)
def load_samples(
    wb: EkfBlock,
    c: int,
    accepted: np.ndarray,
    z: np.ndarray,
    r_mount: np.ndarray,
    r_var: np.ndarray,
) -> None:
    """The samples column ``c``'s run corrects with after its prediction: ``accepted`` (4,)
    1.0 or 0.0 in ``A_*`` order, the measurements ``z`` (6,) in ``Z_*`` order (the position
    fix's raw north and east: the tree's origin is worked out in the block, from the heading
    after the compass's correction), the ROV's mounting vector (2,) and the variances (4,)
    in ``A_*`` order. After ``load_run``."""
    a = wb.a
    for i in range(4):
        a[_at(R_ACC + i, c)] = accepted[i]
        a[_at(R_RVAR + i, c)] = r_var[i]
    for i in range(6):
        a[_at(R_Z + i, c)] = z[i]
    a[_at(R_MOUNT, c)] = r_mount[0]
    a[_at(R_MOUNT + 1, c)] = r_mount[1]


@njit(inline="always", **JIT_NOALLOC)
def store_run(wb: EkfBlock, c: int, xhat: np.ndarray, P: np.ndarray) -> None:
    """Column ``c``'s predicted state and covariance into ``xhat`` (9,) and ``P`` (9, 9)."""
    a = wb.a
    for i in range(9):
        xhat[i] = a[_at(R_X + i, c)]
    for i in range(9):
        for j in range(9):
            P[i, j] = a[_at(R_P + 9 * i + j, c)]


@njit(inline="always", **JIT_NOALLOC)
def pad_block(wb: EkfBlock, n: int) -> int:
    """Fill the columns from ``n`` up to the next multiple of ``LANES`` (at most ``BLOCK``)
    with copies of column 0 (their results are not read). Returns the padded width
    (``n`` >= 1)."""
    w = min(BLOCK, (n + LANES - 1) // LANES * LANES)
    a = wb.a
    for c in range(n, w):
        for k in range(R_TMP):
            a[_at(k, c)] = a[_at(k, 0)]
        for k in range(R_TAU, N_ROWS):
            a[_at(k, c)] = a[_at(k, 0)]
    return w


@njit(inline="always", **JIT_NOALLOC)
def _model_and_jacobian(
    a: np.ndarray,
    w: int,
    dt: float,
    M: np.ndarray,
    M_inv: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    T_b: np.ndarray,
) -> None:
    """Per run: f(x) (``ekf._model_rhs_cs_into``) and the entries of Phi that the products
    read (``ekf.jacobian_phi_into``), then x += dt f; each with the scalar code's operations
    in its order."""
    M00, M01, M02, M10, M11, M12 = M[0, 0], M[0, 1], M[0, 2], M[1, 0], M[1, 1], M[1, 2]
    mi00, mi01, mi02 = M_inv[0, 0], M_inv[0, 1], M_inv[0, 2]
    mi10, mi11, mi12 = M_inv[1, 0], M_inv[1, 1], M_inv[1, 2]
    mi20, mi21, mi22 = M_inv[2, 0], M_inv[2, 1], M_inv[2, 2]
    dl0, dl1, dl2 = D_l[0], D_l[1], D_l[2]
    dn0, dn1, dn2 = D_nl[0], D_nl[1], D_nl[2]
    tb0, tb1, tb2 = T_b[0], T_b[1], T_b[2]
    for r in range(w):
        c = a[_at(R_CS, r)]
        s = a[_at(R_CS + 1, r)]
        x0, x1, x2 = a[_at(R_X, r)], a[_at(R_X + 1, r)], a[_at(R_X + 2, r)]
        u, v, q = a[_at(R_X + 3, r)], a[_at(R_X + 4, r)], a[_at(R_X + 5, r)]
        b0, b1, b2 = a[_at(R_X + 6, r)], a[_at(R_X + 7, r)], a[_at(R_X + 8, r)]
        k_h = a[_at(R_SPRING, r)]
        pe0, pe1 = a[_at(R_SPRING + 1, r)], a[_at(R_SPRING + 2, r)]
        # --- the model's right-hand side (_model_rhs_cs_into) ---
        fx0 = c * u - s * v
        fx1 = s * u + c * v
        fx2 = q
        fn = -k_h * (x0 - pe0) + b0
        fe = -k_h * (x1 - pe1) + b1
        ax = M00 * u + M01 * v + M02 * q
        ay = M10 * u + M11 * v + M12 * q
        f0 = a[_at(R_TAU, r)] + c * fn + s * fe
        f1 = a[_at(R_TAU + 1, r)] - s * fn + c * fe
        f2 = a[_at(R_TAU + 2, r)] + b2
        f0 -= -ay * q + (dl0 + dn0 * abs(u)) * u
        f1 -= ax * q + (dl1 + dn1 * abs(v)) * v
        f2 -= (ay * u - ax * v) + (dl2 + dn2 * abs(q)) * q
        acc = 0.0
        acc += mi00 * f0
        acc += mi01 * f1
        acc += mi02 * f2
        fx3 = acc
        acc = 0.0
        acc += mi10 * f0
        acc += mi11 * f1
        acc += mi12 * f2
        fx4 = acc
        acc = 0.0
        acc += mi20 * f0
        acc += mi21 * f1
        acc += mi22 * f2
        fx5 = acc
        fx6 = -b0 / tb0
        fx7 = -b1 / tb1
        fx8 = -b2 / tb2
        # --- Phi = I + dt df/dx (jacobian_phi_into), the entries the products read ---
        a[_at(R_PHI + 2, r)] = (-s * u - c * v) * dt
        a[_at(R_PHI + 3, r)] = c * dt
        a[_at(R_PHI + 4, r)] = -s * dt
        a[_at(R_PHI + 9 + 2, r)] = (c * u - s * v) * dt
        a[_at(R_PHI + 9 + 3, r)] = s * dt
        a[_at(R_PHI + 9 + 4, r)] = c * dt
        a[_at(R_PHI + 18 + 5, r)] = 1.0 * dt
        # d(M nu_dot)/dx: g<row><state>; the zeros of jacobian_phi_into kept as 0.0
        g00 = -c * k_h
        g01 = -s * k_h
        g02 = -s * fn + c * fe
        g03 = M10 * q - (dl0 + 2.0 * dn0 * abs(u))
        g04 = M11 * q
        g05 = ay + M12 * q
        g06 = c
        g07 = s
        g08 = 0.0
        g10 = s * k_h
        g11 = -c * k_h
        g12 = -c * fn - s * fe
        g13 = -M00 * q
        g14 = -M01 * q - (dl1 + 2.0 * dn1 * abs(v))
        g15 = -ax - M02 * q
        g16 = -s
        g17 = c
        g18 = 0.0
        g20 = 0.0
        g21 = 0.0
        g22 = 0.0
        g23 = -(M10 * u + ay - M00 * v)
        g24 = -(M11 * u - ax - M01 * v)
        g25 = -(M12 * u - M02 * v) - (dl2 + 2.0 * dn2 * abs(q))
        g26 = 0.0
        g27 = 0.0
        g28 = 1.0
        gr0 = (g00, g01, g02, g03, g04, g05, g06, g07, g08)
        gr1 = (g10, g11, g12, g13, g14, g15, g16, g17, g18)
        gr2 = (g20, g21, g22, g23, g24, g25, g26, g27, g28)
        _phi_row_into(a, r, 3, dt, mi00, mi01, mi02,
                      gr0, gr1, gr2)  # fmt: skip
        _phi_row_into(a, r, 4, dt, mi10, mi11, mi12,
                      gr0, gr1, gr2)  # fmt: skip
        _phi_row_into(a, r, 5, dt, mi20, mi21, mi22,
                      gr0, gr1, gr2)  # fmt: skip
        a[_at(R_PHI + 60, r)] = -dt / tb0 + 1.0
        a[_at(R_PHI + 70, r)] = -dt / tb1 + 1.0
        a[_at(R_PHI + 80, r)] = -dt / tb2 + 1.0
        # --- x += dt f ---
        a[_at(R_X, r)] = x0 + dt * fx0
        a[_at(R_X + 1, r)] = x1 + dt * fx1
        a[_at(R_X + 2, r)] = x2 + dt * fx2
        a[_at(R_X + 3, r)] = u + dt * fx3
        a[_at(R_X + 4, r)] = v + dt * fx4
        a[_at(R_X + 5, r)] = q + dt * fx5
        a[_at(R_X + 6, r)] = b0 + dt * fx6
        a[_at(R_X + 7, r)] = b1 + dt * fx7
        a[_at(R_X + 8, r)] = b2 + dt * fx8


@njit(inline="always", **JIT_NOALLOC)
def _phi_row_into(
    a: np.ndarray,
    r: int,
    i: int,
    dt: float,
    m0: float,
    m1: float,
    m2: float,
    gr0: tuple,
    gr1: tuple,
    gr2: tuple,
) -> None:
    """Row i (3, 4 or 5) of Phi: (M^-1 g)[i - 3, j] dt (``gr0`` ... ``gr2``: g's rows, m0 ...
    m2: M^-1's row i - 3), and 1 added on the diagonal, as ``jacobian_phi_into`` makes it."""
    k = R_PHI + 9 * i
    e0 = (m0 * gr0[0] + m1 * gr1[0] + m2 * gr2[0]) * dt
    e1 = (m0 * gr0[1] + m1 * gr1[1] + m2 * gr2[1]) * dt
    e2 = (m0 * gr0[2] + m1 * gr1[2] + m2 * gr2[2]) * dt
    e3 = (m0 * gr0[3] + m1 * gr1[3] + m2 * gr2[3]) * dt
    e4 = (m0 * gr0[4] + m1 * gr1[4] + m2 * gr2[4]) * dt
    e5 = (m0 * gr0[5] + m1 * gr1[5] + m2 * gr2[5]) * dt
    e6 = (m0 * gr0[6] + m1 * gr1[6] + m2 * gr2[6]) * dt
    e7 = (m0 * gr0[7] + m1 * gr1[7] + m2 * gr2[7]) * dt
    e8 = (m0 * gr0[8] + m1 * gr1[8] + m2 * gr2[8]) * dt
    if i == 3:
        e3 += 1.0
    elif i == 4:
        e4 += 1.0
    else:
        e5 += 1.0
    a[_at(k, r)] = e0
    a[_at(k + 1, r)] = e1
    a[_at(k + 2, r)] = e2
    a[_at(k + 3, r)] = e3
    a[_at(k + 4, r)] = e4
    a[_at(k + 5, r)] = e5
    a[_at(k + 6, r)] = e6
    a[_at(k + 7, r)] = e7
    a[_at(k + 8, r)] = e8


@njit(inline="always", **JIT_NOALLOC)
def _phi_column_into(
    a: np.ndarray, r: int, out: int, stride: int,
    a0: float, a1: float, a2: float, a3: float, a4: float,
    a5: float, a6: float, a7: float, a8: float,
) -> None:  # fmt: skip
    """Phi (a0 ... a8) into the rows ``out + stride * i`` (i = 0 ... 8) of run r:
    ``ekf.phi_times_into``'s sums for one column, without Phi's known zeros."""
    p = R_PHI
    a[_at(out, r)] = a0 + a[_at(p + 2, r)] * a2 + a[_at(p + 3, r)] * a3 + a[_at(p + 4, r)] * a4
    a[_at(out + stride, r)] = (
        a1 + a[_at(p + 11, r)] * a2 + a[_at(p + 12, r)] * a3 + a[_at(p + 13, r)] * a4
    )
    a[_at(out + 2 * stride, r)] = a2 + a[_at(p + 23, r)] * a5
    for i in range(3, 6):
        k = p + 9 * i
        a[_at(out + i * stride, r)] = (
            a[_at(k, r)] * a0
            + a[_at(k + 1, r)] * a1
            + a[_at(k + 2, r)] * a2
            + a[_at(k + 3, r)] * a3
            + a[_at(k + 4, r)] * a4
            + a[_at(k + 5, r)] * a5
            + a[_at(k + 6, r)] * a6
            + a[_at(k + 7, r)] * a7
            + a[_at(k + 8, r)] * a8
        )
    a[_at(out + 6 * stride, r)] = a[_at(p + 60, r)] * a6
    a[_at(out + 7 * stride, r)] = a[_at(p + 70, r)] * a7
    a[_at(out + 8 * stride, r)] = a[_at(p + 80, r)] * a8


@njit(**JIT_NOALLOC)
def predict_block_into(
    wb: EkfBlock,
    w: int,
    dt: float,
    M: np.ndarray,
    M_inv: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    T_b: np.ndarray,
    GQG: np.ndarray,
) -> None:
    """``ekf.predict_into`` of the block's first ``w`` columns (a multiple of ``LANES``:
    ``pad_block``), in place, on the control model (``M`` ... ``GQG``) they share."""
    a = wb.a
    # the heading's cosine and sine, libm's (as predict_into): a loop of its own
    for r in range(w):
        psi = a[_at(R_X + 2, r)]
        a[_at(R_CS, r)] = np.cos(psi)
        a[_at(R_CS + 1, r)] = np.sin(psi)
    _model_and_jacobian(a, w, dt, M, M_inv, D_l, D_nl, T_b)
    # tmp = Phi P, column by column (phi_times_into(tmp, phi, P, False))
    for j in range(9):
        for r in range(w):
            _phi_column_into(
                a, r, R_TMP + j, 9,
                a[_at(R_P + j, r)], a[_at(R_P + 9 + j, r)], a[_at(R_P + 18 + j, r)],
                a[_at(R_P + 27 + j, r)], a[_at(R_P + 36 + j, r)], a[_at(R_P + 45 + j, r)],
                a[_at(R_P + 54 + j, r)], a[_at(R_P + 63 + j, r)], a[_at(R_P + 72 + j, r)],
            )  # fmt: skip
    # P = Phi tmp^T, column j from tmp's row j (phi_times_into(P, phi, tmp, True))
    for j in range(9):
        t = R_TMP + 9 * j
        for r in range(w):
            _phi_column_into(
                a, r, R_P + j, 9,
                a[_at(t, r)], a[_at(t + 1, r)], a[_at(t + 2, r)],
                a[_at(t + 3, r)], a[_at(t + 4, r)], a[_at(t + 5, r)],
                a[_at(t + 6, r)], a[_at(t + 7, r)], a[_at(t + 8, r)],
            )  # fmt: skip
    # + GQG, then (P + P^T) / 2 element by element (predict_into's end)
    for i in range(9):
        q = GQG[i, i]
        k = R_P + 10 * i
        for r in range(w):
            a[_at(k, r)] += q
        for j in range(i):
            q_ij, q_ji = GQG[i, j], GQG[j, i]
            k_ij, k_ji = R_P + 9 * i + j, R_P + 9 * j + i
            for r in range(w):
                v = 0.5 * ((a[_at(k_ij, r)] + q_ij) + (a[_at(k_ji, r)] + q_ji))
                a[_at(k_ij, r)] = v
                a[_at(k_ji, r)] = v


@njit(inline="always", **JIT_NOALLOC)
def accepted_at(wb: EkfBlock, c: int, k: int) -> bool:
    """Whether column ``c`` corrected with its sample ``k`` (``A_*``)."""
    return wb.a[_at(R_ACC + k, c)] > 0.5


@njit(inline="always", **JIT_NOALLOC)
def nis_at(wb: EkfBlock, c: int, k: int) -> float:
    """Column ``c``'s normalised innovation squared ``k`` (0: the compass's, 1 and 2: the
    position fix's north and east) of its last correction."""
    return wb.a[_at(R_NIS + k, c)]


@njit(inline="always", **JIT_NOALLOC)
def _any_accepted(a: np.ndarray, w: int, k: int) -> bool:
    """Whether a column of the first ``w`` corrects with sample ``k``."""
    for r in range(w):
        if a[_at(R_ACC + k, r)] > 0.5:
            return True
    return False


@njit(inline="always", **JIT_NOALLOC)
def _joseph_entry(a: np.ndarray, r: int, i: int, j: int, rv: int, two: bool) -> float:
    """Entry (i, j) of column r's updated covariance before the symmetrising: A - A H^T K^T
    + K R K^T with A = (I - K H) P, from the gain (``R_K``), the measured rows of the old P
    (``R_PROW``), the measured columns of A (``R_ACOL``) and the variance in row ``rv``
    (``ekf.correct_into``'s sums in its order; one measured row without the second row's
    terms, as ``ekf._correct_one_into``)."""
    p_ij = a[_at(R_P + 9 * i + j, r)]
    r0 = a[_at(rv, r)]
    k0i, k0j = a[_at(R_K + i, r)], a[_at(R_K + j, r)]
    if two:
        k1i, k1j = a[_at(R_K + 9 + i, r)], a[_at(R_K + 9 + j, r)]
        a_ij = p_ij - (k0i * a[_at(R_PROW + j, r)] + k1i * a[_at(R_PROW + 9 + j, r)])
        return (a_ij - (a[_at(R_ACOL + i, r)] * k0j + a[_at(R_ACOL + 9 + i, r)] * k1j)) + (
            k0i * r0 * k0j + k1i * r0 * k1j
        )
    a_ij = p_ij - k0i * a[_at(R_PROW + j, r)]
    kr = k0i * r0
    return a_ij - a[_at(R_ACOL + i, r)] * k0j + kr * k0j


@njit(inline="always", **JIT_NOALLOC)
def _joseph_into(a: np.ndarray, w: int, k: int, two: bool) -> None:
    """The covariance's Joseph update of the columns that accept sample ``k``: each entry
    pair (i, j), (j, i) worked out from the old entries (``_joseph_entry``), then
    symmetrised ((P+ + P+^T) / 2, ``ekf._symmetrise``: the diagonal as it is) and written
    where accepted; a pair reads no entry but its own, so the update is in place."""
    acc = R_ACC + k
    rv = R_RVAR + k
    for i in range(9):
        d = R_P + 10 * i
        for r in range(w):
            v = _joseph_entry(a, r, i, i, rv, two)
            a[_at(d, r)] = v if a[_at(acc, r)] > 0.5 else a[_at(d, r)]
        for j in range(i):
            p_ij, p_ji = R_P + 9 * i + j, R_P + 9 * j + i
            for r in range(w):
                v = 0.5 * (_joseph_entry(a, r, i, j, rv, two) + _joseph_entry(a, r, j, i, rv, two))
                keep = a[_at(acc, r)] > 0.5
                a[_at(p_ij, r)] = v if keep else a[_at(p_ij, r)]
                a[_at(p_ji, r)] = v if keep else a[_at(p_ji, r)]


@njit(inline="always", **JIT_NOALLOC)
def _correct_one_block(a: np.ndarray, w: int, k: int, row0: int, z: int, angle: bool) -> None:
    """``ekf._correct_one_into`` of the columns that accept sample ``k`` (measurement row
    ``R_Z + z`` of state ``row0``, an angle wrapped to [-pi, pi) when ``angle``); the
    others keep their state and covariance."""
    acc = R_ACC + k
    for r in range(w):  # the innovation (the wrap's remainder call keeps this loop scalar)
        e0 = a[_at(R_Z + z, r)] - a[_at(R_X + row0, r)]
        if angle:
            e0 = ssa_scalar(e0)
        a[_at(R_E, r)] = e0
    for r in range(w):
        e0 = a[_at(R_E, r)]
        s00 = a[_at(R_P + 10 * row0, r)] + a[_at(R_RVAR + k, r)]
        i00 = 1.0 / s00
        keep = a[_at(acc, r)] > 0.5
        p_rr = a[_at(R_P + 10 * row0, r)]
        for i in range(9):
            ki = a[_at(R_P + 9 * i + row0, r)] * i00
            a[_at(R_K + i, r)] = ki
            xi = a[_at(R_X + i, r)]
            a[_at(R_X + i, r)] = xi + ki * e0 if keep else xi
            a[_at(R_PROW + i, r)] = a[_at(R_P + 9 * row0 + i, r)]
            a[_at(R_ACOL + i, r)] = a[_at(R_P + 9 * i + row0, r)] - ki * p_rr
        if k == A_COMPASS:
            a[_at(R_NIS, r)] = e0 * e0 / s00
    _joseph_into(a, w, k, False)


@njit(inline="always", **JIT_NOALLOC)
def _correct_two_block(a: np.ndarray, w: int, k: int, row0: int, row1: int, z: int) -> None:
    """``ekf.correct_into`` with two measured rows (``row0``, ``row1``; the measurements in
    rows ``R_Z + z``, ``R_Z + z + 1``; the same variance for both) of the columns that
    accept sample ``k``; the others keep their state and covariance."""
    acc = R_ACC + k
    for r in range(w):
        e0 = a[_at(R_Z + z, r)] - a[_at(R_X + row0, r)]
        e1 = a[_at(R_Z + z + 1, r)] - a[_at(R_X + row1, r)]
        rv = a[_at(R_RVAR + k, r)]
        s00 = a[_at(R_P + 10 * row0, r)] + rv
        s01 = a[_at(R_P + 9 * row0 + row1, r)]
        s10 = a[_at(R_P + 9 * row1 + row0, r)]
        s11 = a[_at(R_P + 10 * row1, r)] + rv
        det = s00 * s11 - s01 * s10
        i00, i01, i10, i11 = s11 / det, -s01 / det, -s10 / det, s00 / det
        keep = a[_at(acc, r)] > 0.5
        for i in range(9):
            p_i0 = a[_at(R_P + 9 * i + row0, r)]
            p_i1 = a[_at(R_P + 9 * i + row1, r)]
            k0i = p_i0 * i00 + p_i1 * i10
            k1i = p_i0 * i01 + p_i1 * i11
            a[_at(R_K + i, r)] = k0i
            a[_at(R_K + 9 + i, r)] = k1i
            xi = a[_at(R_X + i, r)]
            a[_at(R_X + i, r)] = xi + (k0i * e0 + k1i * e1) if keep else xi
            a[_at(R_PROW + i, r)] = a[_at(R_P + 9 * row0 + i, r)]
            a[_at(R_PROW + 9 + i, r)] = a[_at(R_P + 9 * row1 + i, r)]
        for i in range(9):
            k0i, k1i = a[_at(R_K + i, r)], a[_at(R_K + 9 + i, r)]
            a[_at(R_ACOL + i, r)] = a[_at(R_P + 9 * i + row0, r)] - (
                k0i * a[_at(R_PROW + row0, r)] + k1i * a[_at(R_PROW + 9 + row0, r)]
            )
            a[_at(R_ACOL + 9 + i, r)] = a[_at(R_P + 9 * i + row1, r)] - (
                k0i * a[_at(R_PROW + row1, r)] + k1i * a[_at(R_PROW + 9 + row1, r)]
            )
        if k == A_POSITION:
            a[_at(R_NIS + 1, r)] = e0 * e0 / s00
            a[_at(R_NIS + 2, r)] = e1 * e1 / s11
    _joseph_into(a, w, k, True)


@njit(**JIT_NOALLOC)
def correct_block_into(wb: EkfBlock, w: int) -> None:
    """The corrections of the block's first ``w`` columns (after ``predict_block_into``)
    with the samples ``load_samples`` gave them, in ``loop._observe_into``'s order: the
    compass (the heading, wrapped), the position fix (the tree's origin from the fix, the
    mounting vector and the heading just corrected: ``loop.tree_measurements_into``'s
    sums), the gyro (the yaw rate), the DVL (the tree's velocity at its origin). A sample
    no column accepts costs nothing; a column that does not accept one keeps its numbers
    bit for bit through it (a select, not a product with zero)."""
    a = wb.a
    if _any_accepted(a, w, A_COMPASS):
        _correct_one_block(a, w, A_COMPASS, 2, Z_PSI, True)
    if _any_accepted(a, w, A_POSITION):
        for r in range(w):  # libm's cosine and sine of the heading, a loop of their own
            a[_at(R_CS, r)] = np.cos(a[_at(R_X + 2, r)])
            a[_at(R_CS + 1, r)] = np.sin(a[_at(R_X + 2, r)])
        for r in range(w):
            c, s = a[_at(R_CS, r)], a[_at(R_CS + 1, r)]
            m0, m1 = a[_at(R_MOUNT, r)], a[_at(R_MOUNT + 1, r)]
            a[_at(R_Z + Z_NORTH, r)] = a[_at(R_Z + Z_NORTH, r)] - (c * m0 - s * m1)
            a[_at(R_Z + Z_EAST, r)] = a[_at(R_Z + Z_EAST, r)] - (s * m0 + c * m1)
        _correct_two_block(a, w, A_POSITION, 0, 1, Z_NORTH)
    if _any_accepted(a, w, A_GYRO):
        _correct_one_block(a, w, A_GYRO, 5, Z_RATE, False)
    if _any_accepted(a, w, A_DVL):
        _correct_two_block(a, w, A_DVL, 3, 4, Z_U)
