"""The one mission driver: advances a mission on a ``Simulation`` by a number of plant steps.

The headless runner calls ``advance()`` with no limit (one request of the mission at a time,
as fast as the machine allows); the console's loop calls ``advance(n)`` with the few steps of
one tick. Either way the executors see the same thing: each request they yield runs in full,
its rows are handed back (``MissionContext.last_log``) and the executor is resumed.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Generator

import numpy as np
from numpy.typing import NDArray

from control.columns import LOG_COLUMNS, Layout, LogRows
from control.simulation import Simulation, SimulationDiverged
from missions import schema, seaway
from missions.legs import LEG_EXECUTORS, MissionContext
from missions.scoring import SCORED_COLUMNS, LegSpan, MissionResult, score
from missions.setup import charted_frame

LEAN_COLUMNS = (*SCORED_COLUMNS, "t_s", "wire_tension")
LEAN_LAYOUT = Layout.of([c for c in LOG_COLUMNS if c.name in LEAN_COLUMNS])
"""What a lean driver's simulation logs (``Simulation.keep_log_columns``): the scored
columns, and what the legs and the wire watch read of a request's rows (the tree's pose, the
time, the wire's tension)."""


_JOINED = threading.local()
"""Per thread, the array a lean run's rows are joined into to be scored when its result keeps
no log (``MissionDriver.result(log=False)``): reused run after run, so a campaign's runs do
not each take a fresh 7 MB array for it (whose first writes cost a page fault every 4 kB)."""


def _joined_rows(parts: list[LogRows], n_thrusters: int) -> LogRows:
    """The parts' rows joined into this thread's reused array (valid until its next call)."""
    if len(parts) == 1:
        return LogRows.join(parts, n_thrusters)  # shared, not copied
    n = sum(len(p) for p in parts)
    width = parts[0].data.shape[1]
    buf: NDArray[np.float64] | None = getattr(_JOINED, "buf", None)
    if buf is None or buf.shape[0] < n or buf.shape[1] != width:
        buf = np.empty((max(n, 1), width))
        _JOINED.buf = buf
    np.concatenate([p.data for p in parts], out=buf[:n])
    return LogRows(buf[:n], n_thrusters, parts[-1].quality_counters.copy(), parts[0].layout)


