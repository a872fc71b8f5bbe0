"""The work site: where the wire hangs from, how long it is, and what the wire does to the tree.

Turns the closed forms of ``sim.wire`` into the per-step environment entries of the plant
(``sim.plant.E_*``) and finds the wire length that hangs the tree at a requested depth.
"""

from __future__ import annotations

import math
from typing import NamedTuple

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
    return float(_stretch(w, ps.wire.axial_stiffness_newton, length_m))


@njit(**JIT_NOALLOC)
def _stretch(w: float, EA: float, L: float) -> float:
    """w L^2 / (2 EA), compiled (``self_weight_stretch`` and the chunks' rows alike)."""
    return 0.5 * w * (L * L) / EA


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


class WireSite(NamedTuple):
    """A parameter set's numbers behind the wire's entries of the environment rows
    (``wire_site``), for the compiled ``wire_entries_into`` and ``chunk_rows_into``."""

    w: float  # the wire's submerged weight per metre [N/m]
    W0: float  # the tree's submerged weight [N]
    EA: float  # the wire's axial stiffness [N]
    drag_q: float  # 0.5 rho d C_D: the current's drag per metre of wire is drag_q |V| V
    tree_D_l: float  # the tree's surge drag, linear [N s/m] (``tree_drag_force``)
    tree_D_nl: float  # and quadratic [N s^2/m^2]
    gl_nodes: np.ndarray  # the geometric compliance's Gauss-Legendre rule (``sim.wire``)
    gl_weights: np.ndarray


def wire_site(ps: ParameterSet) -> WireSite:
    """The ``WireSite`` of a parameter set."""
    wire = ps.wire
    return WireSite(
        float(wire.submerged_weight_per_length()),
        float(ps.tree.submerged_weight_newton),
        float(wire.axial_stiffness_newton),
        0.5 * wire_mod.RHO_WATER * wire.diameter_m * wire.drag_coefficient,
        float(ps.tree.D_l[0]),
        float(ps.tree.D_nl[0]),
        wire_mod._GL_NODES,
        wire_mod._GL_WEIGHTS,
    )


def wire_environment(
    ps: ParameterSet,
    length_m: float,
    crane_tip_n: np.ndarray,
    current_speed_mps: float,
    current_direction_rad: float,
) -> np.ndarray:
    """Wire entries of the environment vector (the rest of it is zero): crane tip, rest length,
    horizontal and vertical stiffness, and the drag offset of the equilibrium point (eq. 2.29
    with F0 = 0, along the current). The numbers every chunk's rows carry
    (``wire_entries_into``)."""
    env = np.empty(plant.N_ENV)
    tip = np.ascontiguousarray(crane_tip_n, dtype=np.float64)
    wire_entries_into(
        env, wire_site(ps), float(length_m), tip, float(current_speed_mps),
        float(current_direction_rad),
    )  # fmt: skip
    return env


@njit(**JIT_NOALLOC)
def wire_entries_into(
    env: np.ndarray,
    S: WireSite,
    length_m: float,
    crane_tip_n: np.ndarray,
    speed_mps: float,
    direction_rad: float,
) -> None:
    """``wire_environment`` into ``env`` (N_ENV,), compiled: the rest length with the wire's
    self-weight stretch, the horizontal stiffness (eq. 2.30, MODEL_NOTES form), the vertical
    stiffness (elastic and geometric in series, eq. 2.25, with the tree's own drag as F0) and
    the drag offset (eq. 2.29 with F0 = 0) along the current; every other entry zero. The
    operations of ``sim.wire``'s closed forms, with libm's logarithm."""
    for i in range(env.shape[0]):
        env[i] = 0.0
    L = length_m
    v = abs(speed_mps)
    env[plant.E_CT] = crane_tip_n[0]
    env[plant.E_CT + 1] = crane_tip_n[1]
    env[plant.E_CT + 2] = crane_tip_n[2]
    env[plant.E_LREST] = L + _stretch(S.w, S.EA, L)
    env[plant.E_KH] = wire_mod.horizontal_stiffness_c(S.w, S.W0, L)
    q = S.drag_q * abs(v) * v  # WireProperties.drag_per_length(|V|)
    f0 = S.tree_D_l * v + S.tree_D_nl * v * v  # tree_drag_force
    compliance = L / S.EA + wire_mod._gauss_compliance(
        q, S.w, S.W0, L, abs(f0), S.gl_nodes, S.gl_weights
    )
    env[plant.E_KZ] = 1.0 / compliance
    offset = wire_mod.horizontal_offset_c(q, S.w, S.W0, L, 0.0)
    env[plant.E_OFF] = offset * math.cos(direction_rad)
    env[plant.E_OFF + 1] = offset * math.sin(direction_rad)


