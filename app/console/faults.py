"""The instructor's commands: inject a fault (now or at a later simulation time) and clear them
all. The view of the faults a snapshot carries is ``app.console.snapshot.FaultView``.

Only the instructor may send these (the HTTP routes and the page's instructor panel check the
instructor token, ``Console.check_instructor``). They are logged like every command, but
marked ``instructor_only``: the operations log shown to trainees leaves them out
(``app.console.operations.trainee_view``), so a trainee sees only the fault's effects and what
the control system's own checks and alarms report. The recording keeps everything.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from app.console.commands import LoopControls
from app.console.errors import ConsoleError
from app.console.snapshot import fault_views
from control.faults import DURATION_MAX_S, FAULT_KINDS, THRUSTER_KINDS, Fault
from missions.schema import MAX_FAULTS

if TYPE_CHECKING:
    from control.simulation import Simulation

MAX_LIVE_FAULTS = MAX_FAULTS
"""Faults active or scheduled at once, at most: as many as a mission file may carry. Each
one costs every step a look (1 342 scheduled ahead took the loop's step p99 to 226 ms)."""
MAX_RUN_FAULTS = 500
"""Faults one run keeps, past ones included (the simulation checks them all each chunk);
clearing the faults or a new run starts the count again."""


def kinds_text() -> str:
    """Every kind with its unit and range, one a line (the panel's help, error messages)."""
    lines = []
    for kind, (unit, lo, hi) in FAULT_KINDS.items():
        value = "no value" if unit == "-" else f"value {lo:g} to {hi:g} {unit}"
        which = ", thruster number" if kind in THRUSTER_KINDS else ""
        lines.append(f"{kind}: {value}{which}")
    return "\n".join(lines)


@dataclass(frozen=True)
class InjectFault:
    """A fault of ``kind`` from ``start_s`` (simulation time; None: now) for ``duration_s``."""

    kind: str
    duration_s: float
    value: float = 0.0
    start_s: float | None = None
    thruster: int = 0
    direction_deg: float = 0.0
    instructor_only = True

    def __post_init__(self) -> None:
        if self.start_s is not None and not (
            isinstance(self.start_s, int | float) and math.isfinite(self.start_s)
        ):
            raise ValueError(f"start_s must be a finite number of seconds, got {self.start_s!r}")
        self.fault(0.0 if self.start_s is None else max(self.start_s, 0.0))  # ranges

    def fault(self, start_s: float) -> Fault:
        return Fault(
            self.kind, start_s, self.duration_s, self.value, self.direction_deg, self.thruster
        )

    def apply(self, loop: LoopControls) -> object:
        session = loop.session
        session.require_live("fault")
        sim = session.sim
        now = sim.t_s
        start = now if self.start_s is None else float(self.start_s)
        if start < now - 1e-9 or start > now + DURATION_MAX_S:
            raise ValueError(
                f"start_s must be in [{now:.2f}, {now + DURATION_MAX_S:.0f}] s "
                f"(now or later, in simulation time), got {start:g}"
            )
        check_room_for_a_fault(sim)
        fault = self.fault(start)
        sim.inject_fault(fault)
        session.note(
            "instructor",
            f"fault injected: {fault.describe()}",
            {
                "kind": fault.kind,
                "start_s": fault.start_s,
                "duration_s": fault.duration_s,
                "value": fault.value,
                "thruster": fault.thruster,
                "direction_deg": fault.direction_deg,
            },
        )
        return {
            "kind": fault.kind,
            "start_s": fault.start_s,
            "duration_s": fault.duration_s,
            "value": fault.value,
            "thruster": fault.thruster,
            "text": fault.describe(),
        }


def check_room_for_a_fault(sim: Simulation) -> None:
    """ConsoleError (409) with the limit when another fault would pass ``MAX_LIVE_FAULTS``
    active or scheduled, or ``MAX_RUN_FAULTS`` in this run."""
    live = len(fault_views(sim.faults, sim.t_s))
    if live >= MAX_LIVE_FAULTS:
        raise ConsoleError(
            f"{live} faults are active or scheduled, the most at once is {MAX_LIVE_FAULTS}: "
            "wait for some to end or clear them (DELETE /api/faults)"
        )
    if len(sim.faults) >= MAX_RUN_FAULTS:
        raise ConsoleError(
            f"this run has had {len(sim.faults)} faults, the most one run keeps is "
            f"{MAX_RUN_FAULTS}: clear them (DELETE /api/faults) or start a new run"
        )


@dataclass(frozen=True)
class ClearFaults:
    """End every injected fault now and drop the scheduled ones."""

    instructor_only = True

    def apply(self, loop: LoopControls) -> object:
        session = loop.session
        session.require_live("clear faults")
        n = len(fault_views(session.sim.faults, session.sim.t_s))
        if n == 0 and not session.sim.faults:
            raise ConsoleError("no fault is active or scheduled")
        session.sim.clear_faults()
        session.note("instructor", f"faults cleared ({n})", {"cleared": n})
        return {"cleared": n}
