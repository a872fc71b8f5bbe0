"""Plan a landing on the docking frame before flying it: can the ROV hold the tree over the
frame in this current, and which way should it turn and where (issue 11).

The steady force the ROV must give to hold the tree still at a pose is what the plant itself
says acts on the pair there: the wire's pull back towards its equilibrium, the current's drag
on the tree and on the ROV (and the added-mass Munk moment), taken from ``sim.plant``'s own
wrench functions with the pair at rest. What the ROV can give in that direction is the
largest multiple of it its thrusters reach inside their force limits (a small linear
programme over the thrusters' forces, surge, sway and yaw). Their ratio is the utilisation
of the pose; a landing is feasible when the pose over the frame needs at most
``FEASIBLE_UTILISATION`` of what the ROV has, leaving the rest for the controller to correct
the errors that the current's wandering and the waves make.

The approach: the tree turns either way, either where it is or over the frame; the plan takes
the way whose worst pose along it needs the least.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from control.simulation import Simulation
from sim import plant, site
from sim.docking import DockingFrame
from sim.gnc import ssa

FloatArray = NDArray[np.float64]

FEASIBLE_UTILISATION = 0.9
"""Largest share of the ROV's thrust that holding the tree over the frame may need: the
controller's integral action, which holds a steady load, is saturated at 90 % of the largest
thrust (thesis eq. 3.19, anti-windup), so a steadier load than that is not held."""
TURN_STEP_RAD = math.radians(5.0)
"""Heading step at which a turn is checked [rad]."""


@dataclass(frozen=True)
class PoseLoad:
    """What holding the tree still at one pose takes."""

    needed_xyn: FloatArray
    """Surge force [N], sway force [N] and yaw moment [N m] the ROV must give, in its own axes."""
    available_xyn: FloatArray
    """The most the thrusters give in the same direction (same ratio of the three) [N, N, N m]."""

    @property
    def utilisation(self) -> float:
        need = float(np.linalg.norm(self.needed_xyn))
        have = float(np.linalg.norm(self.available_xyn))
        return need / have if have > 0.0 else math.inf

    def words(self) -> str:
        n, a = self.needed_xyn, self.available_xyn
        return (
            f"{_newtons(math.hypot(n[0], n[1]), 'N')} and {_newtons(n[2], 'N m')} of yaw moment "
            f"needed, {_newtons(math.hypot(a[0], a[1]), 'N')} and {_newtons(a[2], 'N m')} "
            f"available in that direction ({100.0 * self.utilisation:.0f} % of the thrust)"
        )


def _newtons(value: float, unit: str) -> str:
    """A force or moment in words: kilo from 1000 up."""
    v = abs(value)
    return f"{v / 1e3:.2f} k{unit}" if v >= 1e3 else f"{v:.0f} {unit}"


@dataclass(frozen=True)
class LandingPlan:
    """The approach the dock leg flies, and whether it may."""

    feasible: bool
    reason: str
    """In words: the force over the frame needed against available, and the verdict."""
    at_frame: PoseLoad
    turn_rad: float
    """Signed turn from the present heading to the frame's heading [rad] (either way round)."""
    turn_first: bool
    """Turn where the tree is, then move over the frame (else move first, turn over it)."""
    worst_utilisation: float
    """The largest utilisation along the chosen approach."""


