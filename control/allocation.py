"""Thrust allocation: from a demanded generalised force to thruster forces and propeller speeds.

Thruster model (``sim.thrusters``, shared with the plant and the compiled loop; thesis
eq. 2.13 and 3.22): thruster ``i`` turning at ``n_i`` [rev/s] gives the force

    f_i = K_pos_i n_i^2   for n_i >= 0,        f_i = -K_neg_i n_i^2   for n_i < 0,

with ``|n_i| <= n_max_i``, and the thrusters together give ``tau_b = T @ f`` (6,) on the ROV
body. The force box is therefore ``-K_neg_i n_max_i^2 <= f_i <= K_pos_i n_max_i^2``.

Every allocator works on forces inside that box and converts to speeds at the end with the
inverse model, so a returned speed always reproduces the returned force in the plant.

- ``allocate_pinv``: the thesis's standard allocation (eq. 3.20-3.22), pseudo-inverse then
  each thruster clipped on its own. Cheap, but on an impossible demand the clipping changes
  the direction of the delivered force (the heading loss of thesis fig. 4.14-4.15).
- ``allocate_priority``: recursive null-space allocation with strict priority (Skjetne and
  Kjerstad 2013, thesis section 3.2.5), yaw > sway > surge > heave by default.
- ``allocate_qp``: lexicographic sequence of small quadratic programs (quadprog) on the real
  asymmetric box; gets the most of each DOF in priority order. Slower; for analysis and as the
  reference the other two are judged against.

``pinv`` and ``priority`` run in the 100 Hz loop: everything that depends only on the
configuration (pseudo-inverses, null-space directions) is computed once per
``(config, dofs)`` and cached, and the per-call work of ``priority`` is a numba kernel.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numba
import numpy as np
import quadprog
from numpy.typing import ArrayLike, NDArray

from sim import thrusters

FloatArray = NDArray[np.float64]

N_DOF = 6
SURGE, SWAY, HEAVE, ROLL, PITCH, YAW = range(N_DOF)
DEFAULT_DOFS = (SURGE, SWAY, HEAVE, YAW)
"""DOFs an ROV thrust allocation serves by default (roll and pitch are left to restoring)."""
DEFAULT_PRIORITY = (YAW, SWAY, SURGE, HEAVE)
"""Thesis section 3.2.5: yaw > sway > surge; heave added last."""

_RCOND = 1e-10
"""Relative singular-value cut-off for pseudo-inverses and null spaces (rank decisions)."""
_BOX_TOL = 1e-9
"""Tolerance on the force box, relative to the largest thruster force (rounding only)."""
_QP_REGULARISER = 1e-9
"""Weight of the utilisation-norm term in each QP stage, relative to a full-scale DOF error.
It makes the Hessian positive definite and picks the least-norm solution among the optimal
ones; it biases a stage's error by about this fraction of full-scale force."""
_QP_SLACK = 1e-9
"""Each QP stage sees the box widened by this much (normalised force, so 1e-9 of full scale)
and the result is clipped back. Thrusters already at a limit otherwise make pairs of box
constraints exactly opposite in the null space (an implied equality), which the dual
active-set solver reports as inconsistent."""
_MAX_PRIORITY_THRUSTERS = 12
"""The priority plan tabulates 2**m null-space directions per stage."""


@dataclass(frozen=True, eq=False)
class ThrusterConfig:
    """Thruster layout and limits of one ROV (m thrusters).

    Arrays are copied, converted to float64 and made read-only. Instances compare and hash
    by identity (arrays are not hashable); build one per ROV and reuse it, so the allocators'
    precomputed structures are built once.
    """

    T: FloatArray
    """(6, m) thrust configuration matrix: column i is the generalised force [N, N m] of
    thruster i per newton of thrust (thesis eq. 2.13, B.15, B.29)."""
    k_pos: FloatArray
    """(m,) forward thrust coefficient [N/(rev/s)^2], f = k_pos n^2 for n >= 0."""
    k_neg: FloatArray
    """(m,) backward thrust coefficient [N/(rev/s)^2], f = -k_neg n^2 for n < 0."""
    n_max_rps: FloatArray
    """(m,) propeller speed limit [rev/s], |n| <= n_max_rps."""

    def __post_init__(self) -> None:
        T = _checked_matrix("T", self.T)
        m = T.shape[1]
        object.__setattr__(self, "T", T)
        for name in ("k_pos", "k_neg", "n_max_rps"):
            object.__setattr__(self, name, _checked_positive_vector(name, getattr(self, name), m))

    @property
    def n_thrusters(self) -> int:
        """Number of thrusters m."""
        return int(self.T.shape[1])

    @property
    def f_max_pos(self) -> FloatArray:
        """(m,) largest forward force k_pos n_max^2 [N] (positive)."""
        return self.k_pos * self.n_max_rps**2

    @property
    def f_max_neg(self) -> FloatArray:
        """(m,) largest backward force magnitude k_neg n_max^2 [N] (positive)."""
        return self.k_neg * self.n_max_rps**2


