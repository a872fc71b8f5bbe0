"""The EKF's prediction (control.ekf.predict): its Jacobian, written by hand, against central
differences of the model's own right-hand side, and its covariance step against the dense
textbook form phi P phi^T + GQG computed here with numpy.

Tolerances: a central difference with step h has truncation error h^2/6 |f'''|; with h = 1e-4
times each state's scale and the model's smooth terms that is about 1e-9 of the entries, and
rounding adds eps |f| / h, about 1e-11. The Jacobian must agree to 1e-7 relative to the
largest entry of its block (a sign or a missing term is off by order 1). The covariance step
differs from numpy's only in summation order: 1e-12 relative to the largest entry of P."""

from __future__ import annotations

import numpy as np
import pytest

from control import ekf
from control.config import ControlSettings
from control.simulation import Simulation
from sim import params


def _model(name: str):
    """A control plant model as the loop builds it (masses, damping, the wire's spring)."""
    sim = Simulation(params.load(name), tree_depth_m=100.0, settings=ControlSettings())
    C = sim.C
    return C.M_inv, C.M, C.D_l, C.D_nl, float(C.k_h), np.asarray(C.p_eq), C.T_b, C.GQG


def _state(rng: np.random.Generator) -> np.ndarray:
    # velocities away from 0, where |u| u has its kink (the hand-written slope is 2|u| there)
    x = rng.normal(0.0, 1.0, 9)
    x[3:6] = rng.uniform(0.05, 0.4, 3) * rng.choice([-1.0, 1.0], 3)
    x[6:9] = rng.normal(0.0, 200.0, 3)
    return x


def _f(x, tau, model):
    M_inv, M, D_l, D_nl, k_h, p_eq, T_b, _ = model
    return ekf.model_rhs(x, tau, M_inv, M, D_l, D_nl, k_h, p_eq, T_b)


@pytest.mark.parametrize("name", ["model-scale", "full-scale"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_jacobian_matches_central_differences(name: str, seed: int) -> None:
    model = _model(name)
    M_inv, M, D_l, D_nl, k_h, p_eq, T_b, _ = model
    rng = np.random.default_rng(seed)
    x = _state(rng)
    tau = rng.normal(0.0, 1e3 if name == "full-scale" else 5.0, 3)
    dt = 0.01
    phi = np.empty((9, 9))
    ekf.jacobian_phi_into(
        phi, x, np.cos(x[2]), np.sin(x[2]), dt, M_inv, M, D_l, D_nl, k_h, p_eq, T_b
    )
    J = (phi - np.eye(9)) / dt
    J_fd = np.empty((9, 9))
    for j in range(9):
        h = 1e-4 * max(1.0, abs(x[j]))
        up, down = x.copy(), x.copy()
        up[j] += h
        down[j] -= h
        J_fd[:, j] = (_f(up, tau, model) - _f(down, tau, model)) / (2.0 * h)
    for rows in (slice(0, 3), slice(3, 6), slice(6, 9)):
        scale = np.abs(J_fd[rows]).max()
        np.testing.assert_allclose(J[rows], J_fd[rows], rtol=0.0, atol=1e-7 * scale)
    # the zeros phi_times_into leaves out are zeros of the model
    outside = np.ones((9, 9), dtype=bool)
    outside[0, [0, 2, 3, 4]] = outside[1, [1, 2, 3, 4]] = outside[2, [2, 5]] = False
    outside[3:6, :] = False
    outside[[6, 7, 8], [6, 7, 8]] = False
    assert np.all(phi[outside] == 0.0)
    assert np.all(J_fd[outside] == 0.0)


@pytest.mark.parametrize("seed", [0, 1])
def test_prediction_equals_the_dense_form(seed: int) -> None:
    model = _model("full-scale")
    M_inv, M, D_l, D_nl, k_h, p_eq, T_b, GQG = model
    rng = np.random.default_rng(seed)
    x = _state(rng)
    a = rng.normal(size=(9, 9))
    P = a @ a.T + 0.5 * np.eye(9)
    tau = rng.normal(0.0, 1e3, 3)
    dt = 0.01
    x_new, P_new = ekf.predict(x, P, tau, dt, M_inv, M, D_l, D_nl, k_h, p_eq, T_b, GQG)
    phi = np.empty((9, 9))
    ekf.jacobian_phi_into(
        phi, x, np.cos(x[2]), np.sin(x[2]), dt, M_inv, M, D_l, D_nl, k_h, p_eq, T_b
    )
    dense = phi @ P @ phi.T + GQG
    dense = 0.5 * (dense + dense.T)
    np.testing.assert_allclose(P_new, dense, rtol=0.0, atol=1e-12 * np.abs(dense).max())
    assert np.array_equal(P_new, P_new.T)
    # the state's step is x + dt f(x), the same operations as here; the compiled cosine and
    # sine of the heading may differ from numpy's in the last bit (1e-15 relative)
    np.testing.assert_allclose(x_new, x + dt * _f(x, tau, model), rtol=1e-15, atol=0.0)
