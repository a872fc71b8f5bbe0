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
    Rzyx,
    Tzyx,
    coriolis_force,
    cross,
    gvect,
    mm,
    mtm,
    mtv,
    mv,
    rotation_to_vector,
)
from sim.params import ParameterSet
from sim.thrusters import thrust_from_speed

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


@njit(**JIT)
def _hydro(M_rb, M_a, D_l, D_nl, nu, nu_r, nu_c_dot_lin):
    """Rigid-body Coriolis, added-mass Coriolis, damping and the added-mass part of the water's
    acceleration, as forces on the right-hand side (eq. 2.11-2.12)."""
    c_rb = coriolis_force(M_rb, nu)
    c_a = coriolis_force(M_a, nu_r)
    tau = np.empty(6)
    for i in range(6):
        tau[i] = -c_rb[i] - c_a[i]
        tau[i] -= (D_l[i] + D_nl[i] * abs(nu_r[i])) * nu_r[i]
        for j in range(3):
            tau[i] += M_a[i, j] * nu_c_dot_lin[j]
    return tau


@njit(**JIT)
def _relative_velocity(R_nb, nu, v_c_n, a_c_n):
    """nu_r = nu - nu_c (eq. 2.10) and d/dt of the current's body components."""
    v_c_b = mtv(R_nb, v_c_n)
    nu_r = nu.copy()
    nu_r[0:3] -= v_c_b
    # d/dt (R^T v_c) = R^T a_c - omega x (R^T v_c)
    v_c_dot_b = mtv(R_nb, a_c_n)
    w = nu[3:6]
    v_c_dot_b[0] -= w[1] * v_c_b[2] - w[2] * v_c_b[1]
    v_c_dot_b[1] -= w[2] * v_c_b[0] - w[0] * v_c_b[2]
    v_c_dot_b[2] -= w[0] * v_c_b[1] - w[1] * v_c_b[0]
    return nu_r, v_c_dot_b


@njit(**JIT)
def wire_pivot(env: np.ndarray, W0: float) -> tuple[np.ndarray, float]:
    """Virtual pivot and rest length of the equivalent elastic pendulum (see wire_force_n)."""
    rest = W0 / env[E_KH] - W0 / env[E_KZ]
    pivot = np.empty(3)
    pivot[0] = env[E_CT] + env[E_OFF]
    pivot[1] = env[E_CT + 1] + env[E_OFF + 1]
    pivot[2] = env[E_CT + 2] + env[E_LREST] - rest
    return pivot, rest


@njit(**JIT)
def wire_force_n(p_att_n: np.ndarray, env: np.ndarray, W0: float) -> np.ndarray:
    """Force of the wire on the tree at its attachment point, NED [N].

    The wire is represented by an elastic pendulum: a spring of stiffness k_z (eq. 2.25) from a
    virtual pivot straight above the equilibrium point (crane tip plus the drag offset of
    eq. 2.29), with a rest length chosen so that at the static hang the tension is W0, the
    vertical stiffness is k_z and the horizontal stiffness T / d is exactly k of eq. 2.30. The
    force is central and depends on distance only, so it is conservative (no energy is made by
    the wire), and it vanishes when the wire is slack (eq. 2.28)."""
    pivot, rest = wire_pivot(env, W0)
    dx = p_att_n[0] - pivot[0]
    dy = p_att_n[1] - pivot[1]
    dz = p_att_n[2] - pivot[2]
    d = np.sqrt(dx * dx + dy * dy + dz * dz)
    f = np.zeros(3)
    if d > rest and d > 0.0:
        tension = env[E_KZ] * (d - rest)
        f[0] = -tension * dx / d
        f[1] = -tension * dy / d
        f[2] = -tension * dz / d
    return f