class Thrusters:
    """The ROV's thrusters in surge, sway and yaw, with their force limits.

    ``reach(direction)`` is the linear programme max s such that T3 u = s d with
    u_min <= u <= u_max. Thrusters that give no surge, sway or yaw (the vertical ones) drop
    out: zero thrust on them is inside their limits. With as many of the others as the three
    equations (both ROVs here) the thrust that gives s d is u = s p, p = T3^-1 d, and s is
    the first limit it meets; with one more, u = s p + t n (n spanning T3's null space), the
    programme has two unknowns (s, t) and its optimum is a vertex of a polygon (two thrusters
    at a limit, or one and s = 0), found by enumerating the vertices. Both in closed form, a
    few microseconds where scipy's HiGHS took about a millisecond (a third of a docking
    run's time); any other layout goes to HiGHS. They agree to rounding
    (``tests/test_landing.py``)."""

    FEASIBLE_TOL = 1e-9
    """Relative slack a vertex may have on a force limit and still count as inside (the
    rounding of a 2x2 solve on forces of 1e4 N is some 1e-12 relative)."""

    def __init__(self, sim: Simulation) -> None:
        arr = sim.arrays
        self.T3 = np.asarray(arr.thr_T, float)[[0, 1, 5], :]
        self.u_max = np.asarray(arr.thr_k_pos * arr.thr_n_max**2, float)
        self.u_min = np.asarray(-arr.thr_k_neg * arr.thr_n_max**2, float)
        used = np.any(self.T3 != 0.0, axis=0)
        t_used = self.T3[:, used]
        sv = np.linalg.svd(t_used, compute_uv=False) if t_used.size else np.zeros(0)
        rank = int(np.sum(sv > 1e-12 * sv[0])) if sv.size else 0
        self._nullity = t_used.shape[1] - 3 if rank == 3 else -1
        """0 or 1: closed form; else (-1 or more) HiGHS."""
        if self._nullity not in (0, 1):
            return
        # rank 3: every direction has a thrust, p = T^+ d is one (T T^+ = I)
        self._pinv = np.linalg.pinv(t_used)
        self._hi = self.u_max[used]
        self._lo = self.u_min[used]
        self._tol = self.FEASIBLE_TOL * float(np.max(np.abs(self._hi)))
        if self._nullity == 1:
            null = np.linalg.svd(t_used)[2][-1]
            # the polygon's edges a_j s + b_j t <= c_j: each thruster's upper and lower
            # limit, then s >= 0; a_j depends on the direction, b_j and c_j do not
            self._b = np.concatenate([null, -null, [0.0]])
            self._c = np.concatenate([self._hi, -self._lo, [0.0]])
            self._pairs = np.triu_indices(self._b.size, 1)

    def reach(self, direction: FloatArray) -> float:
        """Largest s with s * direction = T3 u inside the force limits."""
        if self._nullity not in (0, 1):
            return self._reach_highs(direction)
        p = self._pinv @ direction
        if self._nullity == 0:
            # s p_i within [lo_i, hi_i] for every thruster; s = 0 always is (lo <= 0 <= hi)
            with np.errstate(divide="ignore"):
                limit = np.where(p > 0.0, self._hi / p, np.where(p < 0.0, self._lo / p, np.inf))
            return float(max(np.min(limit), 0.0))
        a = np.concatenate([p, -p, [-1.0]])
        b, c = self._b, self._c
        j, k = self._pairs
        det = a[j] * b[k] - a[k] * b[j]
        ok = np.abs(det) > 1e-12 * (np.abs(a[j] * b[k]) + np.abs(a[k] * b[j]) + 1e-300)
        j, k, det = j[ok], k[ok], det[ok]
        s = (c[j] * b[k] - c[k] * b[j]) / det
        t = (a[j] * c[k] - a[k] * c[j]) / det
        inside = np.all(a[:, None] * s + b[:, None] * t <= c[:, None] + self._tol, axis=0)
        return float(max(np.max(s[inside], initial=0.0), 0.0))

    def reach_each(self, directions: FloatArray) -> FloatArray:
        """``reach`` of each row of ``directions`` (k, 3), the same numbers: with as many
        thrusters as equations, each row's p = T3^-1 d as ``reach`` makes it and the first
        limit of all rows at once (``plan_landing`` asks for some 150 poses, 8 us each one by
        one); any other layout one row at a time."""
        if self._nullity != 0 or len(directions) == 0:
            return np.array([self.reach(d) for d in directions], dtype=float)
        p = np.array([self._pinv @ d for d in directions])
        with np.errstate(divide="ignore"):
            limit = np.where(p > 0.0, self._hi / p, np.where(p < 0.0, self._lo / p, np.inf))
        return np.array([float(max(np.min(row), 0.0)) for row in limit])

    def _reach_highs(self, direction: FloatArray) -> float:
        m = self.T3.shape[1]
        c = np.zeros(m + 1)
        c[-1] = -1.0
        a_eq = np.hstack([self.T3, -direction.reshape(3, 1)])
        bounds = [(lo, hi) for lo, hi in zip(self.u_min, self.u_max, strict=True)]
        bounds.append((0.0, None))
        res = linprog(c, A_eq=a_eq, b_eq=np.zeros(3), bounds=bounds, method="highs")
        return float(res.x[-1]) if res.status == 0 else 0.0


