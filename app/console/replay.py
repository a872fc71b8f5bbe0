"""Recordings on disk and their replay in the console: names the recorder writes and the API
accepts, the list of recordings, and ``Replay``, a recorded session played back against
simulation time (read by column name, so recordings of older layouts play too).

A replay shows what the recording holds, nothing made up: each run's scene (docking frame),
mission name and current from its set-up record (``SessionData.run_at``), the current as the
recorded 'command current' events changed it, and the alarms as the recorded ``alarm`` events
say the console showed them (no alarm monitor re-run over the rows with guessed limits).
"""

from __future__ import annotations

import math
import re
import threading
import weakref
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from app.console.alarms import ALARM_NAMES, Alarm
from app.console.errors import ConsoleError
from app.console.snapshot import (
    FaultView,
    ReplayStatus,
    SceneInfo,
    fault_views,
    frame_below_tree,
    frozen_copy,
    trend_rows,
)
from app.recording import (
    SessionData,
    load_session,
    recorded_docking_frame,
    recorded_mission_name,
)
from control.columns import LAYOUT, N_LOG
from control.faults import Fault

FloatArray = NDArray[np.float64]
RECORDING_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,120}\.mcap$")
"""File names the recorder writes and the API accepts (no directories, no traversal)."""


def recording_path(directory: Path, name: str) -> Path:
    """The path of a recording by its file name; ConsoleError for anything else."""
    if not RECORDING_NAME.match(name):
        raise ConsoleError(f"recording name must match {RECORDING_NAME.pattern}, got {name!r}")
    return directory / name


_LOADED: weakref.WeakValueDictionary[tuple[str, int, int], SessionData] = (
    weakref.WeakValueDictionary()
)
_LOADING = threading.Lock()


def load_replay(directory: Path, name: str) -> SessionData:
    """Read a recording for replay (call off the loop task: it can take a while). Watching a
    replay needs no token, so one read is done at a time, and a recording some replay holds
    already is handed out again (its data is only read, never changed; keyed by the file's
    size and time of change): many viewers of one recording cost one read and one copy in
    memory, which goes when the last of them closes it."""
    path = recording_path(directory, name)
    if not path.is_file():
        raise FileNotFoundError(f"no recording named {name}")
    with _LOADING:
        st = path.stat()
        key = (str(path.resolve()), st.st_size, st.st_mtime_ns)
        data = _LOADED.get(key)
        if data is None:
            data = load_session(path)
            _LOADED[key] = data
        return data


def list_recordings(directory: Path) -> list[dict]:
    """Recordings in the directory, newest first."""
    if not directory.is_dir():
        return []
    files = [p for p in directory.glob("*.mcap") if RECORDING_NAME.match(p.name)]
    files.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    return [
        {
            "name": p.name,
            "size_bytes": p.stat().st_size,
            "modified": datetime.fromtimestamp(p.stat().st_mtime, UTC).isoformat(),
        }
        for p in files
    ]


MARK_LABELS = {"mission": "leg", "run": "run", "landing": "landing", "dock": "dock"}
"""Event kinds marked with a word on the replay's scrub bar; commands, operations and alarms
coming on get a plain tick (labels would run into each other)."""
MAX_MARKS = 60


def event_marks(events: list[dict], start_s: float, end_s: float) -> tuple[tuple[float, str], ...]:
    """Marks for the scrub bar from a recording's events: (time, label) with an empty label
    for a plain tick. Legs, new runs and landings are named; commands, operations and alarms
    that came on are ticks; the rest (alarms going off, notes) is left out."""
    marks: list[tuple[float, str]] = []
    for e in events:
        t, kind = e.get("t_s"), e.get("kind")
        if not isinstance(t, int | float) or not start_s <= t <= end_s:
            continue
        data = e.get("data") or {}
        if kind in MARK_LABELS:
            label = MARK_LABELS[kind]
            if kind == "mission" and "leg" in data:
                label = f"L{data['leg']}"
            elif kind == "mission":
                label = str(data.get("state", "mission"))
            marks.append((float(t), label))
        elif kind in ("command", "operation") or (kind == "alarm" and data.get("active", True)):
            marks.append((float(t), ""))
    return tuple(marks[:MAX_MARKS])


JUMP_TEXT_CHARS = 60
"""Characters of an event's text a jump list entry shows at most."""


def event_jumps(events: list[dict], start_s: float, end_s: float) -> tuple[tuple[float, str], ...]:
    """The events a viewer may jump to, in words: (time, text) for each mark of
    ``event_marks`` (legs, runs, landings, commands, alarms coming on), its text the event's
    own ('leg 2 (move) started', 'pause', 'saturation on: ...'): the scrub bar's dots carry
    no words, these say what each is."""
    marked = {t for t, _ in event_marks(events, start_s, end_s)}
    out: list[tuple[float, str]] = []
    for e in events:
        t = e.get("t_s")
        if isinstance(t, int | float) and float(t) in marked:
            text = " ".join(str(e.get("text") or e.get("kind") or "").split())
            if len(text) > JUMP_TEXT_CHARS:
                text = text[: JUMP_TEXT_CHARS - 3] + "..."
            out.append((float(t), text))
    return tuple(out[:MAX_MARKS])