@dataclass(frozen=True)
class AllocationResult:
    """Outcome of one allocation (all arrays read-only)."""

    force_newton: FloatArray
    """(m,) thruster forces [N], inside [-f_max_neg, f_max_pos]."""
    speed_rps: FloatArray
    """(m,) propeller speed commands [rev/s], inside [-n_max, n_max]."""
    tau_achieved: FloatArray
    """(6,) generalised force T @ force_newton on the body [N, N m]."""
    tau_unmet: FloatArray
    """(6,) demanded minus achieved on the allocated DOFs, 0 on the others [N, N m]."""
    utilisation: FloatArray
    """(m,) |f_i| over the limit in that direction, in [0, 1]."""


# --- validation ------------------------------------------------------------------------------


def _frozen(values: FloatArray) -> FloatArray:
    """Return ``values`` marked read-only (the caller owns the array)."""
    values.flags.writeable = False
    return values


def _as_float_array(name: str, value: ArrayLike) -> FloatArray:
    """Copy ``value`` into a float64 array, or raise ValueError naming the field."""
    try:
        return np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}: not a numeric array ({error})") from None


def _checked_matrix(name: str, value: ArrayLike) -> FloatArray:
    """(6, m) finite read-only copy of a thrust configuration matrix."""
    matrix = _as_float_array(name, value)
    if matrix.ndim != 2 or matrix.shape[0] != N_DOF or matrix.shape[1] < 1:
        raise ValueError(f"{name}: expected shape (6, m) with m >= 1, got {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise ValueError(f"{name}: contains NaN or infinity")
    return _frozen(matrix)


def _checked_positive_vector(name: str, value: ArrayLike, m: int) -> FloatArray:
    """(m,) read-only copy of a vector of finite positive numbers."""
    vector = _as_float_array(name, value)
    if vector.shape != (m,):
        raise ValueError(f"{name}: expected shape ({m},) to match T, got {vector.shape}")
    if not np.all(np.isfinite(vector) & (vector > 0.0)):
        raise ValueError(f"{name}: every entry must be finite and > 0, got {vector}")
    return _frozen(vector)


def _checked_vector(name: str, value: ArrayLike, size: int) -> FloatArray:
    """(size,) finite float64 array (a copy when ``value`` is not one already)."""
    vector = np.asarray(value, dtype=np.float64)
    if vector.shape != (size,):
        raise ValueError(f"{name}: expected shape ({size},), got {vector.shape}")
    if not np.all(np.isfinite(vector)):
        raise ValueError(f"{name}: contains NaN or infinity: {vector}")
    return vector


def _checked_dofs(name: str, dofs: tuple[int, ...]) -> NDArray[np.intp]:
    """Validated DOF indices (non-empty, distinct, each in 0..5)."""
    indices = np.array(dofs, dtype=np.intp)
    if indices.ndim != 1 or indices.size == 0:
        raise ValueError(f"{name}: expected a non-empty sequence of DOF indices, got {dofs}")
    if np.any((indices < 0) | (indices >= N_DOF)) or np.unique(indices).size != indices.size:
        raise ValueError(f"{name}: DOF indices must be distinct and in 0..5, got {dofs}")
    return indices


# --- thruster model --------------------------------------------------------------------------


def thrust_from_speed(config: ThrusterConfig, speed_rps: ArrayLike) -> FloatArray:
    """Thruster forces [N] (m,) from propeller speeds [rev/s] (m,), eq. 2.13.

    Speeds beyond +-n_max are saturated first (the motor cannot exceed them), so the force is
    always inside [-f_max_neg, f_max_pos].
    """
    n = _checked_vector("speed_rps", speed_rps, config.n_thrusters)
    return thrusters.thrust_from_speed(n, config.k_pos, config.k_neg, config.n_max_rps)


def speed_from_thrust(config: ThrusterConfig, force_newton: ArrayLike) -> FloatArray:
    """Propeller speeds [rev/s] (m,) giving thruster forces [N] (m,): the inverse of
    ``thrust_from_speed`` (signed square root with the coefficient of the force's sign,
    eq. 3.22), clipped to +-n_max. ``thrust_from_speed(c, speed_from_thrust(c, f)) == f``
    for f inside the force box.
    """
    f = _checked_vector("force_newton", force_newton, config.n_thrusters)
    return thrusters.speed_from_thrust(f, config.k_pos, config.k_neg, config.n_max_rps)


# --- shared precomputation and outputs --------------------------------------------------------


@dataclass(frozen=True)
class _Layout:
    """Everything an allocation call needs from the config, precomputed once per DOF set."""

    T: FloatArray  # (6, m) thrust configuration matrix
    k_pos: FloatArray  # (m,) [N/(rev/s)^2]
    k_neg: FloatArray  # (m,) [N/(rev/s)^2]
    n_max: FloatArray  # (m,) [rev/s]
    f_lo: FloatArray  # (m,) -f_max_neg [N]
    f_hi: FloatArray  # (m,) f_max_pos [N]
    tol: float  # box tolerance for rounding [N]
    dofs: NDArray[np.intp]  # (k,) allocated DOFs, in the order given
    dof_mask: NDArray[np.bool_]  # (6,) True on the allocated DOFs


def _layout(config: ThrusterConfig, dofs: NDArray[np.intp]) -> _Layout:
    """Precompute the force box and DOF mask of ``config`` for the DOFs ``dofs``."""
    mask = np.zeros(N_DOF, dtype=np.bool_)
    mask[dofs] = True
    f_hi, f_max_neg = config.f_max_pos, config.f_max_neg
    return _Layout(
        T=config.T,
        k_pos=config.k_pos,
        k_neg=config.k_neg,
        n_max=config.n_max_rps,
        f_lo=-f_max_neg,
        f_hi=f_hi,
        tol=_BOX_TOL * float(max(f_hi.max(), f_max_neg.max())),
        dofs=dofs,
        dof_mask=mask,
    )


def _result(layout: _Layout, force: FloatArray, tau_b: FloatArray) -> AllocationResult:
    """Assemble an AllocationResult from forces (m,) already inside the box."""
    achieved = layout.T @ force
    limit = np.where(force >= 0.0, layout.f_hi, -layout.f_lo)
    return AllocationResult(
        force_newton=_frozen(force),
        speed_rps=_frozen(
            thrusters.speed_from_thrust(force, layout.k_pos, layout.k_neg, layout.n_max)
        ),
        tau_achieved=_frozen(achieved),
        tau_unmet=_frozen(np.where(layout.dof_mask, tau_b - achieved, 0.0)),
        utilisation=_frozen(np.minimum(np.abs(force) / limit, 1.0)),
    )


def _checked_demand(tau_b: ArrayLike) -> FloatArray:
    """(6,) finite demanded generalised force [N, N m]."""
    return _checked_vector("tau_b", tau_b, N_DOF)


def _null_projector(rows: FloatArray, m: int) -> FloatArray:
    """(m, m) orthogonal projector onto the null space of ``rows`` (r, m); identity if r = 0."""
    if rows.shape[0] == 0:
        return np.eye(m)
    return np.eye(m) - np.linalg.pinv(rows, rcond=_RCOND) @ rows


def _null_basis(rows: FloatArray, m: int) -> FloatArray:
    """(m, m - rank) orthonormal basis of the null space of ``rows`` (r, m)."""
    if rows.shape[0] == 0 or not np.any(rows):
        return np.eye(m)
    _, singular, vh = np.linalg.svd(rows)
    rank = int(np.sum(singular > _RCOND * singular.max()))
    return np.ascontiguousarray(vh[rank:].T)


# --- standard allocation (eq. 3.20-3.22) -------------------------------------------------------


@dataclass(frozen=True)
class _PinvPlan:
    layout: _Layout
    T_pinv: FloatArray  # (m, k) Moore-Penrose pseudo-inverse of T[dofs] (eq. 3.21)


@lru_cache(maxsize=64)
def _pinv_plan(config: ThrusterConfig, dofs: tuple[int, ...]) -> _PinvPlan:
    indices = _checked_dofs("dofs", dofs)
    T_pinv = np.asarray(np.linalg.pinv(config.T[indices], rcond=_RCOND), dtype=np.float64)
    return _PinvPlan(layout=_layout(config, indices), T_pinv=T_pinv)


def allocate_pinv(
    config: ThrusterConfig, tau_b: ArrayLike, dofs: tuple[int, ...] = DEFAULT_DOFS
) -> AllocationResult:
    """Standard allocation of the thesis (eq. 3.20-3.22) with per-thruster saturation.

    tau_b: (6,) demanded generalised force in BODY [N, N m]; only the rows ``dofs`` are used.
    f = T_d^+ tau_d (least-norm forces, T_d = T[dofs], T_d^+ = T_d^T (T_d T_d^T)^-1 when T_d
    has full row rank, eq. 3.21), then each f_i is clipped to its own limit, which is the same
    as clipping its speed at n_max (eq. 3.22). Clipping thrusters independently changes the
    direction of the delivered force when the demand is impossible.
    """
    plan = _pinv_plan(config, tuple(dofs))
    tau = _checked_demand(tau_b)
    layout = plan.layout
    force = np.minimum(np.maximum(plan.T_pinv @ tau[layout.dofs], layout.f_lo), layout.f_hi)
    return _result(layout, force, tau)


# --- recursive null-space allocation with strict priority --------------------------------------


@dataclass(frozen=True)
class _PriorityPlan:
    layout: _Layout
    A: FloatArray  # (K, m) rows of T in priority order
    D: FloatArray  # (K, 2**m, m) stage direction per set of frozen thrusters (bit mask)
    R: FloatArray  # (K, m, K) least-norm correction serving stages k..K-1 at once


def _least_norm_direction(a: FloatArray, N: FloatArray) -> FloatArray:
    """(m,) d with a @ d = 1 and d in range(N), least norm; zeros if a is (nearly) in the
    span of the constraints that N projects out."""
    v = N @ a
    s = float(a @ v)
    if s <= _RCOND * float(a @ a) or s == 0.0:
        return np.zeros_like(a)
    return v / s


def _stage_directions(A: FloatArray) -> FloatArray:
    """(K, 2**m, m) table: D[k, mask] serves row k in the null space of the rows before it and
    of the thrusters frozen in ``mask`` (bit i set = thruster i frozen at a limit)."""
    K, m = A.shape
    eye = np.eye(m)
    D = np.zeros((K, 2**m, m))
    for k in range(K):
        for mask in range(2**m):
            frozen = [i for i in range(m) if mask >> i & 1]
            N = _null_projector(np.vstack([A[:k], eye[frozen]]), m)
            D[k, mask] = _least_norm_direction(A[k], N)
            D[k, mask, frozen] = 0.0  # exactly, not 1e-16: a frozen thruster must not move
    return D


def _joint_corrections(A: FloatArray) -> FloatArray:
    """(K, m, K) table: R[k] @ r is the least-norm force change, in the null space of rows
    0..k-1, that removes the residual r[k:] of rows k..K-1 at once (r[:k] is ignored)."""
    K, m = A.shape
    R = np.zeros((K, m, K))
    for k in range(K):
        N = _null_projector(A[:k], m)
        R[k][:, k:] = np.linalg.pinv(A[k:] @ N, rcond=_RCOND)
    return R


class _SameNumbers:
    """A ``ThrusterConfig`` that hashes and compares by its numbers (the config itself does
    so by identity): every simulation builds its own config, and a campaign's runs of one
    ROV have the same numbers, so they share one priority plan (its tables cost some 3 ms
    of ``pinv`` per run, more than a second's simulation)."""

    __slots__ = ("_key", "config")

    def __init__(self, config: ThrusterConfig) -> None:
        self.config = config
        self._key = tuple(
            (a.shape, a.tobytes()) for a in (config.T, config.k_pos, config.k_neg, config.n_max_rps)
        )

    def __hash__(self) -> int:
        return hash(self._key)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _SameNumbers) and self._key == other._key


