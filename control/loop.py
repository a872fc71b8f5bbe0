"""The closed loop: plant, sensors, signal checks, observer, reference, controller, allocation.

One compiled kernel (``run_chunk``) advances everything for a chunk of plant steps with the
mission's target held; Python handles commands (targets, gains, modes) between chunks, so the
loop stays fast and commands are applied only between steps. The fixed order within a step is

    sensors -> quality checks -> observer (EKF) -> reference model -> controller (supervisor:
    tree PID, free-ROV PID or the pilot's demand) -> thrust allocation -> thrusters -> plant (RK4)

Every step writes one row of the log (see the ``L_*`` column indices).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from control import ekf, pid, quality, refkernel
from control.allocation import _priority_forces
from control.columns import (
    L_ACCEPT,
    L_BIAS,
    L_CRANE,
    L_DETA_D,
    L_ETA_D,
    L_ETA_HAT,
    L_F,
    L_MODE,
    L_N,
    L_NIS,
    L_NU_HAT,
    L_ROV,
    L_ROV_NU,
    L_T,
    L_TAU_ACH,
    L_TAU_ROV,
    L_TAU_TREE,
    L_TENSION,
    L_TERMS,
    L_TREE,
    L_TREE_NU,
    L_UTIL,
    L_WIRE_LEN,
    L_Y,
    M_MAX,
    N_LOG,
)  # the log row is declared in control.columns
from sim import plant, sensors, thrusters
from sim.gnc import JIT, JIT_NOALLOC, Rzyx_into, mv3_into

EYE3 = np.eye(3)
# the EKF's measured state rows (constant, so no array is made per correction)
_ROWS_PSI = np.array([2])
_ROWS_NE = np.array([0, 1])
_ROWS_R = np.array([5])
_ROWS_UV = np.array([3, 4])


@njit(**JIT)
def _matvec(A: np.ndarray, v: np.ndarray) -> np.ndarray:
    """A @ v for the small matrices of the loop, by a plain loop (no BLAS call)."""
    out = np.empty(A.shape[0])
    for i in range(A.shape[0]):
        acc = 0.0
        for j in range(A.shape[1]):
            acc += A[i, j] * v[j]
        out[i] = acc
    return out


# --- modes, allocation kinds, reference kinds ---
MODE_TREE, MODE_FREE, MODE_MANUAL = 0, 1, 2
ALLOC_PINV, ALLOC_PRIORITY, ALLOC_EXTERNAL = 0, 1, 2
REF_FIRST, REF_THIRD = 0, 1
MANUAL_I_BAND_M, MANUAL_I_BAND_RAD = 0.5, np.radians(3.0)
"""Flown by hand, a hold integrates only within this of its set point (position and depth
[m], heading [rad]): the overshoot after a stick released at speed does not wind it up."""

# --- controller state vector layout (flat float array) ---
CS_I = 0  # 0:3 tree integral, NED forces and yaw moment
CS_E = 3  # 3:6 last pose error
CS_DE = 6  # 6:9 last error rate
CS_REF = 9  # 9:18 reference state (see control.reference)
CS_TAU = 18  # 18:24 last commanded ROV wrench (6)
CS_FI = 24  # 24:28 free-ROV integral
CS_FSP = 28  # 28:32 free-ROV set point [north, east, down, psi]
CS_MODE = 32
CS_LAST_MODE = 33
CS_ALLOC_F = 34  # 34:34+M_MAX externally allocated thruster forces (ALLOC_EXTERNAL)
CS_PILOT = CS_ALLOC_F + M_MAX  # 4: the pilot's demand [X, Y, Z, N] in the ROV's axes [N, N m]
CS_HOLD = CS_PILOT + 4  # 2: the pilot's holds (1.0 on): auto-heading, auto-depth
N_CS = CS_HOLD + 2


class ControlArrays(NamedTuple):
    """Compiled configuration of the control system."""

    feedback_ekf: bool
    use_ff: bool
    ref_kind: int
    ref_params: np.ndarray  # (5, 3): see control.refkernel
    Kp: np.ndarray
    Ki: np.ndarray
    Kd: np.ndarray
    M: np.ndarray
    M_inv: np.ndarray
    D_l: np.ndarray
    D_nl: np.ndarray
    k_h: float
    p_eq: np.ndarray
    A: np.ndarray
    A_inv: np.ndarray
    i_limit: np.ndarray
    heave_newton: float
    r_mount: np.ndarray
    psi_rel: float
    alloc_kind: int
    pinv_T: np.ndarray
    pinv_rows: np.ndarray
    prio_A: np.ndarray
    prio_D: np.ndarray
    prio_R: np.ndarray
    prio_rows: np.ndarray
    f_lo: np.ndarray
    f_hi: np.ndarray
    alloc_tol: float
    k_pos: np.ndarray
    k_neg: np.ndarray
    n_max: np.ndarray
    T6: np.ndarray
    rov_to_tree: np.ndarray
    GQG: np.ndarray
    T_b: np.ndarray
    r_pos: float
    r_psi: float
    r_dvl: float
    r_gyro: float
    q_lo: np.ndarray
    q_hi: np.ndarray
    q_wild: np.ndarray
    q_rate: np.ndarray
    q_frozen: np.ndarray
    q_var: np.ndarray
    free_Kp: np.ndarray
    free_Ki: np.ndarray
    free_Kd: np.ndarray


class QualityState(NamedTuple):
    """Mutable state of the signal checks (see control.quality)."""

    last: np.ndarray  # (11,)
    last_t: np.ndarray  # (5,)
    repeat: np.ndarray  # (5,) int
    hist: np.ndarray  # (11, WINDOW)
    counters: np.ndarray  # (5, 4) int


@njit(inline="always", **JIT)
def allocate(tau6: np.ndarray, C: ControlArrays) -> np.ndarray:
    """Thruster forces for an ROV wrench (pinv or priority, see control.allocation)."""
    if C.alloc_kind == ALLOC_PRIORITY:
        rows = np.empty(C.prio_rows.shape[0])
        for i in range(rows.shape[0]):
            rows[i] = tau6[C.prio_rows[i]]
        return _priority_forces(C.prio_A, C.prio_D, C.prio_R, rows, C.f_lo, C.f_hi, C.alloc_tol)
    m = C.pinv_T.shape[0]
    f = np.zeros(m)
    for i in range(m):
        s = 0.0
        for j in range(C.pinv_rows.shape[0]):
            s += C.pinv_T[i, j] * tau6[C.pinv_rows[j]]
        f[i] = min(max(s, C.f_lo[i]), C.f_hi[i])
    return f


@njit(inline="always", **JIT)
def speeds_from_forces(f: np.ndarray, C: ControlArrays) -> np.ndarray:
    """Propeller speeds for thruster forces: the inverse thruster model (sim.thrusters)."""
    return thrusters.speed_from_thrust(f, C.k_pos, C.k_neg, C.n_max)


@njit(inline="always", **JIT)
def tree_measurements(y: np.ndarray, psi_hat: float, C: ControlArrays):
    """Move the ROV's measurements to the tree's origin (eq. 3.4-3.6), with the configured
    mounting vector r and relative heading. Returns (north_east (2), psi, u_v (2), r)."""
    c, s = np.cos(psi_hat), np.sin(psi_hat)
    r = C.r_mount
    ne = np.empty(2)
    ne[0] = y[0] - (c * r[0] - s * r[1])
    ne[1] = y[1] - (s * r[0] + c * r[1])
    psi = y[4] - C.psi_rel
    cr, sr = np.cos(C.psi_rel), np.sin(C.psi_rel)
    u_t = cr * y[5] - sr * y[6]
    v_t = sr * y[5] + cr * y[6]
    rate = y[10]
    uv = np.empty(2)
    uv[0] = u_t + rate * r[1]
    uv[1] = v_t - rate * r[0]
    return ne, psi, uv, rate


@njit(**JIT)
def _truth_tree(x: np.ndarray):
    """Perfect feedback: the tree's [north, east, psi] and their NED rates."""
    eta = np.array([x[0], x[1], x[5]])
    c, s = np.cos(x[5]), np.sin(x[5])
    deta = np.array([c * x[6] - s * x[7], s * x[6] + c * x[7], x[11]])
    return eta, deta


