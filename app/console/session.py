"""``Session``: what the console's loop task owns — the ``Simulation``, the mission in
progress (driven by the same ``MissionDriver`` as the headless runner), alarms, the session
recorder and the replay — advanced a given number of plant steps at a time.

Nothing here knows about wall-clock time, threads or the network: ``app.console.loop`` paces
the session and feeds it commands; tests drive it directly. Only the loop task may call its
methods.
"""

from __future__ import annotations

import math
import re
import sqlite3
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from app import scores
from app.console.alarms import AlarmLimits, AlarmMonitor
from app.console.errors import ConsoleError
from app.console.operations import Operation, trainee_of
from app.console.replay import Replay, recording_path
from app.console.snapshot import (
    FAULT_LOG_KEEP,
    LoopStats,
    MissionStatus,
    ReplayStatus,
    RowView,
    SceneInfo,
    Snapshot,
    TrendBuffer,
    VesselAdvice,
    advice_now,
    default_docking_frame,
    fault_views,
    frozen_copy,
    row_view,
    scene_info,
    vessel_advice,
    winch_view,
)
from app.console.texts import alarm_title
from app.console.viewer_replay import recording_scene
from app.foxglove_live import LiveFeed
from app.recording import (
    SessionData,
    SessionRecorder,
    session_metadata,
)
from control.columns import LogRows
from control.simulation import Simulation, SimulationDiverged, steady_current
from missions import schema
from missions.driver import MissionDriver
from missions.setup import build_simulation

FloatArray = NDArray[np.float64]
LABEL = re.compile(r"^[A-Za-z0-9._-]{0,60}$")
RECORD_FLUSH_ROWS = 50
"""Rows gathered before they are handed to the recorder (0.5 s of plant steps)."""


@dataclass
class PreparedRun:
    """A simulation built away from the loop task (building takes a few tenths of a second),
    ready to be swapped in between two ticks."""

    mission: schema.Mission
    sim: Simulation
    run_legs: bool
    """True: run the mission's legs; False: only its set-up, holding station."""


def station_keeping_mission(params: str, depth_m: float) -> schema.Mission:
    """A set-up with nothing to do: the console's start when no mission is given."""
    return schema.parse_mission(
        {
            "format_version": 1,
            "name": "station keeping",
            "description": "hold the tree where it hangs",
            "setup": {"params": params, "depth_m": depth_m},
            "legs": [{"type": "hold", "duration_s": 1.0}],
        },
        "<console>",
    )


def prepare_run(mission: schema.Mission, run_legs: bool = True) -> PreparedRun:
    """Build the simulation for a mission's set-up (call off the loop task), with the compiled
    kernels of its first chunk loaded (``load_first_chunk``)."""
    load_first_chunk(mission)
    return PreparedRun(mission, build_simulation(mission), run_legs)


def load_first_chunk(mission: schema.Mission) -> None:
    """Load the compiled kernels a chunk of this set-up calls (the closed or open loop's chunk
    kernel, the environment rows, the current's walk) by running one step of a second
    simulation of the same set-up, thrown away; the run handed to the loop is not touched.

    numba compiles a kernel on its first call after a change of the core (tens of seconds) or
    loads it from its cache (a fraction of a second): either would make the paced loop's
    first tick late. Here it happens away from the loop, and only the first time per process.
    A step that fails here is left to the live run to report on its own first tick."""
    try:
        sim = build_simulation(mission)
        sim.step(1)
        # and the form that writes a request of several chunks into the request's rows
        # (``loop.run_chunk_into``: a tick's steps cut at a fault's edge)
        sim.chunk_steps = 1
        sim.step(2)
    except (SimulationDiverged, ValueError):
        pass


SCORES_DB = "scores.sqlite"
"""The scores database, in the recordings folder (``rov-console scores --db``)."""