def _priority_plan(config: ThrusterConfig, priority: tuple[int, ...]) -> _PriorityPlan:
    """The priority allocation's tables for this thruster layout and priority (read only by
    the allocator: shared by every config with the same numbers)."""
    return _priority_plan_of(_SameNumbers(config), priority)


@lru_cache(maxsize=64)
def _priority_plan_of(same: _SameNumbers, priority: tuple[int, ...]) -> _PriorityPlan:
    config = same.config
    indices = _checked_dofs("priority", priority)
    if config.n_thrusters > _MAX_PRIORITY_THRUSTERS:
        raise ValueError(
            f"T: allocate_priority supports at most {_MAX_PRIORITY_THRUSTERS} thrusters, "
            f"got {config.n_thrusters}"
        )
    A = np.ascontiguousarray(config.T[indices])
    return _PriorityPlan(
        layout=_layout(config, indices), A=A, D=_stage_directions(A), R=_joint_corrections(A)
    )


_NOALLOC: dict[str, Any] = {"cache": True, "_nrt": False}
"""The kernels of the closed loop's step: compiled without numba's runtime, so they cannot
allocate (see ``sim.gnc.JIT_NOALLOC``)."""


@numba.njit(cache=True, inline="always")
def _dot(a: FloatArray, b: FloatArray) -> float:
    """a @ b for short vectors (a plain loop compiles faster than a BLAS call)."""
    total = 0.0
    for i in range(a.size):
        total += a[i] * b[i]
    return total