@njit(**JIT)
def _rov_pose(x: np.ndarray, y: np.ndarray, use_truth: bool):
    """The ROV's [north, east, down, psi] and rates for the free-ROV controller."""
    eta4 = np.empty(4)
    if use_truth:  # pose and body velocities [u, v, w, r] of the plant state
        eta4[0:3] = x[12:15]
        eta4[3] = x[17]
        u, v, w, r = x[18], x[19], x[20], x[23]
    else:  # fix (north, east), depth sensor, compass, DVL, gyro
        eta4[0:2] = y[0:2]
        eta4[2] = y[3]
        eta4[3] = y[4]
        u, v, w, r = y[5], y[6], y[7], y[10]
    c, s = np.cos(eta4[3]), np.sin(eta4[3])
    deta4 = np.array([c * u - s * v, s * u + c * v, w, r])
    return eta4, deta4


@njit(inline="always", **JIT)
def _observe(
    t: float,
    y: np.ndarray,
    fresh: np.ndarray,
    xhat: np.ndarray,
    P: np.ndarray,
    C: ControlArrays,
    Q: QualityState,
    dt: float,
    log_row: np.ndarray,
):
    """Signal checks, then EKF correction with each accepted fresh sample, then prediction."""
    accepted = np.zeros(5, dtype=np.bool_)
    for k in range(5):
        if fresh[k]:
            accepted[k] = quality.check_sample(
                k,
                y,
                t,
                Q.last,
                Q.last_t,
                Q.repeat,
                Q.hist,
                Q.counters,
                C.q_lo,
                C.q_hi,
                C.q_wild,
                C.q_rate,
                C.q_frozen,
                C.q_var,
                sensors.Y_SENSOR,
            )
    ne, psi_m, uv, rate = tree_measurements(y, xhat[2], C)
    if accepted[sensors.COMPASS]:
        z1 = np.empty(1)
        z1[0] = psi_m
        r1 = np.empty(1)
        r1[0] = C.r_psi
        xhat, P, nis = ekf.correct(xhat, P, z1, _ROWS_PSI, r1, 0)
        log_row[L_NIS + 2] = nis[0]
    if accepted[sensors.POSITION]:
        ne, psi_m, uv, rate = tree_measurements(y, xhat[2], C)
        r2 = np.empty(2)
        r2[0] = r2[1] = C.r_pos
        xhat, P, nis = ekf.correct(xhat, P, ne, _ROWS_NE, r2, -1)
        log_row[L_NIS] = nis[0]
        log_row[L_NIS + 1] = nis[1]
    if accepted[sensors.GYRO]:
        z1 = np.empty(1)
        z1[0] = rate
        r1 = np.empty(1)
        r1[0] = C.r_gyro
        xhat, P, _ = ekf.correct(xhat, P, z1, _ROWS_R, r1, -1)
    if accepted[sensors.DVL]:
        r2 = np.empty(2)
        r2[0] = r2[1] = C.r_dvl
        xhat, P, _ = ekf.correct(xhat, P, uv, _ROWS_UV, r2, -1)
    for k in range(5):
        log_row[L_ACCEPT + k] = 1.0 if accepted[k] else 0.0
    return xhat, P


