"""The console's real-time loop: one asyncio task owns the ``ConsoleEngine`` and steps it
paced to the wall clock.

Pacing: the task wakes every plant step (``dt`` = 0.01 s) on an absolute schedule
``t0 + k dt`` (no drift), applies the commands that arrived since the last tick, advances the
engine by the steps owed at the present speed (0.25 to 50 plant steps per tick, a fraction
carried over between ticks), and publishes a new immutable ``Snapshot``. If it ever falls more
than ``MAX_LAG_S`` behind (the machine stalled) it re-anchors its schedule instead of running a
burst, and counts an overrun.

Commands: HTTP routes (on the event loop) and viser callbacks (on viser's threads) only
``submit`` typed commands to a thread-safe queue and wait on a future; the loop applies them
between steps. A command that fails sets its future's exception and changes nothing else:
nothing a client sends can stop the loop.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import math
import queue
import time
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

from app.console_engine import ConsoleEngine, ConsoleError, PreparedRun
from app.console_state import LoopStats, Snapshot
from control.closed_loop import Gains

SPEED_MIN, SPEED_MAX = 0.25, 50.0
"""Simulated seconds per wall-clock second the loop can run at."""
MAX_LAG_S = 0.25
"""Falling further behind than this re-anchors the schedule (an overrun)."""
MAX_COMMANDS_PER_TICK = 20
"""Commands applied in one tick at most; the rest wait for the next (bounded tick time)."""
JITTER_WINDOW = 500
"""Ticks the published jitter figures are computed over (5 s)."""
HISTORY_TICKS = 120_000
"""Ticks of lateness kept for benchmarks (20 min)."""


class Command(Protocol):
    """Something that changes the run, applied by the loop task between two steps."""

    def apply(self, console: ConsoleLoop) -> object: ...


# ---------------------------------------------------------------------- run control
@dataclass(frozen=True)
class Pause:
    def apply(self, console: ConsoleLoop) -> object:
        console.paused = True
        return {"paused": True}


@dataclass(frozen=True)
class Resume:
    def apply(self, console: ConsoleLoop) -> object:
        if console.engine.error is not None:
            raise ConsoleError(console.engine.error)
        console.paused = False
        return {"paused": False}


@dataclass(frozen=True)
class SetSpeed:
    speed: float

    def apply(self, console: ConsoleLoop) -> object:
        if not (math.isfinite(self.speed) and SPEED_MIN <= self.speed <= SPEED_MAX):
            raise ConsoleError(f"speed must be in [{SPEED_MIN}, {SPEED_MAX}], got {self.speed}")
        console.speed = float(self.speed)
        return {"speed": console.speed}


@dataclass(frozen=True)
class Step:
    """Advance a paused run by a number of plant steps."""

    steps: int = 1

    def apply(self, console: ConsoleLoop) -> object:
        if not console.paused:
            raise ConsoleError("step: pause the run first")
        if not 1 <= self.steps <= 10_000:
            raise ConsoleError(f"steps must be in [1, 10000], got {self.steps}")
        console.engine.advance(self.steps)
        return {"t_s": console.engine.cl.t_s}


@dataclass(frozen=True)
class StartRun:
    """Swap in a prepared closed loop (a mission's set-up, running its legs or not)."""

    run: PreparedRun

    def apply(self, console: ConsoleLoop) -> object:
        console.engine.replace_run(self.run)
        console.engine.note("command", f"start {self.run.mission.name}",
                            {"mission": self.run.mission.name, "legs": self.run.run_legs})
        return {"mission": self.run.mission.name, "running_legs": self.run.run_legs}


@dataclass(frozen=True)
class AbortMission:
    def apply(self, console: ConsoleLoop) -> object:
        console.engine.abort_mission()
        return {"state": "aborted"}


# ---------------------------------------------------------------------- control system
@dataclass(frozen=True)
class SetTarget:
    north_m: float
    east_m: float
    heading_deg: float

    def apply(self, console: ConsoleLoop) -> object:
        eng = console.engine
        eng.require_live("target")
        eng.require_no_mission("target")
        eng.cl.set_target(self.north_m, self.east_m, math.radians(self.heading_deg))
        eng.note("command", "target", {"north_m": self.north_m, "east_m": self.east_m,
                                       "heading_deg": self.heading_deg})
        return {"target": [self.north_m, self.east_m, self.heading_deg]}


@dataclass(frozen=True)
class SetGains:
    gains: Gains

    def apply(self, console: ConsoleLoop) -> object:
        console.engine.cl.set_gains(self.gains)
        g = self.gains
        console.engine.note("command", "gains", {"kp": list(g.kp), "ki": list(g.ki),
                                                 "kd": list(g.kd)})
        return g


@dataclass(frozen=True)
class SetMode:
    mode: Literal["tree", "free"]

    def apply(self, console: ConsoleLoop) -> object:
        console.engine.cl.set_mode(self.mode)
        console.engine.note("command", f"mode {self.mode}", {"mode": self.mode})
        return {"mode": self.mode}


@dataclass(frozen=True)
class SetGrip:
    grip: bool

    def apply(self, console: ConsoleLoop) -> object:
        console.engine.cl.set_grip(self.grip)
        console.engine.note("command", f"grip {self.grip}", {"grip": self.grip})
        return {"grip": self.grip}


@dataclass(frozen=True)
class SetAllocation:
    allocation: Literal["pinv", "priority", "qp"]

    def apply(self, console: ConsoleLoop) -> object:
        console.engine.cl.set_allocation(self.allocation)
        console.engine.note("command", f"allocation {self.allocation}",
                            {"allocation": self.allocation})
        return {"allocation": self.allocation}


# ---------------------------------------------------------------------- environment
@dataclass(frozen=True)
class SetCurrent:
    speed_mps: float
    direction_deg: float

    def apply(self, console: ConsoleLoop) -> object:
        console.engine.set_current(self.speed_mps, self.direction_deg)
        console.engine.note("command", "current", {"speed_mps": self.speed_mps,
                                                   "direction_deg": self.direction_deg})
        return {"speed_mps": self.speed_mps, "direction_deg": self.direction_deg}


@dataclass(frozen=True)
class MoveVessel:
    north_m: float
    east_m: float
    speed_mps: float

    def apply(self, console: ConsoleLoop) -> object:
        console.engine.move_vessel(self.north_m, self.east_m, self.speed_mps)
        console.engine.note("command", "vessel", {"north_m": self.north_m,
                                                  "east_m": self.east_m,
                                                  "speed_mps": self.speed_mps})
        return {"north_m": self.north_m, "east_m": self.east_m}


# ---------------------------------------------------------------------- recording, replay
@dataclass(frozen=True)
class StartRecording:
    label: str = ""

    def apply(self, console: ConsoleLoop) -> object:
        return {"name": console.engine.start_recording(self.label)}


@dataclass(frozen=True)
class StopRecording:
    def apply(self, console: ConsoleLoop) -> object:
        return {"name": console.engine.stop_recording()}


@dataclass(frozen=True)
class OpenReplay:
    """Show a recording read with ``console_engine.load_replay`` (off the loop task)."""

    name: str
    data: object

    def apply(self, console: ConsoleLoop) -> object:
        return console.engine.open_replay(self.name, self.data)


@dataclass(frozen=True)
class PlayReplay:
    playing: bool

    def apply(self, console: ConsoleLoop) -> object:
        rp = console.engine.require_replay()
        if self.playing and rp.index >= len(rp.rows) - 1:
            rp.seek(float(rp.rows[0, 0]))
        rp.playing = self.playing
        return rp.status()


@dataclass(frozen=True)
class SeekReplay:
    t_s: float

    def apply(self, console: ConsoleLoop) -> object:
        rp = console.engine.require_replay()
        rp.seek(self.t_s)
        return rp.status()


@dataclass(frozen=True)
class CloseReplay:
    def apply(self, console: ConsoleLoop) -> object:
        console.engine.require_replay()
        console.engine.close_replay()
        return {"replay": None}


# ---------------------------------------------------------------------- the loop
class ConsoleLoop:
    """Owns the engine; paces it; the only place commands are applied."""

    def __init__(self, engine: ConsoleEngine, *, speed: float = 1.0,
                 paused: bool = False) -> None:
        self.engine = engine
        self.speed = speed
        self.paused = paused
        self.period_s = engine.cl.dt_s
        self._queue: queue.SimpleQueue[tuple[Command, concurrent.futures.Future]] = \
            queue.SimpleQueue()
        self._stop = False
        self._seq = 0
        self._ticks = 0
        self._overruns = 0
        self._lateness = np.zeros(HISTORY_TICKS)
        self._work = np.zeros(JITTER_WINDOW)
        self._stats = LoopStats(self.period_s, 0.0, 0.0, 0, 0, 0.0)
        self._snapshot = engine.snapshot(0, paused, speed, self._stats)
        self.running = False

    # --------------------------------------------------------------- for readers
    @property
    def snapshot(self) -> Snapshot:
        """The latest published state (immutable)."""
        return self._snapshot

    @property
    def ticks(self) -> int:
        """Ticks run so far."""
        return self._ticks

    def lateness_s(self) -> np.ndarray:
        """Wake-up lateness of the ticks so far (up to HISTORY_TICKS, oldest first) [s]."""
        n = min(self._ticks, HISTORY_TICKS)
        if self._ticks <= HISTORY_TICKS:
            return self._lateness[:n].copy()
        i = self._ticks % HISTORY_TICKS
        return np.concatenate([self._lateness[i:], self._lateness[:i]])

    # --------------------------------------------------------------- for writers
    def submit(self, command: Command) -> concurrent.futures.Future:
        """Queue a command (from any thread); the future holds its result or its error."""
        future: concurrent.futures.Future = concurrent.futures.Future()
        self._queue.put((command, future))
        return future

    async def call(self, command: Command, timeout_s: float = 10.0) -> object:
        """Submit and wait (from a coroutine on the loop's event loop or another)."""
        return await asyncio.wait_for(asyncio.wrap_future(self.submit(command)), timeout_s)

    def call_blocking(self, command: Command, timeout_s: float = 10.0) -> object:
        """Submit and wait (from a thread, e.g. a viser callback)."""
        return self.submit(command).result(timeout=timeout_s)

    def stop(self) -> None:
        self._stop = True

    # --------------------------------------------------------------- the task
    async def run(self) -> None:
        """Step until ``stop()``; then fail the commands still queued."""
        self.running = True
        next_t = time.perf_counter()
        owed = 0.0
        try:
            while not self._stop:
                delay = next_t - time.perf_counter()
                await asyncio.sleep(delay if delay > 0 else 0)
                woke = time.perf_counter()
                self._lateness[self._ticks % HISTORY_TICKS] = woke - next_t
                self._drain()
                if self.paused:
                    owed = 0.0
                else:
                    owed += self.speed
                    n = int(owed)
                    owed -= n
                    if n:
                        self.engine.advance(n)
                if self.engine.error is not None:
                    self.paused = True
                self._work[self._ticks % JITTER_WINDOW] = time.perf_counter() - woke
                self._ticks += 1
                self._publish()
                next_t += self.period_s
                if time.perf_counter() - next_t > MAX_LAG_S:
                    next_t = time.perf_counter()
                    self._overruns += 1
                    owed = 0.0
        finally:
            self.running = False
            self._fail_pending()
            self.engine.close()

    def _drain(self) -> None:
        for _ in range(MAX_COMMANDS_PER_TICK):
            try:
                command, future = self._queue.get_nowait()
            except queue.Empty:
                return
            if not future.set_running_or_notify_cancel():
                continue
            try:
                self.engine.flush_recording()
                future.set_result(command.apply(self))
            except Exception as err:
                future.set_exception(err)

    def _fail_pending(self) -> None:
        while True:
            try:
                _, future = self._queue.get_nowait()
            except queue.Empty:
                return
            if future.set_running_or_notify_cancel():
                future.set_exception(ConsoleError("the console is shutting down"))

    def _publish(self) -> None:
        if self._ticks % 50 == 0:
            self._stats = self._compute_stats()
        self._seq += 1
        self._snapshot = self.engine.snapshot(self._seq, self.paused, self.speed, self._stats)

    def _compute_stats(self) -> LoopStats:
        n = min(self._ticks, JITTER_WINDOW)
        if n == 0:
            return self._stats
        idx = (self._ticks - 1 - np.arange(n)) % HISTORY_TICKS
        late_ms = self._lateness[idx] * 1e3
        work_ms = self._work[:min(self._ticks, JITTER_WINDOW)] * 1e3
        return LoopStats(self.period_s, float(np.median(late_ms)),
                         float(np.percentile(late_ms, 99)), self._ticks, self._overruns,
                         float(np.percentile(work_ms, 99)))
