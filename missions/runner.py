"""Run a mission on the closed loop and score it.

Each leg type has an executor in ``LEG_EXECUTORS`` (a registry, not a chain of ifs). An
executor sets targets on the ``ClosedLoop`` and advances it until its end condition (the
reference has arrived and the settle time has passed, or a fixed duration), never longer than
the leg's timeout. The runner slices the log per leg and computes the figures of chapter 4:
RMS of north, east and heading error against the reference, largest thruster utilisation,
time in saturation, and settling.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from control import loop
from control.closed_loop import ClosedLoop, ControlSettings, Gains, LoopLog
from missions import schema
from sim import docking, site
from sim import environment as envmod
from sim import params as params_mod
from sim.docking import DockingFrame, DockingLayout
from sim.gnc import ssa
from sim.simulator import SimulationDiverged

FloatArray = NDArray[np.float64]
CHUNK_S = 1.0
ARRIVED_M = 1e-3
ARRIVED_RAD = math.radians(0.01)
SATURATED = 0.99
"""Utilisation at or above which a thruster counts as saturated."""


@dataclass(frozen=True)
class LegResult:
    """Figures of one leg."""

    index: int
    type: str
    name: str
    start_s: float
    duration_s: float
    rms_north_m: float
    rms_east_m: float
    rms_heading_deg: float
    max_utilisation: float
    saturated_s: float
    timed_out: bool


@dataclass
class MissionResult:
    """Figures of a whole mission (the scored legs, or all legs if none is scored)."""

    name: str
    legs: list[LegResult]
    rms_north_m: float
    rms_east_m: float
    rms_heading_deg: float
    max_thruster_utilisation: float
    saturated_time_s: float
    settling_time_s: float | None
    final_eta_n: list[float]
    diverged: bool
    warnings: list[str]
    quality_counters: dict[str, dict[str, int]]
    landings: list[LandingResult] = field(default_factory=list)
    events: list[dict] = field(default_factory=list)
    log: LoopLog | None = field(default=None, repr=False)

    @property
    def failed(self) -> bool:
        """A mission fails when it diverged, a leg timed out or a landing failed."""
        return (self.diverged or any(leg.timed_out for leg in self.legs) or
                any(not landing.success for landing in self.landings))

    def summary(self) -> dict:
        """JSON-ready figures."""
        return {
            "name": self.name, "rms_north_m": self.rms_north_m, "rms_east_m": self.rms_east_m,
            "rms_heading_deg": self.rms_heading_deg,
            "max_thruster_utilisation": self.max_thruster_utilisation,
            "saturated_time_s": self.saturated_time_s, "settling_time_s": self.settling_time_s,
            "final_eta_n": self.final_eta_n, "diverged": self.diverged,
            "warnings": self.warnings, "quality_counters": self.quality_counters,
            "legs": [vars(leg) for leg in self.legs],
            "landings": [vars(landing) for landing in self.landings],
            "failed": self.failed,
        }


class MissionContext:
    """What an executor works with: the loop and the present target.

    Executors are generators: they set targets and ``yield`` how many seconds the loop should
    run next; whoever drives them (the headless runner at full speed, the console's real-time
    loop in small steps) runs the loop that long and resumes them. Their return value says
    whether the leg finished in time."""

    def __init__(self, cl: ClosedLoop) -> None:
        self.cl = cl
        eta = cl.eta_estimate
        self.target = np.array([eta[0], eta[1], eta[2]])
        self.last_log: FloatArray = np.zeros((0, loop.N_LOG))
        self.previous_row: FloatArray | None = None
        self.charted_frame: DockingFrame | None = None
        self.events: list[dict] = []
        self.landings: list[LandingResult] = []

    def event(self, kind: str, text: str, **data: object) -> None:
        """Note something for the log (leg changes, landings, gain changes)."""
        self.events.append({"t_s": round(self.cl.t_s, 3), "kind": kind, "text": text,
                            "data": data})

    def set_target(self, north: float, east: float, psi: float) -> None:
        self.target = np.array([north, east, psi])
        self.cl.set_target(north, east, psi, heading_mode="absolute")

    def reference_arrived(self) -> bool:
        ref = self.cl.cs[loop.CS_REF:loop.CS_REF + 6]
        return bool(abs(ref[0] - self.target[0]) < ARRIVED_M and
                    abs(ref[1] - self.target[1]) < ARRIVED_M and
                    abs(ref[2] - self.target[2]) < ARRIVED_RAD and
                    np.all(np.abs(ref[3:5]) < 1e-4) and abs(ref[5]) < 1e-5)

    def wait(self, seconds: float, deadline_s: float) -> Iterator[float]:
        """Run for ``seconds``, cut at the deadline."""
        remaining = min(seconds, deadline_s - self.cl.t_s)
        if remaining > 0:
            yield remaining

    def run_until(self, done: Callable[[], bool], deadline_s: float) -> Iterator[float]:
        """Run in chunks until ``done()``; returns False if the deadline came first."""
        while not done():
            if self.cl.t_s >= deadline_s:
                return False
            yield CHUNK_S
        return True

    def go_and_settle(self, north: float, east: float, psi: float, settle_s: float,
                      deadline_s: float) -> Iterator[float]:
        """Set the target, run until the reference arrives, then settle. Returns False on
        timeout."""
        self.set_target(north, east, psi)
        if not (yield from self.run_until(self.reference_arrived, deadline_s)):
            return False
        yield from self.wait(settle_s, deadline_s)
        return True


Executor = Callable[[MissionContext, object, float], Generator[float, None, bool]]


def _hold(ctx: MissionContext, leg: schema.HoldLeg, deadline: float):
    yield from ctx.wait(leg.duration_s, deadline)
    return leg.duration_s <= leg.timeout_s


def _rotate(ctx: MissionContext, leg: schema.RotateLeg, deadline: float):
    t = ctx.target
    return (yield from ctx.go_and_settle(t[0], t[1], t[2] + math.radians(leg.angle_deg),
                                         leg.settle_s, deadline))


def _heading(ctx: MissionContext, heading_deg: float | None) -> float:
    """A heading from a file, taken the short way from the present target."""
    psi = ctx.target[2]
    if heading_deg is None:
        return psi
    return psi + ssa(math.radians(heading_deg) - psi)


def _move(ctx: MissionContext, leg: schema.MoveLeg, deadline: float):
    t = ctx.target
    n, e = (t[0] + leg.north_m, t[1] + leg.east_m) if leg.relative else (leg.north_m, leg.east_m)
    return (yield from ctx.go_and_settle(n, e, _heading(ctx, leg.heading_deg), leg.settle_s,
                                         deadline))


def _step(ctx: MissionContext, leg: schema.StepLeg, deadline: float):
    t = ctx.target
    n, e = (t[0] + leg.north_m, t[1] + leg.east_m) if leg.relative else (leg.north_m, leg.east_m)
    ctx.set_target(n, e, _heading(ctx, leg.heading_deg))
    yield from ctx.wait(leg.duration_s, deadline)
    return leg.duration_s <= leg.timeout_s


def _corners(side: float, clockwise: bool) -> list[tuple[float, float]]:
    """Square corners relative to the start: north first, then east (clockwise seen from
    above in NED) or west."""
    e = side if clockwise else -side
    return [(side, 0.0), (side, e), (0.0, e), (0.0, 0.0)]


def _square(ctx: MissionContext, leg: schema.SquareLeg, deadline: float):
    start = ctx.target.copy()
    psi = _heading(ctx, leg.heading_deg)
    for dn, de in _corners(leg.side_m, leg.clockwise):
        ok = yield from ctx.go_and_settle(start[0] + dn, start[1] + de, psi, leg.settle_s,
                                          deadline)
        if not ok:
            return False
    return True


def _waypoints(ctx: MissionContext, leg: schema.WaypointsLeg, deadline: float):
    start = ctx.target.copy()
    for n, e in leg.points_ne_m:
        tn, te = (start[0] + n, start[1] + e) if leg.relative else (n, e)
        ok = yield from ctx.go_and_settle(tn, te, start[2], leg.settle_s, deadline)
        if not ok:
            return False
    return True


def _gains(ctx: MissionContext, leg: schema.GainsLeg, deadline: float):
    ctx.cl.set_gains(Gains(tuple(leg.kp), tuple(leg.ki), tuple(leg.kd)))
    return True
    yield  # a generator that runs no time


def _mode(ctx: MissionContext, leg: schema.ModeLeg, deadline: float):
    if leg.grip is not None:
        ctx.cl.set_grip(leg.grip)
    ctx.cl.set_mode(leg.mode)
    return True
    yield  # a generator that runs no time


def _winch_done(cl: ClosedLoop) -> bool:
    return abs(cl.sim.wire_length_m - cl.sim.wire_target_m) < 1e-6


def _wire(ctx: MissionContext, leg: schema.WireLeg, deadline: float):
    sim = ctx.cl.sim
    sim.winch_to(sim.wire_length_m + leg.change_m, leg.rate_mps)
    if not (yield from ctx.run_until(lambda: _winch_done(ctx.cl), deadline)):
        return False
    yield from ctx.wait(leg.settle_s, deadline)
    return True


def _vessel(ctx: MissionContext, leg: schema.VesselLeg, deadline: float):
    sim = ctx.cl.sim
    target = np.array([leg.north_m, leg.east_m, 0.0])
    if leg.relative:
        target[0:2] += sim.crane_tip_n[0:2]
    sim.move_crane_tip(target, leg.speed_mps)
    arrived = lambda: np.linalg.norm(sim.crane_tip_n - target) <= 1e-6  # noqa: E731
    if not (yield from ctx.run_until(arrived, deadline)):
        return False
    yield from ctx.wait(leg.settle_s, deadline)
    return True


def _heave(ctx: MissionContext, leg: schema.HeaveLeg, deadline: float):
    ctx.cl.set_heave_force(leg.force_n)
    ctx.event("heave", f"heave force {leg.force_n:g} N")
    return True
    yield  # a generator that runs no time


def _hookup(ctx: MissionContext, leg: schema.HookupLeg, deadline: float):
    cl = ctx.cl
    cl.set_grip(False)
    cl.set_mode("free")
    yield 0.01  # the supervisor hands over to the free-ROV controller
    while True:
        mount = cl.mount_pose_n()
        cl.set_free_setpoint(*mount)
        rov = cl.sim.x[12:18]
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


@dataclass(frozen=True)
class LandingResult:
    """One landing on the docking frame (thesis chapter 5)."""

    success: bool
    miss_m: float
    """Largest funnel-to-post distance when the funnels reached the post tops [m]."""
    heading_error_deg: float
    contact_speed_mps: float
    """Vertical speed of the tree at that moment [m/s]."""
    rests_on: str
    """"frame" (funnels over the posts, down on the landing surface) or "posts"."""
    t_contact_s: float


def _depth_wire(cl: ClosedLoop, cg_depth: float) -> float:
    return site.wire_length_for_depth(cl.sim.ps, cg_depth, cl.sim.crane_tip_n[2],
                                      cl.sim.current_state.speed_mps)


def _aligned(cl: ClosedLoop, frame: DockingFrame, layout: DockingLayout,
             leg: schema.DockLeg) -> bool:
    """Alignment as the operator sees it (the controller's estimate of the tree's pose)."""
    eta = cl.eta_estimate
    pose = np.array([eta[0], eta[1], 0.0, 0.0, 0.0, eta[2]])
    chk = docking.check_alignment(pose, frame, layout)
    return chk.miss_m <= leg.align_tolerance_m and abs(chk.heading_error_deg) <= \
        leg.align_tolerance_deg


def _first_contact(rows: FloatArray, post_top: float, half_h: float) -> int | None:
    bottom = rows[:, loop.L_TREE + 2] + half_h
    hits = np.flatnonzero(bottom >= post_top)
    return int(hits[0]) if hits.size else None


def _dock(ctx: MissionContext, leg: schema.DockLeg, deadline: float):
    cl = ctx.cl
    frame = ctx.charted_frame  # where the operator believes it is
    real = cl.sim.docking_frame  # where it is
    layout = cl.ps.spec.docking.to_numeric()
    half_h = float(cl.sim.ps.tree.dimensions_m[2]) / 2.0
    post_top = frame.post_top_depth_m(layout)
    cl.sim.winch_to(_depth_wire(cl, post_top - leg.hover_m - half_h), 0.1)
    psi = ctx.target[2] + ssa(frame.heading_rad - ctx.target[2])
    ok = yield from ctx.go_and_settle(frame.center_n[0], frame.center_n[1], psi, 0.0, deadline)
    if ok:
        ok = yield from ctx.run_until(
            lambda: _winch_done(cl) and _aligned(cl, frame, layout, leg), deadline)
    if not ok:
        ctx.event("landing", "landing abandoned: not aligned over the frame in time")
        return False
    ctx.event("dock", "aligned over the frame: lowering")
    cl.sim.winch_to(_depth_wire(cl, frame.landing_depth_m - half_h) + 0.3, leg.lower_rate_mps)
    contact: tuple[int, FloatArray, FloatArray] | None = None
    while not _winch_done(cl):
        if cl.t_s >= deadline:
            return False
        yield 0.5
        rows = ctx.last_log
        k = _first_contact(rows, post_top, half_h) if contact is None else None
        if k is not None:
            prev = rows[k - 1] if k > 0 else ctx.previous_row
            contact = (k, rows[k].copy(), (rows[k] if prev is None else prev).copy())
    yield from ctx.wait(leg.settle_s, deadline)
    result = _landing_result(cl, real, layout, contact)
    ctx.landings.append(result)
    verdict = "landed" if result.success else "FAILED landing"
    ctx.event("landing", f"{verdict}: miss {result.miss_m:.3f} m, heading error "
                         f"{result.heading_error_deg:.2f} deg, contact speed "
                         f"{result.contact_speed_mps:.3f} m/s, rests on the {result.rests_on}",
              **vars(result))
    return True


def _landing_result(cl: ClosedLoop, frame: DockingFrame, layout: DockingLayout,
                    contact: tuple[int, FloatArray, FloatArray] | None) -> LandingResult:
    if contact is None:
        return LandingResult(False, math.inf, math.nan, 0.0, "nothing", cl.t_s)
    _, row, prev = contact
    pose = row[loop.L_TREE:loop.L_TREE + 6]
    chk = docking.check_alignment(pose, frame, layout)
    speed = float((row[loop.L_TREE + 2] - prev[loop.L_TREE + 2]) / cl.dt_s)
    bottom = cl.sim.x[2] + float(cl.sim.ps.tree.dimensions_m[2]) / 2.0
    on_frame = bottom > frame.landing_depth_m - 0.2 * layout.post_height_m
    success = chk.captured and speed <= layout.max_landing_speed_mps and on_frame
    return LandingResult(bool(success), chk.miss_m, chk.heading_error_deg, speed,
                         "frame" if on_frame else "posts", float(row[loop.L_T]))


def _lift(ctx: MissionContext, leg: schema.LiftLeg, deadline: float):
    cl = ctx.cl
    frame = ctx.charted_frame
    layout = cl.ps.spec.docking.to_numeric()
    half_h = float(cl.sim.ps.tree.dimensions_m[2]) / 2.0
    post_top = frame.post_top_depth_m(layout)
    cl.sim.winch_to(_depth_wire(cl, post_top - leg.height_m - half_h), leg.rate_mps)
    if not (yield from ctx.run_until(lambda: _winch_done(cl), deadline)):
        return False
    ctx.event("lift", "tree lifted off the frame")
    yield from ctx.wait(leg.settle_s, deadline)
    return True


LEG_EXECUTORS: dict[str, Executor] = {
    "hold": _hold, "wait": _hold, "rotate": _rotate, "move": _move, "step": _step,
    "square": _square, "waypoints": _waypoints, "gains": _gains, "mode": _mode,
    "wire": _wire, "vessel": _vessel, "heave": _heave, "hookup": _hookup, "dock": _dock,
    "lift": _lift,
}


class MissionExecution:
    """A mission in progress, driven one request at a time.

    ``next_request()`` returns how many seconds the loop should run next (None when the
    mission is over); the driver runs the loop, hands the log to ``record()`` and asks again.
    ``abort()`` ends it early. ``result()`` scores what was run."""

    def __init__(self, mission: schema.Mission, cl: ClosedLoop) -> None:
        self.mission = mission
        self.cl = cl
        self.ctx = MissionContext(cl)
        self.ctx.charted_frame = charted_frame(mission)
        self.leg_index = -1
        self.chunks: list[FloatArray] = []
        self.rows = 0
        self.bounds: list[tuple[int, int, bool]] = []
        self.diverged = False
        self.aborted = False
        self._gen: Generator[float, None, bool] | None = None
        self._leg_start = 0

    @property
    def done(self) -> bool:
        return self.leg_index >= len(self.mission.legs) or self.aborted or self.diverged

    @property
    def current_leg(self) -> schema.Leg | None:
        if 0 <= self.leg_index < len(self.mission.legs):
            return self.mission.legs[self.leg_index]
        return None

    def _start_leg(self) -> None:
        self.leg_index += 1
        self._leg_start = self.rows
        if self.leg_index < len(self.mission.legs):
            leg = self.mission.legs[self.leg_index]
            self.ctx.event("leg", f"leg {self.leg_index + 1}/{len(self.mission.legs)}: "
                                  f"{leg.type} {leg.name}".strip(), index=self.leg_index + 1,
                           type=leg.type)
            deadline = self.cl.t_s + leg.timeout_s
            self._gen = LEG_EXECUTORS[leg.type](self.ctx, leg, deadline)

    def _end_leg(self, ok: bool) -> None:
        self.bounds.append((self._leg_start, self.rows, not ok))

    def next_request(self) -> float | None:
        """Seconds to run next, or None when the mission is over."""
        if self.leg_index < 0:
            self._start_leg()
        while not self.done:
            try:
                return float(next(self._gen))
            except StopIteration as stop:
                self._end_leg(bool(stop.value))
                self._start_leg()
        return None

    def record(self, log: LoopLog) -> None:
        """Keep the log of the time just run."""
        if len(self.ctx.last_log):
            self.ctx.previous_row = self.ctx.last_log[-1]
        self.chunks.append(log.data)
        self.ctx.last_log = log.data
        self.rows += len(log.data)

    def mark_diverged(self) -> None:
        self.diverged = True
        self._end_leg(False)

    def abort(self) -> None:
        if not self.done:
            self._end_leg(False)
        self.aborted = True

    def result(self) -> MissionResult:
        data = np.vstack(self.chunks) if self.chunks else np.zeros((0, loop.N_LOG))
        m = self.cl.ps.rov.thrusters.T.shape[1]
        result = _score(self.mission, self.cl, data, self.bounds, m, self.diverged)
        result.landings = list(self.ctx.landings)
        result.events = list(self.ctx.events)
        return result


def build_loop(mission: schema.Mission, seed: int | None = None,
               allocation: str | None = None, feedback: str | None = None,
               feedforward: bool | None = None) -> ClosedLoop:
    """The ClosedLoop a mission's set-up describes (options override the file)."""
    s = mission.setup
    ps = params_mod.load(s.params)
    plant_ps = None
    if s.plant.mass_scale != 1.0 or s.plant.weight_scale != 1.0:
        plant_ps = vary_tree(ps, s.plant.mass_scale, s.plant.weight_scale)
    d = math.radians(s.current.direction_deg)
    db = math.radians(s.current.direction_band_deg)
    cur = envmod.CurrentParams(
        speed_mps=s.current.speed_mps, direction_rad=d,
        speed_min_mps=max(s.current.speed_mps - s.current.speed_band_mps, 0.0),
        speed_max_mps=s.current.speed_mps + s.current.speed_band_mps,
        direction_min_rad=d - db, direction_max_rad=d + db,
        speed_walk_mps_per_sqrt_s=s.current.speed_walk_mps_per_sqrt_s,
        direction_walk_rad_per_sqrt_s=math.radians(s.current.direction_walk_deg_per_sqrt_s))
    waves = None
    if s.waves is not None:
        waves = envmod.WaveParams(significant_height_m=s.waves.significant_height_m,
                                  peak_period_s=s.waves.peak_period_s,
                                  direction_rad=math.radians(s.waves.direction_deg))
    settings = ControlSettings(
        feedback=feedback or s.feedback, allocation=allocation or s.allocation,
        reference=s.reference, feedforward=s.feedforward if feedforward is None else feedforward,
        heave_force_n=s.heave_force_n,
        r_mount_config_m=None if s.r_mount_config_m is None else tuple(s.r_mount_config_m))
    cl = ClosedLoop(ps, tree_depth_m=s.depth_m, settings=settings,
                    crane_tip_n=np.array([*s.crane_tip_n, 0.0]), current=cur, waves=waves,
                    seed=s.seed if seed is None else seed,
                    tree_heading_rad=math.radians(s.heading_deg), plant_ps=plant_ps,
                    start_gripping=s.start_gripping)
    if s.docking_frame is not None:
        chart = charted_frame(mission)
        real_center = chart.center_n + np.asarray(s.docking_frame.survey_error_ne_m, float)
        cl.sim.set_docking_frame(DockingFrame(real_center, chart.heading_rad,
                                              chart.landing_depth_m))
    return cl