@njit(**JIT)
def manual_step(x: np.ndarray, y: np.ndarray, cs: np.ndarray, C: ControlArrays, dt: float):
    """Flown by hand: the pilot's demand (``cs[CS_PILOT:+4]``, ROV axes [X, Y, Z, N]) on the
    axes the pilot is using; the free-ROV station keeping on the others, with its set point at
    the pose where the pilot let go (horizontal position always; heading and depth only with
    the auto-heading and auto-depth holds on, else a released stick is zero thrust). While an
    axis is under the pilot its set point follows the ROV and its integral (what holds against
    the current) is frozen. The step that enters this mode starts the holds where the ROV is,
    their integral set so the thrust does not jump (bumpless, as the free mode). Writes
    ``cs`` in place; returns the ROV wrench (6,)."""
    eta4, deta4 = _rov_pose(x, y, not C.feedback_ekf)
    if int(cs[CS_LAST_MODE]) != MODE_MANUAL:
        cs[CS_FSP : CS_FSP + 4] = eta4
        cs[CS_FI : CS_FI + 4] = pid.bumpless_free_integral(
            cs[CS_TAU : CS_TAU + 6].copy(), eta4, deta4, eta4, C.free_Kp, C.free_Kd
        )
    d = cs[CS_PILOT : CS_PILOT + 4]
    # which of [north+east, down, psi] the pilot flies now
    flown = np.array(
        [
            d[0] != 0.0 or d[1] != 0.0,
            d[2] != 0.0 or cs[CS_HOLD + 1] < 0.5,
            d[3] != 0.0 or cs[CS_HOLD] < 0.5,
        ]
    )
    if flown[0]:
        cs[CS_FSP : CS_FSP + 2] = eta4[0:2]
    if flown[1]:
        cs[CS_FSP + 2] = eta4[2]
    if flown[2]:
        cs[CS_FSP + 3] = eta4[3]
    tau, fi, e4 = pid.free_rov_pid(
        eta4,
        deta4,
        cs[CS_FSP : CS_FSP + 4].copy(),
        cs[CS_FI : CS_FI + 4].copy(),
        C.free_Kp,
        C.free_Ki,
        C.free_Kd,
        dt,
    )
    # conditional integration: a hold catching the ROV after a fast release does not wind up
    band = np.array([MANUAL_I_BAND_M, MANUAL_I_BAND_M, MANUAL_I_BAND_M, MANUAL_I_BAND_RAD])
    for k in range(4):
        if abs(e4[k]) > band[k]:
            fi[k] = cs[CS_FI + k]
    if flown[0]:
        tau[0], tau[1] = d[0], d[1]
        fi[0:2] = cs[CS_FI : CS_FI + 2]
    if flown[1]:
        tau[2] = d[2]
        fi[2] = cs[CS_FI + 2]
    if flown[2]:
        tau[5] = d[3]
        fi[3] = cs[CS_FI + 3]
    cs[CS_FI : CS_FI + 4] = fi
    return tau