def _environment(
    sim: Simulation,
    depth_m: float,
    speed: float,
    direction: float,
    crane_tip_n: FloatArray | None = None,
) -> FloatArray:
    """The plant's environment vector with the tree hung at ``depth_m`` from ``crane_tip_n``
    (default: where the crane tip is now) in a steady current."""
    length = sim.wire_length_for_depth(depth_m)
    tip = sim.crane_tip_n if crane_tip_n is None else crane_tip_n
    env = site.wire_environment(sim.plant_ps, length, tip, speed, direction)
    env[plant.E_VC] = speed * math.cos(direction)
    env[plant.E_VC + 1] = speed * math.sin(direction)
    return env


def pose_load(
    sim: Simulation,
    thrusters: Thrusters,
    north: float,
    east: float,
    psi: float,
    env: FloatArray,
    depth_m: float,
) -> PoseLoad:
    """The ROV's share of holding the pair still at (north, east, psi) at ``depth_m``."""
    return pose_loads(sim, thrusters, np.array([[north, east, psi]]), env, depth_m)[0]


def pose_loads(
    sim: Simulation, thrusters: Thrusters, poses: FloatArray, env: FloatArray, depth_m: float
) -> list[PoseLoad]:
    """``pose_load`` of each pose (north, east, psi) of ``poses`` (k, 3): the forces from one
    compiled call for all of them (``sim.plant.hold_needed_xyn``)."""
    needed_all = plant.hold_needed_xyn(np.ascontiguousarray(poses, float), depth_m, env, sim.arrays)
    norms = np.array([float(np.linalg.norm(needed)) for needed in needed_all])
    moving = norms != 0.0
    units = needed_all[moving] / norms[moving, None]
    reach = np.zeros(len(needed_all))
    reach[moving] = thrusters.reach_each(units)
    unit_all = np.zeros_like(needed_all)
    unit_all[moving] = units
    return [
        PoseLoad(needed, unit * r if m else needed.copy())
        for needed, unit, r, m in zip(needed_all, unit_all, reach, moving, strict=True)
    ]


def plan_landing(
    sim: Simulation, frame: DockingFrame, target_n: FloatArray, depth_m: float
) -> LandingPlan:
    """Check the pose over ``frame`` in the present current and choose the approach from the
    present target (north, east, heading), with the vessel where it stands
    (``missions.assist.plan_vessel`` moves it)."""
    thrusters = Thrusters(sim)
    speed, direction = sim.current_flowing()
    env = _environment(sim, depth_m, speed, direction)
    north, east = float(frame.center_n[0]), float(frame.center_n[1])
    at_frame = pose_load(sim, thrusters, north, east, frame.heading_rad, env, depth_m)
    short = ssa(frame.heading_rad - target_n[2])
    options = []
    for turn in (short, short - math.copysign(2.0 * math.pi, short)):
        steps = max(2, int(abs(turn) / TURN_STEP_RAD) + 1)
        headings = target_n[2] + np.linspace(0.0, turn, steps)
        for turn_first in (True, False):
            n, e = (target_n[0], target_n[1]) if turn_first else (north, east)
            poses = np.column_stack([np.full(steps, n), np.full(steps, e), headings])
            worst = max(p.utilisation for p in pose_loads(sim, thrusters, poses, env, depth_m))
            options.append((worst, abs(turn), turn, turn_first))
    worst, _, turn, turn_first = min(options)
    feasible = at_frame.utilisation <= FEASIBLE_UTILISATION
    current = f"{speed:.3f} m/s towards {math.degrees(direction) % 360:.0f} deg"
    limit = f"{100 * FEASIBLE_UTILISATION:.0f} %"
    if feasible:
        reason = (
            f"landing feasible in {current}: holding the tree over the frame takes "
            f"{at_frame.words()}, within the {limit} allowed"
        )
    else:
        reason = (
            f"landing not feasible in {current} with the frame at "
            f"{math.degrees(frame.heading_rad):.0f} deg: holding the tree over it takes "
            f"{at_frame.words()}, more than the {limit} allowed"
        )
    return LandingPlan(feasible, reason, at_frame, turn, turn_first, worst)
