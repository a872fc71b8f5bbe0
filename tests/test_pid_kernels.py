"""The tree controller's kernels written with scalars (control.pid.tree_pid, feedforward) do
the arithmetic of their vector form, to the bit. The vector form is written out here as it
stood before (numpy expressions, ``ned_to_body``, ``coriolis3``, ``A @`` summed as
``sim.gnc.mv3_into`` sums it), compiled the same
way, and both are run on random states, with and without feedforward, with the integral
inside and beyond its anti-windup limit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numba import njit

from control import ekf, pid
from sim.gnc import JIT, ssa


@njit(**JIT)
def _mv3(A, v):  # type: ignore[no-untyped-def]
    """A 3x3 matrix times a vector as the kernels sum it (``sim.gnc.mv3_into``, row by row,
    left to right), not OpenBLAS's ``gemv``."""
    out = np.empty(3)
    for i in range(3):
        s = 0.0
        for j in range(3):
            s += A[i, j] * v[j]
        out[i] = s
    return out


@njit(**JIT)
def _ff_vector(psi, eta_d, deta_d, ddeta_d, M, D_l, D_nl, k_h, p_eq):
    nu_d = pid.ned_to_body(deta_d, eta_d[2])
    r_d = deta_d[2]
    sv = np.array([-deta_d[1], deta_d[0], 0.0])
    acc = pid.ned_to_body(ddeta_d, eta_d[2]) - r_d * pid.ned_to_body(sv, eta_d[2])
    acc[2] = ddeta_d[2]
    tau = _mv3(M, acc) + ekf.coriolis3(M, nu_d)
    for i in range(3):
        tau[i] += (D_l[i] + D_nl[i] * abs(nu_d[i])) * nu_d[i]
    spring_n = np.array([k_h * (eta_d[0] - p_eq[0]), k_h * (eta_d[1] - p_eq[1]), 0.0])
    return tau + pid.ned_to_body(spring_n, psi)


@njit(**JIT)
def _pid_vector(
    eta, deta, eta_d, deta_d, ddeta_d, i_n, Kp, Ki, Kd, use_ff, M, D_l, D_nl, k_h, p_eq, A,
    A_inv, i_limit_rov, dt,
):  # fmt: skip
    psi = eta[2]
    e = eta - eta_d
    e[2] = ssa(e[2])
    de = deta - deta_d if use_ff else deta.copy()
    p_n = -Kp * e
    d_n = -Kd * de
    terms = np.zeros((4, 3))
    if use_ff:
        terms[3] = _ff_vector(psi, eta_d, deta_d, ddeta_d, M, D_l, D_nl, k_h, p_eq)
    i_rov = _mv3(A, pid.ned_to_body(i_n, psi))
    lo, hi = -i_limit_rov, i_limit_rov
    if use_ff:  # alone or with the feedforward within the limit, whichever leaves more room
        ff_rov = _mv3(A, terms[3])
        lo, hi = np.minimum(lo, lo - ff_rov), np.maximum(hi, hi - ff_rov)
    clipped = np.minimum(np.maximum(i_rov, lo), hi)
    i_use = i_n.copy()
    if np.any(clipped != i_rov):
        i_use = pid.body_to_ned(_mv3(A_inv, clipped), psi)
    terms[0] = pid.ned_to_body(p_n, psi)
    terms[1] = pid.ned_to_body(i_use, psi)
    terms[2] = pid.ned_to_body(d_n, psi)
    tau = terms[0] + terms[1] + terms[2] + terms[3]
    i_next = i_use - Ki * e * dt
    return tau, i_next, terms, e, de