def charted_frame(mission: schema.Mission) -> DockingFrame | None:
    """The docking frame where the mission's chart puts it (what the operator aligns to)."""
    f = mission.setup.docking_frame
    if f is None:
        return None
    return DockingFrame(np.asarray(f.center_ne_m, float), math.radians(f.heading_deg),
                        f.landing_depth_m)


def vary_tree(ps: params_mod.ParameterSet, mass_scale: float,
              weight_scale: float) -> params_mod.ParameterSet:
    """The same parameter set with the tree's mass (rigid-body mass and inertia) and submerged
    weight scaled: the plant of the robustness study (thesis 4.2.3)."""
    tree = ps.spec.tree
    w0 = tree.submerged_weight_n or ps.tree.submerged_weight_n
    new_tree = tree.model_copy(update=dict(
        mass_kg=tree.mass_kg * mass_scale,
        rigid_body_inertia=[v * mass_scale for v in tree.rigid_body_inertia],
        submerged_weight_n=w0 * weight_scale))
    return params_mod.build(ps.spec.model_copy(update=dict(tree=new_tree)))


def _rms(values: FloatArray) -> float:
    return float(np.sqrt(np.mean(values**2))) if values.size else 0.0


def _leg_figures(data: FloatArray, m: int, dt: float) -> tuple[float, float, float, float, float]:
    err_n = data[:, loop.L_TREE] - data[:, loop.L_ETA_D]
    err_e = data[:, loop.L_TREE + 1] - data[:, loop.L_ETA_D + 1]
    err_psi = np.array([ssa(v) for v in data[:, loop.L_TREE + 5] - data[:, loop.L_ETA_D + 2]])
    util = data[:, loop.L_UTIL:loop.L_UTIL + m]
    umax = float(util.max()) if util.size else 0.0
    sat = float(np.sum(np.any(util >= SATURATED, axis=1)) * dt) if util.size else 0.0
    return _rms(err_n), _rms(err_e), math.degrees(_rms(err_psi)), umax, sat


