"""Vessel-assisted landing (issue 44): where the vessel should put the crane tip so that the
ROV holds the tree over the docking frame with thrust to spare, as the sea trial's crew did
(thesis, section 5.2.3: "the captain of the ship was asked to move the ship a bit, so the
equilibrium point would move a bit closer to the setpoint").

The tree hangs as a pendulum: wire, submerged weight and the current's drag put its rest
point downstream of the crane tip. Held anywhere else, the ROV gives the wire's pull back to
that rest point (about the wire's horizontal stiffness, eq. 2.30, times the distance) and
the current's drag on the pair. The force the ROV needs over the frame is therefore linear in
the crane tip's position: the plan moves the crane tip until the rest point lies where the
ROV needs it, over the frame and offset upstream by what takes the current's drag, so that
the thrusters are left with the yaw moment alone, and then, since the ROV's thrust differs
by direction, minimises the share of the thrust needed (``missions.landing.pose_load``'s
utilisation) around that point. The approach flies the tree from where it hangs to the frame
while the vessel moves, tree and crane tip in step, so the wire's pull stays what it was at
the start; the turn to the frame's heading is made either before the move (vessel where it
stands), or over the frame (vessel moved), or where the tree hangs from the vessel as it
stands (reached first, the wire's pull let go), either way round, whichever needs least.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize

from control.simulation import Simulation
from missions import landing
from sim.docking import DockingFrame
from sim.gnc import ssa

FloatArray = NDArray[np.float64]

VESSEL_MODES = ("auto", "advise", "fixed")
"""A dock leg's ``vessel``: move the vessel itself, advise the operator to, or leave it."""
VESSEL_SPEED_MPS = 0.2
"""How fast the dock leg moves the vessel [m/s]: the middle of the 0.1-0.3 m/s at which a
vessel on dynamic positioning is repositioned in small steps during a lift (issue 44); the
``vessel`` leg's default is the slower end, 0.1 m/s."""
ASSIST_UTILISATION = 0.5
"""With ``vessel = "auto"`` or ``"advise"``, the vessel is moved only when holding the tree
over the frame from where it stands needs more than this share of the ROV's thrust: the
crew asked the captain when the commanded force neared the limit, not for every landing."""
MIN_MOVE_M = 0.1
"""A planned move shorter than this is not made [m]."""
REPLAN_S = 30.0
"""The outer loop's period: how often a landing re-plans the vessel's place in the present
current [s] (the vessel takes tens of seconds to move a metre or two)."""
REPLAN_MOVE_M = 0.3
"""With ``vessel = "advise"``, the outer loop repeats its advice only when the planned place
has moved further than this from the last advised [m] (0.3 m of wire offset is some 0.26 kN
at full scale)."""
APPROACH_UTILISATION = 1.0
"""The most the approach with the vessel's help may need on the way (the turn to the frame's
heading, the move): a passing need at the thrusters' limit stalls the tree no longer than it
takes to pass, beyond it the tree stops there."""
ADVISE_TOL_M = 0.5
"""With ``vessel = "advise"``, the operator's move counts as done within this of the planned
place [m] (or when holding over the frame from there needs at most ``ASSIST_UTILISATION``)."""
PATH_SAMPLES = 11
"""Points at which the tree's move with the vessel is checked."""


@dataclass(frozen=True)
class VesselPlan:
    """Where the crane tip should stand for a landing, and the approach flown from there."""

    feasible: bool
    reason: str
    """In words: the force over the frame with the vessel there, and the verdict."""
    from_n: FloatArray
    """Where the crane tip stands now (north, east, down) [m]."""
    crane_tip_n: FloatArray
    """Where it should stand (north, east, down) [m]."""
    at_frame: landing.PoseLoad
    """Holding the tree over the frame with the crane tip there."""
    turn_rad: float
    """Signed turn from the present heading to the frame's [rad]."""
    turn_at: str
    """Where the tree turns to the frame's heading: "start", where it is held, before the
    move; "frame", over the frame after it; "rest", where it hangs from the vessel as the
    vessel stands (the wire pulls nothing there), reached before the turn and the move."""
    rest_ne: FloatArray
    """Where the tree hangs from the vessel as it stands (north, east) [m]."""
    worst: landing.PoseLoad
    """The pose along the approach that needs the largest share of the thrust."""

    @property
    def worst_utilisation(self) -> float:
        return self.worst.utilisation

    @property
    def move_ne_m(self) -> FloatArray:
        """The vessel's move (north, east) [m]."""
        return self.crane_tip_n[0:2] - self.from_n[0:2]

    @property
    def distance_m(self) -> float:
        return float(np.hypot(*self.move_ne_m))

    @property
    def bearing_deg(self) -> float:
        """Compass bearing of the move, 0 north, 90 east, in [0, 360) [deg]."""
        return compass_deg(self.move_ne_m)

    def advice(self) -> str:
        """The operator's instruction, e.g. 'move the vessel 3.2 m towards 045 deg'."""
        tip = self.crane_tip_n
        return (
            f"move the vessel {self.distance_m:.1f} m towards {self.bearing_deg:03.0f} deg "
            f"(crane tip to {tip[0]:.2f} m north, {tip[1]:.2f} m east)"
        )


