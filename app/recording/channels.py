"""What a session file holds: its topics, the setup record and the plot channels.

The log row is declared in ``control.columns``; a plot channel picks named numbers out of it by
block name and element index (``PlotField("yaw_deg", "tree_eta_n", 5, DEG)``), converting the
core's SI units and radians to the interface's degrees and rpm. Newtons are spelt ``_newton``
and newton metres ``_newton_m`` (``_n`` means NED in our names); files written before this
spelling are read by ``control.columns.Layout.from_names``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from control.columns import AXES3, AXES6, COLUMN_NAMES, LAYOUT, LOG_COLUMNS, Layout

FloatArray = NDArray[np.float64]

FORMAT_VERSION = 3
"""Version of this file layout (channels, schemas, metadata keys). 3: ``/session/log`` holds
only the columns no plot channel carries exactly (``session_columns``), the reader takes the
rest back from the plot channels; 2: columns of control.columns (newtons spelt ``_newton``),
the whole row on ``/session/log``, and the setup keys of ``session_metadata``; 1: the first
files (readers take all three)."""
SETUP_RECORD = "setup"
"""Name of the metadata record holding the session's set-up."""
RUN_RECORD_PREFIX = "run."
"""Metadata records ``run.2``, ``run.3``, ... hold the set-up of each run started while the
recording went on (``session_metadata``, with ``start_t_s`` on the recording's time axis); the
``setup`` record holds the first run's."""
RESERVED_SETUP_KEYS = ("params", "columns", "recorder")
"""Keys of the setup record that the recorder writes itself."""

SESSION_TOPIC = "/session/log"
TF_TOPIC = "/tf"
SCENE_TOPIC = "/scene"
WIRE_TOPIC = "/wire"
EVENTS_TOPIC = "/events"
LOG_TOPIC = "/log"

DEG = math.degrees(1.0)
"""Degrees per radian."""
RPM = 60.0
"""Revolutions per minute per revolution per second."""


def column_names() -> list[str]:
    """Flat names of the log row's columns (declared in control.columns), in row order."""
    return list(COLUMN_NAMES)


COLUMNS = column_names()


@dataclass(frozen=True)
class PlotField:
    """One number of a plot channel: element ``index`` of log block ``block``, minus element
    ``minus`` (block, index) when given, times ``scale`` (a unit conversion)."""

    name: str
    block: str
    index: int = 0
    scale: float = 1.0
    minus: tuple[str, int] | None = None

    def __post_init__(self) -> None:
        for block, index in ((self.block, self.index), *([self.minus] if self.minus else [])):
            width = LAYOUT.widths.get(block)
            if width is None or not 0 <= index < width:
                raise ValueError(
                    f"plot field {self.name!r}: element {index} of log block "
                    f"{block!r} does not exist"
                )

    def columns(self, layout: Layout = LAYOUT) -> tuple[int, int | None]:
        """Where the field's element, and the one it subtracts (None: none), sit in a row."""
        minus = None if self.minus is None else _column(layout, *self.minus)
        return _column(layout, self.block, self.index), minus


def _column(layout: Layout, block: str, index: int) -> int:
    return layout.slice(block).start + index


@dataclass(frozen=True)
class PlotChannel:
    """A channel of named numbers for Foxglove's Plot panel."""

    topic: str
    schema_name: str
    description: str
    fields: tuple[PlotField, ...]

    @cached_property
    def _picks(self) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_], FloatArray]:
        """Row index of each field's element and of the one it subtracts, which fields
        subtract, and the scales (for rows in control.columns' layout)."""
        where = [f.columns() for f in self.fields]
        at = np.array([a for a, _ in where], dtype=np.intp)
        has_minus = np.array([m is not None for _, m in where], dtype=bool)
        minus = np.array([a if m is None else m for a, m in where], dtype=np.intp)
        return at, minus, has_minus, np.array([f.scale for f in self.fields])

    def values(self, row: FloatArray) -> list[float]:
        """The fields' numbers in one log row (control.columns' layout), units converted."""
        return self.values_of_rows(row[np.newaxis, :])[0].tolist()

    def values_of_rows(self, rows: FloatArray) -> FloatArray:
        """(k, fields) the fields' numbers in k log rows, units converted."""
        at, minus, has_minus, scale = self._picks
        v = rows[:, at]
        v[:, has_minus] -= rows[:, minus[has_minus]]
        return v * scale


_POSE = ("north_m", "east_m", "down_m", "roll_deg", "pitch_deg", "yaw_deg")
_TERMS = tuple(f"{p}_{a}" for p in ("p", "i", "d", "ff") for a in AXES3)


def _elements(block: str) -> tuple[str, ...]:
    """The flat names of a log block's elements."""
    return next(col.elements for col in LOG_COLUMNS if col.name == block)


def _named(prefix: str, block: str, names: Sequence[str]) -> tuple[PlotField, ...]:
    """One field per element of ``block``, named ``prefix + names[i]``."""
    return tuple(PlotField(f"{prefix}{n}", block, i) for i, n in enumerate(names))


def _pose(block: str) -> tuple[PlotField, ...]:
    """A pose [north, east, down, roll, pitch, yaw]: metres, then degrees."""
    return tuple(PlotField(n, block, i, DEG if i >= 3 else 1.0) for i, n in enumerate(_POSE))


