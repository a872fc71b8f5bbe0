"""Immutable views of the console's state, for readers on other threads and tasks.

The loop task builds a new ``Snapshot`` after every tick and swaps one reference; the HTTP
routes, the telemetry stream and the 3D view only read snapshots, never the loop itself.
Angles are radians here (the core's unit); the API turns them into degrees at its edge.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from app.console.alarms import Alarm
from app.console.operations import Operation
from control.columns import LogRows
from control.config import MODES, Gains
from control.faults import FAULT_KINDS, Fault
from sim.docking import DockingFrame, DockingLayout
from sim.drawing import rov_drawing_box_m
from sim.gnc import Rzyx
from sim.params import ParameterSet

if TYPE_CHECKING:
    from control.simulation import Simulation

FloatArray = NDArray[np.float64]
Vec3 = tuple[float, float, float]
Vec6 = tuple[float, float, float, float, float, float]

TREND_COLUMNS = ("t_s", "north_m", "east_m", "psi_rad", "north_ref_m", "east_ref_m", "psi_ref_rad")
"""Columns of ``Snapshot.trend``: the tree against the reference, one row per 0.1 s."""
TREND_DECIMATION = 10
"""Plant steps per trend row (10 steps of 0.01 s = 0.1 s at the plant's 100 Hz)."""
FAULT_LOG_KEEP = 20
"""Fault starts and ends a snapshot carries (the newest)."""


@dataclass(frozen=True)
class FaultView:
    """One injected fault as the instructor sees it."""

    kind: str
    start_s: float
    duration_s: float
    value: float
    unit: str
    thruster: int
    direction_deg: float
    state: str
    """'active' or 'scheduled'."""
    text: str
    """In words: 'compass bias 20 deg from 30 s for 60 s'."""


def fault_views(faults: Sequence[Fault], t_s: float) -> tuple[FaultView, ...]:
    """Of ``faults``, those active at run time ``t_s`` or still to come (past ones are left
    out), by start: the live run's (``sim.faults`` at ``sim.t_s``) or a replayed moment's."""
    t = t_s + 1e-9
    out = []
    for f in sorted(faults, key=lambda f: f.start_s):
        if f.end_s <= t:
            continue
        out.append(
            FaultView(
                f.kind,
                f.start_s,
                f.duration_s,
                f.value,
                FAULT_KINDS[f.kind][0],
                f.thruster,
                f.direction_deg,
                "active" if f.active(t) else "scheduled",
                f.describe(),
            )
        )
    return tuple(out)


@dataclass(frozen=True)
class WinchView:
    """The winch as the winch station shows it (``winch_view``)."""

    payout_m: float
    """Wire paid out (unstretched) [m]."""
    target_m: float
    """Payout the winch is going to [m]."""
    rate_mps: float
    """Its speed while it moves [m/s]."""
    moving: bool
    heave_compensation: bool | None
    """The crane's heave compensation on; None: the crane tip does not heave (no sea)."""
    tree_down_speed_mps: float
    """The tree's vertical speed, down positive (NED) [m/s]."""


def winch_view(sim: Simulation) -> WinchView:
    """The winch and the tree's vertical speed, read on the loop task."""
    x = sim.plant_state
    down_speed = float((Rzyx(*x[3:6]) @ x[6:9])[2])
    return WinchView(
        float(sim.wire_length_m),
        sim.winch_target_m,
        sim.winch_rate_mps,
        not sim.winch_idle,
        sim.heave_compensation,
        down_speed,
    )


@dataclass(frozen=True)
class SceneInfo:
    """What the 3D view needs to draw the site; changes only with a new set-up."""

    version: int
    params_name: str
    tree_dimensions_m: Vec3
    """[length, width, height] of the tree's box [m]."""
    attachment_height_m: float
    """Wire attachment above the tree's centre of gravity [m]."""
    rov_dimensions_m: Vec3
    """Drawing size of the ROV [m] (not a model parameter: scaled from the ROV's mass)."""
    layout: DockingLayout
    frame: DockingFrame
    n_thrusters: int
    wire_weight_newton_per_m: float
    """Submerged weight of the wire per metre, w [N/m]."""
    tree_weight_newton: float
    """Tree submerged weight W0 [N]."""
    preset_gains: Gains
    """The parameter set's controller gains (the gain sliders' reference)."""
    frame_in_mission: bool = False
    """True when the mission places the docking frame (False: ``frame`` is drawn under the
    tree only to give the scene a seabed)."""
    thruster_configuration: tuple[tuple[float, ...], ...] = ()
    """The columns of the thrust configuration matrix T, one (6,) per thruster (drawing the
    thrusters where the allocation puts them)."""

    @property
    def support_depth_m(self) -> float | None:
        """Depth of the post tops, where a tree coming down rests on the frame [m]."""
        if not self.frame_in_mission:
            return None
        return self.frame.landing_depth_m - self.layout.post_height_m


ADVICE_APPLIED_TOL_M = 0.05
"""The vessel commanded within this of the advised crane tip counts as the advice applied
[m] (the Control tab's vessel form shows the crane tip to 0.01 m)."""


@dataclass(frozen=True)
class VesselAdvice:
    """A dock leg's advice to move the vessel (``vessel = "advise"``, ``missions.assist``),
    which the leg waits for the operator to follow."""

    text: str
    """The leg's words: 'move the vessel 4.8 m towards 016 deg (crane tip to ...)'."""
    crane_tip_ne_m: tuple[float, float]
    """Where the crane tip should go (north, east) [m]."""
    t_s: float
    """Run time when it was given [s]."""
    distance_m: float
    """How far the vessel should move, from where it stood then [m]."""
    bearing_deg: float
    """Which way, as a compass bearing [deg]."""
    applied: bool = False
    """The vessel is commanded there (within ``ADVICE_APPLIED_TOL_M``)."""
    to_go_m: float = 0.0
    """The crane tip's distance from the advised place now [m]."""


def vessel_advice(event: dict) -> VesselAdvice | None:
    """The advice in a mission event (``missions.legs``' kind "vessel", mode "advise"); None
    for any other event (a "vessel" event of mode "auto" is a move the leg made itself)."""
    data = event.get("data", {})
    if event.get("kind") != "vessel" or data.get("mode") != "advise":
        return None
    north, east = (float(v) for v in data["crane_tip_ne_m"])
    return VesselAdvice(
        str(event["text"]),
        (north, east),
        float(event["t_s"]),
        float(data["distance_m"]),
        float(data["bearing_deg"]),
    )


ADVICE_THERE_M = 0.05
"""The crane tip this close to the advised place counts as there [m]."""


def advice_words(advice: VesselAdvice) -> tuple[str, str]:
    """The advice as every station words it: a heading ("Advice", "Advice applied") and what
    to do or, once applied, whether the vessel is on its way or there."""
    given = f"given at {advice.t_s:.0f} s"
    if not advice.applied:
        return "Advice", f"{given}: {advice.text}"
    if advice.to_go_m > ADVICE_THERE_M:
        to_go = f"{advice.to_go_m:.1f} m to go"
        return "Advice applied", f"({given}): the vessel is on its way, {to_go}"
    return "Advice applied", f"({given}): the vessel is there"


def advice_line(snap: Snapshot) -> str | None:
    """The running dock leg's advice to move the vessel as one line in the console's words,
    for the stations that show it beside the console (the supervisor's, the pilot's); the
    console's operator applies it. None without advice."""
    advice = snap.mission.vessel_advice
    if advice is None:
        return None
    heading, words = advice_words(advice)
    return f"{heading} {words}"


def advice_now(advice: VesselAdvice, sim: Simulation) -> VesselAdvice:
    """``advice`` with where the vessel is commanded and stands now: applied or not, and how
    far the crane tip still has to go."""
    tip = np.asarray(advice.crane_tip_ne_m)
    commanded = float(np.hypot(*(sim.crane_target_n[0:2] - tip)))
    to_go = float(np.hypot(*(sim.crane_tip_n[0:2] - tip)))
    return replace(advice, applied=commanded <= ADVICE_APPLIED_TOL_M, to_go_m=to_go)


@dataclass(frozen=True)
class MissionStatus:
    """The mission in progress or the last one run."""

    name: str | None = None
    state: str = "idle"
    """idle | running | completed | failed | aborted | diverged"""
    leg_index: int | None = None
    """1-based index of the running leg."""
    legs_total: int = 0
    leg_type: str | None = None
    leg_name: str | None = None
    result: dict | None = None
    """``MissionResult.summary()`` once the mission has ended."""
    vessel_advice: VesselAdvice | None = None
    """The running dock leg's advice to move the vessel, the newest (None: none, or the
    mission has ended or the leg moved on)."""


@dataclass(frozen=True)
class ReplayStatus:
    """An open replay."""

    name: str
    t_s: float
    start_s: float
    end_s: float
    playing: bool
    complete: bool
    """False when the log was not closed cleanly (its tail was recovered)."""
    marks: tuple[tuple[float, str], ...] = ()
    """Events to mark on the scrub bar: (time [s], label; '' for a plain tick)."""
    jumps: tuple[tuple[float, str], ...] = ()
    """The marked events in words, to jump to: (time [s], the event's text)."""


@dataclass(frozen=True)
class LoopStats:
    """How well the loop keeps its pace (over the last few seconds of ticks)."""

    period_s: float
    jitter_median_ms: float
    jitter_p99_ms: float
    ticks: int
    overruns: int
    """Times the loop fell so far behind that it re-anchored its clock."""
    step_ms_p99: float
    """99th percentile of the time one tick's work took [ms]."""


@dataclass(frozen=True)
class Snapshot:
    """Everything a reader may show, as of one tick."""

    seq: int
    source: str
    """live | replay"""
    t_s: float
    paused: bool
    speed: float
    """Simulated seconds per wall-clock second."""
    tree_eta_n: Vec6
    rov_eta_n: Vec6
    eta_ref: Vec3
    """Reference [north, east, psi] of the tree."""
    eta_hat: Vec3
    """Estimate [north, east, psi] of the tree."""
    thruster_utilisation: tuple[float, ...]
    thruster_force_newton: tuple[float, ...]
    mode: str
    allocation: str | None
    grip: bool | None
    gains: Gains | None
    crane_tip_n: Vec3
    wire_length_m: float
    wire_tension_newton: float | None
    current_speed_mps: float
    current_direction_rad: float
    wire_drag_newton_per_m: float
    mission: MissionStatus
    alarms: tuple[Alarm, ...]
    recording: str | None
    replay: ReplayStatus | None
    scene: SceneInfo
    stats: LoopStats
    warnings: tuple[str, ...] = ()
    error: str | None = None
    quality_counters: tuple[tuple[int, ...], ...] | None = None
    """Signal-check counters: a row a sensor (position, depth, compass, dvl, gyro), a column a
    check (range, wild point, frozen, variance); None in a replay."""
    operations: tuple[Operation, ...] = ()
    """The latest operations (who did what), oldest first."""
    target: Vec3 | None = None
    """The tree's target [north, east, psi] (where the reference model is heading; None in a
    replay)."""
    trend: FloatArray = field(default_factory=lambda: _frozen(np.zeros((0, 7))), repr=False)
    faults: tuple[FaultView, ...] = ()
    """Injected faults active or scheduled (instructor only: the API and the page show them
    to the instructor alone)."""
    fault_log: tuple[tuple[float, str], ...] = ()
    """The latest fault starts and ends, (time [s], what) (instructor only)."""
    winch: WinchView | None = None
    """The winch (None in a replay)."""

    @property
    def active_alarms(self) -> tuple[Alarm, ...]:
        return tuple(a for a in self.alarms if a.active)


def _frozen(a: FloatArray) -> FloatArray:
    a.flags.writeable = False
    return a


def frozen_copy(a: FloatArray) -> FloatArray:
    """A read-only copy (readers on other threads cannot change what the loop publishes)."""
    return _frozen(np.array(a, dtype=float, copy=True))


def default_docking_frame(
    ps: ParameterSet, center_ne: FloatArray, heading_rad: float, tree_depth_m: float
) -> DockingFrame:
    """The frame under the tree's start: post tops half a tree height below its bottom.

    Used until a mission's set-up places the frame (the thesis's chapter 5 frame stands under
    the hook-up point)."""
    layout = ps.spec.docking.to_numeric()
    return frame_below_tree(
        layout, float(ps.tree.dimensions_m[2]), center_ne, heading_rad, tree_depth_m
    )


def frame_below_tree(
    layout: DockingLayout,
    tree_height_m: float,
    center_ne: FloatArray,
    heading_rad: float,
    tree_depth_m: float,
) -> DockingFrame:
    """A frame whose post tops are half a tree height below the bottom of a tree at
    ``tree_depth_m`` (its centre) [m]: landing depth = depth + height + post height."""
    landing = tree_depth_m + tree_height_m / 2.0 + layout.post_height_m + tree_height_m / 2.0
    return DockingFrame(np.asarray(center_ne, float).copy(), heading_rad, landing)


def scene_info(
    ps: ParameterSet, frame: DockingFrame, version: int, frame_in_mission: bool = False
) -> SceneInfo:
    dims = ps.tree.dimensions_m
    return SceneInfo(
        version=version,
        params_name=ps.name,
        tree_dimensions_m=(float(dims[0]), float(dims[1]), float(dims[2])),
        attachment_height_m=float(ps.tree.attachment_height_m),
        rov_dimensions_m=tuple(float(v) for v in rov_drawing_box_m(ps)),  # type: ignore[arg-type]
        layout=ps.spec.docking.to_numeric(),
        frame=frame,
        n_thrusters=int(ps.rov.thrusters.T.shape[1]),
        wire_weight_newton_per_m=float(ps.wire.submerged_weight_per_length()),
        tree_weight_newton=float(ps.tree.submerged_weight_newton),
        preset_gains=Gains.of(ps.gains.kp, ps.gains.ki, ps.gains.kd),
        frame_in_mission=frame_in_mission,
        thruster_configuration=tuple(tuple(map(float, col)) for col in ps.rov.thrusters.T.T),
    )


@dataclass(frozen=True)
class RowView:
    """The parts of one log row a snapshot shows."""

    t_s: float
    tree_eta_n: Vec6
    rov_eta_n: Vec6
    eta_ref: Vec3
    eta_hat: Vec3
    utilisation: tuple[float, ...]
    force_newton: tuple[float, ...]
    mode: str


def row_view(row: FloatArray, n_thrusters: int) -> RowView:
    """Pick one log row (the layout of control.columns) apart."""
    v = LogRows(row[None, :], n_thrusters)

    def seq(name: str) -> tuple[float, ...]:
        return tuple(float(x) for x in np.atleast_1d(v[name][0]))

    mode = float(v["mode"][0])
    mode_code = int(mode) if math.isfinite(mode) else 0
    return RowView(
        t_s=float(v.t_s[0]),
        tree_eta_n=seq("tree_eta_n"),  # type: ignore[arg-type]
        rov_eta_n=seq("rov_eta_n"),  # type: ignore[arg-type]
        eta_ref=seq("eta_ref_n"),  # type: ignore[arg-type]
        eta_hat=seq("eta_hat_n"),  # type: ignore[arg-type]
        utilisation=seq("thruster_utilisation"),
        force_newton=seq("thruster_force"),
        mode=MODES[mode_code] if 0 <= mode_code < len(MODES) else "tree",
    )


def trend_rows(rows: LogRows) -> FloatArray:
    """(k, 7) trend rows (TREND_COLUMNS) from log rows."""
    out = np.empty((len(rows), len(TREND_COLUMNS)))
    tree = rows["tree_eta_n"]
    out[:, 0] = rows.t_s
    out[:, 1:3] = tree[:, 0:2]
    out[:, 3] = tree[:, 5]
    out[:, 4:7] = rows["eta_ref_n"]
    return out


class TrendBuffer:
    """Ring of the last ``capacity`` trend rows (owned by the loop task)."""

    def __init__(self, dt_s: float, capacity: int = 3000) -> None:
        self.dt_s = dt_s
        self._data = np.zeros((capacity, len(TREND_COLUMNS)))
        self._count = 0

    def clear(self) -> None:
        self._count = 0

    def extend(self, rows: LogRows) -> None:
        """Add the log rows that fall on the decimation grid."""
        if len(rows) == 0:
            return
        steps = np.rint(rows.t_s / self.dt_s).astype(np.int64)
        picked = LogRows(
            rows.data[steps % TREND_DECIMATION == 0], rows.n_thrusters, layout=rows.layout
        )
        cap = len(self._data)
        for r in trend_rows(picked)[-cap:]:
            self._data[self._count % cap] = r
            self._count += 1

    def view(self) -> FloatArray:
        """Read-only copy, oldest first."""
        cap = len(self._data)
        if self._count <= cap:
            return frozen_copy(self._data[: self._count])
        i = self._count % cap
        return frozen_copy(np.vstack([self._data[i:], self._data[:i]]))