class MissionDriver:
    """A mission in progress on a simulation.

    ``advance(max_steps)`` runs up to ``max_steps`` plant steps of the mission (None: to the
    end of the mission's present request) and returns their rows; ``done`` says when the
    mission is over; ``abort()`` ends it early; ``result()`` scores what was run."""

    def __init__(self, mission: schema.Mission, sim: Simulation, keep_log: bool = True) -> None:
        self.mission = mission
        self.sim = sim
        self.keep_log = keep_log
        """False: the simulation logs only the columns the scores and the legs read
        (``LEAN_LAYOUT``), not the whole log: a campaign's runs (the whole log of a 500 s
        docking is 47 MB). The figures are the same; the result's ``log`` has those columns
        only."""
        if not keep_log:
            sim.keep_log_columns(LEAN_LAYOUT)
        self.ctx = MissionContext(sim)
        self.ctx.charted_frame = charted_frame(mission)
        self.leg_index = -1
        self.parts: list[LogRows] = []
        self.rows = 0
        self.spans: list[LegSpan] = []
        self.diverged = False
        self.divergence = ""
        self.error = ""
        """Why a leg failed (its executor or the simulation refused what it asked)."""
        self.aborted = False
        self._gen: Generator[float, None, bool] | None = None
        self._leg_start = 0
        self._pending = 0
        """Steps of the present request not yet run."""
        self._request_parts: list[LogRows] = []
        self.wire_watch = (
            seaway.WireWatch(float(sim.plant_ps.tree.submerged_weight_newton))
            if sim.wire_model in ("elastic", "moordyn")
            else None
        )
        """Slack wire and snap loads (missions.seaway), with the elastic or the MoorDyn wire
        (the logged tension is MoorDyn's force on the tree then): each one is an
        event of kind ``wire``, from t = 0 (the vessel's motion ramps in, ``sim.vessel``:
        its start is no step of the crane tip)."""

    # ------------------------------------------------------------------ state
    @property
    def done(self) -> bool:
        return (
            self.leg_index >= len(self.mission.legs)
            or self.aborted
            or self.diverged
            or bool(self.error)
        )

    @property
    def current_leg(self) -> schema.Leg | None:
        if 0 <= self.leg_index < len(self.mission.legs):
            return self.mission.legs[self.leg_index]
        return None

    @property
    def events(self) -> list[dict]:
        return self.ctx.events

    # ------------------------------------------------------------------ legs
    def _start_leg(self) -> None:
        self.leg_index += 1
        self._leg_start = self.rows
        if self.leg_index < len(self.mission.legs):
            leg = self.mission.legs[self.leg_index]
            self.ctx.event(
                "leg",
                f"leg {self.leg_index + 1}/{len(self.mission.legs)}: {leg.type} {leg.name}".strip(),
                index=self.leg_index + 1,
                type=leg.type,
            )
            deadline = self.sim.t_s + leg.timeout_s
            self.ctx.leg = leg
            self.ctx.misses = []
            self._gen = LEG_EXECUTORS[leg.type](self.ctx, leg, deadline)

    def _end_leg(self, ok: bool, error: str = "") -> None:
        leg = self.current_leg
        if leg is None:
            return
        if not error and self.ctx.misses:
            error = self.ctx.misses[0]
            if len(self.ctx.misses) > 1:
                error += f" (and {len(self.ctx.misses) - 1} more targets)"
            self.ctx.event(
                "miss", f"leg {self.leg_index + 1} ({leg.type}) {error}", leg=self.leg_index + 1
            )
        self.spans.append(
            LegSpan(
                self.leg_index + 1,
                leg.type,
                leg.name,
                leg.score,
                self._leg_start,
                self.rows,
                not ok and not error,
                error,
            )
        )

    def _next_request(self) -> bool:
        """Ask the running leg how long to run next (starting legs as they end); False when
        the mission is over. A request is rounded to the nearest whole number of plant steps
        (on purpose: legs cut their waits at deadlines that need not fall on a step)."""
        if self.leg_index < 0:
            self._start_leg()
        while not self.done:
            assert self._gen is not None
            try:
                seconds = float(next(self._gen))
            except StopIteration as stop:
                self._end_leg(bool(stop.value))
                self._start_leg()
                continue
            except Exception as err:  # a leg's failure ends the mission, not its driver
                self._fail_leg(err)
                return False
            if not (math.isfinite(seconds) and seconds >= 0.0):
                self._fail_leg(ValueError(f"the leg asked to run {seconds} s"))
                return False
            self._pending = int(round(seconds / self.sim.dt_s))
            return True
        return False

    def _watch_wire(self, rows: LogRows) -> None:
        watch = self.wire_watch
        assert watch is not None
        for e in watch.feed(rows.t_s, rows["wire_tension"]):
            self.ctx.events.append(
                {
                    "t_s": round(e.t_s, 3),
                    "kind": "wire",
                    "text": e.text(watch.static_newton),
                    "data": {
                        "event": e.kind,
                        "tension_newton": e.tension_newton,
                        "duration_s": e.duration_s,
                        "static_newton": watch.static_newton,
                    },
                }
            )

    def _finish_request(self) -> None:
        """Hand the rows of the request just run to the executor (in the pieces they were
        run in: ``MissionContext.last_log`` joins them if the executor reads them)."""
        parts, self._request_parts = self._request_parts, []
        self.parts.extend(parts)
        self.ctx.hand_back(parts)
        self.rows += sum(len(p) for p in parts)

    # ------------------------------------------------------------------ stepping
    def advance(self, max_steps: int | None = None, rows: bool = True) -> LogRows:
        """Run the mission for up to ``max_steps`` plant steps (None: the rest of the present
        request). Returns the rows run (``rows=False``: none; the result has them). A
        divergence ends the mission (``diverged``, ``divergence`` says why) and returns the
        rows before it.

        A request longer than ``Simulation.long_chunk_steps`` (5 s) runs in pieces of that
        many steps, each a ``Simulation.step`` of its own (the same chunks and numbers; a run does
        not depend on how its time is cut): the rows of a long request then never need one
        array for all of them (a leg's merged polls can ask for minutes, 920 bytes a step;
        fresh arrays that size cost the kernel's writes a page fault every 4 kB)."""
        out: list[LogRows] = []
        budget = max_steps
        while not self.done and (budget is None or budget > 0):
            if self._pending == 0 and not self._next_request():
                break
            if self._pending == 0:  # a wait cut at a deadline less than half a step away
                self._finish_request()
                continue
            k = self._pending if budget is None else min(budget, self._pending)
            k = min(k, max(1, self.sim.long_chunk_steps))
            try:
                piece = self.sim.step(k)
            except SimulationDiverged as err:
                self._mark_diverged(str(err))
                break
            except ValueError as err:
                self._fail_leg(err)
                break
            if rows:
                out.append(piece)
            self._request_parts.append(piece)
            for t_s, text in self.sim.take_fault_log():
                self.ctx.events.append(
                    {"t_s": round(t_s, 3), "kind": "fault", "text": text, "data": {}}
                )
            if self.wire_watch is not None:
                self._watch_wire(piece)
            self._pending -= k
            if self._pending == 0:
                self._finish_request()
                if budget is None:
                    break
            if budget is not None:
                budget -= k
        return LogRows.join(out, self.sim.n_thrusters)

    def run_to_end(
        self,
        log: bool = True,
        *,
        record: Callable[[MissionDriver, LogRows], None] | None = None,
        progress: Callable[[MissionDriver], None] | None = None,
    ) -> MissionResult:
        """Run the mission to its end, one request at a time, and score it: the one headless
        run loop (``runner.run_mission``, a campaign's ``run_one``, ``rov-console run`` and
        ``campaign rerun``).

        ``record(driver, rows)`` gets each request's rows as soon as they are run (a
        recorder: ``driver.events`` holds the events so far); ``progress(driver)`` is called
        after each request; ``log`` as ``result``'s."""
        while not self.done:
            rows = self.advance(rows=record is not None)
            if record is not None:
                record(self, rows)
            if progress is not None:
                progress(self)
        return self.result(log)

    def _fail_leg(self, err: Exception) -> None:
        """The running leg cannot go on: it fails, the mission ends as failed, and the
        simulation is left as it is (still steppable)."""
        text = str(err) if isinstance(err, ValueError) else f"{type(err).__name__}: {err}"
        leg = self.current_leg
        where = f"leg {self.leg_index + 1} ({leg.type})" if leg is not None else "the mission"
        self.error = f"{where} failed: {text}"
        self.ctx.event("error", self.error, leg=self.leg_index + 1)
        if self._request_parts:
            self._finish_request()
        self._end_leg(False, text)
        self._pending = 0

    def _mark_diverged(self, message: str) -> None:
        if self._request_parts:
            self._finish_request()
        self._end_leg(False)
        self.diverged = True
        self.divergence = message

    def abort(self) -> None:
        """End the mission now (the running leg counts as not finished)."""
        if not self.done:
            if self._request_parts:
                self._finish_request()
            self._end_leg(False)
        self._pending = 0
        self.aborted = True

    def result(self, log: bool = True) -> MissionResult:
        """The mission's scores from the rows run so far. ``log=False``: the result keeps no
        ``log`` (a campaign's rows: it keeps only the figures), and the rows are joined for
        scoring into an array reused from one run's result to the next."""
        if not self.parts:
            layout = self.sim.log_layout
            data = LogRows(
                np.zeros((0, layout.width)), self.sim.n_thrusters, self.sim.quality_counters, layout
            )
        elif log:
            data = LogRows.join(self.parts, self.sim.n_thrusters)
        else:
            data = _joined_rows(self.parts, self.sim.n_thrusters)
        result = score(
            self.mission.name,
            data,
            self.spans,
            self.sim.dt_s,
            float(self.sim.ps.tree.dimensions_m.max()),
            self.diverged,
            list(self.sim.startup.warnings),
        )
        result.error = self.error
        if not log:
            result.log = None
        result.landings = list(self.ctx.landings)
        result.events = list(self.ctx.events)
        return result
