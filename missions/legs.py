"""The leg types of a mission: one executor per type in ``LEG_EXECUTORS`` (a registry, not a
chain of ifs).

An executor sets targets and commands on the ``Simulation`` through its public methods and
yields how long to run next, until its end condition (the reference has arrived and the settle
time has passed, or a fixed duration), never longer than the leg's timeout. To add a leg type:
a model in ``missions.schema``, an executor here, and its entry in ``LEG_EXECUTORS``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Generator, Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from control.columns import LAYOUT, Layout, LogRows
from control.config import Gains
from control.simulation import Simulation
from missions import assist, landing, schema
from missions.scoring import LandingResult
from sim import docking
from sim.docking import DockingFrame, DockingLayout
from sim.gnc import ssa

FloatArray = NDArray[np.float64]
LegRun = Generator[float, None, bool]
"""A leg in progress: yields seconds to run next, returns whether it finished in time."""
CHUNK_S = 1.0
"""How long an executor waiting for a condition runs between checks [s]."""
ARRIVED_M = 1e-3
ARRIVED_RAD = math.radians(0.01)
ARRIVED_MPS = 1e-4
ARRIVED_RAD_S = 1e-5
"""The reference has arrived when its pose is within ARRIVED_M (north, east) and ARRIVED_RAD
(heading) of the target and its rates below ARRIVED_MPS and ARRIVED_RAD_S."""
_ARRIVED_TOL = np.array(
    [ARRIVED_M, ARRIVED_M, ARRIVED_RAD, ARRIVED_MPS, ARRIVED_MPS, ARRIVED_RAD_S]
)
MAX_MERGED_POLLS = 600
"""The most polls one request stands for when checks are skipped (``MissionContext.polls``):
a bound on how far ahead a prediction looks."""

Away = Callable[[int, int], int]
"""A prediction for ``MissionContext.polls``: (steps a poll, most polls) -> how many polls
from now certainly end with the executor's condition still false."""