@njit(**JIT)
def wire_force_damped_n(
    p_att_n: np.ndarray, v_att_n: np.ndarray, env: np.ndarray, W0: float
) -> np.ndarray:
    """``wire_force_n`` with the wire's axial damping (``E_WDAMP``): the tension is
    k_z (d - rest) + c d_dot along the wire, d_dot the stretch rate of the attachment point
    against the wire's top (``E_VPIV``); never negative, zero when slack. With c = 0 it is
    ``wire_force_n`` exactly. With ``E_WEXT`` set, the force given from outside
    (``E_FWIRE``, the coupled MoorDyn wire) instead."""
    if env[E_WEXT] > 0.0:
        return env[E_FWIRE : E_FWIRE + 3].copy()
    pivot, rest = wire_pivot(env, W0)
    dx = p_att_n[0] - pivot[0]
    dy = p_att_n[1] - pivot[1]
    dz = p_att_n[2] - pivot[2]
    d = np.sqrt(dx * dx + dy * dy + dz * dz)
    f = np.zeros(3)
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
    return f


@njit(**JIT)
def attachment_velocity_n(x: np.ndarray, R_t: np.ndarray, r_att: np.ndarray) -> np.ndarray:
    """Velocity of the wire's attachment point on the tree, NED [m/s]."""
    return mv(R_t, x[6:9] + cross(x[9:12], r_att))


@njit(**JIT)
def tree_acceleration(
    x: np.ndarray, tau: np.ndarray, env: np.ndarray, P: PlantArrays, R_t: np.ndarray
) -> np.ndarray:
    """nu_dot of the tree for the wrench ``tau`` (tree axes). With the elastic wire, the wire's
    mass lumped at the tree (``E_WMASS``, m_wire L / 3: the first axial mode's share, as in
    T0) moves with the tree's centre along the vertical only (the wire's axial direction);
    its inertia m_w a_down is added to the tree's, (M + m_w u u^T) nu_dot = tau - u m_w
    (e_down . R (omega x v)), u = [R^T e_down, 0], solved with Sherman-Morrison on M^-1."""
    nu_dot = mv(P.tree_M_inv, tau)
    m_w = env[E_WMASS]
    if m_w <= 0.0:
        return nu_dot
    u = np.zeros(6)
    u[0:3] = R_t[2, :]
    cor = cross(x[9:12], x[6:9])
    a_rot = R_t[2, 0] * cor[0] + R_t[2, 1] * cor[1] + R_t[2, 2] * cor[2]
    rhs6 = tau - m_w * a_rot * u
    base = mv(P.tree_M_inv, rhs6)
    minv_u = mv(P.tree_M_inv, u)
    denom = 1.0 + m_w * np.dot(u, minv_u)
    return base - minv_u * (m_w * np.dot(u, base) / denom)


