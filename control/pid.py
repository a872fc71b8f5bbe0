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
integrator, moved back through the tree frame. With the feedforward on, the integral may go
beyond that limit where the integral and the feedforward together stay within it: the
feedforward counters the wire spring's pull towards the crane tip, and where the vessel has
been moved upstream so that the current's drag (which no model term holds) balances that
pull, the integral must cancel the feedforward; clamped alone it could not, and the tree
rested downstream of the frame, short of its alignment tolerance. The integral is never
clamped tighter than eq. 3.19 clamps it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from sim.gnc import JIT, JIT_NOALLOC, mv3_into, ssa_scalar


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
    e[2] = ssa_scalar(e[2])
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
    """Control plant model driven by the reference, tree axes [N, N, N m] (a new array;
    ``feedforward_into`` writes it into one)."""
    tau = np.empty(3)
    feedforward_into(tau, psi, eta_d, deta_d, ddeta_d, M, D_l, D_nl, k_h, p_eq, np.empty(3))
    return tau


@njit(inline="always", **JIT_NOALLOC)
def feedforward_into(
    tau: np.ndarray,
    psi: float,
    eta_d: np.ndarray,
    deta_d: np.ndarray,
    ddeta_d: np.ndarray,
    M: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    k_h: float,
    p_eq: np.ndarray,
    acc: np.ndarray,
) -> None:
    """``feedforward`` into ``tau`` (3,), ``acc`` (3,) a work array.

    Written with scalars (the operations of ``ned_to_body``, ``coriolis3`` and the vector
    sums, in their order); ``M @ acc`` as ``sim.gnc.mv3_into``'s sums (it was OpenBLAS's
    ``gemv``: 30 ns a call, and its last bits depend on the kernel OpenBLAS picks for the
    CPU)."""
    cd, sd = rot2(eta_d[2])
    nu0 = cd * deta_d[0] + sd * deta_d[1]
    nu1 = -sd * deta_d[0] + cd * deta_d[1]
    nu2 = deta_d[2]
    r_d = deta_d[2]
    # d/dt (R^T v_d) = R^T a_d - r_d R^T S v_d  with S = [[0, -1], [1, 0]]
    sv0, sv1 = -deta_d[1], deta_d[0]
    acc[0] = (cd * ddeta_d[0] + sd * ddeta_d[1]) - r_d * (cd * sv0 + sd * sv1)
    acc[1] = (-sd * ddeta_d[0] + cd * ddeta_d[1]) - r_d * (-sd * sv0 + cd * sv1)
    acc[2] = ddeta_d[2]
    mv3_into(tau, M, acc)
    # + C(nu_d) nu_d as in coriolis3, then damping
    ax = M[0, 0] * nu0 + M[0, 1] * nu1 + M[0, 2] * nu2
    ay = M[1, 0] * nu0 + M[1, 1] * nu1 + M[1, 2] * nu2
    tau[0] = tau[0] + -ay * nu2
    tau[1] = tau[1] + ax * nu2
    tau[2] = tau[2] + (ay * nu0 - ax * nu1)
    tau[0] += (D_l[0] + D_nl[0] * abs(nu0)) * nu0
    tau[1] += (D_l[1] + D_nl[1] * abs(nu1)) * nu1
    tau[2] += (D_l[2] + D_nl[2] * abs(nu2)) * nu2
    # + the wire spring at the reference position, in the tree's axes
    c, s = rot2(psi)
    sp0 = k_h * (eta_d[0] - p_eq[0])
    sp1 = k_h * (eta_d[1] - p_eq[1])
    tau[0] = tau[0] + (c * sp0 + s * sp1)
    tau[1] = tau[1] + (-s * sp0 + c * sp1)
    tau[2] = tau[2] + 0.0


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
    terms (4, 3): P, I, D and feedforward parts in tree axes, e (3), de (3)). New arrays
    (``tree_pid_into`` writes into given ones)."""
    tau = np.empty(3)
    i_next = np.empty(3)
    terms = np.empty((4, 3))
    e = np.empty(3)
    de = np.empty(3)
    tree_pid_into(
        tau, i_next, terms, e, de, eta, deta, eta_d, deta_d, ddeta_d, i_n, Kp, Ki, Kd,
        use_ff, M, D_l, D_nl, k_h, p_eq, A, A_inv, i_limit_rov, dt, np.empty((5, 3)),
    )  # fmt: skip
    return tau, i_next, terms, e, de


@njit(inline="always", **JIT_NOALLOC)
def tree_pid_into(
    tau: np.ndarray,
    i_next: np.ndarray,
    terms: np.ndarray,
    e: np.ndarray,
    de: np.ndarray,
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
    work: np.ndarray,
) -> None:
    """``tree_pid`` into tau, i_next (3,), terms (4, 3), e, de (3,); ``work`` (5, 3) holds
    the anti-windup's and the feedforward's vectors. ``i_next`` may be ``i_n`` itself (the
    integral is read before it is written); the other outputs must not alias the inputs."""
    i_b = work[0]
    i_rov = work[1]
    clipped = work[2]
    i_use = work[3]
    psi = eta[2]
    c, s = rot2(psi)
    for k in range(3):
        e[k] = eta[k] - eta_d[k]
        de[k] = deta[k] - deta_d[k] if use_ff else deta[k]
    e[2] = ssa_scalar(e[2])
    if use_ff:
        feedforward_into(terms[3], psi, eta_d, deta_d, ddeta_d, M, D_l, D_nl, k_h, p_eq, work[4])
    else:
        for k in range(3):
            terms[3, k] = 0.0
    # anti-windup (eq. 3.19): clamp the integral part in the ROV frame, alone or, where that
    # leaves it more room, with the feedforward (the integral may cancel a feedforward that a
    # load the model lacks balances: a wire the vessel inclined against the current's drag)
    i_b[0] = c * i_n[0] + s * i_n[1]
    i_b[1] = -s * i_n[0] + c * i_n[1]
    i_b[2] = i_n[2]
    mv3_into(i_rov, A, i_b)
    ff_rov = work[4]
    if use_ff:
        mv3_into(ff_rov, A, terms[3])
    changed = False
    for k in range(3):
        lo, hi = -i_limit_rov[k], i_limit_rov[k]
        if use_ff:
            lo, hi = min(lo, lo - ff_rov[k]), max(hi, hi - ff_rov[k])
        clipped[k] = np.minimum(np.maximum(i_rov[k], lo), hi)
        changed = changed or clipped[k] != i_rov[k]
    if changed:
        # body_to_ned(A_inv @ clipped, psi)
        mv3_into(i_b, A_inv, clipped)
        i_use[0] = c * i_b[0] - s * i_b[1]
        i_use[1] = s * i_b[0] + c * i_b[1]
        i_use[2] = i_b[2]
    else:
        for k in range(3):
            i_use[k] = i_n[k]
    # P, I and D parts moved to the tree's axes (ned_to_body), with p_n = -K_p e, d_n = -K_d de
    p0, p1, p2 = -Kp[0] * e[0], -Kp[1] * e[1], -Kp[2] * e[2]
    d0, d1, d2 = -Kd[0] * de[0], -Kd[1] * de[1], -Kd[2] * de[2]
    terms[0, 0] = c * p0 + s * p1
    terms[0, 1] = -s * p0 + c * p1
    terms[0, 2] = p2
    terms[1, 0] = c * i_use[0] + s * i_use[1]
    terms[1, 1] = -s * i_use[0] + c * i_use[1]
    terms[1, 2] = i_use[2]
    terms[2, 0] = c * d0 + s * d1
    terms[2, 1] = -s * d0 + c * d1
    terms[2, 2] = d2
    for k in range(3):
        tau[k] = terms[0, k] + terms[1, k] + terms[2, k] + terms[3, k]
        i_next[k] = i_use[k] - Ki[k] * e[k] * dt


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
    tau = np.empty(6)
    i_next = np.empty(4)
    e = np.empty(4)
    free_rov_pid_into(tau, i_next, e, eta4, deta4, eta4_d, i4, Kp, Ki, Kd, dt)
    return tau, i_next, e


@njit(inline="always", **JIT_NOALLOC)
def free_rov_pid_into(
    tau: np.ndarray,
    i_next: np.ndarray,
    e: np.ndarray,
    eta4: np.ndarray,
    deta4: np.ndarray,
    eta4_d: np.ndarray,
    i4: np.ndarray,
    Kp: np.ndarray,
    Ki: np.ndarray,
    Kd: np.ndarray,
    dt: float,
) -> None:
    """``free_rov_pid`` into tau (6,), i_next (4,) and e (4,), element by element (the
    operations of the vector form, in its order); the outputs must not alias the inputs."""
    for k in range(4):
        e[k] = eta4[k] - eta4_d[k]
    e[3] = ssa_scalar(e[3])
    # tau_n = -Kp * e - Kd * deta4 + i4
    t0 = -Kp[0] * e[0] - Kd[0] * deta4[0] + i4[0]
    t1 = -Kp[1] * e[1] - Kd[1] * deta4[1] + i4[1]
    t2 = -Kp[2] * e[2] - Kd[2] * deta4[2] + i4[2]
    t3 = -Kp[3] * e[3] - Kd[3] * deta4[3] + i4[3]
    c, s = rot2(eta4[3])
    tau[0] = c * t0 + s * t1
    tau[1] = -s * t0 + c * t1
    tau[2] = t2
    tau[3] = 0.0
    tau[4] = 0.0
    tau[5] = t3
    for k in range(4):
        i_next[k] = i4[k] - Ki[k] * e[k] * dt


def retuned_tree_integral(
    i_n: np.ndarray,
    e: np.ndarray,
    de: np.ndarray,
    kp_old: np.ndarray,
    kd_old: np.ndarray,
    kp_new: np.ndarray,
    kd_new: np.ndarray,
) -> np.ndarray:
    """The tree controller's integral (NED forces and yaw moment, (3,)) after its K_p and
    K_d change from the old to the new, bumpless: the jump of the P and D terms at this
    instant, for the last error ``e`` and its rate ``de``, is moved into the integral, so the
    commanded wrench does not change."""
    old_pd = -kp_old * e - kd_old * de
    new_pd = -kp_new * e - kd_new * de
    return i_n + (old_pd - new_pd)


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
    out = np.empty(3)
    bumpless_tree_integral_into(
        out, tau_rov3, eta, deta, eta_d, deta_d, ddeta_d, Kp, Kd, use_ff, M, D_l, D_nl, k_h,
        p_eq, A_inv, np.empty((3, 3)),
    )  # fmt: skip
    return out


@njit(inline="always", **JIT_NOALLOC)
def bumpless_tree_integral_into(
    out: np.ndarray,
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
    work: np.ndarray,
) -> None:
    """``bumpless_tree_integral`` into ``out`` (3,), ``work`` (3, 3); the vector form's
    operations element by element, ``A_inv @`` as ``sim.gnc.mv3_into``'s sums."""
    psi = eta[2]
    tau_tree = work[0]
    mv3_into(tau_tree, A_inv, tau_rov3)
    if use_ff:
        ff = work[1]
        feedforward_into(ff, psi, eta_d, deta_d, ddeta_d, M, D_l, D_nl, k_h, p_eq, work[2])
        for k in range(3):
            tau_tree[k] = tau_tree[k] - ff[k]
    c, s = rot2(psi)
    b0 = c * tau_tree[0] - s * tau_tree[1]
    b1 = s * tau_tree[0] + c * tau_tree[1]
    b2 = tau_tree[2]
    e0 = eta[0] - eta_d[0]
    e1 = eta[1] - eta_d[1]
    e2 = ssa_scalar(eta[2] - eta_d[2])
    de0 = deta[0] - deta_d[0] if use_ff else deta[0]
    de1 = deta[1] - deta_d[1] if use_ff else deta[1]
    de2 = deta[2] - deta_d[2] if use_ff else deta[2]
    out[0] = b0 + Kp[0] * e0 + Kd[0] * de0
    out[1] = b1 + Kp[1] * e1 + Kd[1] * de1
    out[2] = b2 + Kp[2] * e2 + Kd[2] * de2


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
    out = np.empty(4)
    bumpless_free_integral_into(out, tau_rov6, eta4, deta4, eta4_d, Kp, Kd)
    return out


@njit(inline="always", **JIT_NOALLOC)
def bumpless_free_integral_into(
    out: np.ndarray,
    tau_rov6: np.ndarray,
    eta4: np.ndarray,
    deta4: np.ndarray,
    eta4_d: np.ndarray,
    Kp: np.ndarray,
    Kd: np.ndarray,
) -> None:
    """``bumpless_free_integral`` into ``out`` (4,), element by element; ``out`` must not
    alias the inputs."""
    c, s = rot2(eta4[3])
    t0 = c * tau_rov6[0] - s * tau_rov6[1]
    t1 = s * tau_rov6[0] + c * tau_rov6[1]
    t2 = tau_rov6[2]
    t3 = tau_rov6[5]
    e3 = ssa_scalar(eta4[3] - eta4_d[3])
    out[0] = t0 + Kp[0] * (eta4[0] - eta4_d[0]) + Kd[0] * deta4[0]
    out[1] = t1 + Kp[1] * (eta4[1] - eta4_d[1]) + Kd[1] * deta4[1]
    out[2] = t2 + Kp[2] * (eta4[2] - eta4_d[2]) + Kd[2] * deta4[2]
    out[3] = t3 + Kp[3] * e3 + Kd[3] * deta4[3]