@njit(inline="always", **JIT)
def control_step(
    t: float,
    x: np.ndarray,
    y: np.ndarray,
    fresh: np.ndarray,
    xhat: np.ndarray,
    Pc: np.ndarray,
    cs: np.ndarray,
    target: np.ndarray,
    C: ControlArrays,
    Q: QualityState,
    dt: float,
    log_row: np.ndarray,
):
    """Observer, reference, supervisor and controller for one step. Returns
    (tau_rov6, xhat, Pc, cs). ``cs`` is a fresh copy, updated."""
    cs = cs.copy()
    if C.feedback_ekf:
        xhat, Pc = _observe(t, y, fresh, xhat, Pc, C, Q, dt, log_row)
        eta = xhat[0:3].copy()
        c, s = np.cos(eta[2]), np.sin(eta[2])
        deta = np.array([c * xhat[3] - s * xhat[4], s * xhat[3] + c * xhat[4], xhat[5]])
    else:
        eta, deta = _truth_tree(x)
    mode = int(cs[CS_MODE])
    ref = cs[CS_REF : CS_REF + 9].copy()
    if mode == MODE_TREE and int(cs[CS_LAST_MODE]) != MODE_TREE:
        ref[:] = 0.0
        ref[0:3] = eta
        cs[CS_I : CS_I + 3] = pid.bumpless_tree_integral(
            np.array([cs[CS_TAU], cs[CS_TAU + 1], cs[CS_TAU + 5]]),
            eta,
            deta,
            eta,
            np.zeros(3),
            np.zeros(3),
            C.Kp,
            C.Kd,
            C.use_ff,
            C.M,
            C.D_l,
            C.D_nl,
            C.k_h,
            C.p_eq,
            C.A_inv,
        )
    ref = refkernel.reference_step(C.ref_kind, ref, target, dt, C.ref_params)
    cs[CS_REF : CS_REF + 9] = ref
    tau6 = np.zeros(6)
    if mode == MODE_TREE:
        tau_tree, i_next, terms, e, de = pid.tree_pid(
            eta,
            deta,
            ref[0:3],
            ref[3:6],
            ref[6:9],
            cs[CS_I : CS_I + 3].copy(),
            C.Kp,
            C.Ki,
            C.Kd,
            C.use_ff,
            C.M,
            C.D_l,
            C.D_nl,
            C.k_h,
            C.p_eq,
            EYE3,
            EYE3,
            C.i_limit,
            dt,
        )
        cs[CS_I : CS_I + 3] = i_next
        cs[CS_E : CS_E + 3] = e
        cs[CS_DE : CS_DE + 3] = de
        # allocation works on the tree's origin (see closed_loop.system_thruster_config)
        tau6[0] = tau_tree[0]
        tau6[1] = tau_tree[1]
        tau6[2] = C.heave_newton
        tau6[5] = tau_tree[2]
        tau3 = _matvec(C.A, tau_tree)
        log_row[L_TAU_ROV] = tau3[0]
        log_row[L_TAU_ROV + 1] = tau3[1]
        log_row[L_TAU_ROV + 2] = C.heave_newton
        log_row[L_TAU_ROV + 3] = 0.0
        log_row[L_TAU_ROV + 4] = 0.0
        log_row[L_TAU_ROV + 5] = tau3[2]
        log_row[L_TAU_TREE : L_TAU_TREE + 3] = tau_tree
        for j in range(4):
            log_row[L_TERMS + 3 * j : L_TERMS + 3 * j + 3] = terms[j]
    elif mode == MODE_MANUAL:
        tau_rov6 = manual_step(x, y, cs, C, dt)
        log_row[L_TAU_ROV : L_TAU_ROV + 6] = tau_rov6
        tau6 = _matvec(C.rov_to_tree, tau_rov6)
    else:
        eta4, deta4 = _rov_pose(x, y, not C.feedback_ekf)
        if int(cs[CS_LAST_MODE]) != MODE_FREE:
            cs[CS_FSP : CS_FSP + 4] = eta4
            cs[CS_FI : CS_FI + 4] = pid.bumpless_free_integral(
                cs[CS_TAU : CS_TAU + 6].copy(), eta4, deta4, eta4, C.free_Kp, C.free_Kd
            )
        tau_rov6, fi, _ = pid.free_rov_pid(
            eta4,
            deta4,
            cs[CS_FSP : CS_FSP + 4].copy(),
            cs[CS_FI : CS_FI + 4].copy(),
            C.free_Kp,
            C.free_Ki,
            C.free_Kd,
            dt,
        )
        cs[CS_FI : CS_FI + 4] = fi
        log_row[L_TAU_ROV : L_TAU_ROV + 6] = tau_rov6
        tau6 = _matvec(C.rov_to_tree, tau_rov6)
    cs[CS_LAST_MODE] = mode
    cs[CS_TAU : CS_TAU + 6] = log_row[L_TAU_ROV : L_TAU_ROV + 6]
    log_row[L_ETA_HAT : L_ETA_HAT + 3] = eta
    if C.feedback_ekf:
        log_row[L_NU_HAT : L_NU_HAT + 3] = xhat[3:6]
    else:
        log_row[L_NU_HAT] = x[6]
        log_row[L_NU_HAT + 1] = x[7]
        log_row[L_NU_HAT + 2] = x[11]
    log_row[L_BIAS : L_BIAS + 3] = xhat[6:9]
    log_row[L_ETA_D : L_ETA_D + 3] = ref[0:3]
    log_row[L_DETA_D : L_DETA_D + 3] = ref[3:6]
    log_row[L_MODE] = mode
    return tau6, xhat, Pc, cs