@numba.njit(cache=True, inline="always")
def _step_to_limit(
    f: FloatArray, delta: FloatArray, f_lo: FloatArray, f_hi: FloatArray
) -> tuple[float, int]:
    """Largest alpha in [0, 1] keeping f + alpha delta inside the box, and the index of the
    thruster that stops it (-1 when alpha = 1)."""
    alpha = 1.0
    blocking = -1
    for i in range(f.size):
        if delta[i] > 0.0:
            room = (f_hi[i] - f[i]) / delta[i]
        elif delta[i] < 0.0:
            room = (f_lo[i] - f[i]) / delta[i]
        else:
            continue
        if room < alpha:
            alpha = max(room, 0.0)
            blocking = i
    return alpha, blocking


@numba.njit(cache=True, inline="always")
def _serve_stage_into(
    k: int,
    A: FloatArray,
    D: FloatArray,
    tau_rows: FloatArray,
    f: FloatArray,
    f_lo: FloatArray,
    f_hi: FloatArray,
    delta: FloatArray,
) -> None:
    """Move f (in place) along stage k's least-norm direction towards tau_rows[k], as far as
    the box allows; when thruster i stops it, freeze i at its limit and continue with the
    others. ``delta`` (m,) is a work array."""
    mask = 0
    for _ in range(f.size + 1):
        # delta = D[k, mask] * (tau_rows[k] - a_k f)
        gap = tau_rows[k] - _dot(A[k], f)
        for i in range(f.size):
            delta[i] = D[k, mask, i] * gap
        alpha, blocking = _step_to_limit(f, delta, f_lo, f_hi)
        for i in range(f.size):
            f[i] = f[i] + alpha * delta[i]
        if blocking < 0:
            break
        f[blocking] = f_hi[blocking] if delta[blocking] > 0.0 else f_lo[blocking]
        mask |= 1 << blocking


