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
E_AC = 3  # 3:6 water acceleration, NED [m/s^2]
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
N_ENV = 22

# Contact outcome codes (see contact_state)
CONTACT_NONE, CONTACT_GUIDED, CONTACT_ON_POSTS, CONTACT_LANDED = 0, 1, 2, 3


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
    dock_tolerance: float  # capture radius of a funnel around its post [m]
    dock_skirt: float  # outer radius of a funnel's skirt: a miss inside it lands on the post [m]
    tree_half_height: float  # [m]
    tree_footprint: np.ndarray  # (2,) length and width of the tree's bottom [m]
    contact_k: float  # vertical contact stiffness [N/m]
    contact_c: float  # vertical contact damping [N s/m]
    guide_k: float  # post guidance stiffness per funnel [N/m]
    guide_c: float  # post guidance damping per funnel [N s/m]
    friction_mu: float  # friction coefficient on the landing surface / post tops [-]


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
    )


def _contact_params(ps: ParameterSet) -> dict:
    """Contact with the docking frame: stiff enough that the tree sinks 2 % of its height into
    the contact under its own weight, damped at zeta 0.7 on the tree's heave mass; the
    resulting contact mode (about 9 rad/s full scale, 15 rad/s model scale) is resolved by RK4
    at 100 Hz. The posts guide the funnels with a spring of 5 % of the height per W0, damped
    at zeta 0.7."""
    layout = ps.spec.docking.to_numeric()
    m_heave = ps.tree.M_rb[2, 2] + ps.tree.M_a[2, 2]
    height = float(ps.tree.dimensions_m[2])
    k = ps.tree.submerged_weight_newton / (0.02 * height)
    omega = (k / m_heave) ** 0.5
    # a post in its funnel: the same stiffness sideways, damped like the support
    k_guide = ps.tree.submerged_weight_newton / (0.05 * height)
    m_surge = ps.tree.M_rb[0, 0] + ps.tree.M_a[0, 0]
    n_posts = layout.post_xy_m.shape[0]
    return dict(
        dock_xy=np.ascontiguousarray(layout.post_xy_m, dtype=float),
        dock_post_height=float(layout.post_height_m),
        dock_tolerance=float(layout.tolerance_m),
        dock_skirt=float(3.0 * layout.funnel_mouth_radius_m),
        tree_half_height=height / 2.0,
        tree_footprint=np.array(ps.tree.dimensions_m[0:2], dtype=float),
        contact_k=float(k),
        contact_c=float(2.0 * 0.7 * omega * m_heave),
        guide_k=float(k_guide),
        guide_c=float(2.0 * 0.7 * (k_guide * m_surge / n_posts) ** 0.5),
        friction_mu=0.3,
    )


@njit(**JIT)
def _hydro(M_rb, M_a, D_l, D_nl, nu, nu_r, nu_c_dot_lin):
    """Rigid-body Coriolis, added-mass Coriolis, damping and the added-mass part of the water's
    acceleration, as forces on the right-hand side (eq. 2.11-2.12)."""
    tau = -coriolis_force(M_rb, nu) - coriolis_force(M_a, nu_r)
    for i in range(6):
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
    v_c_dot_b = mtv(R_nb, a_c_n) - cross(nu[3:6], v_c_b)
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


@njit(**JIT)
def contact_state(x: np.ndarray, env: np.ndarray, P: PlantArrays) -> tuple[int, float, float]:
    """Where the tree's bottom is against the docking frame: (code, penetration [m], largest
    funnel miss [m]). GUIDED: every funnel is within the capture tolerance of its post and the
    bottom is below the post tops (the posts steer it); ON_POSTS: a funnel is off its post but
    over it and the bottom reached the post tops; LANDED: the bottom reached the landing
    surface (or the seabed away from the posts)."""
    if env[E_LAND] <= 0.0:
        return CONTACT_NONE, 0.0, 0.0
    bottom = x[2] + P.tree_half_height
    post_top = env[E_LAND] - P.dock_post_height
    c, s = np.cos(x[5]), np.sin(x[5])
    cf, sf = np.cos(env[E_FRAME_PSI]), np.sin(env[E_FRAME_PSI])
    worst = 0.0
    nearest = 1e9
    for i in range(P.dock_xy.shape[0]):
        fx = x[0] + c * P.dock_xy[i, 0] - s * P.dock_xy[i, 1]
        fy = x[1] + s * P.dock_xy[i, 0] + c * P.dock_xy[i, 1]
        px = env[E_FRAME] + cf * P.dock_xy[i, 0] - sf * P.dock_xy[i, 1]
        py = env[E_FRAME + 1] + sf * P.dock_xy[i, 0] + cf * P.dock_xy[i, 1]
        d = np.sqrt((fx - px) ** 2 + (fy - py) ** 2)
        worst = max(worst, d)
        nearest = min(nearest, d)
    if bottom <= post_top:
        return CONTACT_NONE, 0.0, worst
    # captured: within the tolerance at the post tops, or already deeper in the funnels than a
    # tree standing on the post tops ever sinks (three times its static contact penetration,
    # 0.02 of its height): a state reachable only through the funnels, so no memory is needed
    deep = bottom - post_top > 0.06 * 2.0 * P.tree_half_height
    if worst <= P.dock_tolerance or (deep and worst <= P.dock_skirt):
        pen = bottom - env[E_LAND]
        return (CONTACT_LANDED if pen > 0.0 else CONTACT_GUIDED), pen, worst
    if nearest <= P.dock_skirt:
        return CONTACT_ON_POSTS, bottom - post_top, worst
    pen = bottom - env[E_LAND]
    return (CONTACT_LANDED if pen > 0.0 else CONTACT_NONE), pen, worst