@njit(**JIT)
def coupling_wrench(
    x: np.ndarray, P: PlantArrays, R_t: np.ndarray, R_r: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Gripper spring (eq. 2.45-2.47): wrench on the ROV in ROV axes and the equal and opposite
    wrench on the tree in tree axes (the force applied at the mounting point). R_t, R_r are the
    tree's and the ROV's R_nb."""
    nu_t, nu_r = x[6:12], x[18:24]
    R_m = mm(R_t, P.mount_R)
    w_t = nu_t[3:6]
    p_m = x[0:3] + mv(R_t, P.mount_r)
    e_p_b = mtv(R_r, p_m - x[12:15])
    v_m_n = mv(R_t, nu_t[0:3] + cross(w_t, P.mount_r))
    e_v_b = mtv(R_r, v_m_n) - nu_r[0:3]
    e_th = rotation_to_vector(mtm(R_r, R_m))
    e_w = mtv(R_r, mv(R_t, w_t)) - nu_r[3:6]
    w_rov = np.empty(6)
    for i in range(3):
        w_rov[i] = P.coupling_K[i] * e_p_b[i] + P.coupling_C[i] * e_v_b[i]
        w_rov[3 + i] = P.coupling_K[3 + i] * e_th[i] + P.coupling_C[3 + i] * e_w[i]
    R_tr = mtm(R_t, R_r)  # ROV axes -> tree axes
    f_tree_b = -mv(R_tr, w_rov[0:3])
    w_tree = np.empty(6)
    w_tree[0:3] = f_tree_b
    w_tree[3:6] = cross(P.mount_r, f_tree_b) - mv(R_tr, w_rov[3:6])
    return w_rov, w_tree


@njit(**JIT)
def _kinematics(eta: np.ndarray, nu: np.ndarray, R_nb: np.ndarray) -> np.ndarray:
    """eta_dot = J_Theta(eta) nu (eq. 2.1)."""
    out = np.empty(6)
    out[0:3] = mv(R_nb, nu[0:3])
    out[3:6] = mv(Tzyx(eta[3], eta[4]), nu[3:6])
    return out


FRICTION_SLIP_MPS = 0.005
"""Sliding speed at which friction reaches 76 % (tanh 1) of mu N: a smooth Coulomb law."""

# kinds of post contact (see post_penetration)
POST_FREE, POST_WALL, POST_PLATE, POST_SIDE = 0, 1, 2, 3


@njit(**JIT)
def post_penetration(q: np.ndarray, P: PlantArrays) -> tuple[int, float, np.ndarray]:
    """How far one post's top is into the tree: (kind, penetration [m], gradient).

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
    grad = np.zeros(3)
    e = P.tree_half_height - q[2]
    if e <= 0.0:
        return POST_FREE, 0.0, grad
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
            return POST_FREE, 0.0, grad
        p, kind = p_wall, POST_WALL
        if rho + rp > P.dock_mouth_radius and e < p:
            p, kind = e, POST_PLATE
    elif under:
        # under the bottom plate: up through the bottom or into the funnel's lip
        p, kind = e, POST_PLATE
        if p_wall < p:
            p, kind = p_wall, POST_WALL
    else:
        return POST_FREE, 0.0, grad
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
    return kind, p, grad


@njit(**JIT)
def _post_top(x: np.ndarray, env: np.ndarray, P: PlantArrays, i: int) -> np.ndarray:
    """Post i's top from the tree's centre: north and east turned into the tree's heading
    (x fore, y starboard, level), and down."""
    cf, sf = np.cos(env[E_FRAME_PSI]), np.sin(env[E_FRAME_PSI])
    dn = env[E_FRAME] + cf * P.dock_xy[i, 0] - sf * P.dock_xy[i, 1] - x[0]
    de = env[E_FRAME + 1] + sf * P.dock_xy[i, 0] + cf * P.dock_xy[i, 1] - x[1]
    c, s = np.cos(x[5]), np.sin(x[5])
    q = np.empty(3)
    q[0] = c * dn + s * de
    q[1] = -s * dn + c * de
    q[2] = env[E_LAND] - P.dock_post_height - x[2]
    return q


@njit(**JIT)
def _corner_body(P: PlantArrays, j: int) -> np.ndarray:
    c = np.empty(3)
    c[0] = 0.5 * P.tree_footprint[0] * (1.0 if j % 2 == 0 else -1.0)
    c[1] = 0.5 * P.tree_footprint[1] * (1.0 if j < 2 else -1.0)
    c[2] = P.tree_half_height
    return c


@njit(**JIT)
def _friction(v: np.ndarray, normal: float, mu: float) -> tuple[float, float]:
    """Smooth Coulomb friction against the sliding velocity (v[0], v[1]): never adds energy."""
    speed = np.sqrt(v[0] * v[0] + v[1] * v[1])
    if speed < 1e-12:
        return 0.0, 0.0
    scale = mu * normal * np.tanh(speed / FRICTION_SLIP_MPS) / speed
    return -scale * v[0], -scale * v[1]


@njit(**JIT)
def contact_wrench(x: np.ndarray, env: np.ndarray, P: PlantArrays, R_t: np.ndarray) -> np.ndarray:
    """Force (0:3) and moment about the centre (3:6) of the frame and the seabed on the tree,
    tree body axes.

    Seabed and landing surface: a penalty spring with damping under each corner of the tree's
    bottom, with smooth Coulomb friction at the corner's sliding speed. Posts: the penetration
    of ``post_penetration`` against a spring with damping along its gradient (the normal force
    never pulls), friction where a post's top carries the bottom plate. Springs store what
    they take (``contact_energy``); damping and friction only remove energy (the normal force
    is clipped at zero only while the penetration shrinks, which removes energy too)."""
    out = np.zeros(6)
    if env[E_LAND] <= 0.0:
        return out
    nu = x[6:12]
    w = nu[3:6]
    k4, c4 = 0.25 * P.contact_k, 0.25 * P.contact_c
    for j in range(4):
        r = _corner_body(P, j)
        pen = x[2] + mv(R_t, r)[2] - env[E_LAND]
        if pen <= 0.0:
            continue
        v_n = mv(R_t, nu[0:3] + cross(w, r))
        normal = k4 * pen + c4 * v_n[2]
        if normal <= 0.0:
            continue
        f_n = np.empty(3)
        f_n[0], f_n[1] = _friction(v_n, normal, P.friction_mu)
        f_n[2] = -normal
        f_b = mtv(R_t, f_n)
        out[0:3] += f_b
        out[3:6] += cross(r, f_b)
    # posts: their energy depends on north, east, down and heading only (the tree taken level,
    # as in sim.docking), so they push through the centre and turn the tree about the vertical;
    # its generalized force on the heading, as a body moment, is Q_psi * d(psi_dot)/d(omega_b)
    v_n = mv(R_t, nu[0:3])
    cphi, sphi, cth = np.cos(x[3]), np.sin(x[3]), np.cos(x[4])
    psi_dot = (sphi * w[1] + cphi * w[2]) / cth
    c, s = np.cos(x[5]), np.sin(x[5])
    for i in range(P.dock_xy.shape[0]):
        q = _post_top(x, env, P, i)
        kind, pen, grad = post_penetration(q, P)
        if kind == POST_FREE or pen <= 0.0:
            continue
        # the post's top as the tree sees it move; the tree slides over it at minus this
        q_dot = np.empty(3)
        q_dot[0] = -(c * v_n[0] + s * v_n[1]) + psi_dot * q[1]
        q_dot[1] = -(-s * v_n[0] + c * v_n[1]) - psi_dot * q[0]
        q_dot[2] = -v_n[2]
        pen_rate = grad[0] * q_dot[0] + grad[1] * q_dot[1] + grad[2] * q_dot[2]
        normal = P.post_k * pen + P.post_c * pen_rate
        if normal <= 0.0:
            continue
        f = normal * grad
        if kind == POST_PLATE:
            # the bottom plate slides over the post's top: friction in the plate's plane
            fx, fy = _friction(-q_dot, normal, P.friction_mu)
            f[0] += fx
            f[1] += fy
        f_n = np.empty(3)
        f_n[0] = c * f[0] - s * f[1]
        f_n[1] = s * f[0] + c * f[1]
        f_n[2] = f[2]
        out[0:3] += mtv(R_t, f_n)
        m_psi = q[0] * f[1] - q[1] * f[0]
        out[4] += m_psi * sphi / cth
        out[5] += m_psi * cphi / cth
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


@njit(**JIT)
def _froude_krylov(tau: np.ndarray, fk_mass: float, R_nb: np.ndarray, a_c_n: np.ndarray) -> None:
    """Add the Froude-Krylov force rho V a (the undisturbed wave's pressure gradient over the
    body, Morison's equation) to ``tau``'s force, body axes. The water's acceleration is
    taken uniform over the body and acting at the centre of buoyancy, taken at the origin:
    no moment. Zero when the wave load is ``drag`` (the acceleration is zero then)."""
    f_b = mtv(R_nb, a_c_n)
    for i in range(3):
        tau[i] += fk_mass * f_b[i]


@njit(**JIT)
def tree_wrench(x: np.ndarray, env: np.ndarray, P: PlantArrays, R_t: np.ndarray) -> np.ndarray:
    """Net weight, wire, push and hydrodynamic forces on the tree, tree axes (eq. 2.44)."""
    nu = x[6:12]
    nu_rel, v_c_dot_b = _relative_velocity(R_t, nu, env[E_VC : E_VC + 3], env[E_AC : E_AC + 3])
    tau = _hydro(P.tree_M_rb, P.tree_M_a, P.tree_D_l, P.tree_D_nl, nu, nu_rel, v_c_dot_b)
    _froude_krylov(tau, P.tree_fk_mass, R_t, env[E_AC : E_AC + 3])
    f_n = env[E_PUSH : E_PUSH + 3].copy()
    f_n[2] += P.tree_W0
    tau[0:3] += mtv(R_t, f_n)
    p_att_n = x[0:3] + mv(R_t, P.tree_r_att)
    v_att_n = attachment_velocity_n(x, R_t, P.tree_r_att)
    f_wire_b = mtv(R_t, wire_force_damped_n(p_att_n, v_att_n, env, P.tree_W0))
    tau[0:3] += f_wire_b
    tau[3:6] += cross(P.tree_r_att, f_wire_b)
    if env[E_LAND] > 0.0:
        tau += contact_wrench(x, env, P, R_t)
    return tau


@njit(**JIT)
def rov_wrench(
    x: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays, R_r: np.ndarray
) -> np.ndarray:
    """Restoring, thruster and hydrodynamic forces on the ROV, ROV axes (eq. 2.14)."""
    eta, nu = x[12:18], x[18:24]
    nu_rel, v_c_dot_b = _relative_velocity(R_r, nu, env[E_VC : E_VC + 3], env[E_AC : E_AC + 3])
    tau = _hydro(P.rov_M_rb, P.rov_M_a, P.rov_D_l, P.rov_D_nl, nu, nu_rel, v_c_dot_b)
    _froude_krylov(tau, P.rov_fk_mass, R_r, env[E_AC : E_AC + 3])
    tau -= gvect(P.rov_W, P.rov_B, eta[4], eta[3], P.rov_r_cg, P.rov_r_cb)
    tau += mv(P.thr_T, thrust_from_speed(n_rps, P.thr_k_pos, P.thr_k_neg, P.thr_n_max))
    return tau


@njit(**JIT)
def rhs(x: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays) -> np.ndarray:
    """Time derivative of the plant state. Does not modify its arguments."""
    xdot = np.zeros(N_STATE)
    R_t = Rzyx(x[3], x[4], x[5])
    tau_t = tree_wrench(x, env, P, R_t)
    if P.has_rov:
        R_r = Rzyx(x[15], x[16], x[17])
        tau_r = rov_wrench(x, n_rps, env, P, R_r)
        if env[E_GRIP] > 0.0:
            w_rov, w_tree = coupling_wrench(x, P, R_t, R_r)
            tau_r += w_rov
            tau_t += w_tree
        xdot[12:18] = _kinematics(x[12:18], x[18:24], R_r)
        xdot[18:24] = mv(P.rov_M_inv, tau_r)
    xdot[0:6] = _kinematics(x[0:6], x[6:12], R_t)
    xdot[6:12] = tree_acceleration(x, tau_t, env, P, R_t)
    return xdot


@njit(**JIT)
def rk4_step(
    x: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays, dt: float
) -> np.ndarray:
    """One classical Runge-Kutta step with inputs held over the step.

    The stages share one work array and the sums are explicit loops (no temporary arrays);
    each element is computed with the same operations in the same order as the vector form
    ``x + (dt / 6) * (k1 + 2 k2 + 2 k3 + k4)``, so the result is bit for bit the same."""
    n = x.shape[0]
    h2 = 0.5 * dt
    xs = np.empty(n)
    k1 = rhs(x, n_rps, env, P)
    for i in range(n):
        xs[i] = x[i] + h2 * k1[i]
    k2 = rhs(xs, n_rps, env, P)
    for i in range(n):
        xs[i] = x[i] + h2 * k2[i]
    k3 = rhs(xs, n_rps, env, P)
    for i in range(n):
        xs[i] = x[i] + dt * k3[i]
    k4 = rhs(xs, n_rps, env, P)
    h6 = dt / 6.0
    for i in range(n):
        xs[i] = x[i] + h6 * (((k1[i] + 2.0 * k2[i]) + 2.0 * k3[i]) + k4[i])
    return xs


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
    for k in range(n):
        x = rk4_step(x, n_rps, env_series[k], P, dt)
        if not np.all(np.isfinite(x)):
            return states, k
        states[k] = x
    return states, n