@numba.njit(cache=True, inline="always")
def _serve_remaining_into(
    f_new: FloatArray,
    k: int,
    A: FloatArray,
    R: FloatArray,
    tau_rows: FloatArray,
    f: FloatArray,
    f_lo: FloatArray,
    f_hi: FloatArray,
    tol: float,
    residual: FloatArray,
) -> bool:
    """Least-norm f' (into ``f_new``) serving rows k..K-1 at once without moving rows
    0..k-1, and whether f' is inside the box (within tol). ``residual`` (K,) is a work
    array."""
    for j in range(A.shape[0]):
        residual[j] = tau_rows[j] - _dot(A[j], f) if j >= k else 0.0
    for i in range(f.size):
        f_new[i] = f[i] + _dot(R[k, i], residual)
    # np.all(f_new >= f_lo - tol) and np.all(f_new <= f_hi + tol), then the clip, element by
    # element (the same comparisons and numpy's scalar minimum and maximum; no temporaries)
    inside = True
    for i in range(f.size):
        if not f_new[i] >= f_lo[i] - tol:
            inside = False
    if inside:
        for i in range(f.size):
            if not f_new[i] <= f_hi[i] + tol:
                inside = False
    for i in range(f.size):
        f_new[i] = np.minimum(np.maximum(f_new[i], f_lo[i]), f_hi[i])
    return inside