@njit(**JIT_NOALLOC)
def chunk_rows_into(
    env: np.ndarray,
    S: WireSite,
    speeds_mps: np.ndarray,
    directions_rad: np.ndarray,
    wire_m: float,
    wire_target_m: float,
    winch_mps: float,
    crane_tip_n: np.ndarray,
    crane_target_n: np.ndarray,
    crane_mps: float,
    push_n: np.ndarray,
    grip: float,
    frame: np.ndarray,
    dt: float,
    held: np.ndarray,
    first_step: int,
    refresh_steps: int,
    out: np.ndarray,
    spring_held: np.ndarray,
    spring: np.ndarray,
    spring_w: float,
    spring_W0: float,
) -> None:
    """A chunk's environment rows (n, N_ENV) into ``env`` in one call (the simulator makes
    them for every chunk; a dozen Python and numpy calls cost more than the arithmetic).

    Every row carries the wire's slow entries held in ``held`` (N_ENV,): its horizontal and
    vertical stiffness and its drag offset (``wire_entries_into``). Row j's step is
    ``first_step + j``; where that is a multiple of ``refresh_steps`` (a whole second of the
    step grid) they are made anew before the row, from the current at that step and the
    payout and crane tip where that step starts, and held in between, so they do not depend
    on where a run's chunks begin (nor on a chunk running past whole seconds: the simulator's
    long chunks). Every row also carries the ``push_n``, the ``grip`` and the docking
    frame (``frame``: [on (1/0), north, east, heading, landing depth]); row j then its own
    current velocity [V cos(beta), V sin(beta), 0], no water acceleration, the rest length of
    the payout after j + 1 steps of the winch (towards ``wire_target_m``, ``winch_mps`` dt a
    step, the target once within a step of it) plus that payout's self-weight stretch, and the
    crane tip after j + 1 steps towards ``crane_target_n`` (``crane_mps`` dt a step along the
    line to the target, the target once within a step). Each step moves on from the one
    before, so a run gives the same rows bit for bit however it is cut into chunks. Waves are
    added to the rows afterwards. ``out`` (6,) gets [payout at the end, crane tip at the end
    (3), mean speed, mean direction over the chunk] (the means plain sums in order over n).

    The control model's wire spring refreshes with the wire's entries: ``spring_held`` (4,)
    [stiffness k_h, equilibrium north, east, the payout k_h is for] is made anew at the same
    rows, k_h from the payout there (``wire.horizontal_stiffness_c(spring_w, spring_W0,
    payout)``, the simulator's refresh: the wire's weight per metre and the tree's submerged
    weight as the control model has them; ``spring_W0`` <= 0 keeps it as given, for a run
    without control) and the equilibrium under the crane tip there, and row j of ``spring``
    (n, 3) gets the spring in force at step j. The control system takes it from there at
    each step of a chunk that runs past whole seconds (``control.jobs.ClosedChunk``), so such a
    chunk may run while the winch and the crane move."""
    n = env.shape[0]
    sum_v = 0.0
    sum_b = 0.0
    for j in range(n):
        sum_v += speeds_mps[j]
        sum_b += directions_rad[j]
    mean_v = sum_v / n
    mean_b = sum_b / n
    payout = wire_m + 0.0
    winch_step = dt * winch_mps
    tip0, tip1, tip2 = crane_tip_n[0], crane_tip_n[1], crane_tip_n[2]
    crane_step = dt * crane_mps
    tip_now = out[1:4]  # scratch: the crane tip where a refreshing step starts
    for j in range(n):  # each step from the one before: the same whatever the chunks
        if (first_step + j) % refresh_steps == 0:
            tip_now[0], tip_now[1], tip_now[2] = tip0, tip1, tip2
            wire_entries_into(held, S, payout, tip_now, speeds_mps[j], directions_rad[j])
            if spring_W0 > 0.0:
                if payout != spring_held[3]:  # (the simulator's refresh keeps it as well)
                    spring_held[0] = wire_mod.horizontal_stiffness_c(spring_w, spring_W0, payout)
                    spring_held[3] = payout
                spring_held[1] = tip0
                spring_held[2] = tip1
        spring[j, 0] = spring_held[0]
        spring[j, 1] = spring_held[1]
        spring[j, 2] = spring_held[2]
        row = env[j]
        for i in range(row.shape[0]):
            row[i] = held[i]
        for i in range(3):
            row[plant.E_PUSH + i] = push_n[i]
        row[plant.E_GRIP] = grip
        if frame[0] > 0.5:
            row[plant.E_FRAME] = frame[1]
            row[plant.E_FRAME + 1] = frame[2]
            row[plant.E_FRAME_PSI] = frame[3]
            row[plant.E_LAND] = frame[4]
        row[plant.E_VC] = speeds_mps[j] * math.cos(directions_rad[j])
        row[plant.E_VC + 1] = speeds_mps[j] * math.sin(directions_rad[j])
        row[plant.E_VC + 2] = 0.0
        row[plant.E_AC] = 0.0
        row[plant.E_AC + 1] = 0.0
        row[plant.E_AC + 2] = 0.0
        gap = wire_target_m - payout
        if gap != 0.0:
            if abs(gap) <= winch_step:
                payout = wire_target_m + 0.0
            elif gap > 0.0:
                payout = payout + winch_step
            else:
                payout = payout - winch_step
        row[plant.E_LREST] = payout + _stretch(S.w, S.EA, payout)
        if crane_mps > 0.0:
            d0 = crane_target_n[0] - tip0
            d1 = crane_target_n[1] - tip1
            d2 = crane_target_n[2] - tip2
            dist = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            if dist <= crane_step:
                tip0, tip1, tip2 = crane_target_n[0], crane_target_n[1], crane_target_n[2]
            elif dist > 0.0:
                frac = crane_step / dist
                tip0 = tip0 + frac * d0
                tip1 = tip1 + frac * d1
                tip2 = tip2 + frac * d2
        row[plant.E_CT] = tip0
        row[plant.E_CT + 1] = tip1
        row[plant.E_CT + 2] = tip2
    out[0] = payout
    out[1] = tip0
    out[2] = tip1
    out[3] = tip2
    out[4] = mean_v
    out[5] = mean_b
