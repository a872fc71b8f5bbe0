"""What the console's loop task owns: the closed loop, the mission in progress, the session
recorder and the replay, advanced a given number of plant steps at a time.

Nothing here knows about wall-clock time, threads or the network: ``app.console_loop`` paces
the engine and feeds it commands; the engine is driven directly in tests. Only the loop task
may call its methods.
"""

from __future__ import annotations

import math
import re
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from app.alarms import AlarmLimits, AlarmMonitor
from app.console_state import (
    LoopStats,
    MissionStatus,
    ReplayStatus,
    RowView,
    SceneInfo,
    Snapshot,
    TrendBuffer,
    default_docking_frame,
    frozen_copy,
    row_view,
    scene_info,
    trend_rows,
)
from app.recording import SessionRecorder, load_session
from control import loop
from control.closed_loop import ClosedLoop, LoopLog
from missions import runner, schema
from sim import environment as envmod
from sim import params as params_mod
from sim.docking import DockingFrame
from sim.simulator import SimulationDiverged

FloatArray = NDArray[np.float64]
RECORDING_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,120}\.mcap$")
"""File names the recorder writes and the API accepts (no directories, no traversal)."""
LABEL = re.compile(r"^[A-Za-z0-9._-]{0,60}$")
RECORD_FLUSH_ROWS = 50
"""Rows gathered before they are handed to the recorder (0.5 s of plant steps)."""


class ConsoleError(ValueError):
    """A command that cannot be carried out now; the message says why."""


@dataclass
class PreparedRun:
    """A closed loop built away from the loop task (building takes a few tenths of a second),
    ready to be swapped in between two ticks."""

    mission: schema.Mission
    cl: ClosedLoop
    run_legs: bool
    """True: run the mission's legs; False: only its set-up, holding station."""


def station_keeping_mission(params: str, depth_m: float) -> schema.Mission:
    """A set-up with nothing to do: the console's start when no mission is given."""
    return schema.parse_mission({
        "format_version": 1, "name": "station keeping",
        "description": "hold the tree where it hangs",
        "setup": {"params": params, "depth_m": depth_m},
        "legs": [{"type": "hold", "duration_s": 1.0}]}, "<console>")


def prepare_run(mission: schema.Mission, run_legs: bool = True) -> PreparedRun:
    """Build the closed loop for a mission's set-up (call off the loop task)."""
    return PreparedRun(mission, runner.build_loop(mission), run_legs)


def recording_path(directory: Path, name: str) -> Path:
    """The path of a recording by its file name; ConsoleError for anything else."""
    if not RECORDING_NAME.match(name):
        raise ConsoleError(f"recording name must match {RECORDING_NAME.pattern}, got {name!r}")
    return directory / name


def load_replay(directory: Path, name: str):
    """Read a recording for replay (call off the loop task: it can take a while)."""
    path = recording_path(directory, name)
    if not path.is_file():
        raise FileNotFoundError(f"no recording named {name}")
    return load_session(path)


def list_recordings(directory: Path) -> list[dict]:
    """Recordings in the directory, newest first."""
    if not directory.is_dir():
        return []
    files = [p for p in directory.glob("*.mcap") if RECORDING_NAME.match(p.name)]
    files.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    return [{"name": p.name, "size_bytes": p.stat().st_size,
             "modified": datetime.fromtimestamp(p.stat().st_mtime, UTC).isoformat()}
            for p in files]