@numba.njit(cache=True, inline="always")
def _priority_forces(
    A: FloatArray,
    D: FloatArray,
    R: FloatArray,
    tau_rows: FloatArray,
    f_lo: FloatArray,
    f_hi: FloatArray,
    tol: float,
) -> FloatArray:
    """(m,) forces of the recursive null-space allocation (see ``allocate_priority``)."""
    out = np.empty(A.shape[1])
    work = np.empty((3, max(A.shape[0], A.shape[1])))
    _priority_forces_into(out, A, D, R, tau_rows, f_lo, f_hi, tol, work)
    return out


@numba.njit(cache=True, inline="always")
def _priority_forces_into(
    out: FloatArray,
    A: FloatArray,
    D: FloatArray,
    R: FloatArray,
    tau_rows: FloatArray,
    f_lo: FloatArray,
    f_hi: FloatArray,
    tol: float,
    work: FloatArray,
) -> None:
    """``_priority_forces`` into ``out`` (m,), allocating nothing; ``work`` (3, >= max(K, m))
    holds the stage's forces, the step direction and the residual."""
    m = A.shape[1]
    f = work[0, 0:m]
    delta = work[1, 0:m]
    residual = work[2, 0 : A.shape[0]]
    for i in range(m):
        f[i] = 0.0
    for k in range(A.shape[0]):
        if _serve_remaining_into(out, k, A, R, tau_rows, f, f_lo, f_hi, tol, residual):
            return
        _serve_stage_into(k, A, D, tau_rows, f, f_lo, f_hi, delta)
    for i in range(m):
        out[i] = np.minimum(np.maximum(f[i], f_lo[i]), f_hi[i])  # round off at the limits


def allocate_priority(
    config: ThrusterConfig, tau_b: ArrayLike, priority: tuple[int, ...] = DEFAULT_PRIORITY
) -> AllocationResult:
    """Recursive null-space allocation with strict priority (Skjetne and Kjerstad 2013).

    tau_b: (6,) demanded generalised force in BODY [N, N m]; rows ``priority`` are served, the
    first one first (default yaw > sway > surge > heave, thesis section 3.2.5).

    Algorithm, with a_k = T[priority[k]] and f starting at 0 (inside the box):
    for stage k = 0, 1, ..., K-1
      1. Look-ahead: the least-norm change of f in the null space of a_0..a_{k-1} that meets
         all remaining rows k..K-1 at once. If it keeps every thruster inside its limits, take
         it and stop: nothing needs to be given up. (Without this step a high stage served
         alone could saturate a thruster that the lower stages would have relieved, and a
         feasible demand would be missed.) When nothing saturates the result is the
         pseudo-inverse solution T_K^+ tau_K of all allocated rows together.
      2. Otherwise serve row k alone: delta = d_k (tau_k - a_k f), with d_k the least-norm
         direction (a_k d_k = 1) in the null space of a_0..a_{k-1}, so higher priorities keep
         exactly what they got. Take the largest alpha in [0, 1] with f + alpha delta inside
         the box; if alpha < 1 the blocking thruster is frozen at its limit and the rest of
         the error is redistributed along the direction that also leaves it untouched
         (repeated until the error is met or no free direction is left).
    Lower stages then only use what is left. All directions (for every set of frozen
    thrusters) are tabulated once per config; a call costs a few small matrix products.
    The result is strictly prioritised but not always the largest achievable value of the
    lower DOFs; ``allocate_qp`` gives that.
    """
    plan = _priority_plan(config, tuple(priority))
    tau = _checked_demand(tau_b)
    layout = plan.layout
    force = _priority_forces(
        plan.A, plan.D, plan.R, tau[layout.dofs], layout.f_lo, layout.f_hi, layout.tol
    )
    return _result(layout, force, tau)