@njit(inline="always", **JIT)
def finish_step(
    x: np.ndarray,
    f: np.ndarray,
    env_k: np.ndarray,
    xhat: np.ndarray,
    Pc: np.ndarray,
    C: ControlArrays,
    P: plant.PlantArrays,
    dt: float,
    t_next: float,
    held_y: np.ndarray,
    log_row: np.ndarray,
    work: plant.PlantWork,
):
    """Thrusters, plant step and observer prediction, given the allocated forces f, and the
    row's plant columns. Advances the plant state ``x`` in place (through ``work``, no
    allocation) and returns (xhat, Pc). The one step body after allocation: the compiled
    chunk and the Python chunk (QP allocation) both end every step here."""
    n = speeds_from_forces(f, C)
    ach = _matvec(C.T6, f)
    m = f.shape[0]
    for i in range(m):
        lim = C.f_hi[i] if f[i] >= 0.0 else -C.f_lo[i]
        log_row[L_F + i] = f[i]
        log_row[L_N + i] = n[i]
        log_row[L_UTIL + i] = min(abs(f[i]) / lim, 1.0)
    log_row[L_TAU_ACH : L_TAU_ACH + 6] = ach
    plant.rk4_step_into(x, x, n, env_k, P, dt, work)
    if C.feedback_ekf:
        # the observer's input: the achieved wrench moved to the tree (eq. 3.6)
        ach3 = np.empty(3)
        ach3[0], ach3[1], ach3[2] = ach[0], ach[1], ach[5]
        tau_tree = _matvec(C.A_inv, ach3)
        mode = int(log_row[L_MODE])
        on_tree = mode == MODE_TREE or (mode == MODE_MANUAL and env_k[plant.E_GRIP] > 0.5)
        if not on_tree:
            tau_tree[:] = 0.0
        xhat, Pc = ekf.predict(
            xhat, Pc, tau_tree, dt, C.M_inv, C.M, C.D_l, C.D_nl, C.k_h, C.p_eq, C.T_b, C.GQG
        )
    write_plant_row(log_row, t_next, x, held_y, env_k, P, work)
    return xhat, Pc


