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
import collections
import concurrent.futures
import queue
import time

import numpy as np

from app.console.commands import Command
from app.console.errors import ConsoleError
from app.console.operations import ACTOR, Operation, OperationsLog, describe
from app.console.session import Session
from app.console.snapshot import LoopStats, Snapshot

MAX_LAG_S = 0.25
"""Falling further behind than this re-anchors the schedule (an overrun)."""
FINE_WAIT_S = 0.002
"""The last part of each wait before a tick, slept precisely rather than on the event loop's
millisecond timers (measured: median wake-up 1.0 ms late on asyncio's sleep alone)."""

STEP_CHUNK = 50
"""Plant steps of a Step command run in one tick at most (the work of one tick at 50x)."""
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
        self._queue: queue.SimpleQueue[tuple[Command, concurrent.futures.Future, str]] = (
            queue.SimpleQueue()
        )
        self.operations = OperationsLog()
        self._operations: tuple[Operation, ...] = ()
        self._stop = False
        self._seq = 0
        self._ticks = 0
        self._overruns = 0
        self._lateness = np.zeros(HISTORY_TICKS)
        self._work = np.zeros(JITTER_WINDOW)
        self._stats = LoopStats(self.period_s, 0.0, 0.0, 0, 0, 0.0)
        self._snapshot = session.snapshot(0, paused, speed, self._stats)
        self.running = False
        self.faults = 0
        """Errors the loop caught and survived (a step or a publication that failed)."""
        self.last_fault = ""
        self.last_tick_wall = time.monotonic()
        """Wall-clock time (monotonic) of the last tick: a loop that stops ticking is stale."""
        self._stepping: collections.deque[tuple[int, concurrent.futures.Future]] = (
            collections.deque()
        )
        """Step commands in progress: (steps still to run, the command's future)."""
        self._answers: list[tuple[concurrent.futures.Future, object, BaseException | None]] = []
        """This tick's answers to commands (future, result, error), given once the tick's
        snapshot is published: a client that reads the state after its command's answer
        sees the command's effect (``_answer``)."""

    # --------------------------------------------------------------- for readers
    @property
    def snapshot(self) -> Snapshot:
        """The latest published state (immutable)."""
        return self._snapshot

    def health(self, stale_after_s: float = 2.0) -> str:
        """'ok' while the task ticks; 'stopped' when it has ended; 'stalled' when it has not
        ticked for ``stale_after_s`` of wall time."""
        if not self.running:
            return "stopped"
        if time.monotonic() - self.last_tick_wall > stale_after_s:
            return "stalled"
        return "ok"

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
    def submit(self, command: Command, who: str | None = None) -> concurrent.futures.Future:
        """Queue a command (from any thread); the future holds its result or its error.
        ``who`` sent it (default: the context's ``operations.ACTOR``): the operations log
        names them."""
        future: concurrent.futures.Future = concurrent.futures.Future()
        self._queue.put((command, future, who or ACTOR.get()))
        return future

    async def call(self, command: Command, timeout_s: float = 10.0) -> object:
        """Submit and wait (from a coroutine on the loop's event loop or another)."""
        return await asyncio.wait_for(asyncio.wrap_future(self.submit(command)), timeout_s)

    def call_blocking(
        self, command: Command, timeout_s: float = 10.0, who: str | None = None
    ) -> object:
        """Submit and wait (from a thread, e.g. a viser callback)."""
        return self.submit(command, who).result(timeout=timeout_s)

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
                # the event loop's timers wake up to a millisecond late (epoll's timeout is
                # whole milliseconds): sleep on it to FINE_WAIT_S before the tick, then the
                # rest in a precise blocking sleep (the server runs this loop on its own thread
                # and event loop, so nothing else waits meanwhile)
                await asyncio.sleep(delay - FINE_WAIT_S if delay > FINE_WAIT_S else 0)
                rest = next_t - time.perf_counter()
                if rest > 0:
                    time.sleep(rest)
                woke = time.perf_counter()
                self._lateness[self._ticks % HISTORY_TICKS] = woke - next_t
                self._drain()
                if self.paused:
                    owed = 0.0
                    self._run_queued_steps()
                else:
                    owed += self.speed
                    n = int(owed)
                    owed -= n
                    if n:
                        self._advance(n)
                if self.session.error is not None:
                    self.paused = True
                self._work[self._ticks % JITTER_WINDOW] = time.perf_counter() - woke
                self._ticks += 1
                self.last_tick_wall = time.monotonic()
                self._publish_safely()
                self._answer()
                next_t += self.period_s
                if time.perf_counter() - next_t > MAX_LAG_S:
                    next_t = time.perf_counter()
                    self._overruns += 1
                    owed = 0.0
        finally:
            self.running = False
            self._answer()
            self._fail_pending()
            self.session.close()

    def step_later(self, steps: int) -> concurrent.futures.Future:
        """Queue ``steps`` plant steps of a paused run; the returned future resolves to
        {"t_s": ...} once they have run (the loop runs STEP_CHUNK a tick)."""
        future: concurrent.futures.Future = concurrent.futures.Future()
        future.set_running_or_notify_cancel()
        self._stepping.append((steps, future))
        return future

    def _run_queued_steps(self) -> None:
        if not self._stepping:
            return
        left, future = self._stepping[0]
        k = min(left, STEP_CHUNK)
        self._advance(k)
        left -= k
        if left > 0 and self.session.error is None:
            self._stepping[0] = (left, future)
            return
        self._stepping.popleft()
        if self.session.error is not None:
            self._answers.append((future, None, ConsoleError(self.session.error)))
        else:
            self._answers.append((future, {"t_s": self.session.sim.t_s}, None))

    def cancel_steps(self, why: str) -> None:
        while self._stepping:
            _, future = self._stepping.popleft()
            future.set_exception(ConsoleError(why))

    def _advance(self, n: int) -> None:
        """Step the session; whatever goes wrong in a step pauses the run with the reason
        shown, and the loop goes on answering commands (nothing may end the task)."""
        try:
            self.session.advance(n)
        except Exception as err:
            self.session.fail(f"{type(err).__name__}: {err}")
            self.faults += 1

    def _publish_safely(self) -> None:
        try:
            self._publish()
        except Exception as err:
            self.faults += 1
            self.last_fault = f"publishing the state failed: {type(err).__name__}: {err}"

    def _drain(self) -> None:
        for _ in range(MAX_COMMANDS_PER_TICK):
            try:
                command, future, who = self._queue.get_nowait()
            except queue.Empty:
                return
            if not future.set_running_or_notify_cancel():
                continue
            action = describe(command)
            instructor = bool(getattr(command, "instructor_only", False))
            notes_before = self.session.notes_written
            self.session.actor = who
            try:
                self.session.flush_recording()
                result = command.apply(self)
                if isinstance(result, concurrent.futures.Future):
                    _chain(result, future)
                else:
                    self._answers.append((future, result, None))
            except Exception as err:
                self._answers.append((future, None, err))
                if not getattr(command, "quiet", False):  # e.g. the pilot's stick, 20 a second
                    self._log_operation(who, action, f"refused: {err}", False, instructor)
            else:
                noted = self.session.notes_written > notes_before
                if not getattr(command, "quiet", False):
                    self._log_operation(who, action, "done", noted, instructor)
            finally:
                self.session.actor = None

    def _answer(self) -> None:
        """Resolve the futures of the commands this tick applied (after its publication)."""
        answers, self._answers = self._answers, []
        for future, result, err in answers:
            if err is not None:
                future.set_exception(err)
            else:
                future.set_result(result)

    def _log_operation(
        self, who: str, action: str, outcome: str, noted: bool, instructor: bool = False
    ) -> None:
        """Into the operations log (an instructor's command marked as such); and into the
        recording unless the command wrote its own event (which then names ``who``)."""
        entry = self.operations.add(self.session.sim.t_s, who, action, outcome, instructor)
        self._operations = self.operations.latest()
        if not noted:
            data: dict[str, object] = {
                "who": who,
                "action": action,
                "outcome": outcome,
                "utc": entry.utc,
            }
            if instructor:
                data["instructor"] = True
            self.session.note("operation", f"{who}: {action} ({outcome})", data)

    def _fail_pending(self) -> None:
        self.cancel_steps("the console is shutting down")
        while True:
            try:
                _, future, _ = self._queue.get_nowait()
            except queue.Empty:
                return
            if future.set_running_or_notify_cancel():
                future.set_exception(ConsoleError("the console is shutting down"))

    def _publish(self) -> None:
        if self._ticks % 50 == 0:
            self._stats = self._compute_stats()
        self._seq += 1
        self._snapshot = self.session.snapshot(
            self._seq, self.paused, self.speed, self._stats, self._operations
        )

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


def _chain(inner: concurrent.futures.Future, outer: concurrent.futures.Future) -> None:
    """Resolve ``outer`` with ``inner``'s result or error when it is done."""

    def done(f: concurrent.futures.Future) -> None:
        err = f.exception()
        if err is not None:
            outer.set_exception(err)
        else:
            outer.set_result(f.result())

    inner.add_done_callback(done)