# --- lexicographic quadratic programs ----------------------------------------------------------


@dataclass(frozen=True)
class _QpPlan:
    layout: _Layout
    scale: FloatArray  # (m,) newtons per unit of normalised force x = f / scale
    A: FloatArray  # (K, m) rows in priority order, in x, each scaled to unit norm
    row_norm: FloatArray  # (K,) norm of each row before scaling (0 for an unusable DOF)
    Z: tuple[FloatArray, ...]  # K null-space bases (m, n_k) of the rows before stage k


@lru_cache(maxsize=64)
def _qp_plan(config: ThrusterConfig, priority: tuple[int, ...]) -> _QpPlan:
    indices = _checked_dofs("priority", priority)
    layout = _layout(config, indices)
    scale = np.maximum(layout.f_hi, -layout.f_lo)
    rows = config.T[indices] * scale
    row_norm = np.linalg.norm(rows, axis=1)
    A = rows / np.where(row_norm > 0.0, row_norm, 1.0)[:, None]
    m = config.n_thrusters
    return _QpPlan(
        layout=layout,
        scale=scale,
        A=A,
        row_norm=row_norm,
        Z=tuple(_null_basis(A[:k], m) for k in range(len(indices))),
    )


def _qp_stage(
    a: FloatArray, target: float, Z: FloatArray, x: FloatArray, x_lo: FloatArray, x_hi: FloatArray
) -> FloatArray:
    """x + Z z minimising (a (x + Z z) - target)^2 + eps |x + Z z|^2 on the box.

    Moving only in range(Z) keeps the higher-priority rows where they are. Returns x when the
    stage has no freedom left or quadprog fails (numerically degenerate stage).
    """
    g = Z.T @ a
    if Z.shape[1] == 0 or float(g @ g) <= _RCOND:
        return x
    c = float(a @ x) - target
    hessian = 2.0 * (np.outer(g, g) + _QP_REGULARISER * np.eye(Z.shape[1]))
    linear = -2.0 * (c * g + _QP_REGULARISER * (Z.T @ x))
    constraints = np.hstack([Z.T, -Z.T])
    bounds = np.concatenate([x_lo - x, x - x_hi]) - _QP_SLACK
    try:
        z = quadprog.solve_qp(hessian, linear, constraints, bounds, 0)[0]
    except ValueError:
        return x
    return np.clip(x + Z @ z, x_lo, x_hi)


def allocate_qp(
    config: ThrusterConfig, tau_b: ArrayLike, priority: tuple[int, ...] = DEFAULT_PRIORITY
) -> AllocationResult:
    """Constrained optimal allocation: a lexicographic sequence of small QPs (quadprog).

    tau_b: (6,) demanded generalised force in BODY [N, N m]; rows ``priority`` are served in
    that order. Forces are normalised, x_i = f_i / s_i with s_i the larger limit of thruster
    i, so the box is the real asymmetric one, [-f_max_neg_i, f_max_pos_i] / s_i. Stage k
    solves

        min_x  (a_k x - tau_k)^2 + eps |x|^2     (a_k: row k, scaled to unit norm)
        s.t.   box,  a_j x = value reached at stage j for every j < k,

    parametrised as x = x_prev + Z_k z with Z_k an orthonormal basis of the null space of the
    earlier rows, so the equalities hold exactly and the QP has only the 2m box inequalities.
    Each DOF thus gets the most it can without taking anything from a higher one. eps
    (``_QP_REGULARISER``) picks the least utilisation-norm solution among the optimal ones
    and biases each stage by about eps times full-scale force. Not meant for the 100 Hz loop
    (a few QP solves per call).
    """
    plan = _qp_plan(config, tuple(priority))
    tau = _checked_demand(tau_b)
    layout = plan.layout
    x_lo, x_hi = layout.f_lo / plan.scale, layout.f_hi / plan.scale
    x = np.zeros(config.n_thrusters)
    for k, dof in enumerate(layout.dofs):
        if plan.row_norm[k] > 0.0:
            target = float(tau[dof]) / float(plan.row_norm[k])
            x = _qp_stage(plan.A[k], target, plan.Z[k], x, x_lo, x_hi)
    force = np.clip(x * plan.scale, layout.f_lo, layout.f_hi)
    return _result(layout, force, tau)