class MissionContext:
    """What an executor works with: the simulation and the present target.

    Executors are generators: they set targets and ``yield`` how many seconds the simulation
    should run next; the mission driver (``missions.driver``) runs it that long, hands the rows
    back in ``last_log`` and resumes them. Their return value says whether the leg finished in
    time. Executors use only the simulation's public methods."""

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        eta = sim.eta_estimate
        self.target = np.array([eta[0], eta[1], eta[2]])
        self._last_parts: list[LogRows] = []
        self._last_log: LogRows | None = LogRows.empty(sim.n_thrusters)
        self.previous_row: FloatArray | None = None
        """The row before ``last_log``'s first (None before the first request)."""
        self.charted_frame: DockingFrame | None = None
        self.events: list[dict] = []
        self.leg: schema.Leg | None = None
        """The leg being run (set by the driver)."""
        self.misses: list[str] = []
        """Targets of the present leg the tree did not reach within its tolerance."""
        self.landings: list[LandingResult] = []

    def event(self, kind: str, text: str, **data: object) -> None:
        """Note something for the log (leg changes, landings, gain changes)."""
        self.events.append(
            {"t_s": round(self.sim.t_s, 3), "kind": kind, "text": text, "data": data}
        )

    def set_target(self, north: float, east: float, psi: float) -> None:
        self.target = np.array([north, east, psi])
        self.sim.set_target(north, east, psi, heading_mode="absolute")

    @property
    def last_log(self) -> LogRows:
        """The rows of the request just run, joined when first read (a long request comes
        back in pieces, and most executors never read its rows)."""
        if self._last_log is None:
            self._last_log = LogRows.join(self._last_parts, self.sim.n_thrusters)
            self._last_parts = [self._last_log]
        return self._last_log

    def hand_back(self, parts: list[LogRows]) -> None:
        """The driver hands back a request's rows in its pieces: they become ``last_log``, and
        the last row of the rows before becomes ``previous_row``."""
        for part in reversed(self._last_parts):
            if len(part):
                self.previous_row = part.data[-1]
                break
        self._last_parts, self._last_log = list(parts), None

    merge_polls = True
    """Skip the checks a prediction says would fail (``polls``); False polls every time, as
    before predictions (the same figures either way: ``tests/test_merged_polls.py``)."""

    def reference_arrived(self) -> bool:
        ref = self.sim.reference
        return bool(
            abs(ref[0] - self.target[0]) < ARRIVED_M
            and abs(ref[1] - self.target[1]) < ARRIVED_M
            and abs(ref[2] - self.target[2]) < ARRIVED_RAD
            and np.all(np.abs(ref[3:5]) < ARRIVED_MPS)
            and abs(ref[5]) < ARRIVED_RAD_S
        )

    def reference_away(self, poll_steps: int, max_polls: int) -> int:
        """``Away`` for ``reference_arrived``: the reference model run ahead
        (``Simulation.reference_polls_away``)."""
        goal = np.array([self.target[0], self.target[1], self.target[2], 0.0, 0.0, 0.0])
        return self.sim.reference_polls_away(goal, _ARRIVED_TOL, poll_steps, max_polls)

    def winch_away(self, poll_steps: int, max_polls: int) -> int:
        """``Away`` for a condition that needs the winch idle (``Simulation.winch_steps_busy``)."""
        return min(max_polls, self.sim.winch_steps_busy() // poll_steps)

    def polls(self, poll_s: float, deadline_s: float, away: Away | None) -> float:
        """Seconds to run before the next check of a condition polled every ``poll_s``: one
        poll, or, when ``away`` says the next checks would certainly fail, the polls up to the
        first check that might not, in one request. The checks skipped are those the loop
        would have made and failed, and the deadline's too (a poll starts only before the
        deadline), so the run is the same step for step: the simulation's chunks do not
        depend on how requests cut its time (``Simulation.step``). Fewer requests, and
        longer chunks where the winch and crane are still, are what it saves."""
        sim = self.sim
        poll_steps = int(round(poll_s / sim.dt_s))
        if away is None or not self.merge_polls or poll_steps <= 0:
            return poll_s
        n = away(poll_steps, MAX_MERGED_POLLS)
        extra = 0
        while extra < n and (sim.step_index + (extra + 1) * poll_steps) * sim.dt_s < deadline_s:
            extra += 1  # poll extra + 1 would start before the deadline, after a failed check
        if extra == 0:
            return poll_s
        return (extra + 1) * poll_steps * sim.dt_s

    def wait(self, seconds: float, deadline_s: float) -> Iterator[float]:
        """Run for ``seconds``, cut at the deadline."""
        remaining = min(seconds, deadline_s - self.sim.t_s)
        if remaining > 0:
            yield remaining

    def run_until(
        self, done: Callable[[], bool], deadline_s: float, away: Away | None = None
    ) -> LegRun:
        """Run in chunks until ``done()``; returns False if the deadline came first. ``away``
        predicts checks of ``done`` that would fail, to be skipped (``polls``)."""
        while not done():
            if self.sim.t_s >= deadline_s:
                return False
            yield self.polls(CHUNK_S, deadline_s, away)
        return True

    def go_and_settle(
        self, north: float, east: float, psi: float, settle_s: float, deadline_s: float
    ) -> LegRun:
        """Set the target, run until the reference arrives, then settle. Returns False on
        timeout."""
        self.set_target(north, east, psi)
        if not (yield from self.run_until(self.reference_arrived, deadline_s, self.reference_away)):
            return False
        yield from self.wait(settle_s, deadline_s)
        self.check_reached(north, east, psi)
        return True

    def check_reached(self, north: float, east: float, psi: float) -> None:
        """Note a miss when the tree's true pose is outside the leg's tolerance of the target
        (the reference arriving says nothing of the tree: a wrong mount vector or saturated
        thrusters leave it behind)."""
        tol_m = getattr(self.leg, "tolerance_m", None)
        tol_deg = getattr(self.leg, "tolerance_deg", None)
        if tol_m is None or tol_deg is None:
            return
        tree = self.sim.tree_eta_n
        off_m = math.hypot(tree[0] - north, tree[1] - east)
        off_deg = abs(math.degrees(ssa(tree[5] - psi)))
        if off_m > tol_m or off_deg > tol_deg:
            self.misses.append(
                f"did not reach its target: {off_m:.2f} m and {off_deg:.1f} deg off at "
                f"t = {self.sim.t_s:.1f} s (tolerance {tol_m:g} m, {tol_deg:g} deg)"
            )


Executor = Callable[[MissionContext, Any, float], LegRun]
"""An executor: (context, the leg's model, deadline [s]) -> a leg run."""


def _hold(ctx: MissionContext, leg: schema.HoldLeg, deadline: float) -> LegRun:
    yield from ctx.wait(leg.duration_s, deadline)
    return leg.duration_s <= leg.timeout_s


def _rotate(ctx: MissionContext, leg: schema.RotateLeg, deadline: float) -> LegRun:
    t = ctx.target
    return (
        yield from ctx.go_and_settle(
            t[0], t[1], t[2] + math.radians(leg.angle_deg), leg.settle_s, deadline
        )
    )


def _heading(ctx: MissionContext, heading_deg: float | None) -> float:
    """A heading from a file, taken the short way from the present target."""
    psi = ctx.target[2]
    if heading_deg is None:
        return psi
    return psi + ssa(math.radians(heading_deg) - psi)


def _move(ctx: MissionContext, leg: schema.MoveLeg, deadline: float) -> LegRun:
    t = ctx.target
    n, e = (t[0] + leg.north_m, t[1] + leg.east_m) if leg.relative else (leg.north_m, leg.east_m)
    return (
        yield from ctx.go_and_settle(n, e, _heading(ctx, leg.heading_deg), leg.settle_s, deadline)
    )


def _step(ctx: MissionContext, leg: schema.StepLeg, deadline: float) -> LegRun:
    t = ctx.target
    n, e = (t[0] + leg.north_m, t[1] + leg.east_m) if leg.relative else (leg.north_m, leg.east_m)
    psi = _heading(ctx, leg.heading_deg)
    ctx.set_target(n, e, psi)
    yield from ctx.wait(leg.duration_s, deadline)
    if leg.duration_s > leg.timeout_s:
        return False
    ctx.check_reached(n, e, psi)
    return True


def _corners(side: float, clockwise: bool) -> list[tuple[float, float]]:
    """Square corners relative to the start: north first, then east (clockwise seen from
    above in NED) or west."""
    e = side if clockwise else -side
    return [(side, 0.0), (side, e), (0.0, e), (0.0, 0.0)]


def _square(ctx: MissionContext, leg: schema.SquareLeg, deadline: float) -> LegRun:
    start = ctx.target.copy()
    psi = _heading(ctx, leg.heading_deg)
    for dn, de in _corners(leg.side_m, leg.clockwise):
        ok = yield from ctx.go_and_settle(start[0] + dn, start[1] + de, psi, leg.settle_s, deadline)
        if not ok:
            return False
    return True


def _waypoints(ctx: MissionContext, leg: schema.WaypointsLeg, deadline: float) -> LegRun:
    start = ctx.target.copy()
    for n, e in leg.points_ne_m:
        tn, te = (start[0] + n, start[1] + e) if leg.relative else (n, e)
        ok = yield from ctx.go_and_settle(tn, te, start[2], leg.settle_s, deadline)
        if not ok:
            return False
    return True


def _gains(ctx: MissionContext, leg: schema.GainsLeg, deadline: float) -> LegRun:
    ctx.sim.set_gains(Gains.of(leg.kp, leg.ki, leg.kd))
    return True
    yield  # a generator that runs no time


def _mode(ctx: MissionContext, leg: schema.ModeLeg, deadline: float) -> LegRun:
    if leg.grip is not None:
        ctx.sim.set_grip(leg.grip)
    ctx.sim.set_mode(leg.mode)
    return True
    yield  # a generator that runs no time


def _wire(ctx: MissionContext, leg: schema.WireLeg, deadline: float) -> LegRun:
    sim = ctx.sim
    sim.winch_to(sim.wire_length_m + leg.change_m, leg.rate_mps)
    if not (yield from ctx.run_until(lambda: sim.winch_idle, deadline, ctx.winch_away)):
        return False
    yield from ctx.wait(leg.settle_s, deadline)
    return True


def _vessel(ctx: MissionContext, leg: schema.VesselLeg, deadline: float) -> LegRun:
    sim = ctx.sim
    target = np.array([leg.north_m, leg.east_m, 0.0])
    if leg.relative:
        target[0:2] += sim.crane_tip_n[0:2]
    sim.move_vessel(target, leg.speed_mps)
    if not (yield from ctx.run_until(lambda: sim.vessel_at(target), deadline)):
        return False
    yield from ctx.wait(leg.settle_s, deadline)
    return True


def _heave(ctx: MissionContext, leg: schema.HeaveLeg, deadline: float) -> LegRun:
    ctx.sim.set_heave_force(leg.force_newton)
    ctx.event("heave", f"heave force {leg.force_newton:g} N")
    return True
    yield  # a generator that runs no time


def _hookup(ctx: MissionContext, leg: schema.HookupLeg, deadline: float) -> LegRun:
    cl = ctx.sim
    cl.set_grip(False)
    cl.set_mode("free")
    yield 0.01  # the supervisor hands over to the free-ROV controller
    while True:
        mount = cl.mount_pose_n()
        cl.set_free_setpoint(*mount)
        rov = cl.rov_eta_n
        miss = float(np.linalg.norm(rov[0:3] - mount[0:3]))
        if miss <= leg.grip_tolerance_m and abs(ssa(rov[5] - mount[3])) < math.radians(2.0):
            break
        if cl.t_s >= deadline:
            return False
        yield CHUNK_S
    cl.set_grip(True)
    cl.reset_observer()
    cl.set_mode("tree")
    report = cl.check_mount()
    for w in report.warnings:
        ctx.event("alarm", w)
    ctx.event("hookup", f"ROV gripped the tree ({miss:.3f} m from the mount)", miss_m=miss)
    eta = cl.eta_estimate
    ctx.target = eta.copy()
    yield from ctx.wait(5.0, deadline)
    return True


def _aligned(
    cl: Simulation, frame: DockingFrame, layout: DockingLayout, leg: schema.DockLeg
) -> bool:
    """Alignment as the operator sees it (the controller's estimate of the tree's pose)."""
    eta = cl.eta_estimate
    pose = np.array([eta[0], eta[1], 0.0, 0.0, 0.0, eta[2]])
    chk = docking.check_alignment(pose, frame, layout)
    return (
        chk.miss_m <= leg.align_tolerance_m
        and abs(chk.heading_error_deg) <= leg.align_tolerance_deg
    )


def _first_contact(rows: LogRows, post_top: float, half_h: float) -> int | None:
    bottom = rows["tree_eta_n"][:, 2] + half_h
    hits = np.flatnonzero(bottom >= post_top)
    return int(hits[0]) if hits.size else None


class _VesselLoop:
    """The slow outer loop of a landing with ``vessel = "auto"`` or ``"advise"``: every
    ``assist.REPLAN_S`` it checks, in the present current, what holding the tree over the
    frame needs with the crane tip where the vessel is going, and when that is more than
    ``assist.ASSIST_UTILISATION`` of the thrust it plans the vessel's place again and moves
    the vessel there (or advises the operator to, not twice to the same place). Checks
    skipped by a prediction (``MissionContext.polls``) are capped at the loop's period."""

    def __init__(self, ctx: MissionContext, frame: DockingFrame, depth_m: float, mode: str) -> None:
        self.ctx, self.frame, self.depth_m, self.mode = ctx, frame, depth_m, mode
        self.next_s = ctx.sim.t_s + assist.REPLAN_S
        self.advised: FloatArray | None = None

    def check(self) -> None:
        sim = self.ctx.sim
        if sim.t_s < self.next_s:
            return
        self.next_s = sim.t_s + assist.REPLAN_S
        going = np.asarray(sim.crane_target_n, float)
        thrusters = landing.Thrusters(sim)
        now = assist.frame_utilisation(sim, thrusters, self.frame, self.depth_m, going)
        if now.utilisation <= assist.ASSIST_UTILISATION:
            return
        plan = assist.plan_vessel(sim, self.frame, self.ctx.target, self.depth_m)
        if plan.distance_m == 0.0:
            return
        if self.mode == "advise":
            told = self.advised
            if told is not None and np.hypot(*(plan.crane_tip_n - told)[0:2]) <= (
                assist.REPLAN_MOVE_M
            ):
                return
            self.advised = plan.crane_tip_n
        speed, direction = sim.current_flowing()
        now_in = f"in {speed:.3f} m/s towards {math.degrees(direction) % 360:.0f} deg now: "
        _send_vessel(self.ctx, plan, self.mode, now_in)

    def away(self, inner: Away) -> Away:
        def capped(poll_steps: int, max_polls: int) -> int:
            # skip no poll at or after the loop's next check: the polls before it only
            sim = self.ctx.sim
            ahead = (self.next_s - sim.t_s) / (poll_steps * sim.dt_s)
            left = math.ceil(ahead - 1e-9) - 1
            return inner(poll_steps, max(0, min(max_polls, left)))

        return capped


def _send_vessel(ctx: MissionContext, plan: assist.VesselPlan, mode: str, why: str = "") -> None:
    """Move the vessel to the plan's place (auto) or tell the operator where (advise)."""
    u = plan.at_frame.utilisation
    data = {
        "distance_m": round(plan.distance_m, 3),
        "bearing_deg": round(plan.bearing_deg, 1),
        # to the micrometre: the console's form shows it to 2 decimals, as the text does, and a
        # value rounded to 3 first could round the other way (5.675 -> "5.68" against 5.67)
        "crane_tip_ne_m": [round(float(x), 6) for x in plan.crane_tip_n[0:2]],
        "utilisation": u,
        "mode": mode,
    }
    if mode == "auto":
        ctx.sim.move_vessel(plan.crane_tip_n, assist.VESSEL_SPEED_MPS)
        text = (
            f"{why}moving the vessel {plan.distance_m:.1f} m towards "
            f"{plan.bearing_deg:03.0f} deg at {assist.VESSEL_SPEED_MPS:g} m/s "
            f"(then {100 * u:.0f} % of the thrust over the frame)"
        )
    else:
        text = f"{why}{plan.advice()} (then {100 * u:.0f} % of the thrust over the frame)"
    ctx.event("vessel", text, **data)


def _with_vessel(
    ctx: MissionContext,
    plan: assist.VesselPlan,
    mode: str,
    frame: DockingFrame,
    depth_m: float,
    deadline: float,
) -> LegRun:
    """Move the vessel to the plan's place (auto), or advise it and wait for the operator
    (advise), while the tree follows from where it is to over the frame in step with the
    crane tip, so the wire's pull on it stays what it was."""
    sim = ctx.sim
    start = ctx.target.copy()
    centre = np.asarray(frame.center_n[0:2], float)
    tip0, tip1 = plan.from_n[0:2], plan.crane_tip_n[0:2]
    span = tip1 - tip0
    thrusters = landing.Thrusters(sim)
    _send_vessel(ctx, plan, mode)

    def follow() -> bool:
        tip = sim.crane_tip_n[0:2]
        s = float(np.clip(np.dot(tip - tip0, span) / np.dot(span, span), 0.0, 1.0))
        ne = start[0:2] + s * (centre - start[0:2])
        if s > 0.0:
            ctx.set_target(ne[0], ne[1], start[2])
        if mode == "auto":
            return sim.vessel_at(plan.crane_tip_n)
        if not sim.vessel_at(sim.crane_target_n):
            return False  # the vessel is still moving
        near = float(np.hypot(*(tip - tip1))) <= assist.ADVISE_TOL_M
        load = assist.frame_utilisation(sim, thrusters, frame, depth_m, sim.crane_tip_n)
        return near or load.utilisation <= assist.ASSIST_UTILISATION

    return (yield from ctx.run_until(follow, deadline))


def _dock(ctx: MissionContext, leg: schema.DockLeg, deadline: float) -> LegRun:
    cl = ctx.sim
    frame = ctx.charted_frame  # where the operator believes it is
    real = cl.docking_frame  # where it is
    if frame is None or real is None:
        raise ValueError("a dock leg needs setup.docking_frame")
    layout = cl.ps.spec.docking.to_numeric()
    half_h = float(cl.plant_ps.tree.dimensions_m[2]) / 2.0
    post_top = frame.post_top_depth_m(layout)
    hover_depth = post_top - leg.hover_m - half_h
    plan = landing.plan_landing(cl, frame, ctx.target, hover_depth)
    assisted: assist.VesselPlan | None = None
    here = ctx.target
    if leg.vessel != "fixed" and plan.at_frame.utilisation > assist.ASSIST_UTILISATION:
        # from where the tree is (the estimate): not where it is held when the ROV cannot
        # hold it there, as a strong current's pull off its rest can be beyond it
        eta = cl.eta_estimate
        here = np.array([eta[0], eta[1], ctx.target[2] + ssa(eta[2] - ctx.target[2])])
        assisted = assist.plan_vessel(cl, frame, here, hover_depth)
        if not assisted.feasible and not plan.feasible:
            ctx.event("landing", assisted.reason)
            raise ValueError(assisted.reason)
        if not assisted.feasible or assisted.distance_m == 0.0:
            assisted = None  # no move helps: fly it from where the vessel stands
    if not plan.feasible and assisted is None:
        ctx.event("landing", plan.reason)
        raise ValueError(plan.reason)
    outer = None if leg.vessel == "fixed" else _VesselLoop(ctx, frame, hover_depth, leg.vessel)
    cl.winch_to(cl.wire_length_for_depth(hover_depth), 0.1)
    if assisted is None:
        why = yield from _approach(ctx, plan, frame, deadline)
    else:
        ctx.set_target(*here)
        why = yield from _assisted_approach(ctx, assisted, leg.vessel, frame, hover_depth, deadline)
    if not why:
        aligned = yield from ctx.run_until(
            lambda: _outer_check(outer) and cl.winch_idle and _aligned(cl, frame, layout, leg),
            deadline,
            ctx.winch_away if outer is None else outer.away(ctx.winch_away),
        )
        why = "" if aligned else NOT_ALIGNED
    if why:
        ctx.event("landing", f"landing abandoned: {why}")
        return False
    ctx.event("dock", "aligned over the frame: lowering")
    cl.winch_to(cl.wire_length_for_depth(frame.landing_depth_m - half_h) + 0.3, leg.lower_rate_mps)
    contact: tuple[int, FloatArray, FloatArray] | None = None
    contact_layout = LAYOUT  # the layout of the contact's rows (a lean log's, in a campaign)
    lower_away = ctx.winch_away if outer is None else outer.away(ctx.winch_away)
    while not cl.winch_idle:
        if cl.t_s >= deadline:
            return False
        _outer_check(outer)
        yield ctx.polls(0.5, deadline, lower_away)
        rows = ctx.last_log  # (the first contact in them is the first of the polls')
        k = _first_contact(rows, post_top, half_h) if contact is None else None
        if k is not None:
            prev = rows.data[k - 1] if k > 0 else ctx.previous_row
            row = rows.data[k]
            contact = (k, row.copy(), (row if prev is None else prev).copy())
            contact_layout = rows.layout
    yield from ctx.wait(leg.settle_s, deadline)
    result = _landing_result(cl, real, layout, contact, contact_layout)
    ctx.landings.append(result)
    verdict = "landed" if result.success else "FAILED landing"
    ctx.event(
        "landing",
        f"{verdict}: miss {result.miss_m:.3f} m, heading error "
        f"{result.heading_error_deg:.2f} deg, contact speed "
        f"{result.contact_speed_mps:.3f} m/s, rests on the {result.rests_on}",
        **vars(result),
    )
    return True


def _outer_check(outer: _VesselLoop | None) -> bool:
    """Run the outer loop's check (if any); always True, to sit in a condition."""
    if outer is not None:
        outer.check()
    return True


NOT_ALIGNED = "not aligned over the frame in time"
TURN_WAYS = {
    "start": "where it is, then over the frame",
    "rest": "where it hangs from the vessel as it stands, then over the frame",
    "frame": "over the frame",
}
"""Where a vessel-assisted approach turns (``assist.VesselPlan.turn_at``), in words."""
ApproachRun = Generator[float, None, str]
"""An approach in progress: yields seconds to run next, returns '' when over the frame, else
why the landing is abandoned."""


def _approach(
    ctx: MissionContext, plan: landing.LandingPlan, frame: DockingFrame, deadline: float
) -> ApproachRun:
    """Fly over the frame with the vessel where it stands: turn where the tree is and then
    move, or move and then turn over the frame, as the plan says."""
    way = "where it is, then over the frame" if plan.turn_first else "over the frame"
    ctx.event(
        "dock",
        f"{plan.reason}; turning {math.degrees(plan.turn_rad):+.0f} deg {way} "
        f"(at most {100 * plan.worst_utilisation:.0f} % of the thrust on the way)",
        utilisation=plan.at_frame.utilisation,
        turn_deg=math.degrees(plan.turn_rad),
        turn_first=plan.turn_first,
    )
    psi = ctx.target[2] + plan.turn_rad
    t = ctx.target
    if plan.turn_first:
        ok = yield from ctx.go_and_settle(t[0], t[1], psi, 0.0, deadline)
        if ok:
            ok = yield from ctx.go_and_settle(
                frame.center_n[0], frame.center_n[1], psi, 0.0, deadline
            )
    else:
        ok = yield from ctx.go_and_settle(frame.center_n[0], frame.center_n[1], t[2], 0.0, deadline)
        if ok:
            ok = yield from ctx.go_and_settle(
                frame.center_n[0], frame.center_n[1], psi, 0.0, deadline
            )
    return "" if ok else NOT_ALIGNED


def _assisted_approach(
    ctx: MissionContext,
    plan: assist.VesselPlan,
    mode: str,
    frame: DockingFrame,
    depth_m: float,
    deadline: float,
) -> ApproachRun:
    """Fly over the frame with the vessel's help: turn where the plan says (where the tree
    is, or where it hangs from the vessel as it stands, reached first), move the vessel with
    the tree following over the frame, then turn there if not turned yet."""
    way = TURN_WAYS[plan.turn_at]
    ctx.event(
        "dock",
        f"{plan.reason}; turning {math.degrees(plan.turn_rad):+.0f} deg {way} "
        f"(at most {100 * plan.worst_utilisation:.0f} % of the thrust on the way)",
        utilisation=plan.at_frame.utilisation,
        turn_deg=math.degrees(plan.turn_rad),
        turn_first=plan.turn_at != "frame",
        turn_at=plan.turn_at,
    )
    psi = ctx.target[2] + plan.turn_rad
    centre = np.asarray(frame.center_n[0:2], float)
    t = ctx.target
    stops = {"start": [(t[0], t[1], psi)], "rest": [(*plan.rest_ne, t[2]), (*plan.rest_ne, psi)]}
    for north, east, heading in stops.get(plan.turn_at, []):
        if not (yield from ctx.go_and_settle(north, east, heading, 0.0, deadline)):
            return NOT_ALIGNED
    if not (yield from _with_vessel(ctx, plan, mode, frame, depth_m, deadline)):
        told = "as advised" if mode == "advise" else "as planned"
        return f"the vessel was not moved {told} in time"
    ok = yield from ctx.go_and_settle(centre[0], centre[1], psi, 0.0, deadline)
    return "" if ok else NOT_ALIGNED


def _landing_result(
    cl: Simulation,
    frame: DockingFrame,
    layout: DockingLayout,
    contact: tuple[int, FloatArray, FloatArray] | None,
    rows_layout: Layout = LAYOUT,
) -> LandingResult:
    """The landing as it happened: the funnels over the posts when they reached the post tops,
    and where the tree rests after settling. A success ends on the landing surface with every
    funnel around its own post (so with the frame's heading) and touched down slower than the
    limit."""
    if contact is None:
        return LandingResult(False, math.inf, math.nan, 0.0, "nothing", cl.t_s)
    _, row, prev = contact
    pose = rows_layout.take(row, "tree_eta_n")
    chk = docking.check_alignment(pose, frame, layout)
    speed = float((pose[2] - rows_layout.take(prev, "tree_eta_n")[2]) / cl.dt_s)
    rest = docking.check_alignment(cl.tree_eta_n, frame, layout)
    bottom = cl.tree_eta_n[2] + float(cl.plant_ps.tree.dimensions_m[2]) / 2.0
    down = bottom > frame.landing_depth_m - 0.2 * layout.post_height_m
    on_posts = abs(bottom - frame.post_top_depth_m(layout)) < 0.2 * layout.post_height_m
    in_funnels = rest.miss_m <= layout.tolerance_m
    rests_on = (
        "frame" if down and in_funnels else "posts" if on_posts else "seabed" if down else "wire"
    )
    success = rests_on == "frame" and speed <= layout.max_landing_speed_mps
    return LandingResult(
        bool(success),
        chk.miss_m,
        chk.heading_error_deg,
        speed,
        rests_on,
        float(rows_layout.take(row, "t_s")),
        rest.miss_m,
        rest.heading_error_deg,
    )


def _lift(ctx: MissionContext, leg: schema.LiftLeg, deadline: float) -> LegRun:
    cl = ctx.sim
    frame = ctx.charted_frame
    if frame is None:
        raise ValueError("a lift leg needs setup.docking_frame")
    layout = cl.ps.spec.docking.to_numeric()
    half_h = float(cl.plant_ps.tree.dimensions_m[2]) / 2.0
    post_top = frame.post_top_depth_m(layout)
    cl.winch_to(cl.wire_length_for_depth(post_top - leg.height_m - half_h), leg.rate_mps)
    if not (yield from ctx.run_until(lambda: cl.winch_idle, deadline, ctx.winch_away)):
        return False
    ctx.event("lift", "tree lifted off the frame")
    yield from ctx.wait(leg.settle_s, deadline)
    return True


LEG_EXECUTORS: dict[str, Executor] = {
    "hold": _hold,
    "wait": _hold,
    "rotate": _rotate,
    "move": _move,
    "step": _step,
    "square": _square,
    "waypoints": _waypoints,
    "gains": _gains,
    "mode": _mode,
    "wire": _wire,
    "vessel": _vessel,
    "heave": _heave,
    "hookup": _hookup,
    "dock": _dock,
    "lift": _lift,
}