class Session:
    """The live simulation with its mission, alarms, recorder and replay."""

    def __init__(self, run: PreparedRun, recordings_dir: Path) -> None:
        self.recordings_dir = recordings_dir
        self._scene_version = 0
        self._workers = ThreadPoolExecutor(max_workers=1, thread_name_prefix="console-score")
        self.recorder: SessionRecorder | None = None
        self.recording_name: str | None = None
        self._recording_label = ""
        self._rec_rows: list[FloatArray] = []
        self.actor: str | None = None
        self.started_by: str | None = None
        """Who sent the command being applied (set by the loop; None between commands)."""
        self.notes_written = 0
        self._rec_offset_s = 0.0
        """Added to the simulation time in the recording: a run started while recording goes
        on in the same file after the one before."""
        self._rec_wall: list[tuple[float, int]] = []
        """(recording time [s], wall clock [ns]) when the rows waiting to be written had been
        simulated, after the last written (the recording's log times)."""
        self.replay: Replay | None = None
        self.live: LiveFeed | None = None
        """The live feed for Foxglove (``serve --foxglove-port``), when there is one."""
        self._trend_cache = frozen_copy(np.zeros((0, 7)))
        self._trend_wall = 0.0
        self._install(run)

    # ------------------------------------------------------------------ set-up
    def _install(self, run: PreparedRun) -> None:
        self.started_by = self.actor
        """Who started this run (None: the console itself, at start-up)."""
        self.sim = run.sim
        self.mission = run.mission
        if self.live is not None:
            self.live.new_run(run.sim.ps, run.sim.n_thrusters, self._live_origin_ns())
        self.driver = MissionDriver(run.mission, run.sim) if run.run_legs else None
        if self.driver is not None:
            # live, an instructor's fault (a winch slip) or the pilot's changes can move what
            # a leg waits for mid-leg: its checks come every poll, none skipped on a
            # prediction made before (missions.legs.MissionContext.polls)
            self.driver.ctx.merge_polls = False
        self._result: Future | None = None
        name = run.mission.name if run.run_legs else None
        self.mission_status = MissionStatus(
            name=name,
            state="running" if run.run_legs else "idle",
            legs_total=len(run.mission.legs) if run.run_legs else 0,
        )
        sim = self.sim
        frame = sim.docking_frame or default_docking_frame(
            sim.ps, sim.crane_tip_n[0:2], float(sim.tree_eta_n[5]), float(sim.tree_eta_n[2])
        )
        self._scene_version += 1
        self.scene = scene_info(
            sim.ps, frame, self._scene_version, frame_in_mission=sim.docking_frame is not None
        )
        self.monitor = AlarmMonitor(
            AlarmLimits.for_params(sim.ps),
            self.scene.n_thrusters,
            self.scene.tree_weight_newton,
            uses_sensors=sim.settings.feedback == "ekf",
            support_depth_m=self.scene.support_depth_m,
            tree_half_height_m=self.scene.tree_dimensions_m[2] / 2.0,
        )
        self.trend = TrendBuffer(sim.dt_s)
        self.last_row = sim.present_row()
        self.tension_newton: float | None = sim.wire_tension_newton()
        self.error: str | None = None
        self.notices: tuple[str, ...] = ()
        self._faults_noted = 0
        """Entries of ``sim.fault_events`` already written as events."""
        self._mission_events_written = 0
        """Entries of ``driver.events`` already written into the recording."""
        self._advice: VesselAdvice | None = None
        """The running leg's newest advice to move the vessel (``MissionStatus``)."""
        self._advice_events_read = 0
        """Entries of ``driver.events`` already read for advice."""

    def replace_run(self, run: PreparedRun) -> None:
        """Swap in a new simulation. A recording in progress goes on in the same file, its
        time continuing from where the last run stopped, when the new run has the same
        parameter set (the same log layout); otherwise it goes on in a new file, and a notice
        says so."""
        self.close_replay()
        if self._mission_running:
            self._finish_mission("aborted")
        label = self._recording_label
        was_recording = self.recorder is not None
        same_layout = (
            run.sim.ps.name == self.sim.ps.name and run.sim.n_thrusters == self.sim.n_thrusters
        )
        if was_recording and same_layout:
            self.flush_recording()
            self._rec_offset_s += self.sim.t_s - run.sim.t_s + self.sim.dt_s
            self._install(run)
            self._record_run_setup()
            self.note(
                "run",
                f"new run: {run.mission.name}" + (" (its legs)" if run.run_legs else ""),
                {"mission": run.mission.name, "legs": run.run_legs},
            )
            return
        if was_recording:
            old = self.stop_recording()
        self._install(run)
        if was_recording:
            new = self.start_recording(label)
            self.notices = (
                *self.notices[-4:],
                f"recording goes on in {new}: the new run's parameter set "
                f"({run.sim.ps.name}) differs from {old}'s",
            )

    # ------------------------------------------------------------------ stepping
    @property
    def _mission_running(self) -> bool:
        return self.driver is not None and self.mission_status.state == "running"

    def advance(self, n_steps: int) -> None:
        """Advance the live simulation (and its mission) by ``n_steps``, and the API's replay
        (if one is open) by as long: a replay never holds up the live run."""
        if self.replay is not None:
            self.replay.advance(n_steps)
        if self.error is not None or n_steps <= 0:
            return
        remaining = int(n_steps)
        if self._mission_running:
            assert self.driver is not None
            rows = self.driver.advance(remaining)
            self._follow_leg()
            self._follow_vessel_advice()
            self._record_mission_events()
            if len(rows):
                self._take_rows(rows)
            if self.driver.diverged:
                self._diverged(self.driver.divergence)
                return
            if self.driver.error:
                self.notices = (*self.notices[-4:], self.driver.error)
                self._finish_mission("failed")
                self.note("alarm", self.driver.error, {"name": "mission"})
                return
            if not self.driver.done:
                return
            self._finish_mission("completed")
            remaining -= len(rows)
            if remaining <= 0:
                return
        try:
            rows = self.sim.step(remaining)
        except SimulationDiverged as err:
            self._diverged(str(err))
            return
        self._take_rows(rows)

    def _follow_leg(self) -> None:
        """Show the running leg (and note when a new one starts)."""
        assert self.driver is not None
        leg = self.driver.current_leg
        status = self.mission_status
        index = self.driver.leg_index + 1
        if leg is not None and status.leg_index != index:
            self.mission_status = MissionStatus(
                status.name, "running", index, status.legs_total, leg.type, leg.name or None
            )
            self.note(
                "mission", f"leg {index} ({leg.type}) started", {"leg": index, "type": leg.type}
            )

    def _follow_vessel_advice(self) -> None:
        """Keep the running leg's newest advice to move the vessel: a leg's start clears it,
        an advice replaces the one before."""
        assert self.driver is not None
        events = self.driver.events
        for event in events[self._advice_events_read :]:
            if event["kind"] == "leg":
                self._advice = None
            self._advice = vessel_advice(event) or self._advice
        self._advice_events_read = len(events)

    def _finish_mission(self, state: str) -> None:
        driver = self.driver
        if driver is None:
            return
        self._advice = None
        if state == "aborted":
            driver.abort()
        s = self.mission_status
        self.mission_status = MissionStatus(
            s.name, state, s.leg_index, s.legs_total, s.leg_type, s.leg_name
        )
        started_by, log_file = self.started_by, self.recording_name
        db = self.recordings_dir / SCORES_DB

        def score() -> dict:
            result = driver.result()
            summary = result.summary()
            if started_by is not None:  # someone flew it: their score goes in the database
                try:
                    summary["score_id"] = scores.record(
                        db, trainee_of(started_by), result, "console", log_file
                    )
                except (OSError, ValueError, sqlite3.Error) as err:
                    summary["score_error"] = f"scores not stored in {db}: {err}"
            return summary

        self._result = self._workers.submit(score)
        self.note("mission", f"mission {s.name} {state}", {"state": state})

    def fail(self, message: str) -> None:
        """Something in a step went wrong that the simulation did not expect: stop the run
        (a reset goes on), end the mission as failed, say why."""
        self.error = f"the run stopped: {message}; reset to go on"
        if self._mission_running:
            self._finish_mission("failed")
        self.note("error", self.error, {})

    def _diverged(self, message: str) -> None:
        self.error = f"simulation diverged: {message}; reset to go on"
        if self._mission_running:
            self._finish_mission("diverged")
        self.note("error", self.error, {})

    def _follow_docking_frame(self) -> None:
        """A mission leg may place (or move) the docking frame: redraw the site then."""
        frame = self.sim.docking_frame
        if frame is not None and frame is not self.scene.frame:
            self._scene_version += 1
            self.scene = replace(
                self.scene, frame=frame, version=self._scene_version, frame_in_mission=True
            )
            self.monitor.support_depth_m = self.scene.support_depth_m

    def _take_rows(self, rows: LogRows) -> None:
        self._follow_docking_frame()
        self._note_faults()
        self.last_row = rows.last()
        self.trend.extend(rows)
        if self.live is not None:
            self.live.rows(
                rows.data, self.sim.crane_tip_n, float(self.sim.wire_length_m), self.scene.frame
            )
        self.tension_newton = self.sim.wire_tension_newton()
        before = {a.name: a.active for a in self.monitor.state}
        free_setpoint = self.sim.free_setpoint_n
        mount = (float(self.sim.C.k_h), self.sim.sysm.r_rov_from_tree_tree_m)
        for alarm in self.monitor.update(rows, self.tension_newton, free_setpoint, mount):
            if alarm.active != before.get(alarm.name):
                self.note(
                    "alarm",
                    f"{alarm_title(alarm.name)} {'on' if alarm.active else 'off'}"
                    f"{': ' + alarm.message if alarm.message else ''}",
                    {"name": alarm.name, "active": alarm.active},
                )
        if self.recorder is not None:
            self._rec_rows.append(rows.data)
            # when these rows had been simulated: the recording's log times are the wall
            # clock's (SessionRecorder's wall_log_times)
            self._rec_wall.append((float(rows.t_s[-1]) + self._rec_offset_s, time.time_ns()))
            if sum(len(r) for r in self._rec_rows) >= RECORD_FLUSH_ROWS:
                self.flush_recording()

    def _record_mission_events(self) -> None:
        """The mission's own events (legs, landings, misses, the wire's; as ``run --log``
        writes them, at their own times) into the recording; its faults are noted by
        ``_note_faults``, with who injected them."""
        if self.driver is None:
            return
        events = self.driver.events
        if self.recorder is not None:
            self.flush_recording()
            for event in events[self._mission_events_written :]:
                if event["kind"] == "fault":
                    continue
                try:
                    self.recorder.event(
                        max(0.0, event["t_s"] + self._rec_offset_s),
                        event["kind"],
                        event["text"],
                        event["data"],
                    )
                except Exception as err:
                    self._recording_failed(err)
                    return
        self._mission_events_written = len(events)

    def _run_metadata(self, label: str = "") -> dict[str, Any]:
        """The set-up of the present run, as the recording holds it."""
        return session_metadata(
            self.sim,
            self.mission,
            label=label,
            legs_run=self.driver is not None,
            time_offset_s=self._rec_offset_s,
        )

    def _record_run_setup(self) -> None:
        """A run started while recording: its set-up into the recording (``add_run``)."""
        if self.recorder is None:
            return
        try:
            self.recorder.add_run(self._run_metadata(self._recording_label))
        except Exception as err:
            self._recording_failed(err)

    def _note_faults(self) -> None:
        """Fault starts and ends into the recording (events of kind 'fault')."""
        events = self.sim.fault_events
        for t_s, text in events[self._faults_noted :]:
            self.note("fault", text, {"t_s": round(t_s, 3)})
        self._faults_noted = len(events)

    # ------------------------------------------------------------------ commands
    def require_live(self, what: str) -> None:
        """Kept for callers: the live run is always there (a replay, the API's or a
        browser's, runs beside it), so nothing is refused for a replay."""

    def require_no_mission(self, what: str) -> None:
        if self._mission_running:
            raise ConsoleError(
                f"{what}: mission {self.mission_status.name!r} is running; abort it first"
            )

    def abort_mission(self) -> None:
        if not self._mission_running:
            raise ConsoleError("no mission is running")
        self._finish_mission("aborted")

    def set_current(self, speed_mps: float, direction_deg: float) -> None:
        """A steady current (no random walk) [m/s, towards deg]."""
        self.sim.set_current(steady_current(speed_mps, math.radians(direction_deg)))

    def move_vessel(self, north_m: float, east_m: float, speed_mps: float) -> None:
        tip = self.sim.crane_tip_n
        self.sim.move_vessel(np.array([north_m, east_m, tip[2]]), speed_mps)

    def vessel_advice_to_apply(self) -> VesselAdvice:
        """The running leg's advice to move the vessel, not yet applied; ConsoleError saying
        why there is none to apply."""
        if not self._mission_running:
            raise ConsoleError("no vessel advice to apply: no mission is running")
        if self._advice is None:
            raise ConsoleError(
                "no vessel advice to apply: the running leg has given none (a dock leg with "
                'vessel = "advise" gives one when the ROV alone cannot hold the tree over '
                "the frame)"
            )
        advice = advice_now(self._advice, self.sim)
        if advice.applied:
            raise ConsoleError(
                f"the vessel advice given at {advice.t_s:.0f} s is applied already: the vessel "
                "is commanded there"
            )
        return advice

    # ------------------------------------------------------------------ recording
    def note(self, kind: str, text: str, data: dict) -> None:
        """An event in the recording (commands, alarms, mission progress); while the loop
        applies someone's command, the event names them (``who``)."""
        self.notes_written += 1
        if self.actor is not None:
            data = {**data, "who": self.actor}
        if self.live is not None:
            self.live.event(self.sim.t_s, kind, text, data)
        if self.recorder is None:
            return
        self.flush_recording()
        try:
            self.recorder.event(self.sim.t_s + self._rec_offset_s, kind, text, data)
        except Exception as err:
            self._recording_failed(err)

    def start_recording(self, label: str = "") -> str:
        self.require_live("record")
        if self.recorder is not None:
            raise ConsoleError(f"already recording to {self.recording_name}")
        if not LABEL.match(label):
            raise ConsoleError(
                f"label may hold letters, digits, '.', '_' and '-' (at most 60), got {label!r}"
            )
        self.recordings_dir.mkdir(parents=True, exist_ok=True)
        stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
        base = f"{stamp}-{label or self.mission.name.replace(' ', '-')}"
        base = re.sub(r"[^A-Za-z0-9._-]", "-", base)[:100]
        name = f"{base}.mcap"
        k = 1
        while (self.recordings_dir / name).exists():
            k += 1
            name = f"{base}-{k}.mcap"
        self._rec_offset_s = 0.0
        self._rec_wall = [(float(self.sim.t_s), time.time_ns())]
        self.recorder = SessionRecorder(
            recording_path(self.recordings_dir, name),
            metadata=self._run_metadata(label),
            params=self.sim.ps,
            n_thrusters=self.scene.n_thrusters,
            docking=self.scene.frame,
            wall_log_times=True,
        )
        self.recording_name = name
        self._recording_label = label
        self._rec_rows = []
        # a mission already under way: what it did before the recording started goes in too
        self._mission_events_written = 0
        self._record_mission_events()
        self._record_alarms_on()
        return name

    def _record_alarms_on(self) -> None:
        """The alarms on when a recording starts, as events at its first moment: only their
        changes are written as they come, so one on already was missing from the recording
        (its replay and debrief) until it went off."""
        for alarm in self.monitor.state:
            if alarm.active:
                self.note(
                    "alarm",
                    f"{alarm_title(alarm.name)} on{': ' + alarm.message if alarm.message else ''}",
                    {"name": alarm.name, "active": True, "on_at_start": True},
                )

    def flush_recording(self) -> None:
        if self.recorder is None or not self._rec_rows:
            return
        rows = np.vstack(self._rec_rows)
        self._rec_rows = []
        wall, self._rec_wall = self._rec_wall, self._rec_wall[-1:]
        if self._rec_offset_s:
            rows[:, 0] += self._rec_offset_s  # t_s, the first column (control.columns)
        try:
            self.recorder.write_log(
                rows,
                crane_tip_n=self.sim.crane_tip_n.copy(),
                wire_length_m=float(self.sim.wire_length_m),
                docking=self.scene.frame,
                wall=wall,
            )
        except Exception as err:
            self._recording_failed(err)

    def _recording_failed(self, err: Exception) -> None:
        self.notices = (*self.notices[-4:], f"recording stopped: {err}")
        recorder, self.recorder = self.recorder, None
        self.recording_name = None
        try:
            if recorder is not None:
                recorder.close()
        except Exception:
            pass

    def stop_recording(self) -> str:
        if self.recorder is None:
            raise ConsoleError("not recording")
        self.flush_recording()
        name = self.recording_name or ""
        recorder, self.recorder, self.recording_name = self.recorder, None, None
        if recorder is not None:
            recorder.close()
        return name

    # ------------------------------------------------------------------ replay
    def open_replay(self, name: str, data: SessionData) -> ReplayStatus:
        """Open the API's replay of a loaded recording (``load_replay``): it plays beside the
        live run on the loop's clock and is reported in the snapshot's ``replay`` (the live
        run's state stays what the snapshot shows; browsers in the page have replays of
        their own, ``app.console.viewer_replay``)."""
        if name == self.recording_name:
            raise ConsoleError(f"{name} is being recorded; stop the recording first")
        self.replay = Replay(name, data, self._replay_scene(data), self.sim.dt_s)
        return self.replay.status()

    def _replay_scene(self, data: SessionData) -> SceneInfo:
        """The scene of the recorded parameter set (the live one if it cannot be rebuilt)."""
        self._scene_version += 1
        return recording_scene(data, self.scene, self._scene_version)

    def close_replay(self) -> None:
        self.replay = None

    def require_replay(self) -> Replay:
        if self.replay is None:
            raise ConsoleError("no replay is open")
        return self.replay

    # ------------------------------------------------------------------ reading
    def _mission_result(self) -> MissionStatus:
        if self._result is not None and self._result.done():
            s = self.mission_status
            try:
                result = self._result.result()
            except Exception as err:
                result = {"error": str(err)}
            self.mission_status = MissionStatus(
                s.name, s.state, s.leg_index, s.legs_total, s.leg_type, s.leg_name, result
            )
            self._result = None
        return self.mission_status

    def _mission_view(self) -> MissionStatus:
        """The mission's status with its pending vessel advice, applied or not as of now."""
        status = self._mission_result()
        if self._advice is None or not self._mission_running:
            return status
        return replace(status, vessel_advice=advice_now(self._advice, self.sim))

    def _trend(self) -> FloatArray:
        now = time.monotonic()
        if now - self._trend_wall > 0.1:
            self._trend_cache = self.trend.view()
            self._trend_wall = now
        return self._trend_cache

    def snapshot(
        self,
        seq: int,
        paused: bool,
        speed: float,
        stats: LoopStats,
        operations: tuple[Operation, ...] = (),
    ) -> Snapshot:
        """The state as of now (see ``Snapshot``)."""
        sim = self.sim
        v: RowView = row_view(self.last_row, self.scene.n_thrusters)
        return Snapshot(
            seq=seq,
            source="live",
            paused=paused,
            speed=speed,
            **_row_fields(v),
            allocation=sim.settings.allocation,
            grip=bool(sim.gripping),
            gains=sim.gains,
            crane_tip_n=tuple(float(c) for c in sim.crane_tip_n),  # type: ignore[arg-type]
            wire_length_m=float(sim.wire_length_m),
            wire_tension_newton=self.tension_newton,
            current_speed_mps=sim.current_speed_mps,
            current_direction_rad=sim.current_direction_rad,
            wire_drag_newton_per_m=float(sim.ps.wire.drag_per_length(sim.current_speed_mps)),
            mission=self._mission_view(),
            alarms=self.monitor.state,
            recording=self.recording_name,
            replay=None if self.replay is None else self.replay.status(),
            scene=self.scene,
            stats=stats,
            operations=operations,
            warnings=(*sim.startup.warnings, *self.notices),
            error=self.error,
            target=tuple(float(v) for v in sim.target),  # type: ignore[arg-type]
            quality_counters=tuple(tuple(int(c) for c in row) for row in sim.quality_counters),
            trend=self._trend(),
            faults=fault_views(sim.faults, sim.t_s) if sim.faults else (),
            fault_log=tuple(sim.fault_events[-FAULT_LOG_KEEP:]),
            winch=winch_view(sim),
        )

    def start_live_feed(self, port: int, host: str) -> LiveFeed:
        """Serve this session live over the Foxglove WebSocket protocol (read-only)."""
        self.live = LiveFeed(
            self.sim.ps, self.scene.n_thrusters, self._live_origin_ns(), port, host
        )
        return self.live

    def _live_origin_ns(self) -> int:
        """The live feed's time origin: now, less the simulated time (at 1x, log times are
        the wall clock's)."""
        return time.time_ns() - round(self.sim.t_s * 1e9)

    def close(self) -> None:
        """Close the recording, the live feed and the scoring worker (at shutdown)."""
        if self.live is not None:
            self.live.close()
        if self.recorder is not None:
            try:
                self.stop_recording()
            except Exception:
                self.recorder = None
        self._workers.shutdown(wait=False, cancel_futures=True)


def _row_fields(v: RowView) -> dict[str, Any]:
    """The snapshot's fields that come from one log row (live or replayed alike)."""
    return {
        "t_s": v.t_s,
        "tree_eta_n": v.tree_eta_n,
        "rov_eta_n": v.rov_eta_n,
        "eta_ref": v.eta_ref,
        "eta_hat": v.eta_hat,
        "thruster_utilisation": v.utilisation,
        "thruster_force_newton": v.force_newton,
        "mode": v.mode,
    }
