"""Commands: typed requests that change the run, applied by the loop task between two steps
(``PacedLoop.submit``). HTTP routes and the 3D view only build these; each validates what it
carries through the simulation's own methods, and a failing command changes nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from app.console.errors import ConsoleError
from app.console.session import PreparedRun
from app.recording import SessionData
from control.config import Allocation, Gains, Mode

if TYPE_CHECKING:
    from app.console.loop import PacedLoop

SPEED_MIN, SPEED_MAX = 0.25, 50.0
"""Simulated seconds per wall-clock second the loop can run at."""


class Command(Protocol):
    """Something that changes the run, applied by the loop task between two steps."""

    def apply(self, console: PacedLoop) -> object: ...


# ---------------------------------------------------------------------- run control
@dataclass(frozen=True)
class Pause:
    def apply(self, console: PacedLoop) -> object:
        console.paused = True
        return {"paused": True}


@dataclass(frozen=True)
class Resume:
    def apply(self, console: PacedLoop) -> object:
        if console.session.error is not None:
            raise ConsoleError(console.session.error)
        console.paused = False
        return {"paused": False}


@dataclass(frozen=True)
class SetSpeed:
    speed: float

    def apply(self, console: PacedLoop) -> object:
        if not (math.isfinite(self.speed) and SPEED_MIN <= self.speed <= SPEED_MAX):
            raise ConsoleError(f"speed must be in [{SPEED_MIN}, {SPEED_MAX}], got {self.speed}")
        console.speed = float(self.speed)
        return {"speed": console.speed}


@dataclass(frozen=True)
class Step:
    """Advance a paused run by a number of plant steps."""

    steps: int = 1

    def apply(self, console: PacedLoop) -> object:
        if not console.paused:
            raise ConsoleError("step: pause the run first")
        if not 1 <= self.steps <= 10_000:
            raise ConsoleError(f"steps must be in [1, 10000], got {self.steps}")
        console.session.advance(self.steps)
        return {"t_s": console.session.sim.t_s}


@dataclass(frozen=True)
class StartRun:
    """Swap in a prepared closed loop (a mission's set-up, running its legs or not)."""

    run: PreparedRun

    def apply(self, console: PacedLoop) -> object:
        console.session.replace_run(self.run)
        console.session.note(
            "command",
            f"start {self.run.mission.name}",
            {"mission": self.run.mission.name, "legs": self.run.run_legs},
        )
        return {"mission": self.run.mission.name, "running_legs": self.run.run_legs}


@dataclass(frozen=True)
class AbortMission:
    def apply(self, console: PacedLoop) -> object:
        console.session.abort_mission()
        return {"state": "aborted"}


# ---------------------------------------------------------------------- control system
@dataclass(frozen=True)
class SetTarget:
    north_m: float
    east_m: float
    heading_deg: float

    def apply(self, console: PacedLoop) -> object:
        eng = console.session
        eng.require_live("target")
        eng.require_no_mission("target")
        eng.sim.set_target(self.north_m, self.east_m, math.radians(self.heading_deg))
        eng.note(
            "command",
            "target",
            {"north_m": self.north_m, "east_m": self.east_m, "heading_deg": self.heading_deg},
        )
        return {"target": [self.north_m, self.east_m, self.heading_deg]}


@dataclass(frozen=True)
class SetGains:
    gains: Gains

    def apply(self, console: PacedLoop) -> object:
        console.session.sim.set_gains(self.gains)
        g = self.gains
        console.session.note(
            "command", "gains", {"kp": list(g.kp), "ki": list(g.ki), "kd": list(g.kd)}
        )
        return g


@dataclass(frozen=True)
class SetMode:
    mode: Mode

    def apply(self, console: PacedLoop) -> object:
        console.session.sim.set_mode(self.mode)
        console.session.note("command", f"mode {self.mode}", {"mode": self.mode})
        return {"mode": self.mode}


@dataclass(frozen=True)
class SetGrip:
    grip: bool

    def apply(self, console: PacedLoop) -> object:
        console.session.sim.set_grip(self.grip)
        console.session.note("command", f"grip {self.grip}", {"grip": self.grip})
        return {"grip": self.grip}


@dataclass(frozen=True)
class SetAllocation:
    allocation: Allocation

    def apply(self, console: PacedLoop) -> object:
        console.session.sim.set_allocation(self.allocation)
        console.session.note(
            "command", f"allocation {self.allocation}", {"allocation": self.allocation}
        )
        return {"allocation": self.allocation}


# ---------------------------------------------------------------------- environment
@dataclass(frozen=True)
class SetCurrent:
    speed_mps: float
    direction_deg: float

    def apply(self, console: PacedLoop) -> object:
        console.session.set_current(self.speed_mps, self.direction_deg)
        console.session.note(
            "command", "current", {"speed_mps": self.speed_mps, "direction_deg": self.direction_deg}
        )
        return {"speed_mps": self.speed_mps, "direction_deg": self.direction_deg}


@dataclass(frozen=True)
class MoveVessel:
    north_m: float
    east_m: float
    speed_mps: float

    def apply(self, console: PacedLoop) -> object:
        console.session.move_vessel(self.north_m, self.east_m, self.speed_mps)
        console.session.note(
            "command",
            "vessel",
            {"north_m": self.north_m, "east_m": self.east_m, "speed_mps": self.speed_mps},
        )
        return {"north_m": self.north_m, "east_m": self.east_m}


# ---------------------------------------------------------------------- recording, replay
@dataclass(frozen=True)
class StartRecording:
    label: str = ""

    def apply(self, console: PacedLoop) -> object:
        return {"name": console.session.start_recording(self.label)}


@dataclass(frozen=True)
class StopRecording:
    def apply(self, console: PacedLoop) -> object:
        return {"name": console.session.stop_recording()}


@dataclass(frozen=True)
class OpenReplay:
    """Show a recording read with ``app.console.replay.load_replay`` (off the loop task)."""

    name: str
    data: SessionData

    def apply(self, console: PacedLoop) -> object:
        return console.session.open_replay(self.name, self.data)


@dataclass(frozen=True)
class PlayReplay:
    playing: bool

    def apply(self, console: PacedLoop) -> object:
        rp = console.session.require_replay()
        if self.playing and rp.at_end:
            rp.seek(rp.start_s)
        rp.playing = self.playing
        return rp.status()


@dataclass(frozen=True)
class SeekReplay:
    t_s: float

    def apply(self, console: PacedLoop) -> object:
        rp = console.session.require_replay()
        rp.seek(self.t_s)
        return rp.status()


@dataclass(frozen=True)
class CloseReplay:
    def apply(self, console: PacedLoop) -> object:
        console.session.require_replay()
        console.session.close_replay()
        return {"replay": None}