@njit(**JIT)
def contact_force_n(x: np.ndarray, env: np.ndarray, P: PlantArrays) -> np.ndarray:
    """Force (NED, 0:3) and moment (NED axes, about the centre, 3:6) of the frame on the tree:
    a stiff, damped support under the bottom with smooth Coulomb friction on it, and, while the
    funnels ride down the posts, a guidance spring pulling each funnel onto its post."""
    out = np.zeros(6)
    code, pen, worst = contact_state(x, env, P)
    if code == CONTACT_NONE:
        return out
    R = Rzyx(x[3], x[4], x[5])
    v_n = mv(R, x[6:9])
    captured = worst <= P.dock_skirt  # guided or landed inside the funnels
    if captured and (code == CONTACT_GUIDED or code == CONTACT_LANDED):
        c, s = np.cos(x[5]), np.sin(x[5])
        cf, sf = np.cos(env[E_FRAME_PSI]), np.sin(env[E_FRAME_PSI])
        for i in range(P.dock_xy.shape[0]):
            ax_, ay = (
                c * P.dock_xy[i, 0] - s * P.dock_xy[i, 1],
                s * P.dock_xy[i, 0] + c * P.dock_xy[i, 1],
            )
            px = env[E_FRAME] + cf * P.dock_xy[i, 0] - sf * P.dock_xy[i, 1]
            py = env[E_FRAME + 1] + sf * P.dock_xy[i, 0] + cf * P.dock_xy[i, 1]
            vfx = v_n[0] - x[11] * ay
            vfy = v_n[1] + x[11] * ax_
            fx = -P.guide_k * (x[0] + ax_ - px) - P.guide_c * vfx
            fy = -P.guide_k * (x[1] + ay - py) - P.guide_c * vfy
            out[0] += fx
            out[1] += fy
            out[5] += ax_ * fy - ay * fx
    if pen > 0.0:
        normal = P.contact_k * pen + P.contact_c * v_n[2]
        if normal > 0.0:
            out[2] -= normal
            speed = np.sqrt(v_n[0] ** 2 + v_n[1] ** 2)
            scale = P.friction_mu * normal * np.tanh(speed / 0.005) / max(speed, 1e-9)
            out[0] -= scale * v_n[0]
            out[1] -= scale * v_n[1]
            r_turn = np.tanh(x[11] / 0.002)
            out[5] -= P.friction_mu * normal * 0.5 * P.tree_half_height * r_turn
            # a flat bottom on a flat support resists roll and pitch: the support's stiffness
            # spread over the footprint gives k W^2 / 12 (roll) and k L^2 / 12 (pitch)
            roll_k = P.tree_footprint[1] ** 2 / 12.0
            pitch_k = P.tree_footprint[0] ** 2 / 12.0
            out[3] -= roll_k * (P.contact_k * x[3] + P.contact_c * x[9])
            out[4] -= pitch_k * (P.contact_k * x[4] + P.contact_c * x[10])
    return out


@njit(**JIT)
def tree_wrench(x: np.ndarray, env: np.ndarray, P: PlantArrays, R_t: np.ndarray) -> np.ndarray:
    """Net weight, wire, push and hydrodynamic forces on the tree, tree axes (eq. 2.44)."""
    nu = x[6:12]
    nu_rel, v_c_dot_b = _relative_velocity(R_t, nu, env[E_VC : E_VC + 3], env[E_AC : E_AC + 3])
    tau = _hydro(P.tree_M_rb, P.tree_M_a, P.tree_D_l, P.tree_D_nl, nu, nu_rel, v_c_dot_b)
    f_n = env[E_PUSH : E_PUSH + 3].copy()
    f_n[2] += P.tree_W0
    tau[0:3] += mtv(R_t, f_n)
    p_att_n = x[0:3] + mv(R_t, P.tree_r_att)
    f_wire_b = mtv(R_t, wire_force_n(p_att_n, env, P.tree_W0))
    tau[0:3] += f_wire_b
    tau[3:6] += cross(P.tree_r_att, f_wire_b)
    if env[E_LAND] > 0.0:
        contact = contact_force_n(x, env, P)
        # the support acts at the bottom: its horizontal friction also tilts the tree
        f_b = mtv(R_t, contact[0:3])
        tau[0:3] += f_b
        bottom = np.array([0.0, 0.0, P.tree_half_height])
        tau[3:6] += cross(bottom, f_b) + mtv(R_t, contact[3:6])
    return tau


@njit(**JIT)
def rov_wrench(
    x: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays, R_r: np.ndarray
) -> np.ndarray:
    """Restoring, thruster and hydrodynamic forces on the ROV, ROV axes (eq. 2.14)."""
    eta, nu = x[12:18], x[18:24]
    nu_rel, v_c_dot_b = _relative_velocity(R_r, nu, env[E_VC : E_VC + 3], env[E_AC : E_AC + 3])
    tau = _hydro(P.rov_M_rb, P.rov_M_a, P.rov_D_l, P.rov_D_nl, nu, nu_rel, v_c_dot_b)
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
    xdot[6:12] = mv(P.tree_M_inv, tau_t)
    return xdot


@njit(**JIT)
def rk4_step(
    x: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays, dt: float
) -> np.ndarray:
    """One classical Runge-Kutta step with inputs held over the step."""
    k1 = rhs(x, n_rps, env, P)
    k2 = rhs(x + 0.5 * dt * k1, n_rps, env, P)
    k3 = rhs(x + 0.5 * dt * k2, n_rps, env, P)
    k4 = rhs(x + dt * k3, n_rps, env, P)
    return x + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


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
