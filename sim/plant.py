"""Process plant model: the tree on its wire, the ROV, and the gripper spring between them.

Pure compiled numerics. The state is one vector of 24 numbers:

    x = [eta_tree_n (6), nu_tree_b (6), eta_rov_n (6), nu_rov_b (6)]

and everything the outside world imposes during one step (current, crane tip, wire stiffness,
an external push) is one "environment" vector ``env`` (see the ``E_*`` indices), held constant
over the step. ``rhs(x, n_rps, env, P)`` is the time derivative (eq. 2.44 for the tree, 2.14 for
the ROV, 2.45-2.47 for the coupling); ``rk4_step`` advances one step; ``advance`` runs many
steps in compiled code and records them.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from sim.gnc import (
    JIT,
    JIT_NOALLOC,
    Rzyx,
    Rzyx_into,
    Tzyx,
    Tzyx_into,
    coriolis_force_into,
    cross_into,
    gvect_into,
    mm_into,
    mtm_into,
    mtv3_into,
    mv,
    mv3_into,
    mv6_into,
    mv_into,
    rotation_to_vector_into,
)
from sim.params import ParameterSet
from sim.thrusters import thrust_from_speed as thrust_from_speed  # re-exported (tests)
from sim.thrusters import thrust_from_speed_into
from sim.trig import sincos

# State layout.
ETA_T = slice(0, 6)
NU_T = slice(6, 12)
ETA_R = slice(12, 18)
NU_R = slice(18, 24)
N_STATE = 24

# Environment vector layout.
E_VC = 0  # 0:3 water velocity (current + waves) at the work site, NED [m/s]
E_AC = 3  # 3:6 water acceleration, NED [m/s^2] (zero with the ``drag`` wave load)
E_CT = 6  # 6:9 crane tip (where the wire leaves the vessel), NED [m]
E_LREST = 9  # depth below the crane tip of the unloaded wire's end [m]
E_KH = 10  # horizontal wire stiffness at the load [N/m] (eq. 2.30, corrected)
E_KZ = 11  # vertical wire stiffness [N/m] (eq. 2.25)
E_OFF = 12  # 12:14 drag offset of the wire's equilibrium point, NED north/east [m] (eq. 2.29)
E_PUSH = 14  # 14:17 external force on the tree's centre, NED [N]
E_GRIP = 17  # 1 while the ROV grips the tree (coupling spring engaged), 0 when released
E_FRAME = 18  # 18:20 docking frame centre, NED north/east [m]
E_FRAME_PSI = 20  # docking frame heading [rad]
E_LAND = 21  # depth of the frame's landing surface and the seabed around it [m]; 0: no bottom
E_WMASS = 22  # wire mass lumped at the tree, m_wire L / 3 [kg]; 0: the quasi-static wire
E_WDAMP = 23  # axial damping of the wire, a dashpot beside its spring [N s/m]; 0: none
E_VPIV = 24  # 24:27 velocity of the wire's top (crane tip plus pay-out), NED [m/s]
E_FWIRE = 27  # 27:30 wire force on the tree's attachment point from outside (MoorDyn), NED [N]
E_WEXT = 30  # 1: the wire force is E_FWIRE (the plant's own wire is off), 0: the plant's own
N_ENV = 31


class PlantArrays(NamedTuple):
    """Everything the compiled plant needs, as plain arrays and floats."""

    tree_M_rb: np.ndarray
    tree_M_a: np.ndarray
    tree_M_inv: np.ndarray
    tree_D_l: np.ndarray
    tree_D_nl: np.ndarray
    tree_W0: float
    tree_r_att: np.ndarray  # wire attachment point, tree body axes [m]
    rov_M_rb: np.ndarray
    rov_M_a: np.ndarray
    rov_M_inv: np.ndarray
    rov_D_l: np.ndarray
    rov_D_nl: np.ndarray
    rov_W: float
    rov_B: float
    rov_r_cg: np.ndarray
    rov_r_cb: np.ndarray
    thr_T: np.ndarray
    thr_k_pos: np.ndarray
    thr_k_neg: np.ndarray
    thr_n_max: np.ndarray
    mount_r: np.ndarray  # tree origin -> ROV origin, tree axes [m]
    mount_R: np.ndarray  # rotation ROV axes -> tree axes
    coupling_K: np.ndarray
    coupling_C: np.ndarray
    has_rov: bool
    dock_xy: np.ndarray  # (k, 2) funnels in tree axes = posts in frame axes [m]
    dock_post_height: float  # post top above the landing surface [m]
    dock_post_radius: float  # [m]
    dock_mouth_radius: float  # funnel mouth, at the tree's bottom [m]
    dock_bore_radius: float  # funnel bore above the cone [m]
    dock_cone_height: float  # cone from the mouth up to the bore [m]
    tree_half_height: float  # [m]
    tree_footprint: np.ndarray  # (2,) length and width of the tree's bottom [m]
    contact_k: float  # support stiffness under the whole tree [N/m]
    contact_c: float  # support damping under the whole tree [N s/m]
    post_k: float  # stiffness of one post against the tree (funnel wall, bottom, side) [N/m]
    post_c: float  # damping of one post contact [N s/m]
    friction_mu: float  # friction coefficient on the landing surface / post tops [-]
    tree_fk_mass: float  # displaced water rho V of the tree, m - W0 / g, >= 0 [kg]
    rov_fk_mass: float  # displaced water rho V of the ROV, B / g [kg]


def plant_arrays(
    ps: ParameterSet, has_rov: bool = True, r_mount_tree_m: np.ndarray | None = None
) -> PlantArrays:
    """Pack a parameter set for the compiled plant. ``r_mount_tree_m`` overrides where the ROV
    really sits on the tree (used to study a wrongly configured controller)."""
    t, r = ps.tree, ps.rov
    m_t = t.M_rb + t.M_a
    m_r = r.M_rb + r.M_a
    r_mount = ps.mount.r_rov_from_tree_tree_m if r_mount_tree_m is None else r_mount_tree_m
    return PlantArrays(
        tree_M_rb=t.M_rb.copy(),
        tree_M_a=t.M_a.copy(),
        tree_M_inv=np.linalg.inv(m_t),
        tree_D_l=t.D_l.copy(),
        tree_D_nl=t.D_nl.copy(),
        tree_W0=float(t.submerged_weight_newton),
        tree_r_att=np.array([0.0, 0.0, -t.attachment_height_m]),
        rov_M_rb=r.M_rb.copy(),
        rov_M_a=r.M_a.copy(),
        rov_M_inv=np.linalg.inv(m_r),
        rov_D_l=r.D_l.copy(),
        rov_D_nl=r.D_nl.copy(),
        rov_W=float(r.weight_newton),
        rov_B=float(r.buoyancy_newton),
        rov_r_cg=r.r_cg_m.copy(),
        rov_r_cb=r.r_cb_m.copy(),
        thr_T=np.ascontiguousarray(r.thrusters.T),
        thr_k_pos=r.thrusters.k_pos.copy(),
        thr_k_neg=r.thrusters.k_neg.copy(),
        thr_n_max=r.thrusters.n_max_rps.copy(),
        mount_r=np.asarray(r_mount, dtype=float).copy(),
        mount_R=Rzyx(0.0, 0.0, ps.mount.psi_rov_from_tree_rad),
        coupling_K=ps.coupling.stiffness.copy(),
        coupling_C=ps.coupling.damping.copy(),
        has_rov=bool(has_rov),
        **_contact_params(ps),
        tree_fk_mass=displaced_mass_kg(ps),
        rov_fk_mass=float(r.buoyancy_newton) / GRAVITY_MPS2,
    )


GRAVITY_MPS2 = 9.81
"""[m/s^2] (MODEL_NOTES, conventions)."""


def displaced_mass_kg(ps: ParameterSet) -> float:
    """Mass of the water the tree displaces, rho V = m - W0 / g [kg], never below 0.

    Follows the submerged weight W0 of the parameter set, so both readings of the thesis
    (solid steel, W0 = 307 kN: 4.7 t; the added-mass volume 15.7 m^3, W0 = 195 kN: 16.1 t)
    give their own Froude-Krylov force. A W0 above m g (a robustness study's +50 %) is a
    tree heavier than its mass in air, which has no volume: 0."""
    return max(ps.tree.mass_kg - ps.tree.submerged_weight_newton / GRAVITY_MPS2, 0.0)


def _contact_params(ps: ParameterSet) -> dict:
    """Contact with the docking frame and the seabed, as penalty springs with damping.

    The support under the whole tree is stiff enough that the tree sinks 2 % of its height
    into it under its own weight, damped at zeta 0.7 on the tree's heave mass (about 9 rad/s
    full scale, 15 rad/s model scale: resolved by RK4 at 100 Hz); it acts at the four corners
    of the tree's bottom, a quarter each. Each post pushes on the tree (its funnel's wall, the
    bottom plate, the side) with the support's stiffness and damping shared among the posts,
    so a tree standing on the post tops sinks as far as one on the landing surface."""
    layout = ps.spec.docking.to_numeric()
    m_heave = ps.tree.M_rb[2, 2] + ps.tree.M_a[2, 2]
    height = float(ps.tree.dimensions_m[2])
    k = ps.tree.submerged_weight_newton / (0.02 * height)
    omega = (k / m_heave) ** 0.5
    c = 2.0 * 0.7 * omega * m_heave
    n_posts = layout.post_xy_m.shape[0]
    return dict(
        dock_xy=np.ascontiguousarray(layout.post_xy_m, dtype=float),
        dock_post_height=float(layout.post_height_m),
        dock_post_radius=float(layout.post_radius_m),
        dock_mouth_radius=float(layout.funnel_mouth_radius_m),
        dock_bore_radius=float(layout.funnel_bore_radius_m),
        dock_cone_height=float(layout.funnel_cone_height_m),
        tree_half_height=height / 2.0,
        tree_footprint=np.array(ps.tree.dimensions_m[0:2], dtype=float),
        contact_k=float(k),
        contact_c=float(c),
        post_k=float(k / n_posts),
        post_c=float(c / n_posts),
        friction_mu=0.3,
    )


# --- work space of the allocation-free step ---
# ``PlantWork.vec`` rows (each at least N_STATE wide; a function uses the leading elements)
V_XS, V_K1, V_K2, V_K3, V_K4 = 0, 1, 2, 3, 4  # RK4 stage state and slopes
V_F = 5  # thrust of each thruster [N], held over the step
V_THR = 6  # thr_T @ f, the thrusters' wrench on the ROV, held over the step
V_TAU_T, V_TAU_R = 7, 8  # wrenches on the tree and on the ROV
V_NU_REL, V_VCB, V_VCDB, V_CRB, V_CA = 9, 10, 11, 12, 13  # hydrodynamics
V_A, V_B, V_C, V_D = 14, 15, 16, 17  # scratch 3-vectors of one function at a time
V_G = 18  # restoring wrench of the ROV
V_WROV, V_WTREE = 19, 20  # gripper spring wrenches
V_EPB, V_EVB, V_ETH, V_EW = 21, 22, 23, 24  # gripper spring errors
V_U, V_RHS6, V_BASE, V_MINVU = 25, 26, 27, 28  # the wire's mass (Sherman-Morrison)
V_CONTACT = 29  # contact wrench
V_CR, V_CT, V_CVN, V_CFN, V_CFB, V_CQ, V_CG, V_CQD, V_CF = 30, 31, 32, 33, 34, 35, 36, 37, 38
N_VEC = 39
# ``PlantWork.mat`` 3x3 slots
M_RT, M_RR, M_T, M_RM, M_RTR, M_TMP = 0, 1, 2, 3, 4, 5
N_MAT = 6


class PlantWork(NamedTuple):
    """Work arrays of ``rk4_step_into`` and ``rhs_into``: made once (``make_work``) and reused
    for every step, so a step allocates nothing."""

    vec: np.ndarray  # (N_VEC, max(N_STATE, thrusters)) rows of vectors
    mat: np.ndarray  # (N_MAT, 3, 3) rotation and product matrices


@njit(**JIT)
def make_work(n_thrusters: int) -> PlantWork:
    """A fresh work space for a plant with ``n_thrusters`` thrusters."""
    return PlantWork(np.zeros((N_VEC, max(N_STATE, n_thrusters))), np.zeros((N_MAT, 3, 3)))


@njit(**JIT_NOALLOC)
def _hydro_into(tau, M_rb, M_a, D_l, D_nl, nu, nu_r, nu_c_dot_lin, c_rb, c_a):
    """Rigid-body Coriolis, added-mass Coriolis, damping and the added-mass part of the water's
    acceleration, as forces on the right-hand side (eq. 2.11-2.12), into ``tau`` (6,);
    ``c_rb``, ``c_a`` (6,) are work arrays."""
    coriolis_force_into(c_rb, M_rb, nu)
    coriolis_force_into(c_a, M_a, nu_r)
    for i in range(6):
        tau[i] = -c_rb[i] - c_a[i]
        tau[i] -= (D_l[i] + D_nl[i] * abs(nu_r[i])) * nu_r[i]
        for j in range(3):
            tau[i] += M_a[i, j] * nu_c_dot_lin[j]


@njit(**JIT)
def _hydro(M_rb, M_a, D_l, D_nl, nu, nu_r, nu_c_dot_lin):
    """``_hydro_into`` into a new array."""
    tau = np.empty(6)
    _hydro_into(tau, M_rb, M_a, D_l, D_nl, nu, nu_r, nu_c_dot_lin, np.empty(6), np.empty(6))
    return tau


@njit(**JIT_NOALLOC)
def _relative_velocity_into(nu_r, v_c_b, v_c_dot_b, R_nb, nu, v_c_n, a_c_n):
    """nu_r = nu - nu_c (eq. 2.10) into ``nu_r`` (6,), the current's body components into
    ``v_c_b`` (3,) and their rate d/dt (R^T v_c) = R^T a_c - omega x (R^T v_c) into
    ``v_c_dot_b`` (3,)."""
    mtv3_into(v_c_b, R_nb, v_c_n)
    for i in range(6):
        nu_r[i] = nu[i]
    for i in range(3):
        nu_r[i] -= v_c_b[i]
    mtv3_into(v_c_dot_b, R_nb, a_c_n)
    w = nu[3:6]
    v_c_dot_b[0] -= w[1] * v_c_b[2] - w[2] * v_c_b[1]
    v_c_dot_b[1] -= w[2] * v_c_b[0] - w[0] * v_c_b[2]
    v_c_dot_b[2] -= w[0] * v_c_b[1] - w[1] * v_c_b[0]


@njit(**JIT)
def _relative_velocity(R_nb, nu, v_c_n, a_c_n):
    """nu_r = nu - nu_c (eq. 2.10) and d/dt of the current's body components."""
    nu_r = np.empty(6)
    v_c_dot_b = np.empty(3)
    _relative_velocity_into(nu_r, np.empty(3), v_c_dot_b, R_nb, nu, v_c_n, a_c_n)
    return nu_r, v_c_dot_b


