"""Nonlinear PID in the tree frame (thesis eq. 3.8-3.9) with the anti-windup of section 3.2.4,
optional reference feedforward, and the free-ROV station-keeping controller of the supervisor
(section 3.4). Compiled kernels on plain arrays; ``control.loop`` composes them.

Tree controller, with e = [north - north_d, east - east_d, ssa(psi - psi_d)] (NED):

    tau_n    = -K_p e - K_d de/dt + i_n,          i_n_dot = -K_i e          (eq. 3.9)
    tau_tree = R(psi)^T tau_n  (+ feedforward)                               (eq. 3.8)

where de/dt is the measured velocity eta_dot (the thesis's law, so the tree lags a moving
reference) or, with feedforward on, eta_dot - eta_dot_d, and the feedforward is the control
plant model driven by the reference: M nu_d_dot + C(nu_d) nu_d + D(nu_d) nu_d + the wire
spring at the reference position. The integral is kept in force units (i_n), so changing K_i
never bumps the command; a change of K_p or K_d is made bumpless by moving the jump into i_n.

Anti-windup (eq. 3.19): the integral part is moved to the ROV frame (eq. 3.7), saturated there
at 90 % of what the thrusters can give in each DOF alone, and the surplus is taken off the
integrator, moved back through the tree frame.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from control.ekf import coriolis3
from sim.gnc import JIT, ssa


@njit(inline="always", **JIT)
def rot2(psi: float) -> tuple[float, float]:
    """cos and sin of a heading."""
    return np.cos(psi), np.sin(psi)


@njit(inline="always", **JIT)
def ned_to_body(vec_n: np.ndarray, psi: float) -> np.ndarray:
    """[X_n, Y_n, N] -> [X_b, Y_b, N]: rotate the horizontal part by R(psi)^T."""
    c, s = rot2(psi)
    out = np.empty(3)
    out[0] = c * vec_n[0] + s * vec_n[1]
    out[1] = -s * vec_n[0] + c * vec_n[1]
    out[2] = vec_n[2]
    return out


@njit(inline="always", **JIT)
def body_to_ned(vec_b: np.ndarray, psi: float) -> np.ndarray:
    """[X_b, Y_b, N] -> [X_n, Y_n, N]: rotate the horizontal part by R(psi)."""
    c, s = rot2(psi)
    out = np.empty(3)
    out[0] = c * vec_b[0] - s * vec_b[1]
    out[1] = s * vec_b[0] + c * vec_b[1]
    out[2] = vec_b[2]
    return out


@njit(inline="always", **JIT)
def pose_error(eta: np.ndarray, eta_d: np.ndarray) -> np.ndarray:
    """e = eta - eta_d with the heading difference wrapped into [-pi, pi)."""
    e = eta - eta_d
    e[2] = ssa(e[2])
    return e


@njit(inline="always", **JIT)
def feedforward(
    psi: float,
    eta_d: np.ndarray,
    deta_d: np.ndarray,
    ddeta_d: np.ndarray,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
) -> np.ndarray:
    """Control plant model driven by the reference, tree axes [N, N, N m]."""
    nu_d = ned_to_body(deta_d, eta_d[2])
    r_d = deta_d[2]
    # d/dt (R^T v_d) = R^T a_d - r_d R^T S v_d  with S = [[0, -1], [1, 0]]
    sv = np.array([-deta_d[1], deta_d[0], 0.0])
    acc = ned_to_body(ddeta_d, eta_d[2]) - r_d * ned_to_body(sv, eta_d[2])
    acc[2] = ddeta_d[2]
    tau = M @ acc + coriolis3(M, nu_d)
    for i in range(3):
        tau[i] += (D_l[i] + D_nl[i] * abs(nu_d[i])) * nu_d[i]
    spring_n = np.array([k_h * (eta_d[0] - p_eq[0]), k_h * (eta_d[1] - p_eq[1]), 0.0])
    return tau + ned_to_body(spring_n, psi)


@njit(inline="always", **JIT)
def tree_pid(
    eta: np.ndarray,
    deta: np.ndarray,
    eta_d: np.ndarray,
    deta_d: np.ndarray,
    ddeta_d: np.ndarray,
    i_n: np.ndarray,
    Kp: np.ndarray,
    Ki: np.ndarray,
    Kd: np.ndarray,
    use_ff: bool,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    A: np.ndarray,
    A_inv: np.ndarray,
    i_limit_rov: np.ndarray,
    dt: float,
):
    """One step of the tree controller.

    eta, deta: estimated pose and its NED rate; eta_d, deta_d, ddeta_d: reference (NED);
    i_n: integral state (NED forces and yaw moment). A, A_inv: [X, Y, N] wrench maps tree ->
    ROV and back (eq. 3.7 restricted to surge, sway, yaw). Returns (tau_tree (3), i_n_next (3),
    terms (4, 3): P, I, D and feedforward parts in tree axes, e (3), de (3))."""
    psi = eta[2]
    e = pose_error(eta, eta_d)
    de = deta - deta_d if use_ff else deta.copy()
    p_n = -Kp * e
    d_n = -Kd * de
    # anti-windup (eq. 3.19): clamp the integral part in the ROV frame
    i_rov = A @ ned_to_body(i_n, psi)
    clipped = np.minimum(np.maximum(i_rov, -i_limit_rov), i_limit_rov)
    i_use = i_n.copy()
    if np.any(clipped != i_rov):
        i_use = body_to_ned(A_inv @ clipped, psi)
    terms = np.zeros((4, 3))
    terms[0] = ned_to_body(p_n, psi)
    terms[1] = ned_to_body(i_use, psi)
    terms[2] = ned_to_body(d_n, psi)
    if use_ff:
        terms[3] = feedforward(psi, eta_d, deta_d, ddeta_d, M, D_l, D_nl, k_h, p_eq)
    tau = terms[0] + terms[1] + terms[2] + terms[3]
    i_next = i_use - Ki * e * dt
    return tau, i_next, terms, e, de


@njit(**JIT)
def free_rov_pid(
    eta4: np.ndarray,
    deta4: np.ndarray,
    eta4_d: np.ndarray,
    i4: np.ndarray,
    Kp: np.ndarray,
    Ki: np.ndarray,
    Kd: np.ndarray,
    dt: float,
):
    """Station keeping of the ROV alone in [north, east, down, psi] (section 3.4): PID in NED,
    rotated into the ROV's axes. Returns (tau_rov (6,), i4_next, e4)."""
    e = eta4 - eta4_d
    e[3] = ssa(e[3])
    tau_n = -Kp * e - Kd * deta4 + i4
    c, s = rot2(eta4[3])
    tau = np.zeros(6)
    tau[0] = c * tau_n[0] + s * tau_n[1]
    tau[1] = -s * tau_n[0] + c * tau_n[1]
    tau[2] = tau_n[2]
    tau[5] = tau_n[3]
    return tau, i4 - Ki * e * dt, e


