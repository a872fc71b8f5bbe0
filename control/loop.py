"""The closed loop: plant, sensors, signal checks, observer, reference, controller, allocation.

One compiled kernel (``run_chunk``) advances everything for a chunk of plant steps with the
mission's target held; Python handles commands (targets, gains, modes) between chunks, so the
loop stays fast and commands are applied only between steps. The fixed order within a step is

    sensors -> quality checks -> observer (EKF) -> reference model -> controller (supervisor:
    tree PID, free-ROV PID or the pilot's demand with the holds) -> thrust allocation ->
    thrusters -> plant (RK4)

Every step writes one row of the log (see the ``L_*`` column indices).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from control import ekf, pid, quality, refkernel
from control.allocation import _priority_forces_into
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


@njit(**JIT)
def _matvec(A: np.ndarray, v: np.ndarray) -> np.ndarray:
    """A @ v for the small matrices of the loop, by a plain loop (no BLAS call)."""
    out = np.empty(A.shape[0])
    _matvec_into(out, A, v)
    return out


@njit(**JIT_NOALLOC)
def _matvec_into(out: np.ndarray, A: np.ndarray, v: np.ndarray) -> None:
    """``_matvec`` into ``out`` (must not alias ``v``)."""
    for i in range(A.shape[0]):
        acc = 0.0
        for j in range(A.shape[1]):
            acc += A[i, j] * v[j]
        out[i] = acc


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
CS_GRIP = CS_HOLD + 2  # 1.0 while the ROV grips the tree: the step's plant.E_GRIP
CS_LAST_GRIP = CS_GRIP + 1  # CS_GRIP at the last step
CS_HANDOVER = CS_LAST_GRIP + 1  # 3: the hand-over's fading wrench, tree axes [N, N, N m]
CS_FLOWN = CS_HANDOVER + 3  # 2: 1.0 where the pilot flew the gripped tree: [north-east, psi]
N_CS = CS_FLOWN + 2
HANDOVER_FADE_S = 1.0
"""Time constant [s] of the wrench a hand-over between the tree controller and the pilot's
hold adds so the thrust does not jump: long against a step (0.01 s), short against the tree's
swing on its wire (periods of 15 to 45 s), so little of the old thrust (a moving tree's
braking, say) is carried over."""


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


# --- the control system's work space (``ControlWork``): rows of ``vec`` ---
W_ETA, W_DETA, W_REF, W_TAU6, W_TAU_TREE, W_I_NEXT, W_E, W_DE = 0, 1, 2, 3, 4, 5, 6, 7
W_TAU3, W_F, W_N, W_ACH, W_ACH3, W_TAU_OBS = 8, 9, 10, 11, 12, 13
W_F0, W_K0, W_K1 = 14, 17, 18  # the EKF's
W_NE, W_UV, W_ACCEPT, W_BTAU, W_ZERO = 19, 20, 21, 22, 23
W_ETA4, W_DETA4, W_FI, W_E4, W_TAU_ROV, W_ROWS = 24, 25, 26, 27, 28, 29
N_CVEC = 30
CW_WIDTH = 12
"""Width of the work rows: the longest vector of the step (the EKF's 9, the thrusters' M_MAX,
the allocation's rows)."""
MW_PHI, MW_TMP, MW_A = 0, 1, 2  # ``ControlWork.mat`` 9x9 slots: the EKF's Phi, Phi P, Joseph A


class ControlWork(NamedTuple):
    """Work space of the control system's step (as ``sim.plant.PlantWork`` is the plant's):
    every vector and matrix the step makes lives here, so the step allocates nothing. It
    carries no state from one step to the next (each step writes what it reads)."""

    vec: np.ndarray  # (N_CVEC, CW_WIDTH) rows W_*
    mat: np.ndarray  # (3, 9, 9) slots MW_*
    terms: np.ndarray  # (4, 3) the tree controller's P, I, D and feedforward parts
    pid: np.ndarray  # (5, 3) the tree controller's anti-windup and feedforward vectors
    bump: np.ndarray  # (3, 3) the bumpless hand-over's vectors
    alloc: np.ndarray  # (3, CW_WIDTH) the priority allocation's forces, step, residual


@njit(**JIT)
def make_control_work() -> ControlWork:
    """A fresh control work space (once per chunk)."""
    return ControlWork(
        np.zeros((N_CVEC, CW_WIDTH)),
        np.zeros((3, 9, 9)),
        np.zeros((4, 3)),
        np.zeros((5, 3)),
        np.zeros((3, 3)),
        np.zeros((3, CW_WIDTH)),
    )


@njit(**JIT)
def allocate(tau6: np.ndarray, C: ControlArrays) -> np.ndarray:
    """Thruster forces for an ROV wrench (pinv or priority, see control.allocation)."""
    f = np.empty(C.f_lo.shape[0])
    allocate_into(f, tau6, C, make_control_work())
    return f


@njit(inline="always", **JIT_NOALLOC)
def allocate_into(f: np.ndarray, tau6: np.ndarray, C: ControlArrays, W: ControlWork) -> None:
    """``allocate`` into ``f`` (m,), allocating nothing."""
    if C.alloc_kind == ALLOC_PRIORITY:
        rows = W.vec[W_ROWS, 0 : C.prio_rows.shape[0]]
        for i in range(rows.shape[0]):
            rows[i] = tau6[C.prio_rows[i]]
        _priority_forces_into(
            f, C.prio_A, C.prio_D, C.prio_R, rows, C.f_lo, C.f_hi, C.alloc_tol, W.alloc
        )
        return
    for i in range(C.pinv_T.shape[0]):
        s = 0.0
        for j in range(C.pinv_rows.shape[0]):
            s += C.pinv_T[i, j] * tau6[C.pinv_rows[j]]
        f[i] = min(max(s, C.f_lo[i]), C.f_hi[i])


@njit(**JIT)
def tree_measurements(y: np.ndarray, psi_hat: float, C: ControlArrays):
    """Move the ROV's measurements to the tree's origin (eq. 3.4-3.6), with the configured
    mounting vector r and relative heading. Returns (north_east (2), psi, u_v (2), r)."""
    ne = np.empty(2)
    uv = np.empty(2)
    psi, rate = tree_measurements_into(ne, uv, y, psi_hat, C)
    return ne, psi, uv, rate


@njit(inline="always", **JIT_NOALLOC)
def tree_measurements_into(
    ne: np.ndarray, uv: np.ndarray, y: np.ndarray, psi_hat: float, C: ControlArrays
) -> tuple[float, float]:
    """``tree_measurements`` with north_east and u_v into ``ne``, ``uv`` (2,); returns
    (psi, r)."""
    c, s = np.cos(psi_hat), np.sin(psi_hat)
    r = C.r_mount
    ne[0] = y[0] - (c * r[0] - s * r[1])
    ne[1] = y[1] - (s * r[0] + c * r[1])
    return tree_heading(y, C), tree_velocity_into(uv, y, C)


@njit(inline="always", **JIT_NOALLOC)
def tree_velocity_into(uv: np.ndarray, y: np.ndarray, C: ControlArrays) -> float:
    """The DVL's velocity moved to the tree's origin (eq. 3.6) into ``uv`` (2,), from the
    ROV's relative heading and mounting vector and the gyro's yaw rate; returns that rate."""
    r = C.r_mount
    cr, sr = np.cos(C.psi_rel), np.sin(C.psi_rel)
    u_t = cr * y[5] - sr * y[6]
    v_t = sr * y[5] + cr * y[6]
    rate = y[10]
    uv[0] = u_t + rate * r[1]
    uv[1] = v_t - rate * r[0]
    return rate


@njit(inline="always", **JIT_NOALLOC)
def tree_heading(y: np.ndarray, C: ControlArrays) -> float:
    """The tree's heading from the compass (eq. 3.5): the ROV's less the relative heading."""
    return y[4] - C.psi_rel


@njit(**JIT_NOALLOC)
def _truth_tree_into(eta: np.ndarray, deta: np.ndarray, x: np.ndarray) -> None:
    """Perfect feedback: the tree's [north, east, psi] and their NED rates."""
    eta[0], eta[1], eta[2] = x[0], x[1], x[5]
    c, s = np.cos(x[5]), np.sin(x[5])
    deta[0] = c * x[6] - s * x[7]
    deta[1] = s * x[6] + c * x[7]
    deta[2] = x[11]


@njit(**JIT_NOALLOC)
def _rov_pose_into(
    eta4: np.ndarray, deta4: np.ndarray, x: np.ndarray, y: np.ndarray, use_truth: bool
) -> None:
    """The ROV's [north, east, down, psi] and rates for the free-ROV controller."""
    if use_truth:  # pose and body velocities [u, v, w, r] of the plant state
        eta4[0], eta4[1], eta4[2] = x[12], x[13], x[14]
        eta4[3] = x[17]
        u, v, w, r = x[18], x[19], x[20], x[23]
    else:  # fix (north, east), depth sensor, compass, DVL, gyro
        eta4[0], eta4[1] = y[0], y[1]
        eta4[2] = y[3]
        eta4[3] = y[4]
        u, v, w, r = y[5], y[6], y[7], y[10]
    c, s = np.cos(eta4[3]), np.sin(eta4[3])
    deta4[0] = c * u - s * v
    deta4[1] = s * u + c * v
    deta4[2] = w
    deta4[3] = r


@njit(inline="always", **JIT_NOALLOC)
def _observe_into(
    t: float,
    y: np.ndarray,
    fresh: np.ndarray,
    xhat: np.ndarray,
    P: np.ndarray,
    C: ControlArrays,
    Q: QualityState,
    log_row: np.ndarray,
    W: ControlWork,
) -> None:
    """Signal checks, then EKF correction (of ``xhat``, ``P`` in place) with each accepted
    fresh sample."""
    accepted = W.vec[W_ACCEPT, 0:5]
    accept_samples_into(accepted, t, y, fresh, C, Q, log_row)
    ne = W.vec[W_NE, 0:2]
    uv = W.vec[W_UV, 0:2]
    k0 = W.vec[W_K0, 0:9]
    k1 = W.vec[W_K1, 0:9]
    A = W.mat[MW_A]
    psi_m, rate = tree_measurements_into(ne, uv, y, xhat[2], C)
    if accepted[sensors.COMPASS] > 0.5:
        nis, _ = ekf.correct_into(xhat, P, 1, psi_m, 0.0, 2, -1, C.r_psi, 0.0, 0, k0, k1, A)
        log_row[L_NIS + 2] = nis
    if accepted[sensors.POSITION] > 0.5:
        psi_m, rate = tree_measurements_into(ne, uv, y, xhat[2], C)
        nis0, nis1 = ekf.correct_into(
            xhat, P, 2, ne[0], ne[1], 0, 1, C.r_pos, C.r_pos, -1, k0, k1, A
        )
        log_row[L_NIS] = nis0
        log_row[L_NIS + 1] = nis1
    if accepted[sensors.GYRO] > 0.5:
        ekf.correct_into(xhat, P, 1, rate, 0.0, 5, -1, C.r_gyro, 0.0, -1, k0, k1, A)
    if accepted[sensors.DVL] > 0.5:
        ekf.correct_into(xhat, P, 2, uv[0], uv[1], 3, 4, C.r_dvl, C.r_dvl, -1, k0, k1, A)


@njit(inline="always", **JIT_NOALLOC)
def accept_samples_into(
    accepted: np.ndarray,
    t: float,
    y: np.ndarray,
    fresh: np.ndarray,
    C: ControlArrays,
    Q: QualityState,
    log_row: np.ndarray,
) -> None:
    """The signal checks of the step's fresh samples (``Q`` updated): 1.0 or 0.0 per sensor
    into ``accepted`` (5,) and the row's ``L_ACCEPT`` columns."""
    for k in range(5):
        ok = False
        if fresh[k]:
            ok = quality.check_sample(
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
                sensors.Y_FIRST,
                sensors.Y_END,
            )
        accepted[k] = 1.0 if ok else 0.0
    for k in range(5):
        log_row[L_ACCEPT + k] = accepted[k]


@njit(inline="always", **JIT_NOALLOC)
def manual_step_into(
    tau: np.ndarray, x: np.ndarray, y: np.ndarray, cs: np.ndarray, C: ControlArrays, dt: float,
    W: ControlWork,
) -> None:  # fmt: skip
    """Flown by hand with the ROV free of the tree (``manual_tree_step_into`` while it grips
    it): the pilot's demand (``cs[CS_PILOT:+4]``, ROV axes [X, Y, Z, N]) on the
    axes the pilot is using; the free-ROV station keeping on the others, with its set point at
    the pose where the pilot let go (horizontal position always; heading and depth only with
    the auto-heading and auto-depth holds on, else a released stick is zero thrust). While an
    axis is under the pilot its set point follows the ROV and its integral (what holds against
    the current) is frozen. The step that enters this mode starts the holds where the ROV is,
    their integral set so the thrust does not jump (bumpless, as the free mode). Writes
    ``cs`` in place and the ROV wrench into ``tau`` (6,)."""
    eta4 = W.vec[W_ETA4, 0:4]
    deta4 = W.vec[W_DETA4, 0:4]
    _rov_pose_into(eta4, deta4, x, y, not C.feedback_ekf)
    if int(cs[CS_LAST_MODE]) != MODE_MANUAL or cs[CS_LAST_GRIP] > 0.5:
        for k in range(4):
            cs[CS_FSP + k] = eta4[k]
        pid.bumpless_free_integral_into(
            cs[CS_FI : CS_FI + 4], cs[CS_TAU : CS_TAU + 6], eta4, deta4, eta4, C.free_Kp, C.free_Kd
        )
    d = cs[CS_PILOT : CS_PILOT + 4]
    # which of [north+east, down, psi] the pilot flies now
    flown_ne = d[0] != 0.0 or d[1] != 0.0
    flown_down = d[2] != 0.0 or cs[CS_HOLD + 1] < 0.5
    flown_psi = d[3] != 0.0 or cs[CS_HOLD] < 0.5
    if flown_ne:
        cs[CS_FSP] = eta4[0]
        cs[CS_FSP + 1] = eta4[1]
    if flown_down:
        cs[CS_FSP + 2] = eta4[2]
    if flown_psi:
        cs[CS_FSP + 3] = eta4[3]
    fi = W.vec[W_FI, 0:4]
    e4 = W.vec[W_E4, 0:4]
    pid.free_rov_pid_into(
        tau,
        fi,
        e4,
        eta4,
        deta4,
        cs[CS_FSP : CS_FSP + 4],
        cs[CS_FI : CS_FI + 4],
        C.free_Kp,
        C.free_Ki,
        C.free_Kd,
        dt,
    )
    # conditional integration: a hold catching the ROV after a fast release does not wind up
    for k in range(4):
        band = MANUAL_I_BAND_M if k < 3 else MANUAL_I_BAND_RAD
        if abs(e4[k]) > band:
            fi[k] = cs[CS_FI + k]
    if flown_ne:
        tau[0], tau[1] = d[0], d[1]
        fi[0] = cs[CS_FI]
        fi[1] = cs[CS_FI + 1]
    if flown_down:
        tau[2] = d[2]
        fi[2] = cs[CS_FI + 2]
    if flown_psi:
        tau[5] = d[3]
        fi[3] = cs[CS_FI + 3]
    for k in range(4):
        cs[CS_FI + k] = fi[k]


@njit(inline="always", **JIT_NOALLOC)
def manual_tree_step_into(
    tau6: np.ndarray, eta: np.ndarray, deta: np.ndarray, x: np.ndarray, y: np.ndarray,
    cs: np.ndarray, C: ControlArrays, dt: float, log_row: np.ndarray, W: ControlWork,
) -> None:  # fmt: skip
    """Flown by hand while the ROV grips the tree: the pilot's demand on the axes in use;
    the others held by the tree controller, the autopilot's own law (``pid.tree_pid_into``
    on the tree's pose, with its gains, integral and anti-windup), its reference
    (``cs[CS_REF:+9]``) at rest at the pose where the pilot let go: the horizontal position
    always, the heading with auto-heading on. Heave is the autopilot's constant heave force
    with auto-depth on, else the stick. While an axis is flown its reference follows the tree
    and its integral is frozen.

    The hold takes the feedforward whatever the autopilot's law: with its reference at rest
    that is the wire's spring at the hold, the pull of a tree let go away from where the wire
    hangs, which the thesis law (eq. 3.9 alone) leaves to the integral, and the integral's
    anti-windup stops at 90 % of the weaker direction's thrust (at model scale 179 N, the
    spring's pull 7.7 m off). Hand-overs move that share between the integral and the
    feedforward (``_spring_into_integral``), so it is never counted twice.

    The pilot's [X, Y, N] (ROV axes) is moved to the tree's origin (``A_inv``) and replaces
    the law's output on the flown axes there, so the heading hold also takes the moment of
    the pilot's sway about the tree. Entering from the tree controller the law goes on and
    the hand-over's fading wrench (``_hand_over_into``) takes the difference; from anything
    else its integral is set from the last thrust, as the tree controller's start. Writes
    ``tau6`` (the tree-origin wrench the allocation takes), the row's wrench and term columns
    and ``cs``, with the free set point ``cs[CS_FSP:+4]`` where the ROV sits when the tree
    is at its hold (the position alarm's set point in this mode)."""
    last = int(cs[CS_LAST_MODE])
    ref = cs[CS_REF : CS_REF + 9]
    if not (last == MODE_MANUAL and cs[CS_LAST_GRIP] > 0.5):
        for i in range(9):
            ref[i] = eta[i] if i < 3 else 0.0
        if last != MODE_TREE:
            _bumpless_tree_start(cs, eta, deta, True, C, W)
        elif not C.use_ff:  # the tree controller's integral carried the spring
            _spring_into_integral(cs, ref, -1.0, C)
    d = cs[CS_PILOT : CS_PILOT + 4]
    flown_ne = d[0] != 0.0 or d[1] != 0.0
    flown_down = d[2] != 0.0 or cs[CS_HOLD + 1] < 0.5
    flown_psi = d[3] != 0.0 or cs[CS_HOLD] < 0.5
    if flown_ne:
        ref[0], ref[1] = eta[0], eta[1]
    if flown_psi:
        ref[2] = eta[2]
    cs[CS_FLOWN] = 1.0 if flown_ne else 0.0
    cs[CS_FLOWN + 1] = 1.0 if flown_psi else 0.0
    tau_tree = W.vec[W_TAU_TREE, 0:3]
    i_next = W.vec[W_I_NEXT, 0:3]
    e = W.vec[W_E, 0:3]
    de = W.vec[W_DE, 0:3]
    pid.tree_pid_into(
        tau_tree, i_next, W.terms, e, de, eta, deta, ref[0:3], ref[3:6], ref[6:9],
        cs[CS_I : CS_I + 3], C.Kp, C.Ki, C.Kd, True, C.M, C.D_l, C.D_nl, C.k_h, C.p_eq,
        EYE3, EYE3, C.i_limit, dt, W.pid,
    )  # fmt: skip
    for k in range(3):
        if not (flown_psi if k == 2 else flown_ne):
            cs[CS_I + k] = i_next[k]
        cs[CS_E + k] = e[k]
        cs[CS_DE + k] = de[k]
    _hand_over_into(tau_tree, W.terms, cs, C, last == MODE_TREE, dt, W)
    if flown_ne or flown_psi:
        stick = W.vec[W_E4, 0:3]
        stick[0], stick[1], stick[2] = d[0], d[1], d[3]
        at_tree = W.vec[W_FI, 0:3]
        mv3_into(at_tree, C.A_inv, stick)
        if flown_ne:
            tau_tree[0], tau_tree[1] = at_tree[0], at_tree[1]
        if flown_psi:
            tau_tree[2] = at_tree[2]
    heave = d[2] if flown_down else C.heave_newton
    _tree_wrench_out(tau6, tau_tree, heave, C, log_row, W)
    eta4 = W.vec[W_ETA4, 0:4]
    _rov_pose_into(eta4, W.vec[W_DETA4, 0:4], x, y, not C.feedback_ekf)
    c, s = np.cos(ref[2]), np.sin(ref[2])
    r = C.r_mount
    cs[CS_FSP] = ref[0] + (c * r[0] - s * r[1])
    cs[CS_FSP + 1] = ref[1] + (s * r[0] + c * r[1])
    cs[CS_FSP + 2] = eta4[2]
    cs[CS_FSP + 3] = ref[2] + C.psi_rel


@njit(inline="always", **JIT_NOALLOC)
def _spring_into_integral(cs: np.ndarray, ref: np.ndarray, sign: float, C: ControlArrays) -> None:
    """Add ``sign`` times the wire's spring at the reference ``ref`` (NED, k_h (ref - p_eq))
    to the tree controller's integral (NED): +1 when the feedforward that carried it stops
    (the pilot's hold handing over to the thesis law), -1 when it starts."""
    for k in range(2):
        cs[CS_I + k] += sign * (C.k_h * (ref[k] - C.p_eq[k]))


@njit(inline="always", **JIT_NOALLOC)
def _bumpless_tree_start(
    cs: np.ndarray, eta: np.ndarray, deta: np.ndarray, use_ff: bool, C: ControlArrays,
    W: ControlWork,
) -> None:  # fmt: skip
    """The tree controller's integral set so that, with its reference at rest at ``eta``
    (and the feedforward with ``use_ff``), it commands the last ROV wrench
    (``cs[CS_TAU:+6]``): the start of the tree law when it was not running (a hand-over's
    fading wrench left from before is dropped)."""
    for k in range(3):
        cs[CS_HANDOVER + k] = 0.0
    tau_rov3 = W.vec[W_BTAU, 0:3]
    tau_rov3[0], tau_rov3[1], tau_rov3[2] = cs[CS_TAU], cs[CS_TAU + 1], cs[CS_TAU + 5]
    zero = W.vec[W_ZERO, 0:3]
    zero[0] = zero[1] = zero[2] = 0.0
    pid.bumpless_tree_integral_into(
        cs[CS_I : CS_I + 3], tau_rov3, eta, deta, eta, zero, zero, C.Kp, C.Kd, use_ff, C.M,
        C.D_l, C.D_nl, C.k_h, C.p_eq, C.A_inv, W.bump,
    )  # fmt: skip


@njit(inline="always", **JIT_NOALLOC)
def _hand_over_into(
    tau_tree: np.ndarray, terms: np.ndarray, cs: np.ndarray, C: ControlArrays, start: bool,
    dt: float, W: ControlWork,
) -> None:  # fmt: skip
    """The hand-over's fading wrench (``cs[CS_HANDOVER:+3]``, tree axes) between the tree
    controller and the pilot's hold: at a hand-over (``start``) it is set to the last
    commanded wrench less the law's ``tau_tree``, so this step commands the last one, on the
    axes the law held at the last step; on those the pilot flew (``cs[CS_FLOWN:+2]``) it
    is zero, as when the stick is let go. Each step adds it to ``tau_tree`` (and to the
    integral's part of ``terms``, so the parts still add up) and fades it by
    exp(-dt / HANDOVER_FADE_S). The law's own integral is left as it was: a moving tree's
    braking, which an integral set from the last thrust would keep, is carried only while
    the wrench fades. Zero, it changes nothing."""
    b = cs[CS_HANDOVER : CS_HANDOVER + 3]
    if start:
        last = W.vec[W_BTAU, 0:3]
        last[0], last[1], last[2] = cs[CS_TAU], cs[CS_TAU + 1], cs[CS_TAU + 5]
        last_tree = W.vec[W_ZERO, 0:3]
        mv3_into(last_tree, C.A_inv, last)
        for k in range(3):
            flown = cs[CS_FLOWN + (1 if k == 2 else 0)] > 0.5
            b[k] = 0.0 if flown else last_tree[k] - tau_tree[k]
    if b[0] != 0.0 or b[1] != 0.0 or b[2] != 0.0:
        fade = np.exp(-dt / HANDOVER_FADE_S)
        for k in range(3):
            tau_tree[k] += b[k]
            terms[1, k] += b[k]
            b[k] *= fade


@njit(inline="always", **JIT_NOALLOC)
def _tree_wrench_out(
    tau6: np.ndarray, tau_tree: np.ndarray, heave: float, C: ControlArrays,
    log_row: np.ndarray, W: ControlWork,
) -> None:  # fmt: skip
    """The tree controller's wrench ``tau_tree`` (tree axes) and the ROV's ``heave`` into the
    allocation's ``tau6`` (the tree's origin) and the row's ROV wrench (``A tau_tree``), tree
    wrench and term columns (``W.terms``)."""
    tau6[0] = tau_tree[0]
    tau6[1] = tau_tree[1]
    tau6[2] = heave
    tau6[5] = tau_tree[2]
    tau3 = W.vec[W_TAU3, 0:3]
    _matvec_into(tau3, C.A, tau_tree)
    log_row[L_TAU_ROV] = tau3[0]
    log_row[L_TAU_ROV + 1] = tau3[1]
    log_row[L_TAU_ROV + 2] = heave
    log_row[L_TAU_ROV + 3] = 0.0
    log_row[L_TAU_ROV + 4] = 0.0
    log_row[L_TAU_ROV + 5] = tau3[2]
    for k in range(3):
        log_row[L_TAU_TREE + k] = tau_tree[k]
    for j in range(4):
        for k in range(3):
            log_row[L_TERMS + 3 * j + k] = W.terms[j, k]


@njit(**JIT)
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
    (tau_rov6, xhat, Pc, cs), new arrays (``control_step_into`` updates its own in place)."""
    xhat = xhat.copy()
    Pc = Pc.copy()
    cs = cs.copy()
    tau6 = np.empty(6)
    control_step_into(
        tau6, t, x, y, fresh, xhat, Pc, cs, target, C, Q, dt, log_row, make_control_work()
    )
    return tau6, xhat, Pc, cs


@njit(**JIT_NOALLOC)
def control_step_into(
    tau6: np.ndarray,
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
    W: ControlWork,
) -> None:
    """``control_step``: the wrench for the allocation into ``tau6`` (6,); the observer
    (``xhat``, ``Pc``) and the controller state ``cs`` updated in place. Allocates nothing."""
    if C.feedback_ekf:
        _observe_into(t, y, fresh, xhat, Pc, C, Q, log_row, W)
    control_law_into(tau6, x, y, xhat, cs, target, C, dt, log_row, W)


@njit(inline="always", **JIT_NOALLOC)
def control_law_into(
    tau6: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    xhat: np.ndarray,
    cs: np.ndarray,
    target: np.ndarray,
    C: ControlArrays,
    dt: float,
    log_row: np.ndarray,
    W: ControlWork,
) -> None:
    """``control_step_into`` after the observer's corrections: the reference, the controller
    of the mode and the row's control columns, from the corrected estimate ``xhat`` (or,
    without an observer, the plant's state ``x``)."""
    eta = W.vec[W_ETA, 0:3]
    deta = W.vec[W_DETA, 0:3]
    if C.feedback_ekf:
        eta[0], eta[1], eta[2] = xhat[0], xhat[1], xhat[2]
        c, s = np.cos(eta[2]), np.sin(eta[2])
        deta[0] = c * xhat[3] - s * xhat[4]
        deta[1] = s * xhat[3] + c * xhat[4]
        deta[2] = xhat[5]
    else:
        _truth_tree_into(eta, deta, x)
    mode = int(cs[CS_MODE])
    # the pilot's hold of the gripped tree was running: the tree controller goes on from it
    from_hold = int(cs[CS_LAST_MODE]) == MODE_MANUAL and cs[CS_LAST_GRIP] > 0.5
    ref = W.vec[W_REF, 0:9]
    for i in range(9):
        ref[i] = cs[CS_REF + i]
    if mode == MODE_TREE and int(cs[CS_LAST_MODE]) != MODE_TREE:
        for i in range(9):
            ref[i] = eta[i] if i < 3 else 0.0
        if not from_hold:
            _bumpless_tree_start(cs, eta, deta, C.use_ff, C, W)
        elif not C.use_ff:  # the hold's feedforward carried the spring at its reference
            _spring_into_integral(cs, cs[CS_REF : CS_REF + 3], 1.0, C)
    if not (mode == MODE_MANUAL and cs[CS_GRIP] > 0.5):  # the hold sets its own reference
        refkernel.reference_step_into(
            cs[CS_REF : CS_REF + 9], C.ref_kind, ref, target, dt, C.ref_params
        )
    ref = cs[CS_REF : CS_REF + 9]
    for i in range(6):
        tau6[i] = 0.0
    if mode == MODE_TREE:
        tau_tree = W.vec[W_TAU_TREE, 0:3]
        i_next = W.vec[W_I_NEXT, 0:3]
        e = W.vec[W_E, 0:3]
        de = W.vec[W_DE, 0:3]
        terms = W.terms
        pid.tree_pid_into(
            tau_tree,
            i_next,
            terms,
            e,
            de,
            eta,
            deta,
            ref[0:3],
            ref[3:6],
            ref[6:9],
            cs[CS_I : CS_I + 3],
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
            W.pid,
        )
        for k in range(3):
            cs[CS_I + k] = i_next[k]
            cs[CS_E + k] = e[k]
            cs[CS_DE + k] = de[k]
        _hand_over_into(tau_tree, terms, cs, C, from_hold, dt, W)
        # allocation works on the tree's origin (see closed_loop.system_thruster_config)
        _tree_wrench_out(tau6, tau_tree, C.heave_newton, C, log_row, W)
    elif mode == MODE_MANUAL and cs[CS_GRIP] > 0.5:
        manual_tree_step_into(tau6, eta, deta, x, y, cs, C, dt, log_row, W)
    elif mode == MODE_MANUAL:
        tau_rov6 = W.vec[W_TAU_ROV, 0:6]
        manual_step_into(tau_rov6, x, y, cs, C, dt, W)
        for k in range(6):
            log_row[L_TAU_ROV + k] = tau_rov6[k]
        _matvec_into(tau6, C.rov_to_tree, tau_rov6)
    else:
        eta4 = W.vec[W_ETA4, 0:4]
        deta4 = W.vec[W_DETA4, 0:4]
        _rov_pose_into(eta4, deta4, x, y, not C.feedback_ekf)
        if int(cs[CS_LAST_MODE]) != MODE_FREE:
            for k in range(4):
                cs[CS_FSP + k] = eta4[k]
            pid.bumpless_free_integral_into(
                cs[CS_FI : CS_FI + 4],
                cs[CS_TAU : CS_TAU + 6],
                eta4,
                deta4,
                eta4,
                C.free_Kp,
                C.free_Kd,
            )
        tau_rov6 = W.vec[W_TAU_ROV, 0:6]
        fi = W.vec[W_FI, 0:4]
        pid.free_rov_pid_into(
            tau_rov6,
            fi,
            W.vec[W_E4, 0:4],
            eta4,
            deta4,
            cs[CS_FSP : CS_FSP + 4],
            cs[CS_FI : CS_FI + 4],
            C.free_Kp,
            C.free_Ki,
            C.free_Kd,
            dt,
        )
        for k in range(4):
            cs[CS_FI + k] = fi[k]
        for k in range(6):
            log_row[L_TAU_ROV + k] = tau_rov6[k]
        _matvec_into(tau6, C.rov_to_tree, tau_rov6)
    cs[CS_LAST_MODE] = mode
    cs[CS_LAST_GRIP] = cs[CS_GRIP]
    for k in range(6):
        cs[CS_TAU + k] = log_row[L_TAU_ROV + k]
    for k in range(3):
        log_row[L_ETA_HAT + k] = eta[k]
    if C.feedback_ekf:
        for k in range(3):
            log_row[L_NU_HAT + k] = xhat[3 + k]
    else:
        log_row[L_NU_HAT] = x[6]
        log_row[L_NU_HAT + 1] = x[7]
        log_row[L_NU_HAT + 2] = x[11]
    for k in range(3):
        log_row[L_BIAS + k] = xhat[6 + k]
        log_row[L_ETA_D + k] = ref[k]
        log_row[L_DETA_D + k] = ref[3 + k]
    log_row[L_MODE] = mode


@njit(**JIT)
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
    row's plant columns. Advances the plant state ``x`` in place and returns (xhat, Pc), new
    arrays. The Python chunk (QP allocation) ends every step here; the compiled chunk calls
    ``finish_step_into``."""
    xhat = xhat.copy()
    Pc = Pc.copy()
    finish_step_into(
        x, f, env_k, xhat, Pc, C, P, dt, t_next, held_y, log_row, work, make_control_work()
    )
    return xhat, Pc


@njit(inline="always", **JIT_NOALLOC)
def finish_step_into(
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
    W: ControlWork,
) -> None:
    """``finish_step`` with the observer (``xhat``, ``Pc``) predicted in place; allocates
    nothing: ``thrusters_into``, the plant's RK4 step, ``observe_into``."""
    n = W.vec[W_N, 0 : f.shape[0]]
    thrusters_into(n, f, C, log_row, W)
    plant.rk4_step_into(x, x, n, env_k, P, dt, work)
    observe_into(x, env_k, xhat, Pc, C, P, dt, t_next, held_y, log_row, work, W)


@njit(inline="always", **JIT_NOALLOC)
def thrusters_into(
    n: np.ndarray, f: np.ndarray, C: ControlArrays, log_row: np.ndarray, W: ControlWork
) -> None:
    """The propeller speeds for the allocated forces ``f`` into ``n``, and the row's thruster
    columns and achieved wrench (``L_TAU_ACH``, which ``observe_into`` reads back)."""
    m = f.shape[0]
    thrusters.speed_from_thrust_into(n, f, C.k_pos, C.k_neg, C.n_max)
    ach = W.vec[W_ACH, 0:6]
    _matvec_into(ach, C.T6, f)
    for i in range(m):
        lim = C.f_hi[i] if f[i] >= 0.0 else -C.f_lo[i]
        log_row[L_F + i] = f[i]
        log_row[L_N + i] = n[i]
        log_row[L_UTIL + i] = min(abs(f[i]) / lim, 1.0)
    for k in range(6):
        log_row[L_TAU_ACH + k] = ach[k]


@njit(inline="always", **JIT_NOALLOC)
def observer_input_into(
    env_k: np.ndarray, C: ControlArrays, log_row: np.ndarray, W: ControlWork
) -> np.ndarray:
    """The observer's input over the step just taken: the achieved wrench of the step's log
    row moved to the tree (eq. 3.6), zero when the ROV does not hold the tree (by the row's
    mode and, flown by hand, the grip). A view into ``W``: read it before ``W`` is reused."""
    ach3 = W.vec[W_ACH3, 0:3]
    ach3[0] = log_row[L_TAU_ACH]
    ach3[1] = log_row[L_TAU_ACH + 1]
    ach3[2] = log_row[L_TAU_ACH + 5]
    tau_tree = W.vec[W_TAU_OBS, 0:3]
    _matvec_into(tau_tree, C.A_inv, ach3)
    mode = int(log_row[L_MODE])
    on_tree = mode == MODE_TREE or (mode == MODE_MANUAL and env_k[plant.E_GRIP] > 0.5)
    if not on_tree:
        tau_tree[0] = tau_tree[1] = tau_tree[2] = 0.0
    return tau_tree


@njit(inline="always", **JIT_NOALLOC)
def predict_from_row_into(
    env_k: np.ndarray,
    xhat: np.ndarray,
    Pc: np.ndarray,
    C: ControlArrays,
    dt: float,
    log_row: np.ndarray,
    W: ControlWork,
) -> None:
    """The observer's prediction over the step just taken (``xhat``, ``Pc`` in place), from
    the achieved wrench and the mode in the step's log row (``observe_into``'s first part)."""
    if C.feedback_ekf:
        predict_with_input_into(observer_input_into(env_k, C, log_row, W), xhat, Pc, C, dt, W)


@njit(inline="always", **JIT_NOALLOC)
def predict_with_input_into(
    tau_tree: np.ndarray,
    xhat: np.ndarray,
    Pc: np.ndarray,
    C: ControlArrays,
    dt: float,
    W: ControlWork,
) -> None:
    """The observer's prediction (``xhat``, ``Pc`` in place) on C's control model, with the
    input ``tau_tree`` (``observer_input_into``'s)."""
    ekf.predict_into(
        xhat,
        Pc,
        tau_tree,
        dt,
        C.M_inv,
        C.M,
        C.D_l,
        C.D_nl,
        C.k_h,
        C.p_eq,
        C.T_b,
        C.GQG,
        W.vec[W_F0, 0:9],
        W.mat[MW_PHI],
        W.mat[MW_TMP],
    )


@njit(inline="always", **JIT_NOALLOC)
def observe_into(
    x: np.ndarray,
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
    W: ControlWork,
) -> None:
    """After the plant's step: the observer's prediction over it (in place), from the
    achieved wrench of the row (``thrusters_into``), and the row's plant columns."""
    predict_from_row_into(env_k, xhat, Pc, C, dt, log_row, W)
    write_plant_row(log_row, t_next, x, held_y, env_k, P, work)


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
    log = np.empty((env.shape[0], N_LOG))  # zeroed by ``run_chunk_into``
    x, held_y, xhat, Pc, cs, n_done = run_chunk_into(
        k0, x, held_y, xhat, Pc, cs, target, env, noise, fresh, P, C, Q, dt, log
    )
    return x, held_y, xhat, Pc, cs, log, n_done


@njit(**JIT)
def run_chunk_into(
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
    log: np.ndarray,
):
    """``run_chunk`` writing its rows into the caller's ``log`` (len(env), N_LOG), zeroed here
    first, instead of into a new array: a request of several chunks hands each chunk its own
    rows of the request's array (``Simulation.step``), which saves a copy of every row
    (920 bytes a step) and the new array's zeroing. Returns (x, held_y, xhat, Pc, cs, n_done),
    the states new arrays (the caller's are left as they were)."""
    _zero_rows(log)
    # the states are advanced in place (``_closed_steps``): copies
    x = x.copy()
    held_y = held_y.copy()
    xhat = xhat.copy()
    Pc = np.ascontiguousarray(Pc).copy()
    cs = cs.copy()
    work = plant.make_work(P.thr_T.shape[1])
    n_done = _closed_steps(
        k0, x, held_y, xhat, Pc, cs, target, env, noise, fresh, P, C, Q, dt, log, work,
        make_control_work(),
    )  # fmt: skip
    return x, held_y, xhat, Pc, cs, n_done


@njit(**JIT_NOALLOC)
def _zero_rows(log: np.ndarray) -> None:
    """Every number of ``log`` (rows, N_LOG) to 0.0 (the columns a step leaves unwritten stay
    zero, as in a new array of zeros)."""
    for j in range(log.shape[0]):
        for i in range(log.shape[1]):
            log[j, i] = 0.0


@njit(**JIT_NOALLOC)
def _closed_steps(
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
    log: np.ndarray,
    work: plant.PlantWork,
    W: ControlWork,
) -> int:
    """The steps of ``run_chunk``: sensors, control step, allocation, thrusters, plant and
    observer prediction, advancing x, held_y, xhat, Pc, cs (and the signal checks' state Q) in
    place and writing the log's rows, allocating nothing. Returns the number of steps done
    (< n when x stopped being finite)."""
    n = env.shape[0]
    tau6 = W.vec[W_TAU6, 0:6]
    f = W.vec[W_F, 0 : C.f_lo.shape[0]]
    for j in range(n):
        t = (k0 + j) * dt
        row = log[j]
        sensors.sample_into(held_y, x, held_y, noise[j], fresh[j], sensors.Y_SENSOR)
        cs[CS_GRIP] = env[j, plant.E_GRIP]  # the controller knows whether the ROV grips
        control_step_into(tau6, t, x, held_y, fresh[j], xhat, Pc, cs, target, C, Q, dt, row, W)
        allocate_into(f, tau6, C, W)
        # ``finish_step_into`` with the plant's step inlined
        n_rps = W.vec[W_N, 0 : f.shape[0]]
        thrusters_into(n_rps, f, C, row, W)
        plant.rk4_step_into(x, x, n_rps, env[j], P, dt, work)
        observe_into(x, env[j], xhat, Pc, C, P, dt, t + dt, held_y, row, work, W)
        if not plant.all_finite(x):
            return j
    return n


@njit(inline="always", **JIT_NOALLOC)
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
    log = np.empty((env.shape[0], N_LOG))  # zeroed by ``run_open_chunk_into``
    x, held_y, n_done = run_open_chunk_into(k0, x, held_y, n_rps, env, noise, fresh, P, dt, log)
    return x, held_y, log, n_done


@njit(**JIT)
def run_open_chunk_into(
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
):
    """``run_open_chunk`` writing its rows into the caller's ``log`` (len(env), N_LOG), zeroed
    here first (see ``run_chunk_into``). Returns (x, held_y, n_done)."""
    _zero_rows(log)
    x = x.copy()  # advanced in place (see run_chunk_into)
    held_y = held_y.copy()
    work = plant.make_work(n_rps.shape[0])
    n_done = _open_steps(k0, x, held_y, n_rps, env, noise, fresh, P, dt, log, work)
    return x, held_y, n_done


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