def _estimate_fields() -> tuple[PlotField, ...]:
    return (
        PlotField("north_m", "eta_hat_n", 0),
        PlotField("east_m", "eta_hat_n", 1),
        PlotField("yaw_deg", "eta_hat_n", 2, DEG),
        PlotField("u_mps", "nu_hat_tree", 0),
        PlotField("v_mps", "nu_hat_tree", 1),
        PlotField("r_deg_s", "nu_hat_tree", 2, DEG),
        *_named("bias_", "bias_tree", AXES3),
        *_named("nis_", "nis", ("north", "east", "heading")),
    )


def _reference_fields() -> tuple[PlotField, ...]:
    """Reference pose and rate, and the error = true tree minus reference."""
    return (
        PlotField("north_m", "eta_ref_n", 0),
        PlotField("east_m", "eta_ref_n", 1),
        PlotField("yaw_deg", "eta_ref_n", 2, DEG),
        PlotField("north_rate_mps", "eta_ref_rate_n", 0),
        PlotField("east_rate_mps", "eta_ref_rate_n", 1),
        PlotField("yaw_rate_deg_s", "eta_ref_rate_n", 2, DEG),
        PlotField("error_north_m", "tree_eta_n", 0, 1.0, ("eta_ref_n", 0)),
        PlotField("error_east_m", "tree_eta_n", 1, 1.0, ("eta_ref_n", 1)),
        PlotField("error_yaw_deg", "tree_eta_n", 5, DEG, ("eta_ref_n", 2)),
    )


def _measurement_fields() -> tuple[PlotField, ...]:
    """Held sensor values (angles in degrees) and the accepted-sample flags."""
    held = tuple(
        PlotField(e.removeprefix("y_").replace("_rad", "_deg"), "y", i, DEG if "_rad" in e else 1.0)
        for i, e in enumerate(_elements("y"))
    )
    return held + _named("", "accepted", _elements("accepted"))


def _thruster_fields(n_thrusters: int) -> tuple[PlotField, ...]:
    out: list[PlotField] = []
    for i in range(n_thrusters):
        out += [
            PlotField(f"thruster{i + 1}_force_newton", "thruster_force", i),
            PlotField(f"thruster{i + 1}_speed_rpm", "thruster_speed", i, RPM),
            PlotField(f"thruster{i + 1}_utilisation", "thruster_utilisation", i),
        ]
    return tuple(out)


def plot_channels(n_thrusters: int) -> tuple[PlotChannel, ...]:
    """The plot channels for an ROV with ``n_thrusters`` thrusters."""
    forces = (
        *_named("tree_", "tau_tree_cmd", AXES3),
        *_named("rov_cmd_", "tau_rov_cmd_b", AXES6),
        *_named("rov_ach_", "tau_rov_ach_b", AXES6),
        PlotField("mode", "mode"),
    )
    return (
        PlotChannel(
            "/tree/state", "rov_console.TreeState", "true tree pose (NED)", _pose("tree_eta_n")
        ),
        PlotChannel(
            "/rov/state", "rov_console.RovState", "true ROV pose (NED)", _pose("rov_eta_n")
        ),
        PlotChannel(
            "/tree/estimate",
            "rov_console.TreeEstimate",
            "what the controller believes of the tree: pose, body rates, bias, NIS",
            _estimate_fields(),
        ),
        PlotChannel(
            "/reference",
            "rov_console.Reference",
            "reference pose and rate; error = true tree minus reference",
            _reference_fields(),
        ),
        PlotChannel(
            "/measurements",
            "rov_console.Measurements",
            "held sensor values (sim.sensors) and accepted-sample flags",
            _measurement_fields(),
        ),
        PlotChannel(
            "/control/forces",
            "rov_console.ControlForces",
            "commanded force on the tree (tree axes), commanded and achieved ROV "
            "wrench (ROV axes), supervisor mode (0 tree, 1 free)",
            forces,
        ),
        PlotChannel(
            "/thrusters",
            "rov_console.Thrusters",
            "per-thruster force, propeller speed and utilisation",
            _thruster_fields(n_thrusters),
        ),
        PlotChannel(
            "/control/terms",
            "rov_console.ControlTerms",
            "P, I, D and feedforward parts of the tree force (tree axes)",
            _named("", "control_terms", _TERMS),
        ),
    )


WIRE_FIELDS = ("crane_tip_north_m", "crane_tip_east_m", "wire_length_m", "tree_offset_from_tip_m")
"""Fields of ``/wire`` (besides t_s)."""


def carried_columns(n_thrusters: int) -> dict[str, tuple[str, str]]:
    """The log row's columns that a plot channel carries exactly (in the core's unit, not a
    difference): flat column name -> (topic, field name), the first channel that has it.
    ``/session/log`` leaves these out; the reader takes them back from that channel."""
    out: dict[str, tuple[str, str]] = {}
    for ch in plot_channels(n_thrusters):
        for f in ch.fields:
            if f.scale == 1.0 and f.minus is None:
                at, _ = f.columns()
                out.setdefault(LAYOUT.names[at], (ch.topic, f.name))
    return out


def session_columns(n_thrusters: int) -> list[str]:
    """The columns ``/session/log`` writes for an ROV with ``n_thrusters`` thrusters (row
    order): time, the true velocities, angles and propeller speeds (the plot channels give
    them in degrees and rpm), the site, the unused thruster slots, and whatever else no plot
    channel carries exactly."""
    carried = carried_columns(n_thrusters)
    return [c for c in COLUMNS if c not in carried]