@njit(**JIT_NOALLOC)
def wire_pivot_xyz(env: np.ndarray, W0: float) -> tuple[float, float, float, float]:
    """Virtual pivot (north, east, down) [m] and rest length [m] of the wire's equivalent
    elastic pendulum (see ``wire_force_damped_into``)."""
    rest = W0 / env[E_KH] - W0 / env[E_KZ]
    north = env[E_CT] + env[E_OFF]
    east = env[E_CT + 1] + env[E_OFF + 1]
    down = env[E_CT + 2] + env[E_LREST] - rest
    return north, east, down, rest


@njit(**JIT)
def wire_pivot(env: np.ndarray, W0: float) -> tuple[np.ndarray, float]:
    """``wire_pivot_xyz`` as (pivot (3,), rest length)."""
    north, east, down, rest = wire_pivot_xyz(env, W0)
    return np.array([north, east, down]), rest


@njit(**JIT_NOALLOC)
def wire_force_damped_into(
    f: np.ndarray, p_att_n: np.ndarray, v_att_n: np.ndarray, env: np.ndarray, W0: float
) -> None:
    """Force of the wire on the tree at its attachment point into ``f`` (3,), NED [N].

    The wire is represented by an elastic pendulum: a spring of stiffness k_z (eq. 2.25) from a
    virtual pivot straight above the equilibrium point (crane tip plus the drag offset of
    eq. 2.29), with a rest length chosen so that at the static hang the tension is W0, the
    vertical stiffness is k_z and the horizontal stiffness T / d is exactly k of eq. 2.30. The
    spring's force is central and depends on distance only, so it is conservative (no energy
    is made by the wire). The elastic wire adds its axial damping (``E_WDAMP``): the tension
    is k_z (d - rest) + c d_dot along the wire, d_dot the stretch rate of the attachment
    point against the wire's top (``E_VPIV``); never negative, zero when the wire is slack
    (eq. 2.28). With ``E_WEXT`` set, the force given from outside (``E_FWIRE``, the coupled
    MoorDyn wire) instead of the plant's own wire."""
    if env[E_WEXT] > 0.0:
        f[0] = env[E_FWIRE]
        f[1] = env[E_FWIRE + 1]
        f[2] = env[E_FWIRE + 2]
        return
    north, east, down, rest = wire_pivot_xyz(env, W0)
    dx = p_att_n[0] - north
    dy = p_att_n[1] - east
    dz = p_att_n[2] - down
    d = np.sqrt(dx * dx + dy * dy + dz * dz)
    f[0] = 0.0
    f[1] = 0.0
    f[2] = 0.0
    if d > rest and d > 0.0:
        rate = (
            dx * (v_att_n[0] - env[E_VPIV])
            + dy * (v_att_n[1] - env[E_VPIV + 1])
            + dz * (v_att_n[2] - env[E_VPIV + 2])
        ) / d
        tension = env[E_KZ] * (d - rest) + env[E_WDAMP] * rate
        if tension > 0.0:
            f[0] = -tension * dx / d
            f[1] = -tension * dy / d
            f[2] = -tension * dz / d


