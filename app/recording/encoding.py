"""The numeric messages of many log rows at once, as JSON bytes, without building dicts.

``messages`` builds each message as a dict of one row, which ``json_bytes`` then encodes: the
clear definition, and what the scene, the frames and the events still use. The numeric
channels carry most of a recording's messages (ten per kept row), so ``RowEncoder`` writes
their JSON from templates filled with the numbers of a whole batch of rows, taken from the rows
by numpy in one go. The bytes are exactly those of ``json_bytes(plot_message(...))``,
``json_bytes(session_row_message(...))`` and ``json_bytes(wire_message(...))``: Python's JSON
encoder writes a float as its ``repr``, so the template does too, and ``null`` for a
non-finite number (a test checks every channel against the dict builders, NaN and infinities
included).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from app.recording.channels import WIRE_FIELDS, PlotChannel
from control.columns import LAYOUT

FloatArray = NDArray[np.float64]

T_S = LAYOUT.slice("t_s").start
"""Column of the simulation time in a log row."""
TREE_N, TREE_E = LAYOUT.slice("tree_eta_n").start, LAYOUT.slice("tree_eta_n").start + 1
"""Columns of the tree's north and east position in a log row."""


def _number(value: float) -> str:
    """A float as Python's JSON encoder writes it (null for NaN and infinities)."""
    return repr(value) if math.isfinite(value) else "null"


@dataclass(frozen=True)
class ObjectTemplate:
    """``{"t_s":..., name:..., ...}`` of named numbers: compact JSON with the names in order."""

    template: str
    """The object with ``%r`` for each number."""

    @classmethod
    def of(cls, names: tuple[str, ...]) -> ObjectTemplate:
        """The template of ``t_s`` and ``names`` (identifiers: nothing to escape)."""
        return cls("{" + ",".join(f'"{n}":%r' for n in ("t_s", *names)) + "}")

    def fill(self, values: list[float], finite: bool) -> bytes:
        """The JSON of one message (``values``: t_s, then one number per name; ``finite``:
        every value is, so ``repr`` writes each)."""
        if finite:
            return (self.template % tuple(values)).encode()
        return (self.template.replace("%r", "%s") % tuple(map(_number, values))).encode()


def _finite_rows(values: FloatArray) -> list[bool]:
    """Which rows of (k, m) numbers are finite throughout."""
    return [bool(f) for f in np.all(np.isfinite(values), axis=1, keepdims=True)[:, 0]]


def _list_of_numbers(values: list[float], finite: bool) -> str:
    return ",".join(map(repr if finite else _number, values))


WIRE_TEMPLATE = ObjectTemplate.of(WIRE_FIELDS)


@dataclass(frozen=True)
class RowEncoder:
    """The numeric messages of kept rows (control.columns' layout), as JSON bytes."""

    plots: tuple[PlotChannel, ...]
    session_at: NDArray[np.intp]
    """Columns ``/session/log`` writes (``channels.session_columns``)."""

    @cached_property
    def _plot_templates(self) -> tuple[ObjectTemplate, ...]:
        return tuple(ObjectTemplate.of(tuple(f.name for f in ch.fields)) for ch in self.plots)

    def plot_messages(self, rows: FloatArray) -> list[list[bytes]]:
        """Per plot channel, the message of each row."""
        out = []
        for ch, template in zip(self.plots, self._plot_templates, strict=True):
            values = np.column_stack((rows[:, T_S], ch.values_of_rows(rows)))
            out.append(
                [
                    template.fill(v, finite)
                    for v, finite in zip(values.tolist(), _finite_rows(values), strict=True)
                ]
            )
        return out

    def session_messages(self, rows: FloatArray) -> list[bytes]:
        """``/session/log`` of each row: ``{"t_s":..,"row":[..]}``."""
        values = rows[:, self.session_at]
        return [
            b'{"t_s":%s,"row":[%s]}' % (_number(t_s).encode(), _list_of_numbers(r, finite).encode())
            for t_s, r, finite in zip(
                rows[:, T_S].tolist(), values.tolist(), _finite_rows(values), strict=True
            )
        ]

    @staticmethod
    def wire_messages(
        rows: FloatArray, crane_tip_n: FloatArray, wire_length_m: float
    ) -> list[bytes]:
        """``/wire`` of each row (``messages.wire_message``)."""
        tip_n, tip_e = float(crane_tip_n[0]), float(crane_tip_n[1])
        out = []
        for t_s, n, e in rows[:, [T_S, TREE_N, TREE_E]].tolist():
            values = [t_s, tip_n, tip_e, wire_length_m, math.hypot(n - tip_n, e - tip_e)]
            out.append(WIRE_TEMPLATE.fill(values, all(map(math.isfinite, values))))
        return out
