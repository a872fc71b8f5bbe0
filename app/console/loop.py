"""The console's paced loop: one asyncio task owns the ``Session`` and steps it in time with
the wall clock.

Pacing: the task wakes every plant step (``dt`` = 0.01 s) on an absolute schedule
``t0 + k dt`` (no drift), applies the commands that arrived since the last tick, advances the
session by the steps owed at the present speed (0.25 to 50 plant steps per tick, a fraction
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
import queue
import time

import numpy as np

from app.console.commands import Command
from app.console.errors import ConsoleError
from app.console.session import Session
from app.console.snapshot import LoopStats, Snapshot

MAX_LAG_S = 0.25
"""Falling further behind than this re-anchors the schedule (an overrun)."""
MAX_COMMANDS_PER_TICK = 20
"""Commands applied in one tick at most; the rest wait for the next (bounded tick time)."""
JITTER_WINDOW = 500
"""Ticks the published jitter figures are computed over (5 s)."""
HISTORY_TICKS = 120_000
"""Ticks of lateness kept for benchmarks (20 min)."""


# ---------------------------------------------------------------------- the loop
class PacedLoop:
    """Owns the session; paces it; the only place commands are applied."""

    def __init__(self, session: Session, *, speed: float = 1.0, paused: bool = False) -> None:
        self.session = session
        self.speed = speed
        self.paused = paused
        self.period_s = session.sim.dt_s
        self._queue: queue.SimpleQueue[tuple[Command, concurrent.futures.Future]] = (
            queue.SimpleQueue()
        )
        self._stop = False
        self._seq = 0
        self._ticks = 0
        self._overruns = 0
        self._lateness = np.zeros(HISTORY_TICKS)
        self._work = np.zeros(JITTER_WINDOW)
        self._stats = LoopStats(self.period_s, 0.0, 0.0, 0, 0, 0.0)
        self._snapshot = session.snapshot(0, paused, speed, self._stats)
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
                        self.session.advance(n)
                if self.session.error is not None:
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
            self.session.close()

    def _drain(self) -> None:
        for _ in range(MAX_COMMANDS_PER_TICK):
            try:
                command, future = self._queue.get_nowait()
            except queue.Empty:
                return
            if not future.set_running_or_notify_cancel():
                continue
            try:
                self.session.flush_recording()
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
        self._snapshot = self.session.snapshot(self._seq, self.paused, self.speed, self._stats)

    def _compute_stats(self) -> LoopStats:
        n = min(self._ticks, JITTER_WINDOW)
        if n == 0:
            return self._stats
        idx = (self._ticks - 1 - np.arange(n)) % HISTORY_TICKS
        late_ms = self._lateness[idx] * 1e3
        work_ms = self._work[: min(self._ticks, JITTER_WINDOW)] * 1e3
        return LoopStats(
            self.period_s,
            float(np.median(late_ms)),
            float(np.percentile(late_ms, 99)),
            self._ticks,
            self._overruns,
            float(np.percentile(work_ms, 99)),
        )
