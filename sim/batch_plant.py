"""The plant's RK4 step for N independent runs at once, laid out so the compiler vectorises
over the runs (structure of arrays, run index last).

``rk4_batch_into(x_sb, n_rps, env, P, dt, work)`` advances every column of ``x_sb``
(N_STATE, N) by one step of ``sim.plant.rk4_step_into``: run r's state ``x_sb[:, r]``, its
propeller speeds ``n_rps[:, r]`` and its environment row ``env[:, r]`` (N_ENV, N), one
``PlantArrays`` common to the batch. Each run's result is **bit for bit** what the scalar
step gives on that run's column alone: every quantity of the scalar code is a row of N runs
in ``BatchWork``, every loop of the scalar code has an inner ``for r in range(N)``, and each
row is computed with the scalar code's operations in the scalar code's order (no
reassociation; numba compiles without fast-math or contraction into fused multiply-adds).
Matrices of ``PlantArrays`` are read element by element outside the loops over runs, so
those loops only touch rows and the compiler vectorises them (AVX-512 here: checked in the
assembly by ``benchmarks/batch_plant_benchmark.py``). Sines and cosines come from
``sim.trig.sincos`` over a row (branch-free), as in the scalar plant.

What differs between runs is a select per run: gripping (``E_GRIP``), the wire slack or
taut, the wire force from outside (``E_WEXT``), the wire's mass (``E_WMASS``); the work for
the coupling and the wire's mass is skipped for the whole batch when no run needs it (the
same numbers for the runs that do). Contact with the frame and the seabed (``E_LAND`` > 0) is
branchy, per corner and per post: it is evaluated run by run, for the runs near the frame,
by the scalar ``sim.plant.contact_wrench_into`` on a contiguous copy of the run's column (the
same arithmetic); a run clearly above it adds the scalar code's zero wrench as a select.
A run that is not finite stays in its own column; the others go on.

The step allocates nothing (compiled without numba's runtime, ``JIT_NOALLOC``):
``make_batch_work(n_thrusters, n_runs)`` makes the work space once. ``rk4_batch`` is the
allocating form, with checks of its arguments, for tests and tools.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from sim.gnc import JIT, JIT_NOALLOC
from sim.plant import (
    E_AC,
    E_CT,
    E_FWIRE,
    E_GRIP,
    E_KH,
    E_KZ,
    E_LAND,
    E_LREST,
    E_OFF,
    E_PUSH,
    E_VC,
    E_VPIV,
    E_WDAMP,
    E_WEXT,
    E_WMASS,
    N_ENV,
    N_STATE,
    PlantArrays,
    PlantWork,
    contact_reach,
    contact_wrench_trig_into,
    make_work,
)
from sim.thrusters import thrust_of_one
from sim.trig import sincos

# rows of ``BatchWork.trig``: sines and cosines of the tree's and the ROV's angles
T_SPHI, T_CPHI, T_STH, T_CTH, T_SPSI, T_CPSI = 0, 1, 2, 3, 4, 5
T_ROV = 6  # the ROV's six follow the tree's
N_TRIG = 12
# ``BatchWork.vec`` slots, each (6, N): a 6-vector (or a 3-vector in rows 0:3) per run
(
    B_TAU_T,
    B_TAU_R,
    B_NU_REL,
    B_VCB,
    B_VCDB,
    B_CRB,
    B_CA,
    B_MOM,
    B_A,
    B_B,
    B_C,
    B_D,
    B_G,
    B_WROV,
    B_WTREE,
    B_EPB,
    B_EVB,
    B_ETH,
    B_EW,
    B_U,
    B_RHS6,
    B_BASE,
    B_MINVU,
    B_SCAL,
) = range(24)
N_BVEC = 24
# rows of the slot ``B_SCAL``
S_AROT, S_SCALE = 0, 1
# ``BatchWork.mat`` slots, each (3, 3, N)
BM_RT, BM_RR, BM_TT, BM_TR, BM_RM, BM_TMP, BM_RTR = range(7)
N_BMAT = 7


class BatchWork(NamedTuple):
    """Work arrays of ``rk4_batch_into``, the run index last: made once
    (``make_batch_work``) and reused for every step."""

    xs: np.ndarray  # (N_STATE, N) the stage state
    k: np.ndarray  # (4, N_STATE, N) the four slopes
    f: np.ndarray  # (n_thrusters, N) thrust of each thruster [N]
    thr: np.ndarray  # (6, N) the thrusters' wrench on the ROV
    trig: np.ndarray  # (N_TRIG, N) sines and cosines of both bodies' angles
    vec: np.ndarray  # (N_BVEC, 6, N) vectors
    mat: np.ndarray  # (N_BMAT, 3, 3, N) rotations and products
    col_x: np.ndarray  # (N_STATE,) one run's stage state, for the scalar contact
    col_env: np.ndarray  # (N_ENV,) its environment row
    col_R: np.ndarray  # (3, 3) its tree rotation
    col_cw: np.ndarray  # (6,) its contact wrench
    plant: PlantWork  # the scalar contact's work space


@njit(**JIT)
def make_batch_work(n_thrusters: int, n_runs: int) -> BatchWork:
    """A fresh work space for ``n_runs`` runs of a plant with ``n_thrusters`` thrusters."""
    return BatchWork(
        np.zeros((N_STATE, n_runs)),
        np.zeros((4, N_STATE, n_runs)),
        np.zeros((n_thrusters, n_runs)),
        np.zeros((6, n_runs)),
        np.zeros((N_TRIG, n_runs)),
        np.zeros((N_BVEC, 6, n_runs)),
        np.zeros((N_BMAT, 3, 3, n_runs)),
        np.zeros(N_STATE),
        np.zeros(N_ENV),
        np.zeros((3, 3)),
        np.zeros(6),
        make_work(n_thrusters),
    )


# --- row kernels: the scalar ``sim.gnc`` helpers with a run index ---


@njit(inline="always", **JIT_NOALLOC)
def _sincos_rows(s_out: np.ndarray, c_out: np.ndarray, x: np.ndarray) -> None:
    """``sim.trig.sincos`` of every element of the row ``x`` (branch-free: vectorised)."""
    for r in range(x.shape[0]):
        s_out[r], c_out[r] = sincos(x[r])


@njit(inline="always", **JIT_NOALLOC)
def _trig_rows(trig: np.ndarray, x: np.ndarray, first: int, base: int) -> None:
    """Sines and cosines of x[first:first + 3] (phi, theta, psi) into trig[base:base + 6]."""
    _sincos_rows(trig[base + T_SPHI], trig[base + T_CPHI], x[first])
    _sincos_rows(trig[base + T_STH], trig[base + T_CTH], x[first + 1])
    _sincos_rows(trig[base + T_SPSI], trig[base + T_CPSI], x[first + 2])


@njit(inline="always", **JIT_NOALLOC)
def _rzyx_rows(R: np.ndarray, trig: np.ndarray, base: int) -> None:
    """``gnc.Rzyx_into`` per run, from the sines and cosines in trig[base:base + 6]."""
    for r in range(R.shape[2]):
        sphi, cphi = trig[base + T_SPHI, r], trig[base + T_CPHI, r]
        sth, cth = trig[base + T_STH, r], trig[base + T_CTH, r]
        spsi, cpsi = trig[base + T_SPSI, r], trig[base + T_CPSI, r]
        R[0, 0, r] = cpsi * cth
        R[0, 1, r] = -spsi * cphi + cpsi * sth * sphi
        R[0, 2, r] = spsi * sphi + cpsi * cphi * sth
        R[1, 0, r] = spsi * cth
        R[1, 1, r] = cpsi * cphi + sphi * sth * spsi
        R[1, 2, r] = -cpsi * sphi + sth * spsi * cphi
        R[2, 0, r] = -sth
        R[2, 1, r] = cth * sphi
        R[2, 2, r] = cth * cphi


@njit(inline="always", **JIT_NOALLOC)
def _tzyx_rows(T: np.ndarray, trig: np.ndarray, base: int) -> None:
    """``gnc.Tzyx_into`` per run with tan theta = sin theta / cos theta (as ``rhs_into``)."""
    for r in range(T.shape[2]):
        sphi, cphi = trig[base + T_SPHI, r], trig[base + T_CPHI, r]
        cth = trig[base + T_CTH, r]
        tth = trig[base + T_STH, r] / cth
        T[0, 0, r] = 1.0
        T[0, 1, r] = sphi * tth
        T[0, 2, r] = cphi * tth
        T[1, 0, r] = 0.0
        T[1, 1, r] = cphi
        T[1, 2, r] = -sphi
        T[2, 0, r] = 0.0
        T[2, 1, r] = sphi / cth
        T[2, 2, r] = cphi / cth


@njit(inline="always", **JIT_NOALLOC)
def _mv3_rows(out: np.ndarray, A: np.ndarray, x: np.ndarray) -> None:
    """``gnc.mv3_into`` per run: out[:, r] = A[:, :, r] @ x[:, r] (out must not alias x)."""
    for i in range(3):
        for r in range(out.shape[1]):
            s = 0.0
            s += A[i, 0, r] * x[0, r]
            s += A[i, 1, r] * x[1, r]
            s += A[i, 2, r] * x[2, r]
            out[i, r] = s


@njit(inline="always", **JIT_NOALLOC)
def _mtv3_rows(out: np.ndarray, A: np.ndarray, x: np.ndarray) -> None:
    """``gnc.mtv3_into`` per run: out[:, r] = A[:, :, r]^T @ x[:, r]."""
    for j in range(3):
        for r in range(out.shape[1]):
            s = 0.0
            s += A[0, j, r] * x[0, r]
            s += A[1, j, r] * x[1, r]
            s += A[2, j, r] * x[2, r]
            out[j, r] = s


@njit(inline="always", **JIT_NOALLOC)
def _mv3_const_rows(out: np.ndarray, A: np.ndarray, v: np.ndarray) -> None:
    """``gnc.mv3_into`` of per-run matrices and one vector: out[:, r] = A[:, :, r] @ v."""
    v0, v1, v2 = v[0], v[1], v[2]
    for i in range(3):
        for r in range(out.shape[1]):
            s = 0.0
            s += A[i, 0, r] * v0
            s += A[i, 1, r] * v1
            s += A[i, 2, r] * v2
            out[i, r] = s


@njit(inline="always", **JIT_NOALLOC)
def _mv6c_rows(out: np.ndarray, M: np.ndarray, x: np.ndarray) -> None:
    """``gnc.mv6_into`` of one 6x6 matrix and per-run vectors: out[:, r] = M @ x[:, r]
    (each element summed from 0.0 in the order of the columns)."""
    for i in range(6):
        m0, m1, m2, m3, m4, m5 = M[i, 0], M[i, 1], M[i, 2], M[i, 3], M[i, 4], M[i, 5]
        for r in range(out.shape[1]):
            s = 0.0
            s += m0 * x[0, r]
            s += m1 * x[1, r]
            s += m2 * x[2, r]
            s += m3 * x[3, r]
            s += m4 * x[4, r]
            s += m5 * x[5, r]
            out[i, r] = s


@njit(inline="always", **JIT_NOALLOC)
def _cross_rows(out: np.ndarray, a: np.ndarray, b: np.ndarray) -> None:
    """``gnc.cross_into`` per run (out must not alias a or b)."""
    for r in range(out.shape[1]):
        out[0, r] = a[1, r] * b[2, r] - a[2, r] * b[1, r]
        out[1, r] = a[2, r] * b[0, r] - a[0, r] * b[2, r]
        out[2, r] = a[0, r] * b[1, r] - a[1, r] * b[0, r]


@njit(inline="always", **JIT_NOALLOC)
def _mm_const_rows(out: np.ndarray, A: np.ndarray, B: np.ndarray) -> None:
    """``gnc.mm_into`` of per-run A and one B: out[:, :, r] = A[:, :, r] @ B."""
    for i in range(3):
        for j in range(3):
            b0, b1, b2 = B[0, j], B[1, j], B[2, j]
            for r in range(out.shape[2]):
                s = 0.0
                s += A[i, 0, r] * b0
                s += A[i, 1, r] * b1
                s += A[i, 2, r] * b2
                out[i, j, r] = s


@njit(inline="always", **JIT_NOALLOC)
def _mtm_rows(out: np.ndarray, A: np.ndarray, B: np.ndarray) -> None:
    """``gnc.mtm_into`` per run: out[:, :, r] = A[:, :, r]^T @ B[:, :, r]."""
    for i in range(3):
        for j in range(3):
            for r in range(out.shape[2]):
                s = 0.0
                s += A[0, i, r] * B[0, j, r]
                s += A[1, i, r] * B[1, j, r]
                s += A[2, i, r] * B[2, j, r]
                out[i, j, r] = s


@njit(inline="always", **JIT_NOALLOC)
def _coriolis_rows(out: np.ndarray, M: np.ndarray, nu: np.ndarray, mom: np.ndarray) -> None:
    """``gnc.coriolis_force_into`` per run; ``mom`` (6, N) holds the momenta M nu."""
    _mv6c_rows(mom, M, nu)
    for r in range(out.shape[1]):
        a0, a1, a2 = mom[0, r], mom[1, r], mom[2, r]
        b0, b1, b2 = mom[3, r], mom[4, r], mom[5, r]
        n0, n1, n2, n3, n4, n5 = nu[0, r], nu[1, r], nu[2, r], nu[3, r], nu[4, r], nu[5, r]
        out[0, r] = -(a1 * n5 - a2 * n4)
        out[1, r] = -(a2 * n3 - a0 * n5)
        out[2, r] = -(a0 * n4 - a1 * n3)
        out[3, r] = -(a1 * n2 - a2 * n1) - (b1 * n5 - b2 * n4)
        out[4, r] = -(a2 * n0 - a0 * n2) - (b2 * n3 - b0 * n5)
        out[5, r] = -(a0 * n1 - a1 * n0) - (b0 * n4 - b1 * n3)


# --- the plant's pieces with a run index (sim.plant's functions of the same names) ---


@njit(inline="always", **JIT_NOALLOC)
def _fluid_wrench_rows(
    tau: np.ndarray,
    nu: np.ndarray,
    R: np.ndarray,
    M_rb: np.ndarray,
    M_a: np.ndarray,
    D_l: np.ndarray,
    D_nl: np.ndarray,
    fk_mass: float,
    env: np.ndarray,
    work: BatchWork,
) -> None:
    """``plant._fluid_wrench_into`` per run (``_relative_velocity_into``, ``_hydro_into``,
    ``_froude_krylov_into``)."""
    vec = work.vec
    n = tau.shape[1]
    nu_rel = vec[B_NU_REL]
    v_c_b = vec[B_VCB]
    v_c_dot_b = vec[B_VCDB]
    _mtv3_rows(v_c_b, R, env[E_VC : E_VC + 3])
    for i in range(6):
        for r in range(n):
            nu_rel[i, r] = nu[i, r]
    for i in range(3):
        for r in range(n):
            nu_rel[i, r] -= v_c_b[i, r]
    _mtv3_rows(v_c_dot_b, R, env[E_AC : E_AC + 3])
    for r in range(n):
        w0, w1, w2 = nu[3, r], nu[4, r], nu[5, r]
        c0, c1, c2 = v_c_b[0, r], v_c_b[1, r], v_c_b[2, r]
        v_c_dot_b[0, r] -= w1 * c2 - w2 * c1
        v_c_dot_b[1, r] -= w2 * c0 - w0 * c2
        v_c_dot_b[2, r] -= w0 * c1 - w1 * c0
    c_rb = vec[B_CRB]
    c_a = vec[B_CA]
    _coriolis_rows(c_rb, M_rb, nu, vec[B_MOM])
    _coriolis_rows(c_a, M_a, nu_rel, vec[B_MOM])
    for i in range(6):
        dl, dnl = D_l[i], D_nl[i]
        ma0, ma1, ma2 = M_a[i, 0], M_a[i, 1], M_a[i, 2]
        for r in range(n):
            nr = nu_rel[i, r]
            t = -c_rb[i, r] - c_a[i, r]
            t -= (dl + dnl * abs(nr)) * nr
            t += ma0 * v_c_dot_b[0, r]
            t += ma1 * v_c_dot_b[1, r]
            t += ma2 * v_c_dot_b[2, r]
            tau[i, r] = t
    tmp = vec[B_A]
    _mtv3_rows(tmp, R, env[E_AC : E_AC + 3])
    for i in range(3):
        for r in range(n):
            tau[i, r] += fk_mass * tmp[i, r]


@njit(inline="always", **JIT_NOALLOC)
def _wire_force_rows(
    f: np.ndarray, p_att: np.ndarray, v_att: np.ndarray, env: np.ndarray, W0: float
) -> None:
    """``plant.wire_force_damped_into`` per run, its branches as selects: the force given
    from outside where ``E_WEXT`` is set, zero where the wire is slack."""
    for r in range(f.shape[1]):
        rest = W0 / env[E_KH, r] - W0 / env[E_KZ, r]
        dx = p_att[0, r] - (env[E_CT, r] + env[E_OFF, r])
        dy = p_att[1, r] - (env[E_CT + 1, r] + env[E_OFF + 1, r])
        dz = p_att[2, r] - (env[E_CT + 2, r] + env[E_LREST, r] - rest)
        d = np.sqrt(dx * dx + dy * dy + dz * dz)
        rate = (
            dx * (v_att[0, r] - env[E_VPIV, r])
            + dy * (v_att[1, r] - env[E_VPIV + 1, r])
            + dz * (v_att[2, r] - env[E_VPIV + 2, r])
        ) / d
        tension = env[E_KZ, r] * (d - rest) + env[E_WDAMP, r] * rate
        taut = (d > rest) & (d > 0.0) & (tension > 0.0)
        f0 = -tension * dx / d if taut else 0.0
        f1 = -tension * dy / d if taut else 0.0
        f2 = -tension * dz / d if taut else 0.0
        ext = env[E_WEXT, r] > 0.0
        f[0, r] = env[E_FWIRE, r] if ext else f0
        f[1, r] = env[E_FWIRE + 1, r] if ext else f1
        f[2, r] = env[E_FWIRE + 2, r] if ext else f2


@njit(inline="always", **JIT_NOALLOC)
def _contact_runs(
    tau: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, work: BatchWork
) -> None:
    """Add the contact wrench to ``tau`` for each run with a landing surface
    (``E_LAND`` > 0), as ``plant.tree_wrench_into`` does.

    A run whose tree is clearly above the surface and the posts' tops (its centre's depth
    plus the farthest its bottom corners reach, or plus half its height and the posts'
    height, plus ``CONTACT_MARGIN_M``, still above the surface) has a contact wrench of
    exactly zero: no corner penetrates and every post is free (``post_penetration_into``'s
    first test). It gets the scalar code's ``tau += 0.0`` as a select over the row (the
    scalar plant skips such a tree's contact too: ``plant.contact_reach``). The others (near
    the frame, or not finite) get the scalar ``plant.contact_wrench_trig_into`` on a copy of
    their column, with their sines and cosines from ``work.trig`` (the same arithmetic)."""
    reach = contact_reach(P)
    n = tau.shape[1]
    any_near = False
    for r in range(n):
        land = env[E_LAND, r]
        far = x[2, r] + reach < land
        skip = (land > 0.0) & far
        any_near |= (land > 0.0) & (not far)
        for i in range(6):
            tau[i, r] = tau[i, r] + 0.0 if skip else tau[i, r]
    if not any_near:
        return
    R = work.mat[BM_RT]
    col_x, col_env, col_R, col_cw = work.col_x, work.col_env, work.col_R, work.col_cw
    for r in range(n):
        land = env[E_LAND, r]
        if not (land > 0.0 and not x[2, r] + reach < land):
            continue
        for i in range(N_STATE):
            col_x[i] = x[i, r]
        for i in range(N_ENV):
            col_env[i] = env[i, r]
        for i in range(3):
            for j in range(3):
                col_R[i, j] = R[i, j, r]
        trig = work.trig
        contact_wrench_trig_into(
            col_cw,
            col_x,
            col_env,
            P,
            col_R,
            work.plant,
            trig[T_SPHI, r],
            trig[T_CPHI, r],
            trig[T_CTH, r],
            trig[T_SPSI, r],
            trig[T_CPSI, r],
        )
        for i in range(6):
            tau[i, r] += col_cw[i]


@njit(inline="always", **JIT_NOALLOC)
def _tree_wrench_rows(
    tau: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, work: BatchWork
) -> None:
    """``plant.tree_wrench_into`` per run."""
    vec = work.vec
    R = work.mat[BM_RT]
    n = tau.shape[1]
    _fluid_wrench_rows(
        tau,
        x[6:12],
        R,
        P.tree_M_rb,
        P.tree_M_a,
        P.tree_D_l,
        P.tree_D_nl,
        P.tree_fk_mass,
        env,
        work,
    )
    a = vec[B_A]
    b = vec[B_B]
    c = vec[B_C]
    d = vec[B_D]
    W0 = P.tree_W0
    for i in range(3):
        for r in range(n):
            b[i, r] = env[E_PUSH + i, r]
    for r in range(n):
        b[2, r] += W0
    _mtv3_rows(a, R, b)
    for i in range(3):
        for r in range(n):
            tau[i, r] += a[i, r]
    # the wire at its attachment point (attachment_velocity_into: tmp = w x r_att + v, R tmp)
    _mv3_const_rows(c, R, P.tree_r_att)
    for i in range(3):
        for r in range(n):
            c[i, r] = x[i, r] + c[i, r]
    ra0, ra1, ra2 = P.tree_r_att[0], P.tree_r_att[1], P.tree_r_att[2]
    for r in range(n):
        w0, w1, w2 = x[9, r], x[10, r], x[11, r]
        a[0, r] = w1 * ra2 - w2 * ra1
        a[1, r] = w2 * ra0 - w0 * ra2
        a[2, r] = w0 * ra1 - w1 * ra0
    for i in range(3):
        for r in range(n):
            a[i, r] = x[6 + i, r] + a[i, r]
    _mv3_rows(d, R, a)
    _wire_force_rows(b, c, d, env, W0)
    _mtv3_rows(a, R, b)
    for i in range(3):
        for r in range(n):
            tau[i, r] += a[i, r]
    for r in range(n):
        a0, a1, a2 = a[0, r], a[1, r], a[2, r]
        c[0, r] = ra1 * a2 - ra2 * a1
        c[1, r] = ra2 * a0 - ra0 * a2
        c[2, r] = ra0 * a1 - ra1 * a0
    for i in range(3):
        for r in range(n):
            tau[3 + i, r] += c[i, r]
    _contact_runs(tau, x, env, P, work)


@njit(inline="always", **JIT_NOALLOC)
def _rov_wrench_rows(
    tau: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, work: BatchWork
) -> None:
    """``plant.rov_wrench_into`` per run (the thrusters' wrench in ``work.thr``)."""
    _fluid_wrench_rows(
        tau,
        x[18:24],
        work.mat[BM_RR],
        P.rov_M_rb,
        P.rov_M_a,
        P.rov_D_l,
        P.rov_D_nl,
        P.rov_fk_mass,
        env,
        work,
    )
    W, B, r_bg, r_bb = P.rov_W, P.rov_B, P.rov_r_cg, P.rov_r_cb
    wb = W - B
    m0 = r_bg[0] * W - r_bb[0] * B
    m1 = r_bg[1] * W - r_bb[1] * B
    m2 = r_bg[2] * W - r_bb[2] * B
    trig, thr = work.trig, work.thr
    for r in range(tau.shape[1]):
        sphi, cphi = trig[T_ROV + T_SPHI, r], trig[T_ROV + T_CPHI, r]
        sth, cth = trig[T_ROV + T_STH, r], trig[T_ROV + T_CTH, r]
        # gvect_into, subtracted, then the thrusters' wrench added
        tau[0, r] -= wb * sth
        tau[1, r] -= -wb * cth * sphi
        tau[2, r] -= -wb * cth * cphi
        tau[3, r] -= -m1 * cth * cphi + m2 * cth * sphi
        tau[4, r] -= m2 * sth + m0 * cth * cphi
        tau[5, r] -= -m0 * cth * sphi - m1 * sth
        for i in range(6):
            tau[i, r] += thr[i, r]


@njit(inline="always", **JIT_NOALLOC)
def _coupling_rows(x: np.ndarray, P: PlantArrays, work: BatchWork) -> None:
    """``plant.coupling_wrench_into`` per run, into ``work.vec[B_WROV]`` and
    ``work.vec[B_WTREE]``."""
    vec, mat = work.vec, work.mat
    n = x.shape[1]
    R_t, R_r = mat[BM_RT], mat[BM_RR]
    a = vec[B_A]
    b = vec[B_B]
    R_m = mat[BM_RM]
    _mm_const_rows(R_m, R_t, P.mount_R)
    mr = P.mount_r
    mr0, mr1, mr2 = mr[0], mr[1], mr[2]
    # position error: R_r^T (p_m - p_rov), p_m = p_tree + R_t r_mount
    _mv3_const_rows(a, R_t, mr)
    for i in range(3):
        for r in range(n):
            a[i, r] = x[i, r] + a[i, r]
    for i in range(3):
        for r in range(n):
            a[i, r] = a[i, r] - x[12 + i, r]
    e_p_b = vec[B_EPB]
    _mtv3_rows(e_p_b, R_r, a)
    # velocity error: R_r^T R_t (v_t + w_t x r_mount) - v_rov
    for r in range(n):
        w0, w1, w2 = x[9, r], x[10, r], x[11, r]
        a[0, r] = w1 * mr2 - w2 * mr1
        a[1, r] = w2 * mr0 - w0 * mr2
        a[2, r] = w0 * mr1 - w1 * mr0
    for i in range(3):
        for r in range(n):
            a[i, r] = x[6 + i, r] + a[i, r]
    _mv3_rows(b, R_t, a)
    e_v_b = vec[B_EVB]
    _mtv3_rows(e_v_b, R_r, b)
    for i in range(3):
        for r in range(n):
            e_v_b[i, r] = e_v_b[i, r] - x[18 + i, r]
    R_tmp = mat[BM_TMP]
    _mtm_rows(R_tmp, R_r, R_m)
    e_th = vec[B_ETH]
    for r in range(n):
        e_th[0, r] = 0.5 * (R_tmp[2, 1, r] - R_tmp[1, 2, r])
        e_th[1, r] = 0.5 * (R_tmp[0, 2, r] - R_tmp[2, 0, r])
        e_th[2, r] = 0.5 * (R_tmp[1, 0, r] - R_tmp[0, 1, r])
    _mv3_rows(a, R_t, x[9:12])
    e_w = vec[B_EW]
    _mtv3_rows(e_w, R_r, a)
    for i in range(3):
        for r in range(n):
            e_w[i, r] = e_w[i, r] - x[21 + i, r]
    w_rov = vec[B_WROV]
    w_tree = vec[B_WTREE]
    K, C = P.coupling_K, P.coupling_C
    for i in range(3):
        kp, cv, kt, cw = K[i], C[i], K[3 + i], C[3 + i]
        for r in range(n):
            w_rov[i, r] = kp * e_p_b[i, r] + cv * e_v_b[i, r]
            w_rov[3 + i, r] = kt * e_th[i, r] + cw * e_w[i, r]
    R_tr = mat[BM_RTR]
    _mtm_rows(R_tr, R_t, R_r)  # ROV axes -> tree axes
    _mv3_rows(a, R_tr, w_rov[0:3])
    for i in range(3):
        for r in range(n):
            w_tree[i, r] = -a[i, r]
    for r in range(n):
        f0, f1, f2 = w_tree[0, r], w_tree[1, r], w_tree[2, r]
        b[0, r] = mr1 * f2 - mr2 * f1
        b[1, r] = mr2 * f0 - mr0 * f2
        b[2, r] = mr0 * f1 - mr1 * f0
    _mv3_rows(a, R_tr, w_rov[3:6])
    for i in range(3):
        for r in range(n):
            w_tree[3 + i, r] = b[i, r] - a[i, r]


@njit(inline="always", **JIT_NOALLOC)
def _tree_acceleration_rows(
    nu_dot: np.ndarray, x: np.ndarray, tau: np.ndarray, env: np.ndarray, P: PlantArrays, work
) -> None:
    """``plant.tree_acceleration_into`` per run: M^-1 tau, and where a run has the wire's
    mass (``E_WMASS`` > 0) the Sherman-Morrison correction instead (computed only when a run
    of the batch has it)."""
    n = nu_dot.shape[1]
    M_inv = P.tree_M_inv
    _mv6c_rows(nu_dot, M_inv, tau)
    any_mass = False
    for r in range(n):
        any_mass |= env[E_WMASS, r] > 0.0
    if not any_mass:
        return
    vec = work.vec
    R_t = work.mat[BM_RT]
    u = vec[B_U]
    for i in range(3):
        for r in range(n):
            u[i, r] = R_t[2, i, r]
            u[3 + i, r] = 0.0
    cor = vec[B_A]
    _cross_rows(cor, x[9:12], x[6:9])
    a_rot = vec[B_SCAL, S_AROT]
    for r in range(n):
        a_rot[r] = R_t[2, 0, r] * cor[0, r] + R_t[2, 1, r] * cor[1, r] + R_t[2, 2, r] * cor[2, r]
    rhs6 = vec[B_RHS6]
    for i in range(6):
        for r in range(n):
            rhs6[i, r] = tau[i, r] - env[E_WMASS, r] * a_rot[r] * u[i, r]
    base = vec[B_BASE]
    _mv6c_rows(base, M_inv, rhs6)
    minv_u = vec[B_MINVU]
    _mv6c_rows(minv_u, M_inv, u)
    scale = vec[B_SCAL, S_SCALE]
    for r in range(n):
        u_minv_u = 0.0
        for i in range(6):
            u_minv_u += u[i, r] * minv_u[i, r]
        u_base = 0.0
        for i in range(6):
            u_base += u[i, r] * base[i, r]
        m_w = env[E_WMASS, r]
        denom = 1.0 + m_w * u_minv_u
        scale[r] = m_w * u_base / denom
    for i in range(6):
        for r in range(n):
            corrected = base[i, r] - minv_u[i, r] * scale[r]
            nu_dot[i, r] = corrected if env[E_WMASS, r] > 0.0 else nu_dot[i, r]


@njit(inline="always", **JIT_NOALLOC)
def rhs_batch_into(
    xdot: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, work: BatchWork
) -> None:
    """``plant.rhs_into`` for every run: the slope of column r of ``x`` (N_STATE, N) into
    column r of ``xdot``, the thrusters' wrench taken from ``work.thr``."""
    vec, mat, trig = work.vec, work.mat, work.trig
    n = x.shape[1]
    _trig_rows(trig, x, 3, 0)
    R_t = mat[BM_RT]
    _rzyx_rows(R_t, trig, 0)
    tau_t = vec[B_TAU_T]
    _tree_wrench_rows(tau_t, x, env, P, work)
    if P.has_rov:
        _trig_rows(trig, x, 15, T_ROV)
        R_r = mat[BM_RR]
        _rzyx_rows(R_r, trig, T_ROV)
        tau_r = vec[B_TAU_R]
        _rov_wrench_rows(tau_r, x, env, P, work)
        any_grip = False
        for r in range(n):
            any_grip |= env[E_GRIP, r] > 0.0
        if any_grip:
            _coupling_rows(x, P, work)
            w_rov = vec[B_WROV]
            w_tree = vec[B_WTREE]
            for i in range(6):
                for r in range(n):
                    grip = env[E_GRIP, r] > 0.0
                    tau_r[i, r] = tau_r[i, r] + w_rov[i, r] if grip else tau_r[i, r]
                    tau_t[i, r] = tau_t[i, r] + w_tree[i, r] if grip else tau_t[i, r]
        T_r = mat[BM_TR]
        _tzyx_rows(T_r, trig, T_ROV)
        _mv3_rows(xdot[12:15], R_r, x[18:21])
        _mv3_rows(xdot[15:18], T_r, x[21:24])
        _mv6c_rows(xdot[18:24], P.rov_M_inv, tau_r)
    else:
        for i in range(12, N_STATE):
            for r in range(n):
                xdot[i, r] = 0.0
    T_t = mat[BM_TT]
    _tzyx_rows(T_t, trig, 0)
    _mv3_rows(xdot[0:3], R_t, x[6:9])
    _mv3_rows(xdot[3:6], T_t, x[9:12])
    _tree_acceleration_rows(xdot[6:12], x, tau_t, env, P, work)


@njit(inline="always", **JIT_NOALLOC)
def thruster_wrench_batch_into(n_rps: np.ndarray, P: PlantArrays, work: BatchWork) -> None:
    """``plant.thruster_wrench_into`` for every run, into ``work.thr`` (6, N)."""
    f, thr = work.f, work.thr
    m, n = n_rps.shape[0], n_rps.shape[1]
    for j in range(m):
        kp, kn, nmax = P.thr_k_pos[j], P.thr_k_neg[j], P.thr_n_max[j]
        for r in range(n):
            f[j, r] = thrust_of_one(n_rps[j, r], kp, kn, nmax)
    T = P.thr_T
    for i in range(6):
        for r in range(n):
            thr[i, r] = 0.0
        for j in range(m):
            t = T[i, j]
            for r in range(n):
                thr[i, r] += t * f[j, r]


@njit(**JIT_NOALLOC)
def rk4_batch_into(
    x_sb: np.ndarray,
    n_rps: np.ndarray,
    env: np.ndarray,
    P: PlantArrays,
    dt: float,
    work: BatchWork,
) -> None:
    """One RK4 step of every run, in place: column r of ``x_sb`` (N_STATE, N) becomes what
    ``plant.rk4_step_into`` makes of it with ``n_rps[:, r]`` (n_thrusters, N) and
    ``env[:, r]`` (N_ENV, N), bit for bit. ``work`` from ``make_batch_work(n_thrusters, N)``;
    nothing is allocated and the shapes are not checked (``rk4_batch`` checks them)."""
    n_state, n = x_sb.shape[0], x_sb.shape[1]
    thruster_wrench_batch_into(n_rps, P, work)
    xs = work.xs
    k = work.k
    k1, k2, k3, k4 = k[0], k[1], k[2], k[3]
    h2 = 0.5 * dt
    for i in range(n_state):
        for r in range(n):
            xs[i, r] = x_sb[i, r]
    for stage in range(4):
        rhs_batch_into(k[stage], xs, env, P, work)
        if stage == 0:
            for i in range(n_state):
                for r in range(n):
                    xs[i, r] = x_sb[i, r] + h2 * k1[i, r]
        elif stage == 1:
            for i in range(n_state):
                for r in range(n):
                    xs[i, r] = x_sb[i, r] + h2 * k2[i, r]
        elif stage == 2:
            for i in range(n_state):
                for r in range(n):
                    xs[i, r] = x_sb[i, r] + dt * k3[i, r]
    h6 = dt / 6.0
    for i in range(n_state):
        for r in range(n):
            x_sb[i, r] = x_sb[i, r] + h6 * (
                ((k1[i, r] + 2.0 * k2[i, r]) + 2.0 * k3[i, r]) + k4[i, r]
            )


def rk4_batch(
    x_sb: np.ndarray, n_rps: np.ndarray, env: np.ndarray, P: PlantArrays, dt: float
) -> np.ndarray:
    """``rk4_batch_into`` on a copy of ``x_sb``, with a fresh work space and its arguments'
    shapes checked: the new states (N_STATE, N)."""
    x = np.ascontiguousarray(x_sb, dtype=float).copy()
    n_rps = np.ascontiguousarray(n_rps, dtype=float)
    env = np.ascontiguousarray(env, dtype=float)
    if x.ndim != 2 or x.shape[0] != N_STATE:
        raise ValueError(f"x_sb must have shape ({N_STATE}, runs), got {x.shape}")
    n = x.shape[1]
    m = P.thr_T.shape[1]
    if n_rps.shape != (m, n):
        raise ValueError(f"n_rps must have shape ({m}, {n}) (thrusters, runs), got {n_rps.shape}")
    if env.shape != (N_ENV, n):
        raise ValueError(f"env must have shape ({N_ENV}, {n}) (N_ENV, runs), got {env.shape}")
    if not dt > 0.0:
        raise ValueError(f"dt must be > 0 s, got {dt}")
    rk4_batch_into(x, n_rps, env, P, float(dt), make_batch_work(m, n))
    return x