def settling_time(data: FloatArray, dt: float, tol_m: float, tol_deg: float) -> float | None:
    """Time from the last change of the reference until the tree stays within tol of it."""
    ref = data[:, loop.L_ETA_D:loop.L_ETA_D + 3]
    moving = np.any(np.abs(np.diff(ref, axis=0)) > 1e-9, axis=1)
    last_change = int(np.flatnonzero(moving)[-1]) + 1 if moving.any() else 0
    err_pos = np.hypot(data[:, loop.L_TREE] - ref[:, 0], data[:, loop.L_TREE + 1] - ref[:, 1])
    err_psi = np.degrees(np.abs([ssa(v) for v in data[:, loop.L_TREE + 5] - ref[:, 2]]))
    outside = (err_pos > tol_m) | (err_psi > tol_deg)
    out_idx = np.flatnonzero(outside[last_change:])
    if out_idx.size == 0:
        return 0.0
    last_out = last_change + int(out_idx[-1])
    if last_out >= len(outside) - 1:
        return None
    return (last_out + 1 - last_change) * dt


def run_mission(mission: schema.Mission, seed: int | None = None, allocation: str | None = None,
                feedback: str | None = None, feedforward: bool | None = None,
                progress: Callable[[MissionExecution], None] | None = None) -> MissionResult:
    """Execute all legs as fast as the machine allows and score them."""
    cl = build_loop(mission, seed=seed, allocation=allocation, feedback=feedback,
                    feedforward=feedforward)
    exe = MissionExecution(mission, cl)
    while (seconds := exe.next_request()) is not None:
        try:
            exe.record(cl.run(seconds))
        except SimulationDiverged:
            exe.mark_diverged()
        if progress:
            progress(exe)
    return exe.result()