def compass_deg(ne: FloatArray) -> float:
    """The compass bearing of a (north, east) vector in [0, 360) [deg]; 0 for a zero vector."""
    # the second modulo maps a tiny negative angle, which the first rounds to 360, to 0
    return math.degrees(math.atan2(float(ne[1]), float(ne[0]))) % 360.0 % 360.0


def frame_utilisation(
    sim: Simulation,
    thrusters: landing.Thrusters,
    frame: DockingFrame,
    depth_m: float,
    crane_tip_n: FloatArray,
) -> landing.PoseLoad:
    """Holding the tree over ``frame`` at its heading, ``depth_m`` deep, in the present
    current, with the crane tip at ``crane_tip_n`` (NED, m)."""
    env = landing._environment(sim, depth_m, *sim.current_flowing(), crane_tip_n)
    n, e = float(frame.center_n[0]), float(frame.center_n[1])
    return landing.pose_load(sim, thrusters, n, e, frame.heading_rad, env, depth_m)


def best_crane_tip(
    sim: Simulation, thrusters: landing.Thrusters, frame: DockingFrame, depth_m: float
) -> FloatArray:
    """The crane tip (NED, m) that needs least of the ROV's thrust over the frame: first the
    point where the surge and sway forces vanish (the force is linear in the crane tip: two
    differences of 1 m give its slope), then the utilisation minimised around it (its
    minimum need not be at zero force: a sway force on the mount's lever can take yaw)."""
    tip0 = np.asarray(sim.crane_tip_n, float).copy()

    def need(ne: FloatArray) -> FloatArray:
        tip = np.array([ne[0], ne[1], tip0[2]])
        return frame_utilisation(sim, thrusters, frame, depth_m, tip).needed_xyn

    f0 = need(tip0[0:2])
    slope = np.column_stack([need(tip0[0:2] + d) - f0 for d in np.eye(2)])
    step, *_ = np.linalg.lstsq(slope[0:2], -f0[0:2], rcond=None)
    start = tip0[0:2] + step

    def cost(ne: FloatArray) -> float:
        tip = np.array([ne[0], ne[1], tip0[2]])
        return frame_utilisation(sim, thrusters, frame, depth_m, tip).utilisation

    best = minimize(
        cost,
        start,
        method="Nelder-Mead",
        options={"xatol": 0.01, "fatol": 1e-4, "initial_simplex": _simplex(start, 0.5)},
    )
    ne = best.x if best.fun <= cost(start) else start
    return np.array([ne[0], ne[1], tip0[2]])


def _simplex(ne: FloatArray, size_m: float) -> FloatArray:
    return ne + np.array([[0.0, 0.0], [size_m, 0.0], [0.0, size_m]])


def _path_worst(
    sim: Simulation,
    thrusters: landing.Thrusters,
    depth_m: float,
    start_ne: FloatArray,
    end_ne: FloatArray,
    psi: float,
    tip_start: FloatArray,
    tip_end: FloatArray,
    skip_first: bool = False,
) -> landing.PoseLoad:
    """The pose needing most along a straight move of the tree at heading ``psi`` while the
    crane tip moves in step from ``tip_start`` to ``tip_end`` (``skip_first``: from just
    after the start)."""
    loads = []
    speed, direction = sim.current_flowing()
    for s in np.linspace(0.0, 1.0, PATH_SAMPLES)[1 if skip_first else 0 :]:
        tip = tip_start + s * (tip_end - tip_start)
        ne = start_ne + s * (end_ne - start_ne)
        env = landing._environment(sim, depth_m, speed, direction, tip)
        loads.append(landing.pose_load(sim, thrusters, ne[0], ne[1], psi, env, depth_m))
    return _most(loads)


def _most(loads: list[landing.PoseLoad]) -> landing.PoseLoad:
    return max(loads, key=lambda load: load.utilisation)


def _turn_worst(
    sim: Simulation,
    thrusters: landing.Thrusters,
    depth_m: float,
    ne: FloatArray,
    psi0: float,
    turn: float,
    tip: FloatArray,
) -> landing.PoseLoad:
    """The pose needing most while turning by ``turn`` at (north, east) ``ne`` (the first
    heading left out: the turn starts from a pose the way has already reached)."""
    steps = max(2, int(abs(turn) / landing.TURN_STEP_RAD) + 1)
    headings = psi0 + np.linspace(0.0, turn, steps)[1:]
    steps -= 1
    poses = np.column_stack([np.full(steps, ne[0]), np.full(steps, ne[1]), headings])
    env = landing._environment(sim, depth_m, *sim.current_flowing(), tip)
    return _most(landing.pose_loads(sim, thrusters, poses, env, depth_m))


