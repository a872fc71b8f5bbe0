"""Recordings on disk and their replay in the console: names the recorder writes and the API
accepts, the list of recordings, and ``Replay``, a recorded session played back against
simulation time (read by column name, so recordings of older layouts play too).
"""

from __future__ import annotations

import math
import re
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from app.console.alarms import AlarmLimits, AlarmMonitor
from app.console.errors import ConsoleError
from app.console.snapshot import ReplayStatus, SceneInfo, frozen_copy, trend_rows
from app.recording import SessionData, load_session, recorded_mission_name
from control.columns import LAYOUT, N_LOG, LogRows

FloatArray = NDArray[np.float64]
RECORDING_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,120}\.mcap$")
"""File names the recorder writes and the API accepts (no directories, no traversal)."""


def recording_path(directory: Path, name: str) -> Path:
    """The path of a recording by its file name; ConsoleError for anything else."""
    if not RECORDING_NAME.match(name):
        raise ConsoleError(f"recording name must match {RECORDING_NAME.pattern}, got {name!r}")
    return directory / name


def load_replay(directory: Path, name: str) -> SessionData:
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


class Replay:
    """A recorded session played back against simulation time (the recorder keeps rows at its
    numeric rate, e.g. 20 Hz: the replay shows the last row at or before its clock)."""

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
        self.scene = scene
        self.dt_s = dt_s
        self.index = 0
        self.clock_s = float(self.times[0])
        self.playing = False
        self.trend_all = frozen_copy(trend_rows(self.log))
        self.mission = recorded_mission_name(data.metadata or {}, name)
        self.marks = event_marks(data.events, float(self.times[0]), float(self.times[-1]))
        self.monitor = self._new_monitor()
        self.monitor.update(self._rows(0, 1), self._tension(0))

    def _rows(self, start: int, stop: int) -> LogRows:
        return LogRows(self.log.data[start:stop], self.log.n_thrusters, layout=self.log.layout)

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

    def _new_monitor(self) -> AlarmMonitor:
        limits = AlarmLimits(
            position_error_m=self.scene.layout.tolerance_m, sample_period_s=(1.0,) * 5
        )
        return AlarmMonitor(
            limits,
            self.scene.n_thrusters,
            self.scene.tree_weight_newton,
            uses_sensors=self.log.layout.has("accepted")
            and bool(np.any(self.log["accepted"] > 0.5)),
            support_depth_m=self.scene.support_depth_m,
            tree_half_height_m=self.scene.tree_dimensions_m[2] / 2.0,
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
            self.monitor.update(self._rows(self.index + 1, new + 1), self._tension(new))
            self.index = new
        if self.clock_s >= self.end_s:
            self.playing = False

    def seek(self, t_s: float) -> None:
        if not math.isfinite(t_s):
            raise ConsoleError(f"replay time must be finite, got {t_s}")
        self.clock_s = float(np.clip(t_s, self.start_s, self.end_s))
        self.index = self._index_at(self.clock_s)
        self.monitor = self._new_monitor()
        first = int(np.searchsorted(self.times, self.clock_s - 10.0))
        self.monitor.update(self._rows(first, self.index + 1), self._tension(self.index))

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
        )
