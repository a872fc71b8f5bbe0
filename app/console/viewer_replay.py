"""Replays that belong to one reader (a browser in the page): a recording played back on its
own clock while the live run goes on.

``ViewerReplay`` wraps a ``Replay`` with a lock (its owner's callbacks and the view's
publisher thread both touch it) and a wall clock; ``snapshot`` turns the replayed row into a
``Snapshot`` shaped like the live one, so the same panels, scene and plots draw either.
``recording_scene`` rebuilds the scene of a recording's parameter set and docking frame.
Nothing here touches the ``Session``: opening, playing or closing a viewer's replay never
changes what the loop steps or what anyone else sees.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import replace

import numpy as np

from app.console.errors import ConsoleError
from app.console.replay import Replay
from app.console.snapshot import (
    MissionStatus,
    ReplayStatus,
    SceneInfo,
    Snapshot,
    default_docking_frame,
    row_view,
    scene_info,
)
from app.recording import SessionData, recorded_docking_frame
from control.columns import LAYOUT
from sim import params as params_mod

MAX_WALL_STEP_S = 1.0
"""Longest wall-clock gap taken in one advance (a stalled publisher does not make the replay
jump ahead by the whole stall)."""
CLOCK_TICK_S = 1e-3
"""The replay clock's unit of advance [s] (rows are shown by time, whatever their rate)."""


def recording_scene(data: SessionData, fallback: SceneInfo, version: int) -> SceneInfo:
    """The scene of a recording: its parameter set and docking frame (the frame the first row
    implies when the recording names none); ``fallback`` with the given version when the
    parameter set cannot be rebuilt from the recording."""
    meta = data.metadata or {}
    try:
        ps = params_mod.build(params_mod.parse_spec(meta["params"], "<recording>"))
    except (KeyError, TypeError, ValueError):
        return replace(fallback, version=version)
    frame = recorded_docking_frame(meta)
    in_mission = frame is not None
    if frame is None:
        first = np.asarray(data.rows, float)[0]
        tree = LAYOUT.take(first, "tree_eta_n")
        frame = default_docking_frame(ps, tree[0:2], float(tree[5]), float(tree[2]))
    return scene_info(ps, frame, version, frame_in_mission=in_mission)


def replay_snapshot(rp: Replay, live: Snapshot, speed: float | None = None) -> Snapshot:
    """What a reader of the replay sees: the replayed row, its run's scene, mission and current,
    the alarms recorded as shown then, and its trend, with the live run's sequence number,
    loop statistics, operations and recording (those belong to the console, not to the
    recording). ``speed``: the replay's own speed (the live run's when
    None)."""
    v = row_view(rp.row(), rp.scene.n_thrusters)
    crane_tip_n, wire_length_m, tension_newton = rp.site()
    return Snapshot(
        seq=live.seq,
        source="replay",
        paused=not rp.playing,
        speed=live.speed if speed is None else speed,
        t_s=rp.data.run_time_s(v.t_s),  # the run's own clock, as the console showed it
        tree_eta_n=v.tree_eta_n,
        rov_eta_n=v.rov_eta_n,
        eta_ref=v.eta_ref,
        eta_hat=v.eta_hat,
        thruster_utilisation=v.utilisation,
        thruster_force_newton=v.force_newton,
        mode=v.mode,
        allocation=None,
        grip=None,
        gains=None,
        crane_tip_n=crane_tip_n,
        wire_length_m=wire_length_m,
        wire_tension_newton=tension_newton,
        current_speed_mps=rp.current.speed_mps,
        current_direction_rad=rp.current.direction_rad,
        wire_drag_newton_per_m=0.0,
        mission=MissionStatus(name=rp.mission, state="replay"),
        alarms=rp.alarms,
        faults=rp.faults,
        recording=live.recording,
        replay=rp.status(),
        scene=rp.scene,
        stats=live.stats,
        operations=live.operations,
        trend=rp.trend(),
    )


class ViewerReplay:
    """One reader's replay: opened from a loaded recording, played on the wall clock at its
    own speed (simulated seconds per wall second; the live run's speed is the live run's
    business), paused, sought and closed by its owner alone."""

    def __init__(
        self, name: str, data: SessionData, live: Snapshot, version: int, speed: float = 1.0
    ) -> None:
        scene = recording_scene(data, live.scene, version)
        self._replay = Replay(name, data, scene, CLOCK_TICK_S)
        self._lock = threading.Lock()
        self._wall: float | None = None
        self.speed = 1.0
        self.set_speed(speed)

    def set_speed(self, speed: float) -> None:
        """Play at ``speed`` times real time from now on (its owner keeps it in the loop's
        range, ``commands.SPEED_MIN`` to ``SPEED_MAX``)."""
        if not (math.isfinite(speed) and speed > 0.0):
            raise ConsoleError(f"replay speed must be a positive number, got {speed:g}")
        self.advance(self.speed)  # the time played so far at the old speed
        with self._lock:
            self.speed = float(speed)

    @property
    def name(self) -> str:
        return self._replay.name

    def play(self, playing: bool, now: float | None = None) -> ReplayStatus:
        """Play from ``now`` (the wall clock ``advance`` is given; ``time.monotonic`` unless
        told), or pause."""
        now = time.monotonic() if now is None else now
        with self._lock:
            rp = self._replay
            if playing and rp.at_end:
                rp.seek(rp.start_s)
            rp.playing = playing
            self._wall = now if playing else None
            return rp.status()

    def seek(self, t_s: float) -> ReplayStatus:
        if not math.isfinite(t_s):
            raise ConsoleError(f"replay time must be finite, got {t_s}")
        with self._lock:
            self._replay.seek(t_s)
            return self._replay.status()

    def status(self) -> ReplayStatus:
        with self._lock:
            return self._replay.status()

    def run_time_s(self, t_s: float) -> float:
        """Recording time ``t_s`` on the clock of the run going on then, the console's."""
        return self._replay.data.run_time_s(t_s)

    def advance(self, speed: float, now: float | None = None) -> None:
        """Move the replay's clock by the wall time since the last call, times ``speed``."""
        now = time.monotonic() if now is None else now
        with self._lock:
            rp = self._replay
            if not rp.playing or self._wall is None:
                self._wall = now if rp.playing else None
                return
            wall = min(max(now - self._wall, 0.0), MAX_WALL_STEP_S)
            self._wall = now
            steps = int(round(wall * speed / rp.dt_s))
            if steps > 0:
                rp.advance(steps)
            else:  # keep the fraction for the next call
                self._wall = now - wall

    def snapshot(self, live: Snapshot) -> Snapshot:
        """The replay as of now, advanced first at its own speed."""
        self.advance(self.speed)
        with self._lock:
            return replay_snapshot(self._replay, live, self.speed)