def plan_vessel(
    sim: Simulation, frame: DockingFrame, target_n: FloatArray, depth_m: float
) -> VesselPlan:
    """Where the crane tip should stand to land on ``frame`` in the present current, and the
    approach from the present target (north, east, heading) with the vessel moving: feasible
    when holding the tree over the frame from there needs at most
    ``landing.FEASIBLE_UTILISATION`` of the thrust."""
    thrusters = landing.Thrusters(sim)
    tip0 = np.asarray(sim.crane_tip_n, float).copy()
    tip = best_crane_tip(sim, thrusters, frame, depth_m)
    at_frame = frame_utilisation(sim, thrusters, frame, depth_m, tip)
    if math.hypot(*(tip - tip0)[0:2]) < MIN_MOVE_M:
        tip = tip0
        at_frame = frame_utilisation(sim, thrusters, frame, depth_m, tip)
    start = np.asarray(target_n[0:2], float)
    centre = np.asarray(frame.center_n[0:2], float)
    # where the tree hangs from the vessel as it stands: the rest point moves with the tip
    rest = centre - (tip - tip0)[0:2]
    psi0, psi1 = float(target_n[2]), frame.heading_rad
    short = float(ssa(psi1 - psi0))

    def path(
        a: FloatArray,
        b: FloatArray,
        psi: float,
        t0: FloatArray,
        t1: FloatArray,
        skip_first: bool = False,
    ) -> landing.PoseLoad:
        return _path_worst(sim, thrusters, depth_m, a, b, psi, t0, t1, skip_first)

    def turning(ne: FloatArray, turn: float, at_tip: FloatArray) -> landing.PoseLoad:
        return _turn_worst(sim, thrusters, depth_m, ne, psi0, turn, at_tip)

    # the pose the tree is held at now is no part of the way: it is where the way starts
    in_step_turned = path(start, centre, psi1, tip0, tip)
    in_step_unturned = path(start, centre, psi0, tip0, tip, skip_first=True)
    to_rest = path(start, rest, psi0, tip0, tip0, skip_first=True)
    from_rest = path(rest, centre, psi1, tip0, tip)
    options = []
    for turn in (short, short - math.copysign(2.0 * math.pi, short)):
        # in order of preference: the vessel sets off at once, the tree turns once there
        ways = {
            "frame": [in_step_unturned, turning(centre, turn, tip)],
            "start": [turning(start, turn, tip0), in_step_turned],
            "rest": [to_rest, turning(rest, turn, tip0), from_rest],
        }
        for rank, (turn_at, loads) in enumerate(ways.items()):
            worst = _most(loads)
            # any way within the share that asks for the vessel is as good as any other
            good = max(worst.utilisation, ASSIST_UTILISATION)
            options.append(((good, abs(turn), rank), turn, turn_at, worst))
    _, turn, turn_at, worst = min(options, key=lambda o: o[0])
    feasible = (
        at_frame.utilisation <= landing.FEASIBLE_UTILISATION
        and worst.utilisation <= APPROACH_UTILISATION
    )
    plan = VesselPlan(feasible, "", tip0, tip, at_frame, turn, turn_at, rest, worst)
    return dataclasses.replace(plan, reason=_reason(sim, frame, plan))


def _reason(sim: Simulation, frame: DockingFrame, plan: VesselPlan) -> str:
    speed, direction = sim.current_flowing()
    current = f"{speed:.3f} m/s towards {math.degrees(direction) % 360:.0f} deg"
    limit = f"{100 * landing.FEASIBLE_UTILISATION:.0f} %"
    where = (
        f"with the vessel moved {plan.distance_m:.1f} m towards {plan.bearing_deg:03.0f} deg"
        if plan.distance_m > 0.0
        else "with the vessel where it stands"
    )
    frame_deg = f"{math.degrees(frame.heading_rad):.0f} deg"
    if plan.feasible:
        return (
            f"landing feasible in {current} {where}: holding the tree over the frame takes "
            f"{plan.at_frame.words()}, within the {limit} allowed"
        )
    if plan.at_frame.utilisation <= landing.FEASIBLE_UTILISATION:
        return (
            f"landing not feasible in {current} with the frame at {frame_deg} wherever the "
            f"vessel stands: {where}, holding the tree over the frame would be within the "
            f"{limit} allowed, but the least the way there asks (from where the tree is, "
            f"turning to {frame_deg} either way, there, where it hangs or over the frame) is "
            f"{plan.worst.words()}, more than the thrusters have"
        )
    return (
        f"landing not feasible in {current} with the frame at {frame_deg} wherever the "
        f"vessel stands: at the best place ({where.removeprefix('with the ')}) holding the "
        f"tree over it takes {plan.at_frame.words()}, more than the {limit} allowed"
    )