RUN_SCENE_VERSIONS = 1 << 20
"""A later run's scene has the recording's scene version plus this times the run's index:
owners count scene versions up by one, so a run's scene never takes another scene's version
(the view redraws the site when the version changes)."""
TIME_SLACK_S = 1e-9
"""Events and run starts at the shown row's time count as come [s]."""


def run_scenes(data: SessionData, first: SceneInfo) -> tuple[SceneInfo, ...]:
    """The scene of each run of a recording (one for a file without runs): ``first`` (the
    recording's scene, of its setup record) for the first run; for a later one the same
    parameter set with that run's docking frame, or, when it places none, a frame under the
    tree where the run starts (as the console draws it)."""
    scenes = [first]
    for k, run in enumerate(data.runs[1:], start=1):
        frame = recorded_docking_frame(run)
        in_mission = frame is not None
        if frame is None:
            start = run.get("start_t_s")
            at = float(start) if isinstance(start, int | float) else math.inf
            i = int(np.searchsorted(data.t_s, at - TIME_SLACK_S))
            tree = data.log["tree_eta_n"][min(i, len(data.t_s) - 1)]
            frame = frame_below_tree(
                first.layout,
                first.tree_dimensions_m[2],
                tree[0:2],
                float(tree[5]),
                float(tree[2]),
            )
        version = first.version + k * RUN_SCENE_VERSIONS
        scenes.append(replace(first, frame=frame, frame_in_mission=in_mission, version=version))
    return tuple(scenes)


def _run_start_s(data: SessionData, index: int) -> float:
    """Where run ``index`` starts on the recording's time axis [s] (-inf for the first: it
    holds everything before the second)."""
    start = data.runs[index].get("start_t_s") if index > 0 else None
    return float(start) if isinstance(start, int | float) else -math.inf


@dataclass(frozen=True)
class RecordedCurrent:
    """The sea current of a replayed moment, as recorded."""

    speed_mps: float
    direction_rad: float
    """Direction the current flows towards [rad]."""


def recorded_current(data: SessionData, t_s: float) -> RecordedCurrent:
    """The current at recording time ``t_s``: the set-up current of the run going on then,
    changed by that run's 'command current' events up to ``t_s`` (zero when the set-up
    records none)."""
    k = data.run_index_at(t_s)
    setup = data.run_at(t_s).get("current")
    setup = setup if isinstance(setup, dict) else {}
    speed, direction_deg = setup.get("speed_mps", 0.0), setup.get("direction_deg", 0.0)
    start = _run_start_s(data, k)
    latest = -math.inf
    for e in data.events:
        t, values = e.get("t_s"), e.get("data") or {}
        if e.get("kind") != "command" or e.get("text") != "current":
            continue
        if not isinstance(t, int | float) or not start <= t <= t_s + TIME_SLACK_S or t < latest:
            continue
        latest = float(t)
        speed = values.get("speed_mps", speed)
        direction_deg = values.get("direction_deg", direction_deg)
    return RecordedCurrent(float(speed), math.radians(float(direction_deg)))


def recorded_alarms(events: list[dict], start_s: float, t_s: float) -> tuple[Alarm, ...]:
    """The alarms as the console showed them at recording time ``t_s``, from the recorded
    ``alarm`` events from ``start_s`` (the run's start: a new run starts with none) to
    ``t_s``: each alarm as its last event left it, in ``ALARM_NAMES`` order. An event's text
    is '<title> on: <message>' (``Session._take_rows``); the message is what follows."""
    last: dict[str, Alarm] = {}
    latest: dict[str, float] = {}
    for e in events:
        t, values = e.get("t_s"), e.get("data") or {}
        name = values.get("name")
        if e.get("kind") != "alarm" or name not in ALARM_NAMES or not isinstance(t, int | float):
            continue
        if not start_s <= t <= t_s + TIME_SLACK_S or t < latest.get(name, -math.inf):
            continue
        active = bool(values.get("active", False))
        message = str(e.get("text", "")).partition(": ")[2] if active else ""
        last[name], latest[name] = Alarm(name, active, message), float(t)
    return tuple(last.get(n, Alarm(n, False, "")) for n in ALARM_NAMES)


def recorded_faults(data: SessionData, t_s: float) -> tuple[FaultView, ...]:
    """The instructor's faults as the console listed them at recording time ``t_s``: those
    injected in the run going on then (the ``instructor`` events of ``InjectFault``, which
    hold the fault's kind, value, thruster and its start and duration on the run's clock) and
    not cleared since (``ClearFaults``' event), active or still to come. An event that does not
    make a fault (another tool's, or damaged) is passed over."""
    index = data.run_index_at(t_s)
    start = _run_start_s(data, index)
    faults: list[Fault] = []
    for e in data.events:
        t, values = e.get("t_s"), e.get("data") or {}
        if e.get("kind") != "instructor" or not isinstance(t, int | float):
            continue
        if not start <= t <= t_s + TIME_SLACK_S or not isinstance(values, dict):
            continue
        if "cleared" in values:
            faults.clear()
            continue
        try:
            faults.append(
                Fault(
                    str(values["kind"]),
                    float(values["start_s"]),
                    float(values["duration_s"]),
                    float(values.get("value", 0.0)),
                    float(values.get("direction_deg", 0.0)),
                    int(values.get("thruster", 0)),
                )
            )
        except (KeyError, TypeError, ValueError):
            continue
    return fault_views(faults, data.run_time_s(t_s))