@njit(**JIT)
def wire_force_damped_n(
    p_att_n: np.ndarray, v_att_n: np.ndarray, env: np.ndarray, W0: float
) -> np.ndarray:
    """``wire_force_damped_into`` into a new array."""
    f = np.empty(3)
    wire_force_damped_into(f, p_att_n, v_att_n, env, W0)
    return f


@njit(**JIT_NOALLOC)
def attachment_velocity_into(
    out: np.ndarray, x: np.ndarray, R_t: np.ndarray, r_att: np.ndarray, tmp: np.ndarray
) -> None:
    """``attachment_velocity_n`` into ``out`` (3,); ``tmp`` (3,) is a work array."""
    cross_into(tmp, x[9:12], r_att)
    for i in range(3):
        tmp[i] = x[6 + i] + tmp[i]
    mv3_into(out, R_t, tmp)


@njit(**JIT)
def attachment_velocity_n(x: np.ndarray, R_t: np.ndarray, r_att: np.ndarray) -> np.ndarray:
    """Velocity of the wire's attachment point on the tree, NED [m/s]."""
    out = np.empty(3)
    attachment_velocity_into(out, x, R_t, r_att, np.empty(3))
    return out


@njit(inline="always", **JIT_NOALLOC)
def tree_acceleration_into(
    nu_dot: np.ndarray,
    x: np.ndarray,
    tau: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    R_t: np.ndarray,
    work: PlantWork,
) -> None:
    """nu_dot of the tree for the wrench ``tau`` (tree axes), into ``nu_dot`` (6,). With the
    elastic wire, the wire's mass lumped at the tree (``E_WMASS``, m_wire L / 3: the first
    axial mode's share, as in T0) moves with the tree's centre along the vertical only (the
    wire's axial direction); its inertia m_w a_down is added to the tree's,
    (M + m_w u u^T) nu_dot = tau - u m_w (e_down . R (omega x v)), u = [R^T e_down, 0],
    solved with Sherman-Morrison on M^-1."""
    mv6_into(nu_dot, P.tree_M_inv, tau)
    m_w = env[E_WMASS]
    if m_w <= 0.0:
        return
    vec = work.vec
    u = vec[V_U, 0:6]
    for i in range(3):
        u[i] = R_t[2, i]
        u[3 + i] = 0.0
    cor = vec[V_A, 0:3]
    cross_into(cor, x[9:12], x[6:9])
    a_rot = R_t[2, 0] * cor[0] + R_t[2, 1] * cor[1] + R_t[2, 2] * cor[2]
    rhs6 = vec[V_RHS6, 0:6]
    for i in range(6):
        rhs6[i] = tau[i] - m_w * a_rot * u[i]
    base = vec[V_BASE, 0:6]
    mv6_into(base, P.tree_M_inv, rhs6)
    minv_u = vec[V_MINVU, 0:6]
    mv6_into(minv_u, P.tree_M_inv, u)
    # the dot products summed in order from 0.0 (as the batch plant does; BLAS's ddot, which
    # np.dot calls, sums in an order of its own)
    u_minv_u = 0.0
    for i in range(6):
        u_minv_u += u[i] * minv_u[i]
    u_base = 0.0
    for i in range(6):
        u_base += u[i] * base[i]
    denom = 1.0 + m_w * u_minv_u
    scale = m_w * u_base / denom
    for i in range(6):
        nu_dot[i] = base[i] - minv_u[i] * scale


@njit(**JIT)
def tree_acceleration(
    x: np.ndarray, tau: np.ndarray, env: np.ndarray, P: PlantArrays, R_t: np.ndarray
) -> np.ndarray:
    """``tree_acceleration_into`` into a new array."""
    nu_dot = np.empty(6)
    tree_acceleration_into(nu_dot, x, tau, env, P, R_t, make_work(P.thr_T.shape[1]))
    return nu_dot


