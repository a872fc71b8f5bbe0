"""The observers' prediction of a block of runs (``control.batch_ekf``) against the run-by-run
prediction (``control.ekf.predict_into``): every run's state and covariance bit for bit, over
several steps, at block widths that are and are not a multiple of the lanes, with the zeros,
signed zeros and asymmetries that decide the bits of the scalar code's products."""

from __future__ import annotations

import numpy as np
import pytest

from control import batch_ekf, ekf, loop
from control.config import ControlSettings
from control.simulation import Simulation
from sim import params


def _model(name: str):
    C = Simulation(params.load(name), tree_depth_m=100.0, settings=ControlSettings()).C
    return C.M, C.M_inv, C.D_l, C.D_nl, C.T_b, C.GQG


def _runs(rng: np.random.Generator, n: int, scale: float):
    x = rng.normal(size=(n, 9)) * np.array([10, 10, 3, 0.3, 0.3, 0.05, 1, 1, 10]) * scale
    x[0, 3:6] = 0.0  # at rest: |u| u's kink and 0 * M's entries
    x[-1, 3] = -0.0
    P = np.empty((n, 9, 9))
    for r in range(n):
        A = rng.normal(size=(9, 9))
        P[r] = A @ A.T
    P[n // 2, 0, 1] += 1e-9  # a covariance not exactly symmetric (the products read both)
    tau = rng.normal(size=(n, 3)) * scale
    tau[0] = 0.0  # the ROV off the tree
    k_h = rng.uniform(0.5, 2.0, n) * 1e3 * scale
    p_eq = rng.normal(size=(n, 2))
    return x, P, tau, k_h, p_eq


@pytest.mark.parametrize("name, scale", [("full-scale", 1e4), ("model-scale", 1.0)])
@pytest.mark.parametrize("n", [1, 5, 8, 13, batch_ekf.BLOCK])
def test_a_block_predicts_each_run_bit_for_bit_as_alone(name: str, scale: float, n: int) -> None:
    M, M_inv, D_l, D_nl, T_b, GQG = _model(name)
    rng = np.random.default_rng(n)
    x0, P0, tau, k_h, p_eq = _runs(rng, n, scale)
    dt = 0.01
    wb = batch_ekf.make_ekf_block()
    x_b, P_b = x0.copy(), P0.copy()
    for _ in range(3):
        for r in range(n):
            batch_ekf.load_run(wb, r, x_b[r], P_b[r], tau[r], k_h[r], p_eq[r])
        w = batch_ekf.pad_block(wb, n)
        assert w % batch_ekf.LANES == 0 and n <= w <= batch_ekf.BLOCK
        batch_ekf.predict_block_into(wb, w, dt, M, M_inv, D_l, D_nl, T_b, GQG)
        for r in range(n):
            batch_ekf.store_run(wb, r, x_b[r], P_b[r])
    work = np.empty(9), np.empty((9, 9)), np.empty((9, 9))
    for r in range(n):
        x, P = x0[r].copy(), P0[r].copy()
        for _ in range(3):
            ekf.predict_into(
                x, P, tau[r], dt, M_inv, M, D_l, D_nl, k_h[r], p_eq[r], T_b, GQG, *work
            )
        # the bits, signs of zeros included (array_equal would take -0.0 for 0.0)
        assert x.tobytes() == x_b[r].tobytes(), r
        assert P.tobytes() == P_b[r].tobytes(), r
        assert not np.array_equal(P, P0[r])  # it moved


def test_a_run_of_the_block_is_its_own() -> None:
    # the same run in every column but one: that column's numbers, and only its, differ
    M, M_inv, D_l, D_nl, T_b, GQG = _model("full-scale")
    rng = np.random.default_rng(7)
    x0, P0, tau, k_h, p_eq = _runs(rng, 1, 1e4)
    wb = batch_ekf.make_ekf_block()
    for c in range(16):
        spring = k_h[0] * (2.0 if c == 9 else 1.0)
        batch_ekf.load_run(wb, c, x0[0], P0[0], tau[0], spring, p_eq[0])
    batch_ekf.predict_block_into(wb, 16, 0.01, M, M_inv, D_l, D_nl, T_b, GQG)
    out = np.empty((16, 9)), np.empty((16, 9, 9))
    for c in range(16):
        batch_ekf.store_run(wb, c, out[0][c], out[1][c])
    differ = [c for c in range(16) if not np.array_equal(out[1][c], out[1][0])]
    assert differ == [9]


@pytest.mark.parametrize("n", [1, 7, batch_ekf.BLOCK])
def test_a_block_corrects_each_run_bit_for_bit_as_alone(n: int) -> None:
    # after the prediction, each column corrects with the samples it accepts, in
    # loop._observe_into's order (compass, position fix, gyro, DVL), each run with its own
    # mounting vector and variances; the state, covariance and logged innovations are the
    # scalar code's bits, and a column keeps its numbers through a sample it does not accept
    sim = Simulation(params.load("full-scale"), tree_depth_m=100.0, settings=ControlSettings())
    C = sim.C
    M, M_inv, D_l, D_nl, T_b, GQG = C.M, C.M_inv, C.D_l, C.D_nl, C.T_b, C.GQG
    rng = np.random.default_rng(100 + n)
    x0, P0, tau, k_h, p_eq = _runs(rng, n, 1e4)
    y = rng.normal(size=(n, 11)) * 0.5
    y[:, 0:2] = x0[:, 0:2] + rng.normal(size=(n, 2))
    y[:, 4] = x0[:, 2] + C.psi_rel + rng.normal(size=n) * 0.1
    y[0, 4] = x0[0, 2] + C.psi_rel + 6.0  # an innovation past pi: the compass's wrap
    acc = rng.random((n, 4)) < 0.6
    acc[0] = True
    if n > 1:
        acc[-1] = False  # a column that takes no sample at all
    runs_C = [
        C._replace(
            r_mount=C.r_mount + rng.normal(size=C.r_mount.shape),
            r_psi=float(rng.uniform(1e-4, 1e-2)),
            r_pos=float(rng.uniform(0.1, 2.0)),
            r_gyro=float(rng.uniform(1e-6, 1e-4)),
            r_dvl=float(rng.uniform(1e-3, 1e-1)),
        )
        for _ in range(n)
    ]
    dt = 0.01
    wb = batch_ekf.make_ekf_block()
    for r in range(n):
        Cr = runs_C[r]
        batch_ekf.load_run(wb, r, x0[r], P0[r], tau[r], k_h[r], p_eq[r])
        _, psi_m, uv, _ = loop.tree_measurements(y[r], 0.0, Cr)
        z = np.array([psi_m, y[r, 0], y[r, 1], y[r, 10], uv[0], uv[1]])
        r_var = np.array([Cr.r_psi, Cr.r_pos, Cr.r_gyro, Cr.r_dvl])
        batch_ekf.load_samples(wb, r, acc[r].astype(float), z, Cr.r_mount, r_var)
    w = batch_ekf.pad_block(wb, n)
    batch_ekf.predict_block_into(wb, w, dt, M, M_inv, D_l, D_nl, T_b, GQG)
    batch_ekf.correct_block_into(wb, w)
    k0, k1, A = np.empty(9), np.empty(9), np.empty((9, 9))
    work = np.empty(9), np.empty((9, 9)), np.empty((9, 9))
    for r in range(n):
        Cr = runs_C[r]
        x, P = x0[r].copy(), P0[r].copy()
        ekf.predict_into(x, P, tau[r], dt, M_inv, M, D_l, D_nl, k_h[r], p_eq[r], T_b, GQG, *work)
        x_pred, P_pred = x.copy(), P.copy()
        ne, psi_m, uv, rate = loop.tree_measurements(y[r], x[2], Cr)
        nis = [0.0, 0.0, 0.0]
        if acc[r, batch_ekf.A_COMPASS]:
            nis[0], _ = ekf.correct_into(x, P, 1, psi_m, 0.0, 2, -1, Cr.r_psi, 0.0, 0, k0, k1, A)
        if acc[r, batch_ekf.A_POSITION]:
            ne, psi_m, uv, rate = loop.tree_measurements(y[r], x[2], Cr)
            nis[1], nis[2] = ekf.correct_into(
                x, P, 2, ne[0], ne[1], 0, 1, Cr.r_pos, Cr.r_pos, -1, k0, k1, A
            )
        if acc[r, batch_ekf.A_GYRO]:
            ekf.correct_into(x, P, 1, rate, 0.0, 5, -1, Cr.r_gyro, 0.0, -1, k0, k1, A)
        if acc[r, batch_ekf.A_DVL]:
            ekf.correct_into(x, P, 2, uv[0], uv[1], 3, 4, Cr.r_dvl, Cr.r_dvl, -1, k0, k1, A)
        x_b, P_b = np.empty(9), np.empty((9, 9))
        batch_ekf.store_run(wb, r, x_b, P_b)
        assert x.tobytes() == x_b.tobytes(), r
        assert P.tobytes() == P_b.tobytes(), r
        if acc[r].any():
            assert not np.array_equal(P, P_pred)  # it corrected
        else:
            assert x.tobytes() == x_pred.tobytes() and P.tobytes() == P_pred.tobytes()
        for k, which in (
            (0, batch_ekf.A_COMPASS),
            (1, batch_ekf.A_POSITION),
            (2, batch_ekf.A_POSITION),
        ):
            assert batch_ekf.accepted_at(wb, r, which) == acc[r, which]
            if acc[r, which]:
                assert batch_ekf.nis_at(wb, r, k) == nis[k], (r, k)