class Replay:
    """A recorded session played back against simulation time (the recorder keeps rows at its
    numeric rate, e.g. 20 Hz: the replay shows the last row at or before its clock), with the
    scene, mission, current and alarms of the run going on at that row (see the module's
    docstring). ``scene``: the recording's scene (of its first run's set-up)."""

    def __init__(self, name: str, data: SessionData, scene: SceneInfo, dt_s: float) -> None:
        self.name = name
        self.data = data
        rows = np.asarray(data.rows, float)
        if rows.ndim != 2 or rows.shape[0] == 0:
            raise ConsoleError(f"recording {name} holds no log rows to replay")
        self.log = data.log
        for block in ("t_s", "tree_eta_n", "rov_eta_n", "eta_ref_n", "eta_hat_n"):
            if not self.log.layout.has(block):
                raise ConsoleError(f"recording {name} has no {block} columns to replay")
        self.times = self.log.t_s
        self.scenes = run_scenes(data, scene)
        self.dt_s = dt_s
        self.index = 0
        self.clock_s = float(self.times[0])
        self.playing = False
        self.trend_all = frozen_copy(trend_rows(self.log))
        self.marks = event_marks(data.events, float(self.times[0]), float(self.times[-1]))
        self.jumps = event_jumps(data.events, float(self.times[0]), float(self.times[-1]))
        self._shown()

    def _shown(self) -> None:
        """What goes with the present row: its run's index, current and alarms."""
        t = self.t_s
        self.run_index = self.data.run_index_at(t)
        self.current = recorded_current(self.data, t)
        start = _run_start_s(self.data, self.run_index)
        self.alarms = recorded_alarms(self.data.events, start, t)
        self.faults = recorded_faults(self.data, t)

    @property
    def scene(self) -> SceneInfo:
        """The scene of the run going on at the present row."""
        return self.scenes[min(self.run_index, len(self.scenes) - 1)]

    @property
    def mission(self) -> str:
        """The name of the mission of the run going on at the present row."""
        return recorded_mission_name(self.data.run_at(self.t_s), self.name)

    def row(self) -> FloatArray:
        """The present row, in the live layout (blocks the file lacks are NaN)."""
        out = np.full(N_LOG, np.nan)
        src = self.log.data[self.index]
        for block in self.log.layout.starts:
            out[LAYOUT.slice(block)] = src[self.log.layout.slice(block)]
        return out

    def _tension(self, index: int) -> float:
        """Wire tension recorded in that row (logs carry the site: crane tip, wire, tension)."""
        if not self.log.layout.has("wire_tension"):
            return math.nan
        return float(self.log["wire_tension"][index])

    def site(self) -> tuple[tuple[float, float, float], float, float]:
        """Crane tip (NED), wire rest length and tension at the present row."""
        if not self.log.layout.has("crane_tip_ne"):
            return (math.nan, math.nan, 0.0), math.nan, math.nan
        tip = self.log["crane_tip_ne"][self.index]
        return (
            (float(tip[0]), float(tip[1]), 0.0),
            float(self.log["wire_rest_length"][self.index]),
            self._tension(self.index),
        )

    @property
    def t_s(self) -> float:
        return float(self.times[self.index])

    @property
    def start_s(self) -> float:
        return float(self.times[0])

    @property
    def end_s(self) -> float:
        return float(self.times[-1])

    @property
    def at_end(self) -> bool:
        return self.index >= len(self.times) - 1

    def _index_at(self, t_s: float) -> int:
        k = int(np.searchsorted(self.times, t_s + 1e-9, side="right")) - 1
        return int(np.clip(k, 0, len(self.times) - 1))

    def advance(self, n_steps: int) -> None:
        """Move the replay clock by n plant steps (when playing)."""
        if not self.playing or n_steps <= 0:
            return
        self.clock_s = min(self.clock_s + n_steps * self.dt_s, self.end_s)
        new = self._index_at(self.clock_s)
        if new > self.index:
            self.index = new
            self._shown()
        if self.clock_s >= self.end_s:
            self.playing = False

    def seek(self, t_s: float) -> None:
        if not math.isfinite(t_s):
            raise ConsoleError(f"replay time must be finite, got {t_s}")
        self.clock_s = float(np.clip(t_s, self.start_s, self.end_s))
        self.index = self._index_at(self.clock_s)
        self._shown()

    def trend(self) -> FloatArray:
        k = self.index + 1
        return self.trend_all[max(0, k - 3000) : k]

    def status(self) -> ReplayStatus:
        return ReplayStatus(
            self.name,
            self.t_s,
            self.start_s,
            self.end_s,
            self.playing,
            bool(self.data.complete),
            self.marks,
            self.jumps,
        )