@njit(inline="always", **JIT_NOALLOC)
def coupling_wrench_into(
    w_rov: np.ndarray,
    w_tree: np.ndarray,
    x: np.ndarray,
    P: PlantArrays,
    R_t: np.ndarray,
    R_r: np.ndarray,
    work: PlantWork,
) -> None:
    """Gripper spring (eq. 2.45-2.47): wrench on the ROV in ROV axes into ``w_rov`` (6,) and
    the equal and opposite wrench on the tree in tree axes (the force applied at the mounting
    point) into ``w_tree`` (6,). R_t, R_r are the tree's and the ROV's R_nb."""
    vec, mat = work.vec, work.mat
    nu_t, nu_r = x[6:12], x[18:24]
    a = vec[V_A, 0:3]
    b = vec[V_B, 0:3]
    R_m = mat[M_RM]
    mm_into(R_m, R_t, P.mount_R)
    w_t = nu_t[3:6]
    # position error: R_r^T (p_m - p_rov), p_m = p_tree + R_t r_mount
    mv3_into(a, R_t, P.mount_r)
    for i in range(3):
        a[i] = x[i] + a[i]
    for i in range(3):
        a[i] = a[i] - x[12 + i]
    e_p_b = vec[V_EPB, 0:3]
    mtv3_into(e_p_b, R_r, a)
    # velocity error: R_r^T R_t (v_t + w_t x r_mount) - v_rov
    cross_into(a, w_t, P.mount_r)
    for i in range(3):
        a[i] = nu_t[i] + a[i]
    mv3_into(b, R_t, a)
    e_v_b = vec[V_EVB, 0:3]
    mtv3_into(e_v_b, R_r, b)
    for i in range(3):
        e_v_b[i] = e_v_b[i] - nu_r[i]
    R_tmp = mat[M_TMP]
    mtm_into(R_tmp, R_r, R_m)
    e_th = vec[V_ETH, 0:3]
    rotation_to_vector_into(e_th, R_tmp)
    mv3_into(a, R_t, w_t)
    e_w = vec[V_EW, 0:3]
    mtv3_into(e_w, R_r, a)
    for i in range(3):
        e_w[i] = e_w[i] - nu_r[3 + i]
    for i in range(3):
        w_rov[i] = P.coupling_K[i] * e_p_b[i] + P.coupling_C[i] * e_v_b[i]
        w_rov[3 + i] = P.coupling_K[3 + i] * e_th[i] + P.coupling_C[3 + i] * e_w[i]
    R_tr = mat[M_RTR]
    mtm_into(R_tr, R_t, R_r)  # ROV axes -> tree axes
    mv3_into(a, R_tr, w_rov[0:3])
    for i in range(3):
        w_tree[i] = -a[i]
    cross_into(b, P.mount_r, w_tree[0:3])
    mv3_into(a, R_tr, w_rov[3:6])
    for i in range(3):
        w_tree[3 + i] = b[i] - a[i]


