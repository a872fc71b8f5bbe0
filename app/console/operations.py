"""The operations log: who did what to the run, when, and whether it was done.

Every command the loop applies is logged with its sender ("viewer 3 (Anna)" for a browser,
"API 127.0.0.1" for an HTTP client) and its outcome. The page shows the latest entries to
everyone watching, and the session writes each one into the recording's events, so a review of
a trial can tell whose pause stopped the run.
"""

from __future__ import annotations

import contextvars
import dataclasses
import re
from collections import deque
from dataclasses import dataclass
from datetime import UTC, datetime

ACTOR: contextvars.ContextVar[str] = contextvars.ContextVar("console_actor", default="console")
"""Who is sending commands in this context (set per HTTP request by ``app.api.guards``)."""
KEEP = 200
"""Entries kept in memory (the recording keeps them all)."""


@dataclass(frozen=True)
class Operation:
    """One command applied (or refused)."""

    utc: str
    """Wall-clock time, ISO 8601 UTC to the second."""
    t_s: float
    """Simulation time when it was applied [s]."""
    who: str
    action: str
    outcome: str
    """'done' or 'refused: <why>'."""
    instructor: bool = False
    """An instructor's command (a fault): shown to the instructor only (``trainee_view``)."""


def describe(command: object) -> str:
    """A short account of a command: its own ``summary()`` when it has one, else its name in
    words and its values."""
    summary = getattr(command, "summary", None)
    if callable(summary):
        return str(summary())
    words = re.sub(r"(?<!^)(?=[A-Z])", " ", type(command).__name__).lower()
    if not dataclasses.is_dataclass(command):
        return words
    parts = []
    for f in dataclasses.fields(command):
        parts.append(f"{f.name} {_value_text(getattr(command, f.name))}")
    return f"{words}: {', '.join(parts)}" if parts else words


def _value_text(value: object) -> str:
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, tuple | list):
        return "(" + ", ".join(_value_text(v) for v in value) + ")"
    mission = getattr(value, "mission", None)
    if mission is not None and hasattr(mission, "name"):
        return str(mission.name)  # a prepared run: its mission's name
    if dataclasses.is_dataclass(value):
        return ", ".join(
            f"{f.name} {_value_text(getattr(value, f.name))}" for f in dataclasses.fields(value)
        )
    if hasattr(value, "metadata") and hasattr(value, "rows"):
        return "recording"  # replay data: too big to print
    text = str(value)
    return text if len(text) <= 40 else text[:37] + "..."


def trainee_of(who: str) -> str:
    """The trainee behind an operations-log name: the name typed in the page ("viewer 3
    (Anna)" -> "Anna", the pilot page's "pilot (Anna)" -> "Anna", the crew's stations' "winch
    (Anna)" and "supervisor (Anna)" alike), else the sender as logged
    ("API 127.0.0.1", "viewer 3")."""
    match = re.fullmatch(r"(?:viewer \d+|pilot|winch|supervisor) \((.+)\)", who)
    return match.group(1) if match else who


class OperationsLog:
    """The latest operations (oldest first)."""

    def __init__(self) -> None:
        self._entries: deque[Operation] = deque(maxlen=KEEP)

    def add(
        self, t_s: float, who: str, action: str, outcome: str, instructor: bool = False
    ) -> Operation:
        entry = Operation(
            datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
            float(t_s),
            who,
            action,
            outcome,
            instructor,
        )
        self._entries.append(entry)
        return entry

    def latest(self, n: int = 20) -> tuple[Operation, ...]:
        return tuple(self._entries)[-n:]


def trainee_view(operations: tuple[Operation, ...]) -> tuple[Operation, ...]:
    """What a trainee may see of the operations log: everything but the instructor's commands
    (the faults they inject or clear; the trainee sees only the faults' effects)."""
    return tuple(op for op in operations if not op.instructor)