@pytest.mark.parametrize("use_ff", [True, False])
def test_tree_pid_is_its_vector_form_to_the_bit(use_ff: bool) -> None:
    rng = np.random.default_rng(5)
    clipped_cases = 0
    for _ in range(300):
        M = np.diag(rng.uniform(1e3, 1e5, 3)) + rng.normal(0.0, 50.0, (3, 3))
        M = 0.5 * (M + M.T)
        A = np.eye(3) + rng.normal(0.0, 0.3, (3, 3))
        args = (
            rng.normal(0.0, 2.0, 3),  # eta
            rng.normal(0.0, 0.2, 3),  # deta
            rng.normal(0.0, 2.0, 3),  # eta_d
            rng.normal(0.0, 0.2, 3),  # deta_d
            rng.normal(0.0, 0.05, 3),  # ddeta_d
            rng.normal(0.0, 3e3, 3),  # i_n
            rng.uniform(1e2, 1e4, 3),  # Kp
            rng.uniform(1.0, 1e2, 3),  # Ki
            rng.uniform(1e2, 1e4, 3),  # Kd
            use_ff,
            M,
            rng.uniform(10.0, 1e3, 3),  # D_l
            rng.uniform(10.0, 1e3, 3),  # D_nl
            float(rng.uniform(10.0, 1e3)),  # k_h
            rng.normal(0.0, 1.0, 2),  # p_eq
            A,
            np.linalg.inv(A),
            rng.uniform(1e3, 5e3, 3),  # i_limit_rov
            0.01,
        )
        got = pid.tree_pid(*args)
        want = _pid_vector(*args)
        for a, b in zip(got, want, strict=True):
            assert np.array_equal(a, b)
        i_rov = A @ pid.ned_to_body(args[5], args[0][2])
        clipped_cases += int(np.any(np.abs(i_rov) > args[17]))
    assert clipped_cases > 10  # the anti-windup branch was taken


def test_the_integral_may_cancel_an_opposing_feedforward_beyond_its_own_limit() -> None:
    """Defect (issue 44's one failed landing of 200): with the vessel moved upstream, the
    feedforward's wire spring asks some 4.3 kN that the current's drag balances, and the
    integral must cancel it; clamped alone at the anti-windup's limit, it could not, and the
    tree rested 0.6 m off the frame. Heading 0, A = I: body, ROV and NED axes coincide."""
    zero = np.zeros(3)
    lim = np.array([3000.0, 3000.0, 3000.0])
    k_h = 1000.0
    p_eq = np.array([0.0, 4.3])  # the crane tip's equilibrium 4.3 m east of the reference

    def integral_term(i_sway: float) -> tuple[float, float]:
        _, _, terms, _, _ = pid.tree_pid(
            zero, zero, zero, zero, zero, np.array([0.0, i_sway, 0.0]), np.ones(3),
            np.ones(3), np.ones(3), True, np.eye(3), np.ones(3), np.ones(3), k_h, p_eq,
            np.eye(3), np.eye(3), lim, 0.01,
        )  # fmt: skip
        return float(terms[1, 1]), float(terms[3, 1])

    used, ff = integral_term(4000.0)
    assert ff == pytest.approx(-4300.0)  # k_h x 4.3 m, against the wire's pull east
    assert used == 4000.0  # beyond 3 kN alone, but with the feedforward -300 N: not clipped
    used, ff = integral_term(8000.0)
    assert used == pytest.approx(lim[1] - ff)  # the pair clipped at +3 kN: 7.3 kN
    used, _ = integral_term(-5000.0)
    assert used == -lim[1]  # the same way as the feedforward: clipped as eq. 3.19 clips it
    used, _ = integral_term(-2000.0)
    assert used == -2000.0  # within the limit alone: never clipped tighter than eq. 3.19


@given(
    st.lists(st.floats(-50.0, 50.0), min_size=12, max_size=12),
    st.lists(st.floats(0.0, 1e5), min_size=12, max_size=12),
)
def test_a_retune_keeps_p_plus_i_plus_d(values, gains):
    """``pid.retuned_tree_integral``: the integral takes the P and D terms' jump, so P + I + D
    is the same before and after new gains (to the rounding of sums of terms up to 5e6)."""
    i_n, e, de = (np.array(values[k : k + 3]) for k in (0, 3, 6))
    kp_old, kd_old, kp_new, kd_new = (np.array(gains[k : k + 3]) for k in (0, 3, 6, 9))
    i_new = pid.retuned_tree_integral(i_n, e, de, kp_old, kd_old, kp_new, kd_new)
    before = -kp_old * e - kd_old * de + i_n
    after = -kp_new * e - kd_new * de + i_new
    np.testing.assert_allclose(after, before, rtol=0, atol=1e-8 * (1.0 + np.abs(before).max()))