class _Replay:
    """A recorded session played back against simulation time (the recorder keeps rows at its
    numeric rate, e.g. 20 Hz: the replay shows the last row at or before its clock)."""

    def __init__(self, name: str, data, scene: SceneInfo, dt_s: float) -> None:
        self.name = name
        self.data = data
        self.rows = np.asarray(data.rows, float)
        if self.rows.ndim != 2 or self.rows.shape[0] == 0 or self.rows.shape[1] < loop.N_LOG:
            raise ConsoleError(f"recording {name} holds no log rows to replay")
        self.scene = scene
        self.dt_s = dt_s
        self.index = 0
        self.clock_s = float(self.rows[0, loop.L_T])
        self.playing = False
        self.trend_all = frozen_copy(trend_rows(self.rows))
        meta = getattr(data, "metadata", {}) or {}
        self.mission = str(meta.get("mission", name))
        self.monitor = self._new_monitor()
        self.monitor.update(self.rows[:1], self._tension(0))

    def _tension(self, index: int) -> float:
        """Wire tension recorded in that row (logs carry the site: crane tip, wire, tension)."""
        return float(self.rows[index, loop.L_SITE + 3])

    def site(self) -> tuple[tuple[float, float, float], float, float]:
        """Crane tip (NED), wire rest length and tension at the present row."""
        row = self.rows[self.index]
        return ((float(row[loop.L_SITE]), float(row[loop.L_SITE + 1]), 0.0),
                float(row[loop.L_SITE + 2]), float(row[loop.L_SITE + 3]))

    def _new_monitor(self) -> AlarmMonitor:
        limits = AlarmLimits(position_error_m=self.scene.layout.tolerance_m,
                             sample_period_s=(1.0,) * 5)
        return AlarmMonitor(limits, self.scene.n_thrusters, self.scene.tree_weight_n,
                            uses_sensors=bool(np.any(self.rows[:, loop.L_ACCEPT] > 0.5)))

    @property
    def t_s(self) -> float:
        return float(self.rows[self.index, loop.L_T])

    @property
    def end_s(self) -> float:
        return float(self.rows[-1, loop.L_T])

    def _index_at(self, t_s: float) -> int:
        k = int(np.searchsorted(self.rows[:, loop.L_T], t_s + 1e-9, side="right")) - 1
        return int(np.clip(k, 0, len(self.rows) - 1))

    def advance(self, n_steps: int) -> None:
        """Move the replay clock by n plant steps (when playing)."""
        if not self.playing or n_steps <= 0:
            return
        self.clock_s = min(self.clock_s + n_steps * self.dt_s, self.end_s)
        new = self._index_at(self.clock_s)
        if new > self.index:
            self.monitor.update(self.rows[self.index + 1:new + 1], self._tension(new))
            self.index = new
        if self.clock_s >= self.end_s:
            self.playing = False

    def seek(self, t_s: float) -> None:
        if not math.isfinite(t_s):
            raise ConsoleError(f"replay time must be finite, got {t_s}")
        self.clock_s = float(np.clip(t_s, self.rows[0, loop.L_T], self.end_s))
        self.index = self._index_at(self.clock_s)
        self.monitor = self._new_monitor()
        t = self.rows[:, loop.L_T]
        first = int(np.searchsorted(t, self.clock_s - 10.0))
        self.monitor.update(self.rows[first:self.index + 1], self._tension(self.index))

    def trend(self) -> FloatArray:
        k = self.index + 1
        return self.trend_all[max(0, k - 3000):k]

    def status(self) -> ReplayStatus:
        return ReplayStatus(self.name, self.t_s, float(self.rows[0, loop.L_T]), self.end_s,
                            self.playing, bool(getattr(self.data, "complete", True)))


