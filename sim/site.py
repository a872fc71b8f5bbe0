"""The work site: where the wire hangs from, how long it is, and what the wire does to the tree.

Turns the closed forms of ``sim.wire`` into the per-step environment entries of the plant
(``sim.plant.E_*``) and finds the wire length that hangs the tree at a requested depth.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sim import plant
from sim import wire as wire_mod
from sim.gnc import JIT_NOALLOC
from sim.params import ParameterSet


def tree_drag_force(ps: ParameterSet, current_speed_mps: float) -> float:
    """F0 of eq. 2.27 without the ROV: the tree's own drag in the current, using its surge
    coefficients (the face the thesis's fit was made for) [N]."""
    v = abs(current_speed_mps)
    return float(ps.tree.D_l[0] * v + ps.tree.D_nl[0] * v * v)


def vertical_stiffness(ps: ParameterSet, length_m: float, current_speed_mps: float) -> float:
    """Elastic and geometric stiffness in series for this set's wire and tree (eq. 2.25)."""
    return wire_mod.vertical_stiffness(
        ps.wire,
        ps.tree.submerged_weight_newton,
        length_m,
        current_speed_mps,
        tree_drag_force(ps, current_speed_mps),
    )


def self_weight_stretch(ps: ParameterSet, length_m: float) -> float:
    """Stretch of the wire under its own weight alone, w L^2 / (2 EA) [m]."""
    w = ps.wire.submerged_weight_per_length()
    return 0.5 * w * length_m**2 / ps.wire.axial_stiffness_newton


def wire_length_for_depth(
    ps: ParameterSet,
    tree_depth_m: float,
    crane_tip_depth_m: float = 0.0,
    current_speed_mps: float = 0.0,
) -> float:
    """Unstretched wire length that hangs the tree's centre at ``tree_depth_m`` in still
    equilibrium: depth = crane tip + L + self-weight stretch + W0 / k_z(L) + z_a."""
    drop = tree_depth_m - crane_tip_depth_m - ps.tree.attachment_height_m
    if drop <= 1.0:
        raise ValueError(
            f"depth must put the tree more than 1 m below the crane tip plus the "
            f"attachment height ({ps.tree.attachment_height_m + 1.0:.2f} m), "
            f"got {tree_depth_m} m"
        )
    length = drop
    for _ in range(50):
        k_z = vertical_stiffness(ps, length, current_speed_mps)
        new = drop - self_weight_stretch(ps, length) - ps.tree.submerged_weight_newton / k_z
        if abs(new - length) < 1e-9:
            break
        length = new
    return length


def wire_environment(
    ps: ParameterSet,
    length_m: float,
    crane_tip_n: np.ndarray,
    current_speed_mps: float,
    current_direction_rad: float,
) -> np.ndarray:
    """Wire entries of the environment vector (the rest of it is zero): crane tip, rest length,
    horizontal and vertical stiffness, and the drag offset of the equilibrium point (eq. 2.29
    with F0 = 0, along the current)."""
    w = ps.wire.submerged_weight_per_length()
    w0 = ps.tree.submerged_weight_newton
    q = ps.wire.drag_per_length(abs(current_speed_mps))
    env = np.zeros(plant.N_ENV)
    env[plant.E_CT : plant.E_CT + 3] = crane_tip_n
    env[plant.E_LREST] = length_m + self_weight_stretch(ps, length_m)
    env[plant.E_KH] = wire_mod.horizontal_stiffness(w, w0, length_m)
    env[plant.E_KZ] = vertical_stiffness(ps, length_m, current_speed_mps)
    offset = wire_mod.horizontal_offset(q, w, w0, length_m, 0.0)
    env[plant.E_OFF] = offset * math.cos(current_direction_rad)
    env[plant.E_OFF + 1] = offset * math.sin(current_direction_rad)
    return env


@njit(**JIT_NOALLOC)
def environment_rows_into(
    env: np.ndarray,
    base: np.ndarray,
    speeds_mps: np.ndarray,
    directions_rad: np.ndarray,
    lengths_m: np.ndarray,
    stretch_m: float,
    crane_n: np.ndarray,
) -> None:
    """A chunk's environment rows (n, N_ENV) into ``env``: each row ``base`` (the wire's
    entries for the chunk's mean current, the push, the grip and the frame), with step j's
    current velocity ``[V cos(beta), V sin(beta), 0]``, no water acceleration, the wire's rest
    length ``lengths_m[j] + stretch_m`` and the crane tip ``crane_n[j]`` (``crane_n`` (n, 3),
    or (1, 3): a crane tip that stays put). The same operations on the same numbers as the
    numpy form it replaces (a repeat of ``base`` and whole-column products and sums: the
    simulator makes these rows for every chunk, and the dozen numpy calls cost more than
    the arithmetic); waves are added to the rows afterwards."""
    n = env.shape[0]
    still = crane_n.shape[0] == 1
    for j in range(n):
        row = env[j]
        for i in range(base.shape[0]):
            row[i] = base[i]
        row[plant.E_VC] = speeds_mps[j] * math.cos(directions_rad[j])
        row[plant.E_VC + 1] = speeds_mps[j] * math.sin(directions_rad[j])
        row[plant.E_VC + 2] = 0.0
        row[plant.E_AC] = 0.0
        row[plant.E_AC + 1] = 0.0
        row[plant.E_AC + 2] = 0.0
        row[plant.E_LREST] = lengths_m[j] + stretch_m
        c = crane_n[0] if still else crane_n[j]
        row[plant.E_CT] = c[0]
        row[plant.E_CT + 1] = c[1]
        row[plant.E_CT + 2] = c[2]
