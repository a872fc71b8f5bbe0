"""Control plant model (thesis section 2.4.2, eq. 2.48): the tree with the ROV rigidly attached,
in 3 DOF (surge, sway, yaw) about the tree's origin, and the wrench maps between the tree's and
the ROV's frames (eq. 3.6-3.7).

Everything here is built from the *configured* mounting vector ``r`` (tree origin -> ROV origin,
tree axes): the value the controller believes. The plant may have the ROV elsewhere.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from sim import wire as wm
from sim.gnc import Hmtrx, Rzyx
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]
DOF3 = np.array([0, 1, 5])
"""Rows/columns of the 6-DOF vectors kept in the 3-DOF model: surge, sway, yaw."""


@dataclass(frozen=True)
class SystemModel:
    """3-DOF control plant model of the connected system, tree origin, tree axes."""

    M: FloatArray
    """(3, 3) total mass: tree + added + ROV moved to the tree origin (eq. 2.48)."""
    D_l: FloatArray
    """(3,) linear damping (diagonal part) [N s/m, N m s/rad]."""
    D_nl: FloatArray
    """(3,) quadratic damping (diagonal part) [N s^2/m^2, N m s^2/rad^2]."""
    k_h: float
    """Horizontal wire stiffness at the configured depth [N/m] (eq. 2.30)."""
    rov_to_tree: FloatArray
    """(6, 6) wrench map ROV axes -> tree origin and axes, H(r)^T J(r) (eq. 3.6)."""
    tree_to_rov: FloatArray
    """(6, 6) its inverse, J(r)^-1 H(r)^-T (eq. 3.7)."""
    r_rov_from_tree_tree_m: FloatArray
    """(3,) configured mounting vector [m]."""
    psi_rov_from_tree_rad: float
    """Configured heading of the ROV relative to the tree [rad]."""


def _rotation6(psi: float) -> FloatArray:
    """J(r): block-diagonal rotation ROV axes -> tree axes for a relative heading psi."""
    R = Rzyx(0.0, 0.0, psi)
    J = np.zeros((6, 6))
    J[0:3, 0:3] = R
    J[3:6, 3:6] = R
    return J


def system_model(
    ps: ParameterSet, wire_length_m: float, r_rov_from_tree_tree_m: FloatArray | None = None
) -> SystemModel:
    """Build the control plant model for this parameter set at this wire length."""
    r = (
        ps.mount.r_rov_from_tree_tree_m
        if r_rov_from_tree_tree_m is None
        else np.asarray(r_rov_from_tree_tree_m, dtype=float)
    )
    psi = ps.mount.psi_rov_from_tree_rad
    J = _rotation6(psi)
    H = Hmtrx(r)
    # nu_rov (ROV axes) = J^T H nu_tree: kinetic energy gives M_sys = H^T J M_rov J^T H
    to_rov_vel = J.T @ H
    m_rov = to_rov_vel.T @ (ps.rov.M_rb + ps.rov.M_a) @ to_rov_vel
    d_l_rov = to_rov_vel.T @ np.diag(ps.rov.D_l) @ to_rov_vel
    d_nl_rov = to_rov_vel.T @ np.diag(ps.rov.D_nl) @ to_rov_vel
    m6 = ps.tree.M_rb + ps.tree.M_a + m_rov
    rov_to_tree = H.T @ J
    w = ps.wire.submerged_weight_per_length()
    return SystemModel(
        M=m6[np.ix_(DOF3, DOF3)],
        D_l=ps.tree.D_l[DOF3] + np.diag(d_l_rov)[DOF3],
        D_nl=ps.tree.D_nl[DOF3] + np.diag(d_nl_rov)[DOF3],
        k_h=wm.horizontal_stiffness(w, ps.tree.submerged_weight_newton, wire_length_m),
        rov_to_tree=rov_to_tree,
        tree_to_rov=np.asarray(np.linalg.inv(rov_to_tree), dtype=np.float64),
        r_rov_from_tree_tree_m=r.copy(),
        psi_rov_from_tree_rad=psi,
    )


def memo_by_arrays(fn: Callable[..., FloatArray]) -> Callable[..., FloatArray]:
    """Remember a function of float arrays by their shapes and bytes (up to 64 argument sets)
    and hand out copies. For the capacities below, small linear programs worked out again
    for every run although a campaign's runs share one ROV (some 10 ms a run, 4 % of a
    full-scale docking run)."""
    memo: dict[bytes, FloatArray] = {}

    @functools.wraps(fn)
    def remembered(*arrays: FloatArray) -> FloatArray:
        args = [np.ascontiguousarray(a, dtype=np.float64) for a in arrays]
        key = repr([a.shape for a in args]).encode() + b"".join(a.tobytes() for a in args)
        if key not in memo:
            if len(memo) >= 64:
                memo.clear()
            memo[key] = fn(*args)
        return memo[key].copy()

    return remembered


@memo_by_arrays
def dof_capacity(T: FloatArray, f_max_neg: FloatArray, f_max_pos: FloatArray) -> FloatArray:
    """Largest force each of surge, sway and yaw can have ALONE (the other two and heave zero)
    for thrusters with configuration T (6 x m) and force limits, the weaker of the two
    directions [N, N, N m]: a small linear program over the thruster forces."""
    rows = T[[0, 1, 2, 5]]
    bounds = list(zip(-f_max_neg, f_max_pos, strict=True))
    out = np.zeros(3)
    for k, row in enumerate((0, 1, 3)):
        others = [i for i in range(4) if i != row]
        best = math.inf
        for sign in (1.0, -1.0):
            res = linprog(
                -sign * rows[row],
                A_eq=rows[others],
                b_eq=np.zeros(3),
                bounds=bounds,
                method="highs",
            )
            best = min(best, sign * float(rows[row] @ res.x)) if res.success else 0.0
        out[k] = best
    return out
