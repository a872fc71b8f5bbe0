"""Commands: typed requests that change the run, applied by the loop task between two steps
(``PacedLoop.submit``). HTTP routes and the 3D view only build these; each validates what it
carries through the simulation's own methods, and a failing command changes nothing.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from concurrent.futures import Future
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np

from app.console.errors import ConsoleError
from app.console.session import PreparedRun, Session
from app.recording import SessionData
from app.recording.notes import NOTE_KIND, note_author, note_text
from control.config import Allocation, Gains, Mode
from control.simulation import WINCH_RATE_MAX_MPS, WIRE_LENGTH_RANGE_M, Simulation
from missions.assist import VESSEL_SPEED_MPS

SPEED_MIN, SPEED_MAX = 0.25, 50.0
"""Simulated seconds per wall-clock second the loop can run at."""
STEPS_MAX = 1000
"""Plant steps one Step command may run (10 s simulated; bounded work per request)."""
TARGET_RANGE_M = 10_000.0
"""Targets north and east within +-this of the origin [m]."""
HEADING_RANGE_DEG = 3600.0
"""Heading targets within +-this [deg] (ten turns)."""
CURRENT_MAX_MPS = 3.0
"""Strongest current the console sets [m/s] (well beyond the ROV's capacity)."""
DIRECTION_RANGE_DEG = 360.0
VESSEL_RANGE_M = 1000.0
"""Crane tip north and east within +-this [m]."""
VESSEL_SPEED_MAX_MPS = 5.0
REPLAY_T_MAX_S = 1.0e7
GAIN_BAND_FACTOR = 4.0
"""The console sets each controller gain within 0 to this many times the parameter set's gain:
a band wide enough to tune by hand (the thesis's own tuning moved gains by about 2x) that keeps
an operator's typing slip (99 999 for 9 999) from reaching the thrusters. Mission files set
gains through their own legs, bounded by the schema."""
AXIS_NAMES = ("surge", "sway", "yaw")


def gain_band(preset: float) -> float:
    """Largest gain the console sets for a term whose parameter-set value is ``preset``."""
    return GAIN_BAND_FACTOR * preset if preset > 0.0 else 1.0


def check_gain_band(gains: Gains | Mapping[str, Sequence[float]], preset: Gains) -> None:
    """ValueError naming the first gain outside its band (see ``GAIN_BAND_FACTOR``);
    ``gains``: a Gains or {term: (surge, sway, yaw)}."""
    for term in ("kp", "ki", "kd"):
        values = getattr(gains, term) if isinstance(gains, Gains) else gains[term]
        for axis, value, ref in zip(AXIS_NAMES, values, getattr(preset, term), strict=True):
            number(f"gain {term} {axis}", value, 0.0, gain_band(ref))


def number(
    name: str, value: object, lo: float, hi: float, unit: str = "", lo_open: bool = False
) -> float:
    """``value`` as a float, or ValueError naming the field and its range: booleans and text
    are refused (not coerced), NaN and infinities are 'must be finite'."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a number, got {type(value).__name__}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    if v < lo or v > hi or (lo_open and v == lo):
        bracket = "(" if lo_open else "["
        raise ValueError(
            f"{name} must be in {bracket}{lo:g}, {hi:g}]{' ' + unit if unit else ''}, got {v:g}"
        )
    return v


class LoopControls(Protocol):
    """What a command may change: the session, the pause and speed of the loop that steps it,
    and the steps queued while paused. ``app.console.loop.PacedLoop`` is the one loop; the
    commands know it only by this (the loop imports them, not they the loop)."""

    session: Session
    paused: bool
    speed: float

    def step_later(self, steps: int) -> Future: ...

    def cancel_steps(self, why: str) -> None: ...


class Command(Protocol):
    """Something that changes the run, applied by the loop task between two steps."""

    def apply(self, loop: LoopControls) -> object: ...


# ---------------------------------------------------------------------- run control
@dataclass(frozen=True)
class Pause:
    def apply(self, loop: LoopControls) -> object:
        loop.paused = True
        return {"paused": True}


@dataclass(frozen=True)
class Resume:
    def apply(self, loop: LoopControls) -> object:
        if loop.session.error is not None:
            raise ConsoleError(loop.session.error)
        loop.paused = False
        loop.cancel_steps("step: the run was resumed")
        return {"paused": False}


@dataclass(frozen=True)
class SetSpeed:
    speed: float

    def __post_init__(self) -> None:
        number("speed", self.speed, SPEED_MIN, SPEED_MAX)

    def apply(self, loop: LoopControls) -> object:
        loop.speed = number("speed", self.speed, SPEED_MIN, SPEED_MAX)
        return {"speed": loop.speed}


@dataclass(frozen=True)
class Step:
    """Advance a paused run by a number of plant steps. The loop runs them over the next ticks
    (at most ``STEP_CHUNK`` a tick, so the server keeps answering) and the command's result,
    the simulation time reached, comes when they are done."""

    steps: int = 1

    def __post_init__(self) -> None:
        if isinstance(self.steps, bool) or not isinstance(self.steps, int):
            raise ValueError(f"steps must be a whole number, got {type(self.steps).__name__}")
        if not 1 <= self.steps <= STEPS_MAX:
            raise ValueError(f"steps must be in [1, {STEPS_MAX}], got {self.steps}")

    def apply(self, loop: LoopControls) -> object:
        if not loop.paused:
            raise ConsoleError("step: pause the run first")
        return loop.step_later(self.steps)


@dataclass(frozen=True)
class StartRun:
    """Swap in a prepared closed loop (a mission's set-up, running its legs or not)."""

    run: PreparedRun

    def apply(self, loop: LoopControls) -> object:
        stopped_by_error = loop.session.error is not None
        loop.session.replace_run(self.run)
        if stopped_by_error:  # the run had stopped itself; a fresh one runs again
            loop.paused = False
        loop.session.note(
            "command",
            f"start {self.run.mission.name}",
            {"mission": self.run.mission.name, "legs": self.run.run_legs},
        )
        return {"mission": self.run.mission.name, "running_legs": self.run.run_legs}


@dataclass(frozen=True)
class AbortMission:
    def apply(self, loop: LoopControls) -> object:
        loop.session.abort_mission()
        return {"state": "aborted"}


# ---------------------------------------------------------------------- control system
@dataclass(frozen=True)
class SetTarget:
    north_m: float
    east_m: float
    heading_deg: float

    def __post_init__(self) -> None:
        number("north_m", self.north_m, -TARGET_RANGE_M, TARGET_RANGE_M, "m")
        number("east_m", self.east_m, -TARGET_RANGE_M, TARGET_RANGE_M, "m")
        number("heading_deg", self.heading_deg, -HEADING_RANGE_DEG, HEADING_RANGE_DEG, "deg")

    def apply(self, loop: LoopControls) -> object:
        eng = loop.session
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

    def apply(self, loop: LoopControls) -> object:
        sim = loop.session.sim
        check_gain_band(self.gains, Gains.of(sim.ps.gains.kp, sim.ps.gains.ki, sim.ps.gains.kd))
        sim.set_gains(self.gains)
        g = self.gains
        loop.session.note(
            "command", "gains", {"kp": list(g.kp), "ki": list(g.ki), "kd": list(g.kd)}
        )
        return g


@dataclass(frozen=True)
class SetMode:
    mode: Mode

    def apply(self, loop: LoopControls) -> object:
        loop.session.sim.set_mode(self.mode)
        loop.session.note("command", f"mode {self.mode}", {"mode": self.mode})
        return {"mode": self.mode}


@dataclass(frozen=True)
class SetGrip:
    grip: bool

    def __post_init__(self) -> None:
        if not isinstance(self.grip, bool):
            raise ValueError(f"grip must be true or false, got {type(self.grip).__name__}")

    def apply(self, loop: LoopControls) -> object:
        loop.session.sim.set_grip(self.grip)
        loop.session.note("command", f"grip {self.grip}", {"grip": self.grip})
        return {"grip": self.grip}


@dataclass(frozen=True)
class SetAllocation:
    allocation: Allocation

    def apply(self, loop: LoopControls) -> object:
        loop.session.sim.set_allocation(self.allocation)
        loop.session.note(
            "command", f"allocation {self.allocation}", {"allocation": self.allocation}
        )
        return {"allocation": self.allocation}


# ---------------------------------------------------------------------- environment
@dataclass(frozen=True)
class SetCurrent:
    speed_mps: float
    direction_deg: float

    def __post_init__(self) -> None:
        number("speed_mps", self.speed_mps, 0.0, CURRENT_MAX_MPS, "m/s")
        number(
            "direction_deg", self.direction_deg, -DIRECTION_RANGE_DEG, DIRECTION_RANGE_DEG, "deg"
        )

    def apply(self, loop: LoopControls) -> object:
        loop.session.set_current(self.speed_mps, self.direction_deg)
        loop.session.note(
            "command", "current", {"speed_mps": self.speed_mps, "direction_deg": self.direction_deg}
        )
        return {"speed_mps": self.speed_mps, "direction_deg": self.direction_deg}


@dataclass(frozen=True)
class MoveVessel:
    north_m: float
    east_m: float
    speed_mps: float

    def __post_init__(self) -> None:
        number("north_m", self.north_m, -VESSEL_RANGE_M, VESSEL_RANGE_M, "m")
        number("east_m", self.east_m, -VESSEL_RANGE_M, VESSEL_RANGE_M, "m")
        number("speed_mps", self.speed_mps, 0.0, VESSEL_SPEED_MAX_MPS, "m/s", lo_open=True)

    def apply(self, loop: LoopControls) -> object:
        loop.session.move_vessel(self.north_m, self.east_m, self.speed_mps)
        loop.session.note(
            "command",
            "vessel",
            {"north_m": self.north_m, "east_m": self.east_m, "speed_mps": self.speed_mps},
        )
        return {"north_m": self.north_m, "east_m": self.east_m}


@dataclass(frozen=True)
class ApplyVesselAdvice:
    """Follow the running dock leg's advice to move the vessel (``vessel = "advise"``): a
    ``MoveVessel`` to the advised crane tip at the speed the leg's "auto" moves the vessel,
    ``missions.assist.VESSEL_SPEED_MPS``. Refused (ConsoleError) when there is no advice to
    apply, or it is applied already."""

    def apply(self, loop: LoopControls) -> object:
        advice = loop.session.vessel_advice_to_apply()
        north, east = advice.crane_tip_ne_m
        MoveVessel(north, east, VESSEL_SPEED_MPS).apply(loop)
        return {
            "north_m": north,
            "east_m": east,
            "speed_mps": VESSEL_SPEED_MPS,
            "advice": advice.text,
            "advice_t_s": advice.t_s,
        }


# ---------------------------------------------------------------------- the winch station
WINCH_SPEED_MAX_MPS = WINCH_RATE_MAX_MPS
"""Fastest the winch station pays out or hauls in [m/s]: the simulation's winch limit."""
WINCH_DISTANCE_MAX_M = 1000.0
"""Longest one pay-out or haul-in the station asks for [m] (none given: until stopped)."""


def winch_state(sim: Simulation) -> dict[str, object]:
    """What a winch command answers: the payout, where the winch is going and how fast."""
    return {
        "payout_m": float(sim.wire_length_m),
        "target_m": sim.winch_target_m,
        "rate_mps": sim.winch_rate_mps,
        "moving": not sim.winch_idle,
        "heave_compensation": sim.heave_compensation,
    }


@dataclass(frozen=True)
class _WinchRun:
    """Run the winch at ``speed_mps`` for ``distance_m`` (None: until stopped, or until the
    wire's end of travel, ``WIRE_LENGTH_RANGE_M``). Not while a mission runs its legs (its
    dock legs drive the winch): abort it first."""

    speed_mps: float
    distance_m: float | None = None
    direction: ClassVar[float] = 1.0
    """+1 pays out (the tree goes down), -1 hauls in."""

    def __post_init__(self) -> None:
        number("speed_mps", self.speed_mps, 0.0, WINCH_SPEED_MAX_MPS, "m/s", lo_open=True)
        if self.distance_m is not None:
            number("distance_m", self.distance_m, 0.0, WINCH_DISTANCE_MAX_M, "m", lo_open=True)

    def apply(self, loop: LoopControls) -> object:
        eng = loop.session
        eng.require_no_mission("winch")
        sim = eng.sim
        lo, hi = WIRE_LENGTH_RANGE_M
        now = float(sim.wire_length_m)
        far = math.inf if self.distance_m is None else self.distance_m
        target = min(max(now + self.direction * far, lo), hi)
        if abs(target - now) < 1e-6:
            end = "paid out to its end" if self.direction > 0 else "hauled in to its end"
            raise ConsoleError(f"winch: the wire is {end} ({target:g} m of [{lo:g}, {hi:g}] m)")
        sim.winch_to(target, self.speed_mps)
        eng.note("command", describe_winch(self), {"target_m": target, "speed_mps": self.speed_mps})
        return winch_state(sim)


def describe_winch(command: _WinchRun) -> str:
    way = "pay out" if command.direction > 0 else "haul in"
    far = "until stopped" if command.distance_m is None else f"{command.distance_m:g} m"
    return f"winch {way} {far} at {command.speed_mps:g} m/s"


@dataclass(frozen=True)
class WinchPayOut(_WinchRun):
    """Pay out: the tree goes down."""

    direction: ClassVar[float] = 1.0


@dataclass(frozen=True)
class WinchHaulIn(_WinchRun):
    """Haul in: the tree comes up."""

    direction: ClassVar[float] = -1.0


@dataclass(frozen=True)
class WinchStop:
    """Stop the winch where it is. Allowed while a mission runs (the all-stop is always the
    winch operator's); a dock leg waiting for its payout then waits until its timeout."""

    def apply(self, loop: LoopControls) -> object:
        eng = loop.session
        sim = eng.sim
        sim.winch_to(float(sim.wire_length_m), sim.winch_rate_mps or WINCH_SPEED_MAX_MPS)
        eng.note("command", "winch stop", {"payout_m": float(sim.wire_length_m)})
        return winch_state(sim)


@dataclass(frozen=True)
class HeaveCompensation:
    """The crane's active heave compensation on or off (``Simulation.set_heave_compensation``;
    refused when the crane tip does not heave in this run)."""

    on: bool

    def __post_init__(self) -> None:
        if not isinstance(self.on, bool):
            raise ValueError("heave compensation 'on' must be true or false")

    def summary(self) -> str:
        """The operations log's words ('heave compensation on', not 'on on')."""
        return f"heave compensation {'on' if self.on else 'off'}"

    def apply(self, loop: LoopControls) -> object:
        eng = loop.session
        eng.sim.set_heave_compensation(self.on)
        eng.note("command", self.summary(), {"on": self.on})
        return winch_state(eng.sim)


# ---------------------------------------------------------------------- recording, replay
@dataclass(frozen=True)
class StartRecording:
    label: str = ""

    def apply(self, loop: LoopControls) -> object:
        return {"name": loop.session.start_recording(self.label)}


@dataclass(frozen=True)
class StopRecording:
    def apply(self, loop: LoopControls) -> object:
        return {"name": loop.session.stop_recording()}


@dataclass(frozen=True)
class OpenReplay:
    """Show a recording read with ``app.console.replay.load_replay`` (off the loop task)."""

    name: str
    data: SessionData

    def apply(self, loop: LoopControls) -> object:
        return loop.session.open_replay(self.name, self.data)


@dataclass(frozen=True)
class PlayReplay:
    playing: bool

    def apply(self, loop: LoopControls) -> object:
        rp = loop.session.require_replay()
        if self.playing and rp.at_end:
            rp.seek(rp.start_s)
        rp.playing = self.playing
        return rp.status()


@dataclass(frozen=True)
class SeekReplay:
    t_s: float

    def __post_init__(self) -> None:
        number("t_s", self.t_s, 0.0, REPLAY_T_MAX_S, "s")

    def apply(self, loop: LoopControls) -> object:
        rp = loop.session.require_replay()
        rp.seek(self.t_s)
        return rp.status()


@dataclass(frozen=True)
class CloseReplay:
    def apply(self, loop: LoopControls) -> object:
        loop.session.require_replay()
        loop.session.close_replay()
        return {"replay": None}


@dataclass(frozen=True)
class AddNote:
    """A note at the present time of the live run: an event of kind ``note`` in the
    recording (when one is being made), on the live feed's ``/events`` and in the operations
    log, with its author (the sender's name when none is given)."""

    text: str
    author: str = ""

    def __post_init__(self) -> None:
        note_text(self.text)
        if self.author:
            note_author(self.author)

    def apply(self, loop: LoopControls) -> object:
        session = loop.session
        author = note_author(self.author) if self.author else (session.actor or "operator")
        session.note(NOTE_KIND, note_text(self.text), {"author": author})
        return {"t_s": session.sim.t_s, "author": author, "recording": session.recording_name}