@njit(**JIT_NOALLOC)
def write_plant_row(
    row: np.ndarray,
    t: float,
    x: np.ndarray,
    y: np.ndarray,
    env_k: np.ndarray,
    P: plant.PlantArrays,
    work: plant.PlantWork,
) -> None:
    """Time, plant state, held sensor values and the site into a log row (``work``: the
    plant's work space, used between steps). Allocates nothing."""
    row[L_T] = t
    for i in range(6):
        row[L_TREE + i] = x[i]
        row[L_TREE_NU + i] = x[6 + i]
        row[L_ROV + i] = x[12 + i]
        row[L_ROV_NU + i] = x[18 + i]
    for i in range(11):
        row[L_Y + i] = y[i]
    log_site(row, x, env_k, P, work)


@njit(inline="always", **JIT_NOALLOC)
def log_site(
    row: np.ndarray, x: np.ndarray, env_k: np.ndarray, P: plant.PlantArrays, work: plant.PlantWork
) -> None:
    """The vessel's crane tip, the wire's payout and its tension at the tree, into a log row."""
    row[L_CRANE] = env_k[plant.E_CT]
    row[L_CRANE + 1] = env_k[plant.E_CT + 1]
    row[L_WIRE_LEN] = env_k[plant.E_LREST]
    R_t = work.mat[plant.M_RT]
    cphi, sphi = np.cos(x[3]), np.sin(x[3])
    Rzyx_into(R_t, cphi, sphi, np.cos(x[4]), np.sin(x[4]), np.cos(x[5]), np.sin(x[5]))
    p_att = work.vec[plant.V_A, 0:3]
    mv3_into(p_att, R_t, P.tree_r_att)
    for i in range(3):
        p_att[i] += x[i]
    v_att = work.vec[plant.V_B, 0:3]
    plant.attachment_velocity_into(v_att, x, R_t, P.tree_r_att, work.vec[plant.V_C, 0:3])
    f = work.vec[plant.V_D, 0:3]
    plant.wire_force_damped_into(f, p_att, v_att, env_k, P.tree_W0)
    row[L_TENSION] = np.sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])


