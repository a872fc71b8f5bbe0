"""What a session sends on each channel: the channels with their schemas, and the messages of
a batch of log rows or of an event. The file (``writer.SessionRecorder``) and the live view
for Foxglove (``app.foxglove_live``) both send exactly these, so a recording and a live
connection show the same topics, schemas and numbers.

Log rows are decimated by their simulation time (``Decimator``): every kept row of the numeric
rate feeds ``/session/log`` (the columns no plot channel carries exactly), ``/tf``, the plot
channels and ``/wire``; the rows of the slower scene rate feed ``/scene``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from app.recording import schemas
from app.recording.channels import (
    EVENTS_TOPIC,
    LOG_TOPIC,
    SCENE_TOPIC,
    SESSION_TOPIC,
    TF_TOPIC,
    WIRE_TOPIC,
    carried_columns,
    plot_channels,
    session_columns,
)
from app.recording.encoding import T_S, RowEncoder
from app.recording.messages import (
    event_message,
    json_bytes,
    log_message,
    scene_geometry,
    scene_message,
    tf_message,
)
from control.columns import COLUMN_NAMES
from sim.docking import DockingFrame
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]

GRID_EPS = 1e-9
"""Slack when putting a row time on the decimation grid (times are sums of 0.01 s steps)."""


@dataclass
class Decimator:
    """Keeps the first row at or after each multiple of 1/rate_hz of simulation time."""

    rate_hz: float
    last_slot: float = -math.inf

    def select(self, t_s: FloatArray) -> NDArray[np.bool_]:
        """Mask of the rows to keep (rows in time order); remembers the last slot taken."""
        slots = np.floor(t_s * self.rate_hz + GRID_EPS)
        previous = np.concatenate(([self.last_slot], slots[:-1]))
        keep = slots > np.maximum.accumulate(previous)
        if len(slots):
            self.last_slot = max(self.last_slot, float(slots.max()))
        return keep


@dataclass(frozen=True)
class ChannelSpec:
    """One channel: its topic, JSON schema (its ``title`` is the schema's name) and the
    channel's metadata."""

    topic: str
    schema: dict
    metadata: dict[str, str]


@dataclass(frozen=True)
class RowBatch:
    """Kept rows of one hand-over, with what the scene needs to draw them."""

    rows: FloatArray
    numeric: NDArray[np.bool_]
    """Which rows are of the numeric rate (the others are of the scene rate only)."""
    scene: NDArray[np.bool_]
    crane_tip_n: FloatArray | None
    wire_length_m: float
    docking: DockingFrame | None
    times_ns: NDArray[np.int64] | None = None
    """Each kept row's log time [ns] when the caller said when the rows were simulated (the
    wall clock); None: ``origin_ns`` plus the row's simulation time."""


WallAnchors = Sequence[tuple[float, int]]
"""(simulation time [s], wall-clock time [ns since 1970]) pairs, in time order: when the
console had simulated up to that time."""


def wall_times_ns(t_s: FloatArray, anchors: WallAnchors, after_ns: int) -> NDArray[np.int64]:
    """The wall-clock time each row of ``t_s`` was simulated at [ns]: between two anchors in
    proportion to the simulation time (a tick's rows come at once; spread over the tick, each
    row has its own time, which readers join the channels of a row by), the anchors' own
    times at either end, and each later than ``after_ns`` and the row before: never ahead of
    the wall clock when the rows were handed over, never two rows at one time."""
    t = np.asarray(t_s, float)
    if len(anchors) == 0 or len(t) == 0:
        return np.zeros(len(t), dtype=np.int64)
    at = np.array([a[0] for a in anchors], float)
    wall = np.array([a[1] for a in anchors], float)
    out = np.interp(t, at, wall, left=wall[0], right=wall[-1]).astype(np.int64)
    # strictly increasing, by 1 ns at least: the running maximum of out[k] - k, plus k
    k = np.arange(len(out), dtype=np.int64)
    return np.maximum.accumulate(np.maximum(out - k, after_ns + 1)) + k


class SessionStream:
    """The channels of a session of ``n_thrusters`` thrusters and its messages; log times are
    ``origin_ns`` plus the simulation time."""

    def __init__(
        self,
        params: ParameterSet,
        n_thrusters: int,
        numeric_rate_hz: float,
        scene_rate_hz: float,
        origin_ns: int,
    ) -> None:
        self.plots = plot_channels(n_thrusters)
        self.session_columns = session_columns(n_thrusters)
        self.carried = carried_columns(n_thrusters)
        session_at = np.array([COLUMN_NAMES.index(c) for c in self.session_columns], dtype=np.intp)
        self._encoder = RowEncoder(self.plots, session_at)
        self._geo = scene_geometry(params)
        self._numeric = Decimator(numeric_rate_hz)
        self._scene = Decimator(scene_rate_hz)
        self.origin_ns = int(origin_ns)
        self.last_ns = -1
        """The latest log time given to a row (wall-clock stamps go on after it)."""

    def channels(self) -> list[ChannelSpec]:
        """Every channel, in the order a file registers them."""
        specs = [
            ChannelSpec(
                SESSION_TOPIC,
                schemas.session_log_schema(),
                {
                    "kind": "table",
                    "columns": json.dumps(self.session_columns),
                    "carried": json.dumps(self.carried),
                },
            ),
            ChannelSpec(TF_TOPIC, schemas.frame_transforms_schema(), {}),
            ChannelSpec(SCENE_TOPIC, schemas.scene_update_schema(), {}),
        ]
        specs += [
            ChannelSpec(ch.topic, schemas.plot_schema(ch), {"kind": "numeric"}) for ch in self.plots
        ]
        specs += [
            ChannelSpec(WIRE_TOPIC, schemas.wire_schema(), {"kind": "numeric"}),
            ChannelSpec(EVENTS_TOPIC, schemas.event_schema(), {"kind": "events"}),
            ChannelSpec(LOG_TOPIC, schemas.log_schema(), {}),
        ]
        return specs

    def keep(
        self,
        rows: FloatArray,
        t_s: FloatArray,
        crane_tip_n: FloatArray | None,
        wire_length_m: float,
        docking: DockingFrame | None,
        wall: WallAnchors | None = None,
    ) -> RowBatch | None:
        """The rows of a hand-over that the decimators keep (None: none), in time order after
        the rows kept before; ``wall``: when the rows were simulated (their log times are
        then the wall clock's, ``wall_times_ns``)."""
        numeric = self._numeric.select(t_s)
        scene = self._scene.select(t_s)
        keep = numeric | scene
        if not np.any(keep):
            return None
        times_ns = None
        if wall:
            times_ns = wall_times_ns(t_s[keep], wall, self.last_ns)
            self.last_ns = int(times_ns[-1])
        return RowBatch(
            rows[keep], numeric[keep], scene[keep], crane_tip_n, wire_length_m, docking, times_ns
        )

    def t_ns(self, t_s: float) -> int:
        return self.origin_ns + round(t_s * 1e9)

    def row_messages(self, batch: RowBatch) -> Iterator[tuple[str, int, bytes]]:
        """(topic, log time [ns], JSON bytes) of every message of a batch, row by row in
        channel order."""
        rows = batch.rows
        times_ns = (
            [self.t_ns(t_s) for t_s in rows[:, T_S].tolist()]
            if batch.times_ns is None
            else batch.times_ns.tolist()
        )
        numeric_rows = rows[batch.numeric]
        session = self._encoder.session_messages(numeric_rows)
        plots = self._encoder.plot_messages(numeric_rows)
        wire = (
            None
            if batch.crane_tip_n is None
            else self._encoder.wire_messages(numeric_rows, batch.crane_tip_n, batch.wire_length_m)
        )
        j = 0
        for k, t_ns in enumerate(times_ns):
            if batch.numeric[k]:
                yield SESSION_TOPIC, t_ns, session[j]
                yield TF_TOPIC, t_ns, json_bytes(tf_message(t_ns, rows[k]))
                for ch, messages in zip(self.plots, plots, strict=True):
                    yield ch.topic, t_ns, messages[j]
                if wire is not None:
                    yield WIRE_TOPIC, t_ns, wire[j]
                j += 1
            if batch.scene[k]:
                scene = scene_message(t_ns, rows[k], self._geo, batch.crane_tip_n, batch.docking)
                yield SCENE_TOPIC, t_ns, json_bytes(scene)

    def event_messages(
        self,
        t_s: float,
        kind: str,
        text: str,
        data: dict | None = None,
        wall_ns: int | None = None,
    ) -> list[tuple[str, int, bytes]]:
        """The messages of an event at simulation time ``t_s``: on ``/events`` and on
        ``/log`` (Foxglove's Log panel), logged at ``wall_ns`` (the wall clock when it
        happened) when given, else at ``origin_ns`` plus ``t_s``. ValueError when it is not
        a finite time >= 0, has no kind, or its data cannot be written as JSON."""
        if not math.isfinite(t_s) or t_s < 0.0:
            raise ValueError(f"event time must be a finite number of seconds >= 0, got {t_s}")
        if not kind:
            raise ValueError("event kind must not be empty")
        try:
            event = json_bytes(event_message(t_s, kind, text, data))
        except (TypeError, ValueError) as err:
            raise ValueError(f"event data cannot be written as JSON: {err}") from None
        t_ns = self.t_ns(t_s) if wall_ns is None else int(wall_ns)
        return [
            (EVENTS_TOPIC, t_ns, event),
            (LOG_TOPIC, t_ns, json_bytes(log_message(t_ns, kind, text))),
        ]