@njit(**JIT)
def coupling_wrench(
    x: np.ndarray, P: PlantArrays, R_t: np.ndarray, R_r: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``coupling_wrench_into`` into new arrays: (wrench on the ROV, ROV axes; wrench on the
    tree, tree axes)."""
    w_rov = np.empty(6)
    w_tree = np.empty(6)
    coupling_wrench_into(w_rov, w_tree, x, P, R_t, R_r, make_work(P.thr_T.shape[1]))
    return w_rov, w_tree


@njit(**JIT_NOALLOC)
def _kinematics_into(
    out: np.ndarray, nu: np.ndarray, R_nb: np.ndarray, T_theta: np.ndarray
) -> None:
    """eta_dot = J_Theta(eta) nu (eq. 2.1) into ``out`` (6,), with R_nb and T_Theta given."""
    mv3_into(out[0:3], R_nb, nu[0:3])
    mv3_into(out[3:6], T_theta, nu[3:6])


@njit(**JIT)
def _kinematics(eta: np.ndarray, nu: np.ndarray, R_nb: np.ndarray) -> np.ndarray:
    """eta_dot = J_Theta(eta) nu (eq. 2.1)."""
    out = np.empty(6)
    _kinematics_into(out, nu, R_nb, Tzyx(eta[3], eta[4]))
    return out


FRICTION_SLIP_MPS = 0.005
"""Sliding speed at which friction reaches 76 % (tanh 1) of mu N: a smooth Coulomb law."""

# kinds of post contact (see post_penetration)
POST_FREE, POST_WALL, POST_PLATE, POST_SIDE = 0, 1, 2, 3


@njit(inline="always", **JIT_NOALLOC)
def post_penetration_into(grad: np.ndarray, q: np.ndarray, P: PlantArrays) -> tuple[int, float]:
    """How far one post's top is into the tree: (kind, penetration [m]), the gradient into
    ``grad`` (3,).

    ``q`` is the post's top from the tree's centre, in level axes turned to the tree's heading
    (x fore, y starboard, z down); the tree is taken level (roll and pitch are fractions of a
    degree on the wire), so the post stands along the tree's vertical. Its tip is
    ``e = H/2 - q_z`` above the tree's bottom plane. With the post's axis under a funnel's
    mouth, the post meets the funnel's wall: a cone from the mouth radius at the bottom
    narrowing to the bore radius ``cone height`` higher, then the bore; penetration
    ``rho + r_post - R(e)`` (rho: the post's axis from the funnel's centre). Where the post's
    top also overlaps the bottom plate around the mouth, the nearer of the wall and the plate
    (penetration ``e``) takes it. Away from the mouths and under the tree's footprint, the post
    pushes up on the bottom; anywhere under the footprint, out through the nearest side when
    that is nearer still (a post beside a tree that came down next to it). Choosing the
    nearer surface keeps the penetration continuous (the cone is no flatter than 45 deg, so
    wall and plate agree at the lip), so the contact energy ``0.5 k p^2`` has no jumps.

    The gradient is d(penetration)/dq: the force of the post on the tree is ``N * gradient``
    (level axes turned to the tree's heading) at the post's top, ``N`` the normal force."""
    grad[0] = 0.0
    grad[1] = 0.0
    grad[2] = 0.0
    e = P.tree_half_height - q[2]
    if e <= 0.0:
        return POST_FREE, 0.0
    # nearest funnel
    best, dx, dy = 1e300, 0.0, 0.0
    for j in range(P.dock_xy.shape[0]):
        ddx = q[0] - P.dock_xy[j, 0]
        ddy = q[1] - P.dock_xy[j, 1]
        r2 = ddx * ddx + ddy * ddy
        if r2 < best:
            best, dx, dy = r2, ddx, ddy
    rho = np.sqrt(best)
    rp = P.dock_post_radius
    slope = (P.dock_mouth_radius - P.dock_bore_radius) / P.dock_cone_height
    if e < P.dock_cone_height:
        radius, d_radius_de = P.dock_mouth_radius - slope * e, -slope
    else:
        radius, d_radius_de = P.dock_bore_radius, 0.0
    p_wall = rho + rp - radius
    ux, uy = (dx / rho, dy / rho) if rho > 1e-12 else (1.0, 0.0)
    half_l, half_w = 0.5 * P.tree_footprint[0] + rp, 0.5 * P.tree_footprint[1] + rp
    under = abs(q[0]) < half_l and abs(q[1]) < half_w
    if rho < P.dock_mouth_radius:
        # under the mouth: free in the funnel, or against its wall, or against the plate if
        # the post's top reaches past the lip
        if p_wall <= 0.0:
            return POST_FREE, 0.0
        p, kind = p_wall, POST_WALL
        if rho + rp > P.dock_mouth_radius and e < p:
            p, kind = e, POST_PLATE
    elif under:
        # under the bottom plate: up through the bottom or into the funnel's lip
        p, kind = e, POST_PLATE
        if p_wall < p:
            p, kind = p_wall, POST_WALL
    else:
        return POST_FREE, 0.0
    # or out through the nearest side, if that is nearer (a post beside a tree that came down
    # next to it); taken under the mouth too, so nothing jumps where the mouth meets a side
    side_x = half_l - abs(q[0])
    side_y = half_w - abs(q[1])
    if under and side_x < p:
        p, kind = side_x, POST_SIDE
    if under and side_y < p:
        p, kind = side_y, POST_SIDE
    if kind == POST_PLATE:
        grad[2] = -1.0
    elif kind == POST_WALL:
        grad[0], grad[1] = ux, uy
        grad[2] = d_radius_de  # de/dq_z = -1 and dp/de = -dR/de
    elif p == side_x:
        grad[0] = -1.0 if q[0] > 0.0 else 1.0
    else:
        grad[1] = -1.0 if q[1] > 0.0 else 1.0
    return kind, p


@njit(**JIT)
def post_penetration(q: np.ndarray, P: PlantArrays) -> tuple[int, float, np.ndarray]:
    """``post_penetration_into`` with the gradient in a new array: (kind, penetration [m],
    gradient)."""
    grad = np.empty(3)
    kind, p = post_penetration_into(grad, q, P)
    return kind, p, grad


@njit(inline="always", **JIT_NOALLOC)
def _post_top_into(q: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, i: int) -> None:
    """Post i's top from the tree's centre into ``q`` (3,): north and east turned into the
    tree's heading (x fore, y starboard, level), and down."""
    sf, cf = sincos(env[E_FRAME_PSI])
    s, c = sincos(x[5])
    _post_top_trig_into(q, x, env, P, i, sf, cf, s, c)


@njit(inline="always", **JIT_NOALLOC)
def _post_top_trig_into(
    q: np.ndarray,
    x: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    i: int,
    sf: float,
    cf: float,
    s: float,
    c: float,
) -> None:
    """``_post_top_into`` with the sine and cosine of the frame's heading (sf, cf) and of the
    tree's (s, c) given: the contact computes them once for all posts."""
    dn = env[E_FRAME] + cf * P.dock_xy[i, 0] - sf * P.dock_xy[i, 1] - x[0]
    de = env[E_FRAME + 1] + sf * P.dock_xy[i, 0] + cf * P.dock_xy[i, 1] - x[1]
    q[0] = c * dn + s * de
    q[1] = -s * dn + c * de
    q[2] = env[E_LAND] - P.dock_post_height - x[2]


@njit(**JIT)
def _post_top(x: np.ndarray, env: np.ndarray, P: PlantArrays, i: int) -> np.ndarray:
    """``_post_top_into`` into a new array."""
    q = np.empty(3)
    _post_top_into(q, x, env, P, i)
    return q


@njit(inline="always", **JIT_NOALLOC)
def _corner_body_into(c: np.ndarray, P: PlantArrays, j: int) -> None:
    """Corner j of the tree's bottom, tree body axes [m], into ``c`` (3,)."""
    c[0] = 0.5 * P.tree_footprint[0] * (1.0 if j % 2 == 0 else -1.0)
    c[1] = 0.5 * P.tree_footprint[1] * (1.0 if j < 2 else -1.0)
    c[2] = P.tree_half_height


@njit(**JIT)
def _corner_body(P: PlantArrays, j: int) -> np.ndarray:
    c = np.empty(3)
    _corner_body_into(c, P, j)
    return c


@njit(**JIT_NOALLOC)
def _friction_xy(vx: float, vy: float, normal: float, mu: float) -> tuple[float, float]:
    """Smooth Coulomb friction against the sliding velocity (vx, vy): never adds energy."""
    speed = np.sqrt(vx * vx + vy * vy)
    if speed < 1e-12:
        return 0.0, 0.0
    scale = mu * normal * np.tanh(speed / FRICTION_SLIP_MPS) / speed
    return -scale * vx, -scale * vy


@njit(**JIT)
def _friction(v: np.ndarray, normal: float, mu: float) -> tuple[float, float]:
    """Smooth Coulomb friction against the sliding velocity (v[0], v[1]): never adds energy."""
    return _friction_xy(v[0], v[1], normal, mu)


@njit(inline="always", **JIT_NOALLOC)
def contact_wrench_into(
    out: np.ndarray,
    x: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    R_t: np.ndarray,
    work: PlantWork,
) -> None:
    """``contact_wrench_trig_into`` with the sines and cosines of the tree's roll, pitch and
    heading computed here."""
    sphi, cphi = sincos(x[3])
    cth = sincos(x[4])[1]
    s, c = sincos(x[5])
    contact_wrench_trig_into(out, x, env, P, R_t, work, sphi, cphi, cth, s, c)


@njit(inline="always", **JIT_NOALLOC)
def contact_wrench_trig_into(
    out: np.ndarray,
    x: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    R_t: np.ndarray,
    work: PlantWork,
    sphi: float,
    cphi: float,
    cth: float,
    s: float,
    c: float,
) -> None:
    """Force (0:3) and moment about the centre (3:6) of the frame and the seabed on the tree,
    tree body axes, into ``out`` (6,).

    Seabed and landing surface: a penalty spring with damping under each corner of the tree's
    bottom, with smooth Coulomb friction at the corner's sliding speed. Posts: the penetration
    of ``post_penetration`` against a spring with damping along its gradient (the normal force
    never pulls), friction where a post's top carries the bottom plate. Springs store what
    they take (``contact_energy``); damping and friction only remove energy (the normal force
    is clipped at zero only while the penetration shrinks, which removes energy too).

    ``sphi, cphi``, ``cth`` and ``s, c`` are the sine and cosine of the tree's roll, the cosine
    of its pitch and the sine and cosine of its heading (``sim.trig.sincos``, as the
    right-hand side has them already); the frame's heading's are computed once here for all
    the posts."""
    for i in range(6):
        out[i] = 0.0
    if env[E_LAND] <= 0.0:
        return
    vec = work.vec
    r = vec[V_CR, 0:3]
    tmp = vec[V_CT, 0:3]
    v_n = vec[V_CVN, 0:3]
    f_n = vec[V_CFN, 0:3]
    f_b = vec[V_CFB, 0:3]
    nu = x[6:12]
    w = nu[3:6]
    k4, c4 = 0.25 * P.contact_k, 0.25 * P.contact_c
    for j in range(4):
        _corner_body_into(r, P, j)
        mv3_into(tmp, R_t, r)
        pen = x[2] + tmp[2] - env[E_LAND]
        if pen <= 0.0:
            continue
        cross_into(tmp, w, r)
        for i in range(3):
            tmp[i] = nu[i] + tmp[i]
        mv3_into(v_n, R_t, tmp)
        normal = k4 * pen + c4 * v_n[2]
        if normal <= 0.0:
            continue
        f_n[0], f_n[1] = _friction_xy(v_n[0], v_n[1], normal, P.friction_mu)
        f_n[2] = -normal
        mtv3_into(f_b, R_t, f_n)
        for i in range(3):
            out[i] += f_b[i]
        cross_into(tmp, r, f_b)
        for i in range(3):
            out[3 + i] += tmp[i]
    # posts: their energy depends on north, east, down and heading only (the tree taken level,
    # as in sim.docking), so they push through the centre and turn the tree about the vertical;
    # its generalized force on the heading, as a body moment, is Q_psi * d(psi_dot)/d(omega_b)
    mv3_into(v_n, R_t, nu[0:3])
    psi_dot = (sphi * w[1] + cphi * w[2]) / cth
    sf, cf = sincos(env[E_FRAME_PSI])
    q = vec[V_CQ, 0:3]
    grad = vec[V_CG, 0:3]
    q_dot = vec[V_CQD, 0:3]
    f = vec[V_CF, 0:3]
    for i in range(P.dock_xy.shape[0]):
        _post_top_trig_into(q, x, env, P, i, sf, cf, s, c)
        kind, pen = post_penetration_into(grad, q, P)
        if kind == POST_FREE or pen <= 0.0:
            continue
        # the post's top as the tree sees it move; the tree slides over it at minus this
        q_dot[0] = -(c * v_n[0] + s * v_n[1]) + psi_dot * q[1]
        q_dot[1] = -(-s * v_n[0] + c * v_n[1]) - psi_dot * q[0]
        q_dot[2] = -v_n[2]
        pen_rate = grad[0] * q_dot[0] + grad[1] * q_dot[1] + grad[2] * q_dot[2]
        normal = P.post_k * pen + P.post_c * pen_rate
        if normal <= 0.0:
            continue
        for k in range(3):
            f[k] = normal * grad[k]
        if kind == POST_PLATE:
            # the bottom plate slides over the post's top: friction in the plate's plane
            fx, fy = _friction_xy(-q_dot[0], -q_dot[1], normal, P.friction_mu)
            f[0] += fx
            f[1] += fy
        f_n[0] = c * f[0] - s * f[1]
        f_n[1] = s * f[0] + c * f[1]
        f_n[2] = f[2]
        mtv3_into(f_b, R_t, f_n)
        for k in range(3):
            out[k] += f_b[k]
        m_psi = q[0] * f[1] - q[1] * f[0]
        out[4] += m_psi * sphi / cth
        out[5] += m_psi * cphi / cth


@njit(**JIT)
def contact_wrench(x: np.ndarray, env: np.ndarray, P: PlantArrays, R_t: np.ndarray) -> np.ndarray:
    """``contact_wrench_into`` into a new array."""
    out = np.empty(6)
    contact_wrench_into(out, x, env, P, R_t, make_work(P.thr_T.shape[1]))
    return out


@njit(**JIT)
def contact_energy(x: np.ndarray, env: np.ndarray, P: PlantArrays) -> float:
    """Energy stored in the contact springs [J] (what ``contact_wrench`` would give back)."""
    if env[E_LAND] <= 0.0:
        return 0.0
    R_t = Rzyx(x[3], x[4], x[5])
    energy = 0.0
    for j in range(4):
        pen = x[2] + mv(R_t, _corner_body(P, j))[2] - env[E_LAND]
        if pen > 0.0:
            energy += 0.5 * 0.25 * P.contact_k * pen * pen
    for i in range(P.dock_xy.shape[0]):
        kind, pen, _ = post_penetration(_post_top(x, env, P, i), P)
        if kind != POST_FREE and pen > 0.0:
            energy += 0.5 * P.post_k * pen * pen
    return energy


@njit(**JIT_NOALLOC)
def _froude_krylov_into(
    tau: np.ndarray, fk_mass: float, R_nb: np.ndarray, a_c_n: np.ndarray, tmp: np.ndarray
) -> None:
    """Add the Froude-Krylov force rho V a (the undisturbed wave's pressure gradient over the
    body, Morison's equation) to ``tau``'s force, body axes. The water's acceleration is
    taken uniform over the body and acting at the centre of buoyancy, taken at the origin:
    no moment. Zero when the wave load is ``drag`` (the acceleration is zero then). ``tmp``
    (3,) is a work array."""
    mtv3_into(tmp, R_nb, a_c_n)
    for i in range(3):
        tau[i] += fk_mass * tmp[i]


@njit(**JIT_NOALLOC)
def _fluid_wrench_into(
    tau: np.ndarray,
    nu: np.ndarray,
    R: np.ndarray,
    M_rb: np.ndarray,
    M_a: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    fk_mass: float,
    env: np.ndarray,
    work: PlantWork,
) -> None:
    """The water's wrench on one body (its velocity ``nu``, rotation ``R``), body axes, into
    ``tau`` (6,): relative-velocity damping, Coriolis and added mass in the moving water, and
    the Froude-Krylov force of the water's acceleration. The tree and the ROV share it."""
    vec = work.vec
    nu_rel = vec[V_NU_REL, 0:6]
    v_c_b = vec[V_VCB, 0:3]
    v_c_dot_b = vec[V_VCDB, 0:3]
    _relative_velocity_into(
        nu_rel, v_c_b, v_c_dot_b, R, nu, env[E_VC : E_VC + 3], env[E_AC : E_AC + 3]
    )
    _hydro_into(tau, M_rb, M_a, D_l, D_nl, nu, nu_rel, v_c_dot_b, vec[V_CRB, 0:6], vec[V_CA, 0:6])
    _froude_krylov_into(tau, fk_mass, R, env[E_AC : E_AC + 3], vec[V_A, 0:3])


@njit(inline="always", **JIT_NOALLOC)
def tree_wrench_into(
    tau: np.ndarray,
    x: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    R_t: np.ndarray,
    work: PlantWork,
) -> None:
    """Net weight, wire, push and hydrodynamic forces on the tree, tree axes (eq. 2.44), into
    ``tau`` (6,) (``tree_wrench_trig_into``, the sines and cosines of the tree's angles
    computed here)."""
    sphi, cphi = sincos(x[3])
    cth = sincos(x[4])[1]
    s, c = sincos(x[5])
    tree_wrench_trig_into(tau, x, env, P, R_t, work, sphi, cphi, cth, s, c)


CONTACT_MARGIN_M = 0.01
"""[m] A tree more than its reach plus this above the landing surface cannot touch it (see
``contact_reach``). The depths compared (some 400 m) carry rounding errors of about 1e-13 m,
eleven orders below this margin; a larger margin only makes the contact's arithmetic run on
more steps where it finds nothing."""


@njit(inline="always", **JIT_NOALLOC)
def contact_reach(P: PlantArrays) -> float:
    """[m] How far below its centre the tree (its bottom corners, or its bottom and the
    posts' height) can touch anything, plus ``CONTACT_MARGIN_M``: a tree whose centre's depth
    plus this is above the landing surface has no contact (no corner below the surface, and
    every post free: ``post_penetration_into``'s first test)."""
    half_l, half_w = 0.5 * P.tree_footprint[0], 0.5 * P.tree_footprint[1]
    hh = P.tree_half_height
    reach = max(np.sqrt(half_l * half_l + half_w * half_w + hh * hh), hh + P.dock_post_height)
    return reach + CONTACT_MARGIN_M


@njit(inline="always", **JIT_NOALLOC)
def tree_wrench_trig_into(
    tau: np.ndarray,
    x: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    R_t: np.ndarray,
    work: PlantWork,
    sphi: float,
    cphi: float,
    cth: float,
    spsi: float,
    cpsi: float,
) -> None:
    """``tree_wrench_into`` with the sines and cosines of the tree's roll (sphi, cphi) and
    heading (spsi, cpsi) and the cosine of its pitch (cth) given (``rhs_into`` has them).

    The contact wrench is computed only for a tree within ``contact_reach`` of the landing
    surface: farther up it is exactly zero (every term of ``contact_wrench_trig_into`` is
    skipped), and ``tau`` gets the same ``+ 0.0`` it got from the zero wrench. In a docking
    run the tree hangs far above the frame for most of its steps, where the contact's corners
    and posts would cost a fifth of the plant's step for nothing."""
    vec = work.vec
    _fluid_wrench_into(
        tau,
        x[6:12],
        R_t,
        P.tree_M_rb,
        P.tree_M_a,
        P.tree_D_l,
        P.tree_D_nl,
        P.tree_fk_mass,
        env,
        work,
    )
    a = vec[V_A, 0:3]
    b = vec[V_B, 0:3]
    c = vec[V_C, 0:3]
    d = vec[V_D, 0:3]
    # push and net weight, NED
    b[0] = env[E_PUSH]
    b[1] = env[E_PUSH + 1]
    b[2] = env[E_PUSH + 2]
    b[2] += P.tree_W0
    mtv3_into(a, R_t, b)
    for i in range(3):
        tau[i] += a[i]
    # the wire at its attachment point
    mv3_into(c, R_t, P.tree_r_att)
    for i in range(3):
        c[i] = x[i] + c[i]
    attachment_velocity_into(d, x, R_t, P.tree_r_att, a)
    wire_force_damped_into(b, c, d, env, P.tree_W0)
    mtv3_into(a, R_t, b)
    for i in range(3):
        tau[i] += a[i]
    cross_into(c, P.tree_r_att, a)
    for i in range(3):
        tau[3 + i] += c[i]
    land = env[E_LAND]
    if land > 0.0:
        if x[2] + contact_reach(P) < land:
            for i in range(6):
                tau[i] += 0.0  # the zero wrench (it turns a -0.0 into 0.0, as it did)
        else:
            cw = vec[V_CONTACT, 0:6]
            contact_wrench_trig_into(cw, x, env, P, R_t, work, sphi, cphi, cth, spsi, cpsi)
            for i in range(6):
                tau[i] += cw[i]


@njit(**JIT)
def tree_wrench(x: np.ndarray, env: np.ndarray, P: PlantArrays, R_t: np.ndarray) -> np.ndarray:
    """``tree_wrench_into`` into a new array."""
    tau = np.empty(6)
    tree_wrench_into(tau, x, env, P, R_t, make_work(P.thr_T.shape[1]))
    return tau


@njit(inline="always", **JIT_NOALLOC)
def rov_wrench_into(
    tau: np.ndarray,
    x: np.ndarray,
    thrust_b: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    R_r: np.ndarray,
    sth: float,
    cth: float,
    sphi: float,
    cphi: float,
    work: PlantWork,
) -> None:
    """Restoring, thruster and hydrodynamic forces on the ROV, ROV axes (eq. 2.14), into
    ``tau`` (6,). ``thrust_b`` is the thrusters' wrench thr_T @ f; sth ... cphi are the sines
    and cosines of the ROV's pitch and roll."""
    vec = work.vec
    _fluid_wrench_into(
        tau,
        x[18:24],
        R_r,
        P.rov_M_rb,
        P.rov_M_a,
        P.rov_D_l,
        P.rov_D_nl,
        P.rov_fk_mass,
        env,
        work,
    )
    g = vec[V_G, 0:6]
    gvect_into(g, P.rov_W, P.rov_B, sth, cth, sphi, cphi, P.rov_r_cg, P.rov_r_cb)
    for i in range(6):
        tau[i] -= g[i]
    for i in range(6):
        tau[i] += thrust_b[i]


@njit(inline="always", **JIT_NOALLOC)
def thruster_wrench_into(
    out: np.ndarray, n_rps: np.ndarray, P: PlantArrays, work: PlantWork
) -> None:
    """The thrusters' wrench on the ROV, thr_T @ f(n), into ``out`` (6,): computed once per
    step, the propeller speeds being held over it."""
    f = work.vec[V_F, 0 : n_rps.shape[0]]
    thrust_from_speed_into(f, n_rps, P.thr_k_pos, P.thr_k_neg, P.thr_n_max)
    mv_into(out, P.thr_T, f)


@njit(**JIT)
def rov_wrench(
    x: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays, R_r: np.ndarray
) -> np.ndarray:
    """Restoring, thruster and hydrodynamic forces on the ROV, ROV axes (eq. 2.14)."""
    work = make_work(P.thr_T.shape[1])
    thrust_b = np.empty(6)
    thruster_wrench_into(thrust_b, n_rps, P, work)
    tau = np.empty(6)
    sth, cth = sincos(x[16])
    sphi, cphi = sincos(x[15])
    rov_wrench_into(tau, x, thrust_b, env, P, R_r, sth, cth, sphi, cphi, work)
    return tau


@njit(inline="always", **JIT_NOALLOC)
def rhs_into(
    xdot: np.ndarray,
    x: np.ndarray,
    thrust_b: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    work: PlantWork,
) -> None:
    """Time derivative of the plant state into ``xdot`` (N_STATE,), allocating nothing.
    ``thrust_b`` is the thrusters' wrench (``thruster_wrench_into``). The cosines and sines
    of each body's angles are computed once (``sim.trig.sincos``, the batch plant's own
    arithmetic) and shared by R_nb, T_Theta (tan theta as sin / cos) and g(eta)."""
    vec, mat = work.vec, work.mat
    sphi, cphi = sincos(x[3])
    sth, cth = sincos(x[4])
    spsi, cpsi = sincos(x[5])
    R_t = mat[M_RT]
    Rzyx_into(R_t, cphi, sphi, cth, sth, cpsi, spsi)
    tau_t = vec[V_TAU_T, 0:6]
    tree_wrench_trig_into(tau_t, x, env, P, R_t, work, sphi, cphi, cth, spsi, cpsi)
    T_theta = mat[M_T]
    if P.has_rov:
        sphi_r, cphi_r = sincos(x[15])
        sth_r, cth_r = sincos(x[16])
        spsi_r, cpsi_r = sincos(x[17])
        R_r = mat[M_RR]
        Rzyx_into(R_r, cphi_r, sphi_r, cth_r, sth_r, cpsi_r, spsi_r)
        tau_r = vec[V_TAU_R, 0:6]
        rov_wrench_into(tau_r, x, thrust_b, env, P, R_r, sth_r, cth_r, sphi_r, cphi_r, work)
        if env[E_GRIP] > 0.0:
            w_rov = vec[V_WROV, 0:6]
            w_tree = vec[V_WTREE, 0:6]
            coupling_wrench_into(w_rov, w_tree, x, P, R_t, R_r, work)
            for i in range(6):
                tau_r[i] += w_rov[i]
                tau_t[i] += w_tree[i]
        Tzyx_into(T_theta, cphi_r, sphi_r, cth_r, sth_r / cth_r)
        _kinematics_into(xdot[12:18], x[18:24], R_r, T_theta)
        mv6_into(xdot[18:24], P.rov_M_inv, tau_r)
    else:
        for i in range(12, N_STATE):
            xdot[i] = 0.0
    Tzyx_into(T_theta, cphi, sphi, cth, sth / cth)
    _kinematics_into(xdot[0:6], x[6:12], R_t, T_theta)
    tree_acceleration_into(xdot[6:12], x, tau_t, env, P, R_t, work)


@njit(**JIT)
def rhs(x: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays) -> np.ndarray:
    """Time derivative of the plant state. Does not modify its arguments. (Allocates its
    result and a work space: the stepping code calls ``rhs_into``.)"""
    work = make_work(P.thr_T.shape[1])
    thrust_b = np.empty(6)
    thruster_wrench_into(thrust_b, n_rps, P, work)
    xdot = np.empty(N_STATE)
    rhs_into(xdot, x, thrust_b, env, P, work)
    return xdot


@njit(**JIT_NOALLOC)
def rk4_step_into(
    out: np.ndarray,
    x: np.ndarray,
    n_rps: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    dt: float,
    work: PlantWork,
) -> None:
    """One classical Runge-Kutta step with inputs held over the step, into ``out``
    (N_STATE,), allocating nothing: the stage state and the slopes live in ``work``, and the
    thrusters' wrench is computed once for the four stages (the propeller speeds are held).
    ``out`` may be ``x`` itself (each element of x is read for the last time just before
    the same element of out is written).

    Each element is computed with the same operations in the same order as the vector form
    ``x + (dt / 6) * (k1 + 2 k2 + 2 k3 + k4)``."""
    vec = work.vec
    n = x.shape[0]
    thrust_b = vec[V_THR, 0:6]
    thruster_wrench_into(thrust_b, n_rps, P, work)
    xs = vec[V_XS, 0:n]
    k1 = vec[V_K1, 0:n]
    k2 = vec[V_K2, 0:n]
    k3 = vec[V_K3, 0:n]
    k4 = vec[V_K4, 0:n]
    h2 = 0.5 * dt
    # the four stages as one loop round one (inlined) right-hand side, so ``P`` is not passed
    # to a call four times per step: stage s evaluates the slope at xs into row V_K1 + s
    # (stage 0 at a copy of x: the same numbers), then sets the next stage's state
    for i in range(n):
        xs[i] = x[i]
    for stage in range(min(4, work.vec.shape[0])):
        k = vec[V_K1 + stage, 0:n]
        rhs_into(k, xs, thrust_b, env, P, work)
        if stage == 0:
            for i in range(n):
                xs[i] = x[i] + h2 * k1[i]
        elif stage == 1:
            for i in range(n):
                xs[i] = x[i] + h2 * k2[i]
        elif stage == 2:
            for i in range(n):
                xs[i] = x[i] + dt * k3[i]
    h6 = dt / 6.0
    for i in range(n):
        out[i] = x[i] + h6 * (((k1[i] + 2.0 * k2[i]) + 2.0 * k3[i]) + k4[i])


@njit(**JIT)
def rk4_step(
    x: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays, dt: float
) -> np.ndarray:
    """``rk4_step_into`` into a new state (with a fresh work space: loops over many steps
    make one work space and call ``rk4_step_into``)."""
    out = np.empty(x.shape[0])
    rk4_step_into(out, x, n_rps, env, P, dt, make_work(n_rps.shape[0]))
    return out


@njit(**JIT_NOALLOC)
def all_finite(x: np.ndarray) -> bool:
    """True when every element of x is finite (``np.all(np.isfinite(x))`` without its
    temporary array)."""
    for i in range(x.shape[0]):
        if not np.isfinite(x[i]):
            return False
    return True


@njit(**JIT)
def advance(
    x0: np.ndarray, n_rps: np.ndarray, env_series: np.ndarray, P: PlantArrays, dt: float
) -> tuple[np.ndarray, int]:
    """Run len(env_series) steps with constant propeller speeds.

    Returns (states, n_done): states[k] is the state at the END of step k. n_done is smaller
    than the number of steps when the state stopped being finite (the caller raises)."""
    n = env_series.shape[0]
    states = np.empty((n, N_STATE))
    x = x0.copy()
    work = make_work(n_rps.shape[0])
    for k in range(n):
        rk4_step_into(x, x, n_rps, env_series[k], P, dt, work)
        if not all_finite(x):
            return states, k
        states[k] = x
    return states, n


@njit(**JIT)
def hold_needed_xyn(
    poses: np.ndarray, depth_m: float, env: np.ndarray, P: PlantArrays
) -> np.ndarray:
    """What the ROV's thrusters must give to hold the gripped pair still at each pose: row i
    for pose ``poses[i] = (north, east, psi)`` of the tree at ``depth_m``, the ROV where its
    mount puts it, both at rest (``missions.landing``'s plan checks every heading of a turn
    with it). The surge force [N], sway force [N] and yaw moment [N m] in the ROV's axes,
    about its origin: minus the sum of the tree's wrench (``tree_wrench_into``, moved to the
    ROV) and the ROV's own with its thrusters off (``rov_wrench_into``). The rotations'
    products are ``sim.gnc``'s 3x3 loops, not OpenBLAS's, whose last bits depend on the CPU;
    one call for all poses instead of two compiled calls and a dozen numpy ones per pose.
    Returns (len(poses), 3)."""
    k = poses.shape[0]
    m = P.thr_T.shape[1]
    out = np.empty((k, 3))
    work = make_work(m)
    x = np.zeros(N_STATE)
    thrust_b = np.empty(6)
    thruster_wrench_into(thrust_b, np.zeros(m), P, work)
    w_tree = np.empty(6)
    w_rov = np.empty(6)
    rot_t = np.empty((3, 3))
    rot_r = np.empty((3, 3))
    offset = np.empty(3)
    f_tree = np.empty(3)
    m_tree = np.empty(3)
    r_tree = np.empty(3)
    rot_m = P.mount_R
    psi_mount = np.arctan2(rot_m[1, 0], rot_m[0, 0])
    mtv3_into(r_tree, rot_m, P.mount_r)  # minus the tree's origin from the ROV's, ROV axes
    for i in range(k):
        north, east, psi = poses[i, 0], poses[i, 1], poses[i, 2]
        Rzyx_into(rot_t, 1.0, 0.0, 1.0, 0.0, np.cos(psi), np.sin(psi))
        mm_into(rot_r, rot_t, rot_m)
        mv3_into(offset, rot_t, P.mount_r)
        for j in range(N_STATE):
            x[j] = 0.0
        x[0], x[1], x[2], x[5] = north, east, depth_m, psi
        for a in range(3):
            x[12 + a] = x[a] + offset[a]
        x[17] = psi + psi_mount
        tree_wrench_into(w_tree, x, env, P, rot_t, work)
        sth, cth = sincos(x[16])
        sphi, cphi = sincos(x[15])
        rov_wrench_into(w_rov, x, thrust_b, env, P, rot_r, sth, cth, sphi, cphi, work)
        # the tree's force and moment in the ROV's axes, its yaw moment about the ROV
        mtv3_into(f_tree, rot_m, w_tree[0:3])
        mtv3_into(m_tree, rot_m, w_tree[3:6])
        m_z = m_tree[2] + ((-r_tree[0]) * f_tree[1] - (-r_tree[1]) * f_tree[0])
        out[i, 0] = -(f_tree[0] + w_rov[0])
        out[i, 1] = -(f_tree[1] + w_rov[1])
        out[i, 2] = -(m_z + w_rov[5])
    return out