@njit(**JIT)
def bumpless_tree_integral(
    tau_rov3: np.ndarray,
    eta: np.ndarray,
    deta: np.ndarray,
    eta_d: np.ndarray,
    deta_d: np.ndarray,
    ddeta_d: np.ndarray,
    Kp: np.ndarray,
    Kd: np.ndarray,
    use_ff: bool,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    A_inv: np.ndarray,
) -> np.ndarray:
    """The integral state that makes the tree controller output ``tau_rov3`` (ROV frame,
    [X, Y, N]) right now: used when the supervisor hands over, so thrust does not jump."""
    psi = eta[2]
    e = pose_error(eta, eta_d)
    de = deta - deta_d if use_ff else deta.copy()
    tau_tree = A_inv @ tau_rov3
    if use_ff:
        tau_tree = tau_tree - feedforward(psi, eta_d, deta_d, ddeta_d, M, D_l, D_nl, k_h, p_eq)
    return body_to_ned(tau_tree, psi) + Kp * e + Kd * de


@njit(**JIT)
def bumpless_free_integral(
    tau_rov6: np.ndarray,
    eta4: np.ndarray,
    deta4: np.ndarray,
    eta4_d: np.ndarray,
    Kp: np.ndarray,
    Kd: np.ndarray,
) -> np.ndarray:
    """The free-ROV integral state that reproduces ``tau_rov6`` right now."""
    e = eta4 - eta4_d
    e[3] = ssa(e[3])
    c, s = rot2(eta4[3])
    tau_n = np.empty(4)
    tau_n[0] = c * tau_rov6[0] - s * tau_rov6[1]
    tau_n[1] = s * tau_rov6[0] + c * tau_rov6[1]
    tau_n[2] = tau_rov6[2]
    tau_n[3] = tau_rov6[5]
    return tau_n + Kp * e + Kd * deta4
