"""The plant's RK4 step for N independent runs at once, laid out so the compiler vectorises
over the runs (structure of arrays, run index last).

``rk4_batch_into(x_sb, n_rps, env, P, dt, work)`` advances every column of ``x_sb``
(N_STATE, N) by one step of ``sim.plant.rk4_step_into``: run r's state ``x_sb[:, r]``, its
propeller speeds ``n_rps[:, r]`` and its environment row ``env[:, r]`` (N_ENV, N), one
``PlantArrays`` common to the batch. Each run's result is **bit for bit** what the scalar
step gives on that run's column alone: each quantity of the scalar code is computed with the
scalar code's operations in the scalar code's order (no reassociation; numba compiles
without fast-math or contraction into fused multiply-adds).

Each stage's right-hand side (``rhs_batch_into``) is a few loops over the runs whose bodies
hold a run's whole arithmetic in local variables: ``_tree_loads_into`` (the tree's angles,
rotation and the wrench of the water, its weight and the wire), the contact (below),
``_coupling_into`` (the grip's coupling, a loop of its own: with the ROV's wrench in the same
loop the compiler did not vectorise it) and ``_slopes_into`` (the ROV's wrench, both bodies'
kinematics and accelerations). The matrices of ``PlantArrays`` are read into tuples of
scalars before each loop, so a loop body touches only the runs' rows, has no branch (the
per-run choices are selects) and the compiler vectorises it whole (AVX-512 here: checked in
the assembly by ``benchmarks/batch_plant_benchmark.py``). The runs go in blocks of ``BLOCK``
through flat work arrays whose rows lie a constant ``BLOCK`` apart (``_at``), so the compiler
can tell the rows apart without checks at run time. An earlier form computed each
intermediate as a row of N runs in a 2-D work array, one small loop per row: the same bits,
but some 300 loops a stage whose set-up and remainders cost more than their arithmetic at a
batch's 8 to 32 runs (a step of 8 hanging runs 8.7 us, now 4.5; of 32 runs 15.6, now 11.7:
``docs/speed.md``, twenty-third pass).
Sines and cosines come from ``sim.trig.sincos`` (branch-free), as in the scalar plant.

What differs between runs is a select per run: gripping (``E_GRIP``: the coupling is
computed for every run and added where the run grips), the wire slack or taut, the wire
force from outside (``E_WEXT``), the wire's mass (``E_WMASS``: a loop of its own, run only
when a run of the block has it). Contact with the frame and the seabed (``E_LAND`` > 0) is
branchy, per corner and per post: after the tree's loads, it is evaluated run by run, for
the runs near the frame, by the scalar ``sim.plant.contact_wrench_trig_into`` on a
contiguous copy of the run's column (the same arithmetic); a run clearly above it adds the
scalar code's zero wrench as a select. A run that is not finite stays in its own column; the
others go on.

The step allocates nothing (compiled without numba's runtime, ``JIT_NOALLOC``):
``make_batch_work(n_thrusters)`` makes the work space once. ``rk4_batch`` is the
allocating form, with checks of its arguments, for tests and tools.

A caller whose runs' states live elsewhere (the batch kernel's slots, one run a row) loads
them into a block's columns itself (``load_column``), steps the block (``rk4_block_into``, after
``pad_block``) and takes each column's new state back (``store_column``): no copy through an
intermediate (N_STATE, N) array.
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

# rows of ``BatchWork.tree``: what the first loop leaves for the contact and the second loop
T_SPHI, T_CPHI, T_STH, T_CTH, T_SPSI, T_CPSI = 0, 1, 2, 3, 4, 5  # the tree's sines, cosines
T_R = 6  # its rotation body -> NED, row-major (nine rows)
T_TAU = 15  # the wrench on it of the water, its weight, the wire and the contact (six rows)
N_TREE = 21


LANES = 8
"""The doubles in an AVX-512 register: a block's loops over its runs have no scalar remainder
when their count is a multiple of this (on AVX2, two registers' worth). ``pad_block`` pads
a block to it."""

BLOCK = 64
"""Runs a block: the work arrays hold each quantity as a row of ``BLOCK`` runs, flat, so row
k of run r is element ``k * BLOCK + r`` (``_at``). The rows' distance is a constant the
compiler sees: the rows of one array then need no check against each other at run time
(with the arrays' width a run-time number, LLVM checked every written row against every row
read at each entry of a loop, ~0.7 us, or gave up vectorising). More runs go in blocks."""


@njit(inline="always", **JIT_NOALLOC)
def _at(k: int, r: int) -> np.uint64:
    """Where row k of run r is in a block's flat work array (unsigned: numba then adds no
    wrap-around of negative indices, which hid the rows' constant distance)."""
    return np.uint64(k * BLOCK + r)


@njit(inline="always", **JIT_NOALLOC)
def _rows6(a: np.ndarray, k: int, r: int) -> tuple:
    """Rows k .. k + 5 of run r of a block's flat work array."""
    return (
        a[_at(k, r)],
        a[_at(k + 1, r)],
        a[_at(k + 2, r)],
        a[_at(k + 3, r)],
        a[_at(k + 4, r)],
        a[_at(k + 5, r)],
    )


@njit(inline="always", **JIT_NOALLOC)
def _rows9(a: np.ndarray, k: int, r: int) -> tuple:
    """Rows k .. k + 8 of run r of a block's flat work array (a row-major 3x3 matrix)."""
    return (*_rows6(a, k, r), a[_at(k + 6, r)], a[_at(k + 7, r)], a[_at(k + 8, r)])


class BatchWork(NamedTuple):
    """Work arrays of ``rk4_batch_into``, flat (``_at``): made once (``make_batch_work``)
    and reused for every step."""

    x0: np.ndarray  # (N_STATE rows) the states at the step's start
    xs: np.ndarray  # (N_STATE rows) the stage state
    env: np.ndarray  # (N_ENV rows) the environment rows
    n: np.ndarray  # (n_thrusters rows) propeller speeds [rev/s]
    k: np.ndarray  # (4, N_STATE rows) the four slopes
    f: np.ndarray  # (n_thrusters rows) thrust of each thruster [N]
    thr: np.ndarray  # (6 rows) the thrusters' wrench on the ROV
    tree: np.ndarray  # (N_TREE rows) the tree's trigonometry, rotation and loads (T_*)
    grip: np.ndarray  # (12 rows) the grip's coupling wrench on the ROV, then on the tree
    col_x: np.ndarray  # (N_STATE,) one run's stage state, for the scalar contact
    col_env: np.ndarray  # (N_ENV,) its environment row
    col_R: np.ndarray  # (3, 3) its tree rotation
    col_cw: np.ndarray  # (6,) its contact wrench
    plant: PlantWork  # the scalar contact's work space
    runs: np.ndarray  # (BLOCK,) int64: for a caller's bookkeeping (which run a column holds)


@njit(**JIT)
def make_batch_work(n_thrusters: int) -> BatchWork:
    """A fresh work space for a plant with ``n_thrusters`` thrusters (any number of runs goes
    through one block's work space)."""
    return BatchWork(
        np.zeros(N_STATE * BLOCK),
        np.zeros(N_STATE * BLOCK),
        np.zeros(N_ENV * BLOCK),
        np.zeros(n_thrusters * BLOCK),
        np.zeros((4, N_STATE * BLOCK)),
        np.zeros(n_thrusters * BLOCK),
        np.zeros(6 * BLOCK),
        np.zeros(N_TREE * BLOCK),
        np.zeros(12 * BLOCK),
        np.zeros(N_STATE),
        np.zeros(N_ENV),
        np.zeros((3, 3)),
        np.zeros(6),
        make_work(n_thrusters),
        np.zeros(BLOCK, np.int64),
    )


# --- constants as tuples of scalars, read before a loop over the runs ---


@njit(inline="always", **JIT_NOALLOC)
def _v3(v: np.ndarray) -> tuple:
    return (v[0], v[1], v[2])


@njit(inline="always", **JIT_NOALLOC)
def _v6(v: np.ndarray) -> tuple:
    return (v[0], v[1], v[2], v[3], v[4], v[5])


@njit(inline="always", **JIT_NOALLOC)
def _m9(M: np.ndarray) -> tuple:
    """A 3x3 matrix, row-major."""
    return (M[0, 0], M[0, 1], M[0, 2], M[1, 0], M[1, 1], M[1, 2], M[2, 0], M[2, 1], M[2, 2])


@njit(inline="always", **JIT_NOALLOC)
def _m36(M: np.ndarray) -> tuple:
    """A 6x6 matrix, row-major."""
    return (
        *_v6(M[0]),
        *_v6(M[1]),
        *_v6(M[2]),
        *_v6(M[3]),
        *_v6(M[4]),
        *_v6(M[5]),
    )


# --- one run's arithmetic on scalars: the scalar ``sim.gnc`` and ``sim.plant`` helpers ---


@njit(inline="always", **JIT_NOALLOC)
def _rzyx(sphi: float, cphi: float, sth: float, cth: float, spsi: float, cpsi: float) -> tuple:
    """``gnc.Rzyx_into`` from the angles' sines and cosines, row-major."""
    return (
        cpsi * cth,
        -spsi * cphi + cpsi * sth * sphi,
        spsi * sphi + cpsi * cphi * sth,
        spsi * cth,
        cpsi * cphi + sphi * sth * spsi,
        -cpsi * sphi + sth * spsi * cphi,
        -sth,
        cth * sphi,
        cth * cphi,
    )


@njit(inline="always", **JIT_NOALLOC)
def _t9(A: tuple) -> tuple:
    """The transpose of a row-major 3x3 matrix."""
    return (A[0], A[3], A[6], A[1], A[4], A[7], A[2], A[5], A[8])


@njit(inline="always", **JIT_NOALLOC)
def _mv3(A: tuple, v0: float, v1: float, v2: float) -> tuple:
    """``gnc.mv3_into``: A @ v, each element summed from 0.0 (``_mv3(_t9(A), ...)`` is
    ``gnc.mtv3_into``'s A^T @ v with its sums)."""
    s0 = 0.0
    s0 += A[0] * v0
    s0 += A[1] * v1
    s0 += A[2] * v2
    s1 = 0.0
    s1 += A[3] * v0
    s1 += A[4] * v1
    s1 += A[5] * v2
    s2 = 0.0
    s2 += A[6] * v0
    s2 += A[7] * v1
    s2 += A[8] * v2
    return s0, s1, s2


@njit(inline="always", **JIT_NOALLOC)
def _mtv3(A: tuple, v0: float, v1: float, v2: float) -> tuple:
    """``gnc.mtv3_into``: A^T @ v."""
    return _mv3(_t9(A), v0, v1, v2)


@njit(inline="always", **JIT_NOALLOC)
def _mm_elem(A: tuple, B: tuple, i: int, j: int) -> float:
    """(A @ B)[i, j] as ``gnc.mm_into`` sums it."""
    s = 0.0
    s += A[3 * i] * B[j]
    s += A[3 * i + 1] * B[3 + j]
    s += A[3 * i + 2] * B[6 + j]
    return s


@njit(inline="always", **JIT_NOALLOC)
def _mm(A: tuple, B: tuple) -> tuple:
    """``gnc.mm_into``: A @ B (``_mm(_t9(A), B)`` is ``gnc.mtm_into``'s A^T @ B with its
    sums)."""
    return (
        _mm_elem(A, B, 0, 0),
        _mm_elem(A, B, 0, 1),
        _mm_elem(A, B, 0, 2),
        _mm_elem(A, B, 1, 0),
        _mm_elem(A, B, 1, 1),
        _mm_elem(A, B, 1, 2),
        _mm_elem(A, B, 2, 0),
        _mm_elem(A, B, 2, 1),
        _mm_elem(A, B, 2, 2),
    )


@njit(inline="always", **JIT_NOALLOC)
def _mtm(A: tuple, B: tuple) -> tuple:
    """``gnc.mtm_into``: A^T @ B."""
    return _mm(_t9(A), B)


@njit(inline="always", **JIT_NOALLOC)
def _mv6_elem(M: tuple, i: int, v: tuple) -> float:
    """(M @ v)[i] as ``gnc.mv6_into`` sums it (from 0.0, in the order of the columns)."""
    s = 0.0
    s += M[6 * i] * v[0]
    s += M[6 * i + 1] * v[1]
    s += M[6 * i + 2] * v[2]
    s += M[6 * i + 3] * v[3]
    s += M[6 * i + 4] * v[4]
    s += M[6 * i + 5] * v[5]
    return s


@njit(inline="always", **JIT_NOALLOC)
def _mv6(M: tuple, v: tuple) -> tuple:
    return (
        _mv6_elem(M, 0, v),
        _mv6_elem(M, 1, v),
        _mv6_elem(M, 2, v),
        _mv6_elem(M, 3, v),
        _mv6_elem(M, 4, v),
        _mv6_elem(M, 5, v),
    )


@njit(inline="always", **JIT_NOALLOC)
def _add_where(a: tuple, b: tuple, on: bool) -> tuple:
    """a + b where ``on``, a as it is elsewhere (a select: the scalar code's ``if``)."""
    return (
        a[0] + b[0] if on else a[0],
        a[1] + b[1] if on else a[1],
        a[2] + b[2] if on else a[2],
        a[3] + b[3] if on else a[3],
        a[4] + b[4] if on else a[4],
        a[5] + b[5] if on else a[5],
    )


@njit(inline="always", **JIT_NOALLOC)
def _coriolis(M: tuple, n: tuple) -> tuple:
    """``gnc.coriolis_force_into``: minus C(nu) nu from the momenta M nu."""
    a0, a1, a2 = _mv6_elem(M, 0, n), _mv6_elem(M, 1, n), _mv6_elem(M, 2, n)
    b0, b1, b2 = _mv6_elem(M, 3, n), _mv6_elem(M, 4, n), _mv6_elem(M, 5, n)
    n0, n1, n2, n3, n4, n5 = n
    return (
        -(a1 * n5 - a2 * n4),
        -(a2 * n3 - a0 * n5),
        -(a0 * n4 - a1 * n3),
        -(a1 * n2 - a2 * n1) - (b1 * n5 - b2 * n4),
        -(a2 * n0 - a0 * n2) - (b2 * n3 - b0 * n5),
        -(a0 * n1 - a1 * n0) - (b0 * n4 - b1 * n3),
    )


@njit(inline="always", **JIT_NOALLOC)
def _fluid_elem(
    i: int, crb: tuple, ca: tuple, nr: tuple, D_l: tuple, D_nl: tuple, M_a: tuple, e: tuple
) -> float:
    """Element i of ``plant._hydro_into``'s wrench: minus both Coriolis forces, the linear and
    quadratic damping of the relative velocity, the added mass's share of the current's
    acceleration ``e`` (body axes, with the rotation's term)."""
    t = -crb[i] - ca[i]
    t -= (D_l[i] + D_nl[i] * abs(nr[i])) * nr[i]
    t += M_a[6 * i] * e[0]
    t += M_a[6 * i + 1] * e[1]
    t += M_a[6 * i + 2] * e[2]
    return t


@njit(inline="always", **JIT_NOALLOC)
def _fluid_wrench(
    n: tuple,
    R: tuple,
    M_rb: tuple,
    M_a: tuple,
    D_l: tuple,
    D_nl: tuple,
    fk_mass: float,
    env: np.ndarray,
    r: int,
) -> tuple:
    """``plant._fluid_wrench_into`` of one body of run r (``_relative_velocity_into``,
    ``_hydro_into``, ``_froude_krylov_into``): its velocity ``n`` and rotation ``R``."""
    c0, c1, c2 = _mtv3(R, env[_at(E_VC, r)], env[_at(E_VC + 1, r)], env[_at(E_VC + 2, r)])
    d0, d1, d2 = _mtv3(R, env[_at(E_AC, r)], env[_at(E_AC + 1, r)], env[_at(E_AC + 2, r)])
    n0, n1, n2, n3, n4, n5 = n
    nr = (n0 - c0, n1 - c1, n2 - c2, n3, n4, n5)
    e = (d0 - (n4 * c2 - n5 * c1), d1 - (n5 * c0 - n3 * c2), d2 - (n3 * c1 - n4 * c0))
    crb = _coriolis(M_rb, n)
    ca = _coriolis(M_a, nr)
    return (
        _fluid_elem(0, crb, ca, nr, D_l, D_nl, M_a, e) + fk_mass * d0,
        _fluid_elem(1, crb, ca, nr, D_l, D_nl, M_a, e) + fk_mass * d1,
        _fluid_elem(2, crb, ca, nr, D_l, D_nl, M_a, e) + fk_mass * d2,
        _fluid_elem(3, crb, ca, nr, D_l, D_nl, M_a, e),
        _fluid_elem(4, crb, ca, nr, D_l, D_nl, M_a, e),
        _fluid_elem(5, crb, ca, nr, D_l, D_nl, M_a, e),
    )


@njit(inline="always", **JIT_NOALLOC)
def _wire_force(
    p0: float,
    p1: float,
    p2: float,
    v0: float,
    v1: float,
    v2: float,
    env: np.ndarray,
    r: int,
    W0: float,
) -> tuple:
    """``plant.wire_force_damped_into`` of run r at the attachment point p moving at v, its
    branches as selects: the force given from outside where ``E_WEXT`` is set, zero where
    the wire is slack."""
    rest = W0 / env[_at(E_KH, r)] - W0 / env[_at(E_KZ, r)]
    dx = p0 - (env[_at(E_CT, r)] + env[_at(E_OFF, r)])
    dy = p1 - (env[_at(E_CT + 1, r)] + env[_at(E_OFF + 1, r)])
    dz = p2 - (env[_at(E_CT + 2, r)] + env[_at(E_LREST, r)] - rest)
    d = np.sqrt(dx * dx + dy * dy + dz * dz)
    rate = (
        dx * (v0 - env[_at(E_VPIV, r)])
        + dy * (v1 - env[_at(E_VPIV + 1, r)])
        + dz * (v2 - env[_at(E_VPIV + 2, r)])
    ) / d
    tension = env[_at(E_KZ, r)] * (d - rest) + env[_at(E_WDAMP, r)] * rate
    taut = (d > rest) & (d > 0.0) & (tension > 0.0)
    f0 = -tension * dx / d if taut else 0.0
    f1 = -tension * dy / d if taut else 0.0
    f2 = -tension * dz / d if taut else 0.0
    ext = env[_at(E_WEXT, r)] > 0.0
    return (
        env[_at(E_FWIRE, r)] if ext else f0,
        env[_at(E_FWIRE + 1, r)] if ext else f1,
        env[_at(E_FWIRE + 2, r)] if ext else f2,
    )


@njit(inline="always", **JIT_NOALLOC)
def _tree_loads_into(
    tree: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, n: int
) -> None:
    """The first loop of a stage: each run's tree angles' sines and cosines, its rotation,
    and ``plant.tree_wrench_into``'s wrench but the contact's (the water, the weight and the
    push, the wire at its attachment point) into the rows of ``tree`` (``T_*``)."""
    M_rb, M_a = _m36(P.tree_M_rb), _m36(P.tree_M_a)
    D_l, D_nl = _v6(P.tree_D_l), _v6(P.tree_D_nl)
    fk_mass, W0 = P.tree_fk_mass, P.tree_W0
    ra0, ra1, ra2 = _v3(P.tree_r_att)
    for r in range(n):
        sphi, cphi = sincos(x[_at(3, r)])
        sth, cth = sincos(x[_at(4, r)])
        spsi, cpsi = sincos(x[_at(5, r)])
        R = _rzyx(sphi, cphi, sth, cth, spsi, cpsi)
        w0, w1, w2 = x[_at(9, r)], x[_at(10, r)], x[_at(11, r)]
        nu = (x[_at(6, r)], x[_at(7, r)], x[_at(8, r)], w0, w1, w2)
        t0, t1, t2, t3, t4, t5 = _fluid_wrench(nu, R, M_rb, M_a, D_l, D_nl, fk_mass, env, r)
        # the submerged weight and the push, in NED, into body axes
        a0, a1, a2 = _mtv3(
            R, env[_at(E_PUSH, r)], env[_at(E_PUSH + 1, r)], env[_at(E_PUSH + 2, r)] + W0
        )
        t0 += a0
        t1 += a1
        t2 += a2
        # the wire at its attachment point (attachment_velocity_into: R (v + w x r_att))
        c0, c1, c2 = _mv3(R, ra0, ra1, ra2)
        v0, v1, v2 = _mv3(
            R,
            x[_at(6, r)] + (w1 * ra2 - w2 * ra1),
            x[_at(7, r)] + (w2 * ra0 - w0 * ra2),
            x[_at(8, r)] + (w0 * ra1 - w1 * ra0),
        )
        f0, f1, f2 = _wire_force(
            x[_at(0, r)] + c0, x[_at(1, r)] + c1, x[_at(2, r)] + c2, v0, v1, v2, env, r, W0
        )
        a0, a1, a2 = _mtv3(R, f0, f1, f2)
        t0 += a0
        t1 += a1
        t2 += a2
        t3 += ra1 * a2 - ra2 * a1
        t4 += ra2 * a0 - ra0 * a2
        t5 += ra0 * a1 - ra1 * a0
        tree[_at(T_SPHI, r)], tree[_at(T_CPHI, r)] = sphi, cphi
        tree[_at(T_STH, r)], tree[_at(T_CTH, r)] = sth, cth
        tree[_at(T_SPSI, r)], tree[_at(T_CPSI, r)] = spsi, cpsi
        for i in range(9):
            tree[_at(T_R + i, r)] = R[i]
        tree[_at(T_TAU, r)], tree[_at(T_TAU + 1, r)], tree[_at(T_TAU + 2, r)] = t0, t1, t2
        tree[_at(T_TAU + 3, r)], tree[_at(T_TAU + 4, r)], tree[_at(T_TAU + 5, r)] = t3, t4, t5


@njit(inline="always", **JIT_NOALLOC)
def _contact_runs(x: np.ndarray, env: np.ndarray, P: PlantArrays, work: BatchWork, n: int) -> None:
    """Add the contact wrench to the tree's wrench (``work.tree[T_TAU:]``) for each run with
    a landing surface (``E_LAND`` > 0), as ``plant.tree_wrench_into`` does.

    A run whose tree is clearly above the surface and the posts' tops (its centre's depth
    plus the farthest its bottom corners reach, or plus half its height and the posts'
    height, plus ``CONTACT_MARGIN_M``, still above the surface) has a contact wrench of
    exactly zero: no corner penetrates and every post is free (``post_penetration_into``'s
    first test). It gets the scalar code's ``tau += 0.0`` as a select over the row (the
    scalar plant skips such a tree's contact too: ``plant.contact_reach``). The others (near
    the frame, or not finite) get the scalar ``plant.contact_wrench_trig_into`` on a copy of
    their column, with their sines and cosines from the first loop (the same arithmetic)."""
    reach = contact_reach(P)
    tree = work.tree
    any_near = False
    for r in range(n):
        land = env[_at(E_LAND, r)]
        far = x[_at(2, r)] + reach < land
        skip = (land > 0.0) & far
        any_near |= (land > 0.0) & (not far)
        for i in range(6):
            t = tree[_at(T_TAU + i, r)]
            tree[_at(T_TAU + i, r)] = t + 0.0 if skip else t
    if not any_near:
        return
    col_x, col_env, col_R, col_cw = work.col_x, work.col_env, work.col_R, work.col_cw
    for r in range(n):
        land = env[_at(E_LAND, r)]
        if not (land > 0.0 and not x[_at(2, r)] + reach < land):
            continue
        for i in range(N_STATE):
            col_x[i] = x[_at(i, r)]
        for i in range(N_ENV):
            col_env[i] = env[_at(i, r)]
        for i in range(3):
            for j in range(3):
                col_R[i, j] = tree[_at(T_R + 3 * i + j, r)]
        contact_wrench_trig_into(
            col_cw,
            col_x,
            col_env,
            P,
            col_R,
            work.plant,
            tree[_at(T_SPHI, r)],
            tree[_at(T_CPHI, r)],
            tree[_at(T_CTH, r)],
            tree[_at(T_SPSI, r)],
            tree[_at(T_CPSI, r)],
        )
        for i in range(6):
            tree[_at(T_TAU + i, r)] += col_cw[i]


@njit(inline="always", **JIT_NOALLOC)
def _tzyx(sphi: float, cphi: float, sth: float, cth: float) -> tuple:
    """``gnc.Tzyx_into`` with tan theta = sin theta / cos theta (as ``rhs_into``)."""
    tth = sth / cth
    return (1.0, sphi * tth, cphi * tth, 0.0, cphi, -sphi, 0.0, sphi / cth, cphi / cth)


@njit(inline="always", **JIT_NOALLOC)
def _tree_slopes_into(
    xdot: np.ndarray, x: np.ndarray, tree: np.ndarray, r: int, tau_t: tuple, M_inv: tuple
) -> None:
    """Run r's tree kinematics and ``M^-1 tau`` into ``xdot[0:12]`` (the rotation and the
    angles' sines and cosines from the first loop)."""
    R = _rows9(tree, T_R, r)
    T = _tzyx(tree[_at(T_SPHI, r)], tree[_at(T_CPHI, r)], tree[_at(T_STH, r)], tree[_at(T_CTH, r)])
    xdot[_at(0, r)], xdot[_at(1, r)], xdot[_at(2, r)] = _mv3(
        R, x[_at(6, r)], x[_at(7, r)], x[_at(8, r)]
    )
    xdot[_at(3, r)], xdot[_at(4, r)], xdot[_at(5, r)] = _mv3(
        T, x[_at(9, r)], x[_at(10, r)], x[_at(11, r)]
    )
    a = _mv6(M_inv, tau_t)
    for i in range(6):
        xdot[_at(6 + i, r)] = a[i]


@njit(inline="always", **JIT_NOALLOC)
def _slopes_into(
    xdot: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, work: BatchWork, n: int
) -> None:
    """The second loop of a stage with the ROV: each run's ROV wrench
    (``plant.rov_wrench_into``, the thrusters' from ``work.thr``), the grip's coupling from
    ``work.grip`` added where the run grips, both bodies' kinematics and ``M^-1 tau``."""
    M_rb, M_a = _m36(P.rov_M_rb), _m36(P.rov_M_a)
    D_l, D_nl = _v6(P.rov_D_l), _v6(P.rov_D_nl)
    fk_mass = P.rov_fk_mass
    W, B, r_bg, r_bb = P.rov_W, P.rov_B, P.rov_r_cg, P.rov_r_cb
    wb = W - B
    m0 = r_bg[0] * W - r_bb[0] * B
    m1 = r_bg[1] * W - r_bb[1] * B
    m2 = r_bg[2] * W - r_bb[2] * B
    rov_M_inv, tree_M_inv = _m36(P.rov_M_inv), _m36(P.tree_M_inv)
    tree, thr, grip_w = work.tree, work.thr, work.grip
    for r in range(n):
        sphi, cphi = sincos(x[_at(15, r)])
        sth, cth = sincos(x[_at(16, r)])
        spsi, cpsi = sincos(x[_at(17, r)])
        R_r = _rzyx(sphi, cphi, sth, cth, spsi, cpsi)
        nu = _rows6(x, 18, r)
        t0, t1, t2, t3, t4, t5 = _fluid_wrench(nu, R_r, M_rb, M_a, D_l, D_nl, fk_mass, env, r)
        # gvect_into, subtracted, then the thrusters' wrench added
        t0 -= wb * sth
        t1 -= -wb * cth * sphi
        t2 -= -wb * cth * cphi
        t3 -= -m1 * cth * cphi + m2 * cth * sphi
        t4 -= m2 * sth + m0 * cth * cphi
        t5 -= -m0 * cth * sphi - m1 * sth
        th = _rows6(thr, 0, r)
        tau_r = (t0 + th[0], t1 + th[1], t2 + th[2], t3 + th[3], t4 + th[4], t5 + th[5])
        w_rov = _rows6(grip_w, 0, r)
        w_tree = _rows6(grip_w, 6, r)
        grip = env[_at(E_GRIP, r)] > 0.0
        tau_r = _add_where(tau_r, w_rov, grip)
        tau_t = _add_where(_rows6(tree, T_TAU, r), w_tree, grip)
        T_r = _tzyx(sphi, cphi, sth, cth)
        xdot[_at(12, r)], xdot[_at(13, r)], xdot[_at(14, r)] = _mv3(R_r, nu[0], nu[1], nu[2])
        xdot[_at(15, r)], xdot[_at(16, r)], xdot[_at(17, r)] = _mv3(T_r, nu[3], nu[4], nu[5])
        a = _mv6(rov_M_inv, tau_r)
        for i in range(6):
            xdot[_at(18 + i, r)] = a[i]
        _tree_slopes_into(xdot, x, tree, r, tau_t, tree_M_inv)


@njit(inline="always", **JIT_NOALLOC)
def _coupling_into(x: np.ndarray, P: PlantArrays, work: BatchWork, n: int) -> None:
    """The grip's coupling (``plant.coupling_wrench_into``) of every run, gripping or not,
    into ``work.grip``: the wrench on the ROV (rows 0-5, ROV axes) and on the tree (rows
    6-11, tree axes). A loop of its own: with the ROV's wrench in the same loop, the
    compiler did not vectorise it."""
    mount_R = _m9(P.mount_R)
    mr0, mr1, mr2 = _v3(P.mount_r)
    K, C = _v6(P.coupling_K), _v6(P.coupling_C)
    tree, wc = work.tree, work.grip
    for r in range(n):
        sphi, cphi = sincos(x[_at(15, r)])
        sth, cth = sincos(x[_at(16, r)])
        spsi, cpsi = sincos(x[_at(17, r)])
        R_r = _rzyx(sphi, cphi, sth, cth, spsi, cpsi)
        R_t = _rows9(tree, T_R, r)
        R_m = _mm(R_t, mount_R)
        a0, a1, a2 = _mv3(R_t, mr0, mr1, mr2)
        e_p = _mtv3(
            R_r,
            (x[_at(0, r)] + a0) - x[_at(12, r)],
            (x[_at(1, r)] + a1) - x[_at(13, r)],
            (x[_at(2, r)] + a2) - x[_at(14, r)],
        )
        w0, w1, w2 = x[_at(9, r)], x[_at(10, r)], x[_at(11, r)]
        b0, b1, b2 = _mv3(
            R_t,
            x[_at(6, r)] + (w1 * mr2 - w2 * mr1),
            x[_at(7, r)] + (w2 * mr0 - w0 * mr2),
            x[_at(8, r)] + (w0 * mr1 - w1 * mr0),
        )
        ev0, ev1, ev2 = _mtv3(R_r, b0, b1, b2)
        e_v = (ev0 - x[_at(18, r)], ev1 - x[_at(19, r)], ev2 - x[_at(20, r)])
        R_e = _mtm(R_r, R_m)
        e_th = (0.5 * (R_e[7] - R_e[5]), 0.5 * (R_e[2] - R_e[6]), 0.5 * (R_e[3] - R_e[1]))
        a0, a1, a2 = _mv3(R_t, w0, w1, w2)
        ew0, ew1, ew2 = _mtv3(R_r, a0, a1, a2)
        e_w = (ew0 - x[_at(21, r)], ew1 - x[_at(22, r)], ew2 - x[_at(23, r)])
        w_rov = (
            K[0] * e_p[0] + C[0] * e_v[0],
            K[1] * e_p[1] + C[1] * e_v[1],
            K[2] * e_p[2] + C[2] * e_v[2],
            K[3] * e_th[0] + C[3] * e_w[0],
            K[4] * e_th[1] + C[4] * e_w[1],
            K[5] * e_th[2] + C[5] * e_w[2],
        )
        R_tr = _mtm(R_t, R_r)
        a0, a1, a2 = _mv3(R_tr, w_rov[0], w_rov[1], w_rov[2])
        f0, f1, f2 = -a0, -a1, -a2
        a0, a1, a2 = _mv3(R_tr, w_rov[3], w_rov[4], w_rov[5])
        for i in range(6):
            wc[_at(i, r)] = w_rov[i]
        wc[_at(6, r)], wc[_at(7, r)], wc[_at(8, r)] = f0, f1, f2
        wc[_at(9, r)] = (mr1 * f2 - mr2 * f1) - a0
        wc[_at(10, r)] = (mr2 * f0 - mr0 * f2) - a1
        wc[_at(11, r)] = (mr0 * f1 - mr1 * f0) - a2


@njit(inline="always", **JIT_NOALLOC)
def _tree_only_slopes_into(
    xdot: np.ndarray, x: np.ndarray, P: PlantArrays, work: BatchWork, n: int
) -> None:
    """The second loop of a stage without the ROV: the tree's kinematics and ``M^-1 tau``,
    the ROV's slopes zero."""
    tree_M_inv = _m36(P.tree_M_inv)
    tree = work.tree
    for r in range(n):
        tau_t = _rows6(tree, T_TAU, r)
        _tree_slopes_into(xdot, x, tree, r, tau_t, tree_M_inv)
        for i in range(12, N_STATE):
            xdot[_at(i, r)] = 0.0


@njit(inline="always", **JIT_NOALLOC)
def _wire_mass_into(
    xdot: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, work: BatchWork, n: int
) -> None:
    """``plant.tree_acceleration_into``'s Sherman-Morrison correction for the wire's mass,
    in the tree's accelerations (rows 6-11 of ``xdot``) where a run has it (``E_WMASS`` >
    0): run only when a run of the block has it."""
    any_mass = False
    for r in range(n):
        any_mass |= env[_at(E_WMASS, r)] > 0.0
    if not any_mass:
        return
    M_inv = _m36(P.tree_M_inv)
    tree, grip_w, has_rov = work.tree, work.grip, P.has_rov
    for r in range(n):
        # the tree's whole wrench as the second loop summed it: the grip's added where it grips
        grip = has_rov & (env[_at(E_GRIP, r)] > 0.0)
        tau = _add_where(_rows6(tree, T_TAU, r), _rows6(grip_w, 6, r), grip)
        u = (tree[_at(T_R + 6, r)], tree[_at(T_R + 7, r)], tree[_at(T_R + 8, r)], 0.0, 0.0, 0.0)
        w0, w1, w2 = x[_at(9, r)], x[_at(10, r)], x[_at(11, r)]
        v0, v1, v2 = x[_at(6, r)], x[_at(7, r)], x[_at(8, r)]
        a_rot = u[0] * (w1 * v2 - w2 * v1) + u[1] * (w2 * v0 - w0 * v2) + u[2] * (w0 * v1 - w1 * v0)
        m_w = env[_at(E_WMASS, r)]
        rhs6 = (
            tau[0] - m_w * a_rot * u[0],
            tau[1] - m_w * a_rot * u[1],
            tau[2] - m_w * a_rot * u[2],
            tau[3] - m_w * a_rot * u[3],
            tau[4] - m_w * a_rot * u[4],
            tau[5] - m_w * a_rot * u[5],
        )
        base = _mv6(M_inv, rhs6)
        minv_u = _mv6(M_inv, u)
        u_minv_u = 0.0
        for i in range(6):
            u_minv_u += u[i] * minv_u[i]
        u_base = 0.0
        for i in range(6):
            u_base += u[i] * base[i]
        denom = 1.0 + m_w * u_minv_u
        scale = m_w * u_base / denom
        for i in range(6):
            corrected = base[i] - minv_u[i] * scale
            xdot[_at(6 + i, r)] = corrected if m_w > 0.0 else xdot[_at(6 + i, r)]


@njit(**JIT_NOALLOC)
def rhs_batch_into(
    xdot: np.ndarray, x: np.ndarray, env: np.ndarray, P: PlantArrays, work: BatchWork, n: int
) -> None:
    """``plant.rhs_into`` for the first ``n`` runs of a block: the slope of run r's state
    (rows of ``x``, ``BLOCK`` apart) into ``xdot``, the thrusters' wrench from ``work.thr``.
    Compiled once and called for each stage (inlined four times into the step, its compile
    ran past ten minutes and 24 GB)."""
    _tree_loads_into(work.tree, x, env, P, n)
    _contact_runs(x, env, P, work, n)
    if P.has_rov:
        _coupling_into(x, P, work, n)
        _slopes_into(xdot, x, env, P, work, n)
    else:
        _tree_only_slopes_into(xdot, x, P, work, n)
    _wire_mass_into(xdot, x, env, P, work, n)


@njit(inline="always", **JIT_NOALLOC)
def _thruster_wrench_into(P: PlantArrays, work: BatchWork, n: int) -> None:
    """``plant.thruster_wrench_into`` for the block's first n runs, from their propeller
    speeds in ``work.n``, into ``work.thr``."""
    n_rps, f, thr = work.n, work.f, work.thr
    T = P.thr_T
    m = T.shape[1]
    for j in range(m):
        kp, kn, nmax = P.thr_k_pos[j], P.thr_k_neg[j], P.thr_n_max[j]
        for r in range(n):
            f[_at(j, r)] = thrust_of_one(n_rps[_at(j, r)], kp, kn, nmax)
    for i in range(6):
        for r in range(n):
            thr[_at(i, r)] = 0.0
        for j in range(m):
            t = T[i, j]
            for r in range(n):
                thr[_at(i, r)] += t * f[_at(j, r)]


@njit(inline="always", **JIT_NOALLOC)
def _stage_into(xs: np.ndarray, x0: np.ndarray, h: float, k: np.ndarray, n: int) -> None:
    """The next stage's state x0 + h k of the block's first n runs."""
    for i in range(N_STATE):
        for r in range(n):
            xs[_at(i, r)] = x0[_at(i, r)] + h * k[_at(i, r)]


@njit(**JIT_NOALLOC)
def rk4_block_into(P: PlantArrays, dt: float, work: BatchWork, n: int) -> None:
    """One RK4 step of the block's first ``n`` runs, loaded into ``work.x0``, ``work.env`` and
    ``work.n``: their new states into ``work.xs``, bit for bit ``plant.rk4_step_into``'s."""
    x0, xs, ew = work.x0, work.xs, work.env
    k1, k2, k3, k4 = work.k[0], work.k[1], work.k[2], work.k[3]
    h2 = 0.5 * dt
    h6 = dt / 6.0
    _thruster_wrench_into(P, work, n)
    rhs_batch_into(k1, x0, ew, P, work, n)
    _stage_into(xs, x0, h2, k1, n)
    rhs_batch_into(k2, xs, ew, P, work, n)
    _stage_into(xs, x0, h2, k2, n)
    rhs_batch_into(k3, xs, ew, P, work, n)
    _stage_into(xs, x0, dt, k3, n)
    rhs_batch_into(k4, xs, ew, P, work, n)
    for i in range(N_STATE):
        for r in range(n):
            a = _at(i, r)
            xs[a] = x0[a] + h6 * (((k1[a] + 2.0 * k2[a]) + 2.0 * k3[a]) + k4[a])


@njit(inline="always", **JIT_NOALLOC)
def load_column(
    work: BatchWork, c: int, x_r: np.ndarray, n_r: np.ndarray, env_r: np.ndarray
) -> None:
    """Run state ``x_r`` (N_STATE,), propeller speeds ``n_r`` and environment row ``env_r``
    (N_ENV,) into column ``c`` of the block."""
    x0, ew, nw = work.x0, work.env, work.n
    for i in range(N_STATE):
        x0[_at(i, c)] = x_r[i]
    for i in range(N_ENV):
        ew[_at(i, c)] = env_r[i]
    for i in range(n_r.shape[0]):
        nw[_at(i, c)] = n_r[i]


@njit(inline="always", **JIT_NOALLOC)
def store_column(work: BatchWork, c: int, x_r: np.ndarray) -> None:
    """Column ``c``'s new state (``rk4_block_into``'s) into ``x_r`` (N_STATE,)."""
    xs = work.xs
    for i in range(N_STATE):
        x_r[i] = xs[_at(i, c)]


@njit(inline="always", **JIT_NOALLOC)
def pad_block(work: BatchWork, n: int, m: int) -> int:
    """Fill the columns from ``n`` up to the next multiple of ``LANES`` (at most ``BLOCK``)
    with copies of column 0 (``m`` propeller speeds) that have no landing surface: they cost
    the plain step, no contact, and keep the loops free of a scalar remainder (22 runs took
    14.4 us a step, 24 runs 9.5). Returns the padded width (``n`` >= 1)."""
    w = min(BLOCK, (n + LANES - 1) // LANES * LANES)
    x0, ew, nw = work.x0, work.env, work.n
    for c in range(n, w):
        for i in range(N_STATE):
            x0[_at(i, c)] = x0[_at(i, 0)]
        for i in range(N_ENV):
            ew[_at(i, c)] = ew[_at(i, 0)]
        for i in range(m):
            nw[_at(i, c)] = nw[_at(i, 0)]
        ew[_at(E_LAND, c)] = 0.0
    return w


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
    ``env[:, r]`` (N_ENV, N), bit for bit, in blocks of ``BLOCK`` runs copied into the
    block's flat work arrays. ``work`` from ``make_batch_work``; nothing is allocated and
    the shapes are not checked (``rk4_batch`` checks them)."""
    x0, xs, ew, nw = work.x0, work.xs, work.env, work.n
    m = n_rps.shape[0]
    for c0 in range(0, x_sb.shape[1], BLOCK):
        n = min(BLOCK, x_sb.shape[1] - c0)
        for i in range(N_STATE):
            for r in range(n):
                x0[_at(i, r)] = x_sb[i, c0 + r]
        for i in range(N_ENV):
            for r in range(n):
                ew[_at(i, r)] = env[i, c0 + r]
        for i in range(m):
            for r in range(n):
                nw[_at(i, r)] = n_rps[i, c0 + r]
        rk4_block_into(P, dt, work, n)
        for i in range(N_STATE):
            for r in range(n):
                x_sb[i, c0 + r] = xs[_at(i, r)]


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
    rk4_batch_into(x, n_rps, env, P, float(dt), make_batch_work(m))
    return x