class ConsoleEngine:
    """The live closed loop with its mission, recorder and replay."""

    def __init__(self, run: PreparedRun, recordings_dir: Path) -> None:
        self.recordings_dir = recordings_dir
        self._scene_version = 0
        self._workers = ThreadPoolExecutor(max_workers=1, thread_name_prefix="console-score")
        self.recorder = None
        self.recording_name: str | None = None
        self._recording_label = ""
        self._rec_rows: list[FloatArray] = []
        self.replay: _Replay | None = None
        self._trend_cache = frozen_copy(np.zeros((0, 7)))
        self._trend_wall = 0.0
        self._install(run)

    # ------------------------------------------------------------------ set-up
    def _install(self, run: PreparedRun) -> None:
        self.cl = run.cl
        self.mission = run.mission
        self.execution = runner.MissionExecution(run.mission, run.cl) if run.run_legs else None
        self._request_steps = 0
        self._request_rows: list[FloatArray] = []
        self._result: Future | None = None
        name = run.mission.name if run.run_legs else None
        self.mission_status = MissionStatus(name=name, state="running" if run.run_legs else
                                            "idle", legs_total=len(run.mission.legs)
                                            if run.run_legs else 0)
        ps = self.cl.ps
        frame = getattr(self.cl.sim, "docking_frame", None) or default_docking_frame(
            ps, self.cl.sim.crane_tip_n[0:2], float(self.cl.sim.x[5]), float(self.cl.sim.x[2]))
        self._scene_version += 1
        self.scene = scene_info(ps, frame, self._scene_version)
        self.monitor = AlarmMonitor(AlarmLimits.for_params(ps), self.scene.n_thrusters,
                                    self.scene.tree_weight_n,
                                    uses_sensors=self.cl.settings.feedback == "ekf")
        self.trend = TrendBuffer(self.cl.dt_s)
        self.last_row = self._initial_row()
        self.tension_n: float | None = self.cl.sim.wire_tension_n()
        self.error: str | None = None
        self.notices: tuple[str, ...] = ()

    def _initial_row(self) -> FloatArray:
        """A log row for the state before the first step."""
        row = np.zeros(loop.N_LOG)
        x = self.cl.sim.x
        row[loop.L_T] = self.cl.t_s
        row[loop.L_TREE:loop.L_TREE + 6] = x[0:6]
        row[loop.L_ROV:loop.L_ROV + 6] = x[12:18]
        row[loop.L_ETA_D:loop.L_ETA_D + 3] = self.cl.target
        row[loop.L_ETA_HAT:loop.L_ETA_HAT + 3] = self.cl.eta_estimate
        row[loop.L_MODE] = self.cl.cs[loop.CS_MODE]
        return row

    def replace_run(self, run: PreparedRun) -> None:
        """Swap in a new closed loop; a recording in progress goes on in a new file (the log's
        time starts again at zero)."""
        self.close_replay()
        if self._mission_running:
            self._finish_mission("aborted")
        label = self._recording_label
        was_recording = self.recorder is not None
        if was_recording:
            self.stop_recording()
        self._install(run)
        if was_recording:
            self.start_recording(label)

    # ------------------------------------------------------------------ stepping
    @property
    def _mission_running(self) -> bool:
        return self.execution is not None and self.mission_status.state == "running"

    def advance(self, n_steps: int) -> None:
        """Advance the replay, or the live loop (and its mission), by ``n_steps`` plant steps."""
        if self.replay is not None:
            self.replay.advance(n_steps)
            return
        remaining = int(n_steps)
        while remaining > 0 and self.error is None:
            if self._mission_running and self._request_steps == 0 and not self._next_request():
                continue
            k = min(remaining, self._request_steps) if self._mission_running else remaining
            try:
                log = self.cl.run(k * self.cl.dt_s)
            except SimulationDiverged as err:
                self._diverged(str(err))
                return
            self._take_rows(log.data)
            remaining -= k
            if self._mission_running:
                self._request_rows.append(log.data)
                self._request_steps -= k
                if self._request_steps == 0:
                    self._record_request()

    def _next_request(self) -> bool:
        """Ask the mission how long to run next; False when it has ended."""
        assert self.execution is not None
        seconds = self.execution.next_request()
        if seconds is None:
            self._finish_mission("completed")
            return False
        self._request_steps = max(1, int(round(seconds / self.cl.dt_s)))
        leg = self.execution.current_leg
        status = self.mission_status
        if leg is not None and status.leg_index != self.execution.leg_index + 1:
            self.mission_status = MissionStatus(
                status.name, "running", self.execution.leg_index + 1, status.legs_total,
                leg.type, leg.name or None)
            self.note("mission", f"leg {self.execution.leg_index + 1} ({leg.type}) started",
                      {"leg": self.execution.leg_index + 1, "type": leg.type})
        return True

    def _record_request(self) -> None:
        if self._request_rows and self.execution is not None:
            data = np.vstack(self._request_rows)
            self.execution.record(LoopLog(data, self.scene.n_thrusters,
                                          self.cl.Q.counters.copy()))
        self._request_rows = []

    def _finish_mission(self, state: str) -> None:
        exe = self.execution
        if exe is None:
            return
        self._record_request()
        if state == "aborted":
            exe.abort()
        elif state == "diverged":
            exe.mark_diverged()
        self._request_steps = 0
        s = self.mission_status
        self.mission_status = MissionStatus(s.name, state, s.leg_index, s.legs_total,
                                            s.leg_type, s.leg_name)
        self._result = self._workers.submit(lambda: exe.result().summary())
        self.note("mission", f"mission {s.name} {state}", {"state": state})

    def _diverged(self, message: str) -> None:
        self.error = f"simulation diverged: {message}; reset to go on"
        if self._mission_running:
            self._finish_mission("diverged")
        self.note("error", self.error, {})

    def _follow_docking_frame(self) -> None:
        """A mission leg may place (or move) the docking frame: redraw the site then."""
        frame = getattr(self.cl.sim, "docking_frame", None)
        if frame is not None and frame is not self.scene.frame:
            self._scene_version += 1
            self.scene = replace(self.scene, frame=frame, version=self._scene_version)

    def _take_rows(self, rows: FloatArray) -> None:
        self._follow_docking_frame()
        self.last_row = rows[-1].copy()
        self.trend.extend(rows)
        self.tension_n = self.cl.sim.wire_tension_n()
        before = {a.name: a.active for a in self.monitor.state}
        for alarm in self.monitor.update(rows, self.tension_n):
            if alarm.active != before.get(alarm.name):
                self.note("alarm", f"{alarm.name} {'on' if alarm.active else 'off'}"
                          f"{': ' + alarm.message if alarm.message else ''}",
                          {"name": alarm.name, "active": alarm.active})
        if self.recorder is not None:
            self._rec_rows.append(rows)
            if sum(len(r) for r in self._rec_rows) >= RECORD_FLUSH_ROWS:
                self.flush_recording()

    # ------------------------------------------------------------------ commands
    def require_live(self, what: str) -> None:
        if self.replay is not None:
            raise ConsoleError(f"{what}: a replay is open; close it first")

    def require_no_mission(self, what: str) -> None:
        if self._mission_running:
            raise ConsoleError(f"{what}: mission {self.mission_status.name!r} is running; "
                               f"abort it first")

    def abort_mission(self) -> None:
        if not self._mission_running:
            raise ConsoleError("no mission is running")
        self._finish_mission("aborted")

    def set_current(self, speed_mps: float, direction_deg: float) -> None:
        """A steady current (no random walk) [m/s, towards deg]."""
        d = math.radians(direction_deg)
        params = envmod.CurrentParams(speed_mps=speed_mps, direction_rad=d,
                                      speed_min_mps=speed_mps, speed_max_mps=speed_mps,
                                      direction_min_rad=d, direction_max_rad=d)
        sim = self.cl.sim
        sim.current_params = params
        sim.current_state = envmod.initial_current(params)

    def move_vessel(self, north_m: float, east_m: float, speed_mps: float) -> None:
        sim = self.cl.sim
        sim.move_crane_tip(np.array([north_m, east_m, sim.crane_tip_n[2]]), speed_mps)

    # ------------------------------------------------------------------ recording
    def note(self, kind: str, text: str, data: dict) -> None:
        """An event in the recording (commands, alarms, mission progress)."""
        if self.recorder is None:
            return
        self.flush_recording()
        try:
            self.recorder.event(self.cl.t_s, kind, text, data)
        except Exception as err:
            self._recording_failed(err)

    def start_recording(self, label: str = "") -> str:
        self.require_live("record")
        if self.recorder is not None:
            raise ConsoleError(f"already recording to {self.recording_name}")
        if not LABEL.match(label):
            raise ConsoleError(f"label may hold letters, digits, '.', '_' and '-' (at most 60), "
                               f"got {label!r}")
        self.recordings_dir.mkdir(parents=True, exist_ok=True)
        stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
        base = f"{stamp}-{label or self.mission.name.replace(' ', '-')}"
        base = re.sub(r"[^A-Za-z0-9._-]", "-", base)[:100]
        name = f"{base}.mcap"
        k = 1
        while (self.recordings_dir / name).exists():
            k += 1
            name = f"{base}-{k}.mcap"
        frame = self.scene.frame
        metadata = {"params_name": self.cl.ps.name, "mission": self.mission.name,
                    "mission_toml": schema.dump_mission(self.mission), "label": label,
                    "started_utc": datetime.now(UTC).isoformat(), "start_t_s": self.cl.t_s,
                    "crane_tip_n": [float(v) for v in self.cl.sim.crane_tip_n],
                    "wire_length_m": float(self.cl.sim.wire_length_m),
                    "docking_frame": {"center_n": [float(v) for v in frame.center_n],
                                      "heading_rad": float(frame.heading_rad),
                                      "landing_depth_m": float(frame.landing_depth_m)}}
        self.recorder = SessionRecorder(self.recordings_dir / name, metadata=metadata,
                                        params=self.cl.ps, n_thrusters=self.scene.n_thrusters)
        self.recording_name = name
        self._recording_label = label
        self._rec_rows = []
        return name

    def flush_recording(self) -> None:
        if self.recorder is None or not self._rec_rows:
            return
        rows = np.vstack(self._rec_rows)
        self._rec_rows = []
        try:
            self.recorder.write_log(rows, crane_tip_n=self.cl.sim.crane_tip_n.copy(),
                                    wire_length_m=float(self.cl.sim.wire_length_m),
                                    docking=self.scene.frame)
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
    def open_replay(self, name: str, data) -> ReplayStatus:
        """Show a loaded recording (``load_replay``) instead of the live run."""
        if name == self.recording_name:
            raise ConsoleError(f"{name} is being recorded; stop the recording first")
        self.replay = _Replay(name, data, self._replay_scene(data), self.cl.dt_s)
        return self.replay.status()

    def _replay_scene(self, data) -> SceneInfo:
        """The scene of the recorded parameter set (the live one if it cannot be rebuilt)."""
        meta = getattr(data, "metadata", {}) or {}
        try:
            ps = params_mod.build(params_mod.parse_spec(meta["params"], "<recording>"))
        except (KeyError, TypeError, ValueError):
            return self.scene
        frame_meta = meta.get("docking_frame")
        if isinstance(frame_meta, dict):
            frame = DockingFrame(np.asarray(frame_meta["center_n"], float),
                                 float(frame_meta["heading_rad"]),
                                 float(frame_meta["landing_depth_m"]))
        else:
            first = np.asarray(data.rows, float)[0]
            frame = default_docking_frame(ps, first[loop.L_TREE:loop.L_TREE + 2],
                                          float(first[loop.L_TREE + 5]),
                                          float(first[loop.L_TREE + 2]))
        self._scene_version += 1
        return scene_info(ps, frame, self._scene_version)

    def close_replay(self) -> None:
        if self.replay is not None:
            self.replay = None
            self._scene_version += 1
            self.scene = replace(self.scene, version=self._scene_version)

    def require_replay(self) -> _Replay:
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
            self.mission_status = MissionStatus(s.name, s.state, s.leg_index, s.legs_total,
                                                s.leg_type, s.leg_name, result)
            self._result = None
        return self.mission_status

    def _trend(self) -> FloatArray:
        now = time.monotonic()
        if now - self._trend_wall > 0.1:
            self._trend_cache = self.trend.view()
            self._trend_wall = now
        return self._trend_cache

    def snapshot(self, seq: int, paused: bool, speed: float, stats: LoopStats) -> Snapshot:
        """The state as of now (see ``Snapshot``)."""
        if self.replay is not None:
            return self._replay_snapshot(seq, paused, speed, stats)
        cl, sim = self.cl, self.cl.sim
        v: RowView = row_view(self.last_row, self.scene.n_thrusters)
        cur = sim.current_state
        return Snapshot(
            seq=seq, source="live", t_s=v.t_s, paused=paused, speed=speed,
            tree_eta_n=v.tree_eta_n, rov_eta_n=v.rov_eta_n, eta_ref=v.eta_ref,
            eta_hat=v.eta_hat, thruster_utilisation=v.utilisation, thruster_force_n=v.force_n,
            mode=v.mode, allocation=cl.settings.allocation, grip=bool(sim.gripping),
            gains=cl.gains, crane_tip_n=tuple(float(c) for c in sim.crane_tip_n),  # type: ignore[arg-type]
            wire_length_m=float(sim.wire_length_m), wire_tension_n=self.tension_n,
            current_speed_mps=float(cur.speed_mps),
            current_direction_rad=float(cur.direction_rad),
            wire_drag_n_per_m=float(cl.ps.wire.drag_per_length(cur.speed_mps)),
            mission=self._mission_result(), alarms=self.monitor.state,
            recording=self.recording_name, replay=None, scene=self.scene, stats=stats,
            warnings=(*cl.startup.warnings, *self.notices), error=self.error,
            trend=self._trend())

    def _replay_snapshot(self, seq: int, paused: bool, speed: float,
                         stats: LoopStats) -> Snapshot:
        rp = self.replay
        assert rp is not None
        v = row_view(rp.rows[rp.index], rp.scene.n_thrusters)
        crane_tip_n, wire_length_m, tension_n = rp.site()
        return Snapshot(
            seq=seq, source="replay", t_s=v.t_s, paused=not rp.playing, speed=speed,
            tree_eta_n=v.tree_eta_n, rov_eta_n=v.rov_eta_n, eta_ref=v.eta_ref,
            eta_hat=v.eta_hat, thruster_utilisation=v.utilisation, thruster_force_n=v.force_n,
            mode=v.mode, allocation=None, grip=None, gains=None,
            crane_tip_n=crane_tip_n,  # type: ignore[arg-type]
            wire_length_m=wire_length_m, wire_tension_n=tension_n,
            current_speed_mps=0.0, current_direction_rad=0.0, wire_drag_n_per_m=0.0,
            mission=MissionStatus(name=rp.mission, state="replay"),
            alarms=rp.monitor.state, recording=self.recording_name, replay=rp.status(),
            scene=rp.scene, stats=stats, trend=rp.trend())

    def close(self) -> None:
        """Close the recording and the scoring worker (at shutdown)."""
        if self.recorder is not None:
            try:
                self.stop_recording()
            except Exception:
                self.recorder = None
        self._workers.shutdown(wait=False, cancel_futures=True)
