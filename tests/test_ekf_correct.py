"""The EKF's correction written for H = rows of the identity (control.ekf.correct) against the
dense textbook form of table 3.1, computed here with numpy: K = P H^T (H P H^T + R)^-1,
x + K (z - H x), Joseph form (I - K H) P (I - K H)^T + K R K^T, symmetrised.

The two differ only in summation order and in the inverse (closed form against LAPACK's LU),
so they agree to rounding: 1e-12 relative to the largest entry of P (a 9x9 covariance with a
condition number below 1e4, so rounding errors of the order 1e-16 x cond stay far below)."""

from __future__ import annotations

import numpy as np
import pytest

from control import ekf


def _dense(x, P, z, rows, r_var, angle_row):
    m = len(rows)
    H = np.zeros((m, 9))
    H[np.arange(m), rows] = 1.0
    innov = z - H @ x
    if angle_row >= 0:
        innov[angle_row] = (innov[angle_row] + np.pi) % (2 * np.pi) - np.pi
    S = H @ P @ H.T + np.diag(r_var)
    K = P @ H.T @ np.linalg.inv(S)
    IKH = np.eye(9) - K @ H
    P_new = IKH @ P @ IKH.T + K @ np.diag(r_var) @ K.T
    return x + K @ innov, 0.5 * (P_new + P_new.T), innov**2 / np.diag(S)


def _covariance(rng: np.random.Generator) -> np.ndarray:
    a = rng.normal(size=(9, 9))
    return a @ a.T + 0.5 * np.eye(9)


@pytest.mark.parametrize(
    "rows, angle_row",
    [([2], 0), ([5], -1), ([0, 1], -1), ([3, 4], -1), ([1, 0], -1), ([2, 6], 0)],
)
def test_correction_of_identity_rows_equals_the_dense_form(rows, angle_row):
    rng = np.random.default_rng(len(rows) * 10 + rows[0])
    for _ in range(20):
        P = _covariance(rng)
        x = rng.normal(size=9)
        z = x[rows] + rng.normal(scale=0.3, size=len(rows))
        if angle_row >= 0:
            z[angle_row] += 2 * np.pi  # the wrap must take it back
        r_var = rng.uniform(0.01, 1.0, size=len(rows))
        rows_a = np.array(rows)
        x0, P0 = x.copy(), P.copy()
        got = ekf.correct(x, P, z, rows_a, r_var, angle_row)
        want = _dense(x, P, z, rows_a, r_var, angle_row)
        scale = np.abs(P).max()
        assert np.allclose(got[0], want[0], rtol=0.0, atol=1e-12 * max(1.0, np.abs(x).max()))
        assert np.allclose(got[1], want[1], rtol=0.0, atol=1e-12 * scale)
        assert np.allclose(got[2], want[2], rtol=1e-12, atol=0.0)
        # symmetric to the bit, and the inputs are left alone
        assert np.array_equal(got[1], got[1].T)
        assert np.array_equal(x, x0) and np.array_equal(P, P0)


def test_correction_refuses_more_than_two_rows():
    P = np.eye(9)
    with pytest.raises(ValueError, match="at most 2 measured rows"):
        ekf.correct(np.zeros(9), P, np.zeros(3), np.array([0, 1, 2]), np.ones(3), -1)


def _two_row_form_with_a_zero_row(x, P, z0, row0, r0, angle):
    """The correction as the two-row code wrote it for one row before the one-row form had a
    function of its own (``tests/corpus/same_figures.json`` was recorded with it): the second
    gain column exactly zero and its terms still added, in the same order. Plain Python
    floats, so the arithmetic is IEEE double without contraction, as in the compiled code."""
    x, P = x.copy(), P.copy()
    e0 = z0 - x[row0]
    if angle:
        e0 = (e0 + np.pi) % (2 * np.pi) - np.pi
    s00 = P[row0, row0] + r0
    i00 = 1.0 / s00
    k0 = [float(P[i, row0] * i00) for i in range(9)]
    k1 = [0.0] * 9
    for i in range(9):
        x[i] = x[i] + (k0[i] * e0 + k1[i] * 0.0)
    A = np.empty((9, 9))
    for i in range(9):
        for j in range(9):
            A[i, j] = P[i, j] - (k0[i] * P[row0, j] + k1[i] * P[row0, j])
    for i in range(9):
        for j in range(9):
            P[i, j] = (
                A[i, j]
                - (A[i, row0] * k0[j] + A[i, row0] * k1[j])
                + (k0[i] * r0 * k0[j] + k1[i] * 0.0 * k1[j])
            )
    for i in range(9):
        for j in range(i):
            v = 0.5 * (P[i, j] + P[j, i])
            P[i, j] = v
            P[j, i] = v
    return x, P, e0 * e0 / s00


@pytest.mark.parametrize("row0, angle", [(5, False), (2, True), (0, False)])
def test_one_row_correction_gives_the_bits_of_the_two_row_form(row0, angle):
    """The one-row correction (the gyro every step, the compass) leaves out the zero second
    row: the same bits as with it, over many random covariances (the observer's figures must
    not move by one ulp)."""
    rng = np.random.default_rng(row0)
    for _ in range(200):
        P = _covariance(rng) * 10.0 ** rng.uniform(-6, 2)
        x = rng.normal(size=9)
        z0 = x[row0] + rng.normal(scale=0.3) + (2 * np.pi if angle else 0.0)
        r0 = 10.0 ** rng.uniform(-6, 0)
        want = _two_row_form_with_a_zero_row(x, P, z0, row0, r0, angle)
        rows, r_var = np.array([row0]), np.array([r0])
        got = ekf.correct(x, P, np.array([z0]), rows, r_var, 0 if angle else -1)
        assert np.array_equal(got[0], want[0])
        assert np.array_equal(got[1], want[1])
        assert got[2][0] == want[2]