@njit(**JIT)
def run_chunk(
    k0: int,
    x: np.ndarray,
    held_y: np.ndarray,
    xhat: np.ndarray,
    Pc: np.ndarray,
    cs: np.ndarray,
    target: np.ndarray,
    env: np.ndarray,
    noise: np.ndarray,
    fresh: np.ndarray,
    P: plant.PlantArrays,
    C: ControlArrays,
    Q: QualityState,
    dt: float,
):
    """Advance len(env) steps with the target held. Returns
    (x, held_y, xhat, Pc, cs, log (n, N_LOG), n_done); n_done < n when the plant diverged."""
    n = env.shape[0]
    log = np.zeros((n, N_LOG))
    # the state and the held sensor values are advanced in place: copies, so the caller's
    # arrays are left as they were
    x = x.copy()
    held_y = held_y.copy()
    work = plant.make_work(P.thr_T.shape[1])
    for j in range(n):
        k = k0 + j
        t = k * dt
        row = log[j]
        sensors.sample_into(held_y, x, held_y, noise[j], fresh[j], sensors.Y_SENSOR)
        tau6, xhat, Pc, cs = control_step(
            t, x, held_y, fresh[j], xhat, Pc, cs, target, C, Q, dt, row
        )
        f = allocate(tau6, C)
        xhat, Pc = finish_step(x, f, env[j], xhat, Pc, C, P, dt, t + dt, held_y, row, work)
        if not plant.all_finite(x):
            return x, held_y, xhat, Pc, cs, log, j
    return x, held_y, xhat, Pc, cs, log, n


@njit(**JIT)
def run_open_chunk(
    k0: int,
    x: np.ndarray,
    held_y: np.ndarray,
    n_rps: np.ndarray,
    env: np.ndarray,
    noise: np.ndarray,
    fresh: np.ndarray,
    P: plant.PlantArrays,
    dt: float,
):
    """The plant with control off: len(env) steps at fixed propeller speeds ``n_rps``, sensors
    sampled at the end of each step. Returns (x, held_y, log (n, N_LOG), n_done); n_done < n
    when the plant diverged."""
    n = env.shape[0]
    log = np.zeros((n, N_LOG))
    x = x.copy()  # advanced in place (see run_chunk)
    held_y = held_y.copy()
    work = plant.make_work(n_rps.shape[0])
    n_done = _open_steps(k0, x, held_y, n_rps, env, noise, fresh, P, dt, log, work)
    return x, held_y, log, n_done


@njit(**JIT_NOALLOC)
def _open_steps(
    k0: int,
    x: np.ndarray,
    held_y: np.ndarray,
    n_rps: np.ndarray,
    env: np.ndarray,
    noise: np.ndarray,
    fresh: np.ndarray,
    P: plant.PlantArrays,
    dt: float,
    log: np.ndarray,
    work: plant.PlantWork,
) -> int:
    """The steps of ``run_open_chunk``, advancing x and held_y in place and writing the log's
    rows, allocating nothing. Returns the number of steps done (< n when x stopped being
    finite)."""
    n = env.shape[0]
    m = n_rps.shape[0]
    for j in range(n):
        row = log[j]
        plant.rk4_step_into(x, x, n_rps, env[j], P, dt, work)
        if not plant.all_finite(x):
            return j
        sensors.sample_into(held_y, x, held_y, noise[j], fresh[j], sensors.Y_SENSOR)
        for i in range(m):
            row[L_N + i] = n_rps[i]
        write_plant_row(row, (k0 + j + 1) * dt, x, held_y, env[j], P, work)
    return n