def _score(mission: schema.Mission, cl: ClosedLoop, data: FloatArray,
           bounds: list[tuple[int, int, bool]], m: int, diverged: bool) -> MissionResult:
    dt = cl.dt_s
    legs = []
    scored_rows = []
    for i, (a, b, timed_out) in enumerate(bounds):
        if i >= len(mission.legs):
            break
        leg = mission.legs[i]
        fig = _leg_figures(data[a:b], m, dt)
        legs.append(LegResult(i + 1, leg.type, leg.name, a * dt, (b - a) * dt, *fig, timed_out))
        if leg.score:
            scored_rows.append(data[a:b])
    scored = np.vstack(scored_rows) if scored_rows else data
    rms_n, rms_e, rms_psi, _, _ = _leg_figures(scored, m, dt)
    full = _leg_figures(data, m, dt)
    final = data[-1, loop.L_TREE:loop.L_TREE + 6] if len(data) else np.zeros(6)
    final_eta = [float(v) for v in final[:3]] + [math.degrees(ssa(float(v))) for v in final[3:]]
    tol_m = 0.1 * max(1.0, cl.ps.tree.dimensions_m.max() / 3.6)
    counters = {name: {check: int(cl.Q.counters[k, j]) for j, check in
                       enumerate(("range", "wild_point", "frozen", "variance"))}
                for k, name in enumerate(("position", "depth", "compass", "dvl", "gyro"))}
    warnings = list(cl.startup.warnings)
    if any(leg.timed_out for leg in legs):
        warnings.append("a leg timed out before its reference arrived: see legs[].timed_out")
    return MissionResult(
        name=mission.name, legs=legs, rms_north_m=rms_n, rms_east_m=rms_e,
        rms_heading_deg=rms_psi, max_thruster_utilisation=full[3], saturated_time_s=full[4],
        settling_time_s=settling_time(data, dt, tol_m, 2.0) if len(data) else None,
        final_eta_n=[round(v, 6) for v in final_eta], diverged=diverged, warnings=warnings,
        quality_counters=counters, log=LoopLog(data, m, cl.Q.counters.copy()))
