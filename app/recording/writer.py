"""Writing a session: ``SessionRecorder`` (one MCAP file) and ``Decimator``.

Decimation
    Log rows (one per plant step) are decimated by their *simulation* time, never by wall time,
    so the same seeded run gives the same messages. A row is kept when it is the first one at or
    after a multiple of 1/rate. Every kept row of the numeric rate feeds the named plot
    channels, ``/wire`` and ``/tf``, and ``/session/log`` gets, exactly, the row's columns that
    no plot channel carries exactly (``channels.session_columns``; the channel's ``carried``
    metadata says which topic and field holds each of the others, and the reader puts the whole
    row back together); the rows of the (slower) scene rate feed ``/scene``.

Crash safety
    Messages are grouped in zstd-compressed chunks. A chunk is closed and handed to the
    operating system (``Writer.flush``) whenever ``flush_interval_s`` of wall time (``clock``)
    or ``flush_interval_sim_s`` of simulated time has passed since the last flush, whichever
    comes first: inside ``write_log`` / ``event`` between rows, and from a background thread
    when the caller is idle (paused simulation). A killed process (SIGKILL) therefore loses at
    most the chunk in progress: never more than ``flush_interval_sim_s`` of simulated time
    (this bound holds however loaded the machine is, since it is counted in the rows written),
    and on an unloaded machine about ``flush_interval_s`` of wall time. The file is not
    fsync'ed; the operating system keeps what was handed to it when a process dies, not when
    the machine loses power.
"""

from __future__ import annotations

import json
import math
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from importlib import metadata as importlib_metadata
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from mcap.writer import CompressionType, Writer
from numpy.typing import NDArray

from app.recording import schemas
from app.recording.channels import (
    COLUMNS,
    EVENTS_TOPIC,
    FORMAT_VERSION,
    LOG_TOPIC,
    RESERVED_SETUP_KEYS,
    SCENE_TOPIC,
    SESSION_TOPIC,
    SETUP_RECORD,
    TF_TOPIC,
    WIRE_TOPIC,
    carried_columns,
    plot_channels,
    session_columns,
)
from app.recording.messages import (
    event_message,
    json_bytes,
    log_message,
    plot_message,
    scene_geometry,
    scene_message,
    session_row_message,
    tf_message,
    wire_message,
)
from control.columns import COLUMN_NAMES, LAYOUT, M_MAX, N_LOG, LogRows
from sim.docking import DockingFrame
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]

GRID_EPS = 1e-9
"""Slack when putting a row time on the decimation grid (times are sums of 0.01 s steps)."""


class RecordingError(RuntimeError):
    """The recorder was used wrongly (closed, bad input)."""


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


def software_version() -> str:
    try:
        return importlib_metadata.version("rov-console")
    except importlib_metadata.PackageNotFoundError:
        return "unknown"


def _crane_tip(value: Sequence[float] | FloatArray) -> FloatArray:
    """[north, east, down] of the crane tip from 2 or 3 numbers [m]."""
    tip = np.asarray(value, dtype=float).ravel()
    if tip.size == 2:
        tip = np.append(tip, 0.0)
    if tip.size != 3 or not np.all(np.isfinite(tip)):
        raise ValueError(f"crane_tip_n must be 2 or 3 finite numbers [m], got {value!r}")
    return tip


def _log_rows(data: FloatArray | LogRows) -> FloatArray:
    """(n, N_LOG) rows in this software's layout, else ValueError."""
    if isinstance(data, LogRows):
        if data.layout.names != COLUMN_NAMES:
            raise ValueError(
                "log rows must be in this software's layout (control.columns), "
                "not a recorded file's"
            )
        data = data.data
    rows = np.asarray(data, dtype=float)
    if rows.ndim != 2 or rows.shape[1] != N_LOG:
        raise ValueError(f"log rows must have shape (n, {N_LOG}), got {rows.shape}")
    return rows


def time_origin_of(metadata: Mapping[str, Any]) -> int:
    """Wall-clock time [ns since 1970, UTC] of simulation time zero: the session's start
    (``started_utc`` at ``start_t_s``) when the metadata gives it, else now. Message log times
    are this plus the simulation time, so Foxglove shows the date the session ran."""
    started = metadata.get("started_utc")
    if isinstance(started, str):
        try:
            moment = datetime.fromisoformat(started)
        except ValueError:
            moment = None
        if moment is not None and moment.tzinfo is not None:
            start_t_s = float(metadata.get("start_t_s", 0.0) or 0.0)
            return round(moment.timestamp() * 1e9) - round(start_t_s * 1e9)
    return time.time_ns()


def _setup_record(
    metadata: Mapping[str, Any],
    ps: ParameterSet,
    n_thrusters: int,
    rates: dict[str, float],
    origin_ns: int = 0,
) -> dict[str, str]:
    """The metadata record: every value JSON-encoded (strings too, so reading is exact).

    A caller's value for a key the recorder writes itself must be the recorder's value."""
    recorder = {
        "format_version": FORMAT_VERSION,
        "software_version": software_version(),
        "mcap_python": importlib_metadata.version("mcap"),
        "n_thrusters": n_thrusters,
        "frames": "world = [north, west, up] (z up); "
        "ned = [north, east, down]; tree, rov, reference: children of ned",
        "time_origin_ns": origin_ns,
        "times": "log time = time_origin_ns + simulation time; messages carry t_s (simulation)",
    } | rates
    own = {"params": ps.spec.model_dump(mode="json"), "columns": COLUMNS, "recorder": recorder}
    clash = sorted(k for k in RESERVED_SETUP_KEYS if k in metadata and metadata[k] != own[k])
    if clash:
        raise ValueError(
            f"metadata keys {clash} are written by the recorder itself (leave them out)"
        )
    out = {}
    for key, value in {**metadata, **own}.items():
        try:
            out[str(key)] = json.dumps(value, sort_keys=True, allow_nan=False)
        except (TypeError, ValueError) as err:
            raise ValueError(f"metadata[{key!r}] cannot be written as JSON: {err}") from None
    return out


def _check_rates(**rates: float) -> None:
    for name, v in rates.items():
        if not (math.isfinite(v) and v > 0.0):
            raise ValueError(f"{name} must be a positive number, got {v}")


class SessionRecorder:
    """Writes one session to an MCAP file (see the module docstring)."""

    def __init__(
        self,
        path: str | Path,
        *,
        metadata: Mapping[str, Any],
        params: ParameterSet,
        n_thrusters: int,
        flush_interval_s: float = 0.5,
        flush_interval_sim_s: float = 1.0,
        numeric_rate_hz: float = 20.0,
        scene_rate_hz: float = 5.0,
        clock: Callable[[], float] = time.monotonic,
        overwrite: bool = False,
        docking: DockingFrame | None = None,
        time_origin_ns: int | None = None,
    ) -> None:
        """Create ``path`` (refuses an existing file unless ``overwrite``), write the header,
        schemas, channels and the ``setup`` metadata record (``metadata``, e.g. from
        ``session_metadata``), and start the flush thread. ``docking``: the docking frame to
        draw from the start (``write_log`` can change it)."""
        if not 1 <= n_thrusters <= M_MAX:
            raise ValueError(f"n_thrusters must be in [1, {M_MAX}], got {n_thrusters}")
        rates = {
            "numeric_rate_hz": numeric_rate_hz,
            "scene_rate_hz": scene_rate_hz,
            "flush_interval_s": flush_interval_s,
            "flush_interval_sim_s": flush_interval_sim_s,
        }
        _check_rates(**rates)
        self._origin_ns = (
            int(time_origin_ns) if time_origin_ns is not None else time_origin_of(metadata)
        )
        setup = _setup_record(metadata, params, n_thrusters, rates, self._origin_ns)
        self._plots = plot_channels(n_thrusters)
        self._session_columns = session_columns(n_thrusters)
        self._session_at = np.array(
            [COLUMN_NAMES.index(c) for c in self._session_columns], dtype=np.intp
        )
        self._carried = carried_columns(n_thrusters)
        self._geo = scene_geometry(params)
        self.path = Path(path)
        self._file: BinaryIO = open(self.path, "wb" if overwrite else "xb")
        try:
            self._writer = Writer(self._file, compression=CompressionType.ZSTD)
            self._writer.start(profile="", library=f"rov-console {software_version()}")
            self._start_file(setup, numeric_rate_hz, scene_rate_hz)
        except BaseException:  # e.g. the disk is full: leave no empty or headless file
            self._file.close()
            self.path.unlink(missing_ok=True)
            raise
        self._crane_tip_n: FloatArray | None = None
        self._wire_length_m = math.nan
        self._docking = docking
        self._last_t_s = -math.inf
        self._clock = clock
        self._flush_interval_s = flush_interval_s
        self._flush_interval_sim_s = flush_interval_sim_s
        self._written_t_s = -math.inf
        """Simulation time of the last row or event written."""
        self._flushed_t_s = -math.inf
        """Simulation time written when the last chunk was closed."""
        self._lock = threading.Lock()
        self._dirty = False
        self._closed = False
        self._last_flush = clock()
        self._stop = threading.Event()
        self._flusher: threading.Thread | None = self._start_flusher()

    def _start_file(
        self, setup: dict[str, str], numeric_rate_hz: float, scene_rate_hz: float
    ) -> None:
        """Schemas, channels and the setup record, handed to the operating system."""
        self._numeric = Decimator(numeric_rate_hz)
        self._scene = Decimator(scene_rate_hz)
        self._channels = self._register_channels()
        self._sequence = dict.fromkeys(self._channels, 0)
        self._writer.add_metadata(SETUP_RECORD, setup)
        self._writer.flush()

    def _start_flusher(self) -> threading.Thread | None:
        """The thread that flushes while the caller is idle."""
        thread = threading.Thread(target=self._flush_loop, name="mcap-flush", daemon=True)
        thread.start()
        return thread

    # ------------------------------------------------------------------ set-up
    def _register_channels(self) -> dict[str, int]:
        w = self._writer

        def add(topic: str, schema: dict, meta: dict[str, str] | None = None) -> None:
            sid = w.register_schema(schema["title"], "jsonschema", json_bytes(schema))
            channels[topic] = w.register_channel(topic, "json", sid, meta or {})

        channels: dict[str, int] = {}
        add(
            SESSION_TOPIC,
            schemas.session_log_schema(),
            {
                "kind": "table",
                "columns": json.dumps(self._session_columns),
                "carried": json.dumps(self._carried),
            },
        )
        add(TF_TOPIC, schemas.frame_transforms_schema())
        add(SCENE_TOPIC, schemas.scene_update_schema())
        for ch in self._plots:
            add(ch.topic, schemas.plot_schema(ch), {"kind": "numeric"})
        add(WIRE_TOPIC, schemas.wire_schema(), {"kind": "numeric"})
        add(EVENTS_TOPIC, schemas.event_schema(), {"kind": "events"})
        add(LOG_TOPIC, schemas.log_schema())
        return channels

    # ------------------------------------------------------------------ writing
    def _add(self, topic: str, t_ns: int, message: dict) -> None:
        cid = self._channels[topic]
        self._sequence[topic] += 1
        self._writer.add_message(
            cid,
            log_time=t_ns,
            publish_time=t_ns,
            data=json_bytes(message),
            sequence=self._sequence[topic],
        )
        self._dirty = True

    def _check_open(self) -> None:
        if self._closed:
            raise RecordingError(f"{self.path}: the recorder is closed")

    def write_log(
        self,
        data: FloatArray | LogRows,
        crane_tip_n: Sequence[float] | FloatArray | None = None,
        wire_length_m: float | None = None,
        docking: DockingFrame | None = None,
    ) -> None:
        """Record log rows (``LogRows`` or an (n, N_LOG) array in ``control.columns`` layout),
        later than every row recorded so far and in time order (else ValueError: a restarted
        simulation needs a new recorder).

        ``crane_tip_n`` (NED, m), ``wire_length_m`` and ``docking``: None keeps the last value
        given; the wire is drawn and ``/wire`` written once a crane tip is known."""
        rows = _log_rows(data)
        t = LAYOUT.take(rows, "t_s")
        with self._lock:
            self._check_open()
            if len(t) and not (t[0] > self._last_t_s and np.all(np.diff(t) > 0.0)):
                raise ValueError(
                    f"log rows must go forward in time after the last recorded "
                    f"t = {self._last_t_s} s; got t = {t[0]} .. {t[-1]} s"
                )
            if crane_tip_n is not None:
                self._crane_tip_n = _crane_tip(crane_tip_n)
            if wire_length_m is not None:
                self._wire_length_m = float(wire_length_m)
            if docking is not None:
                self._docking = docking
            self._last_t_s = float(t[-1]) if len(t) else self._last_t_s
            numeric = self._numeric.select(t)
            scene = self._scene.select(t)
            for k in np.flatnonzero(numeric | scene):
                self._write_row(rows[k], bool(numeric[k]), bool(scene[k]))
                self._maybe_flush()

    def _write_row(self, row: FloatArray, numeric: bool, scene: bool) -> None:
        t_s = float(LAYOUT.take(row, "t_s"))
        self._note_time(t_s)
        t_ns = self._origin_ns + round(t_s * 1e9)
        if numeric:
            self._add(SESSION_TOPIC, t_ns, session_row_message(row, self._session_at))
            self._add(TF_TOPIC, t_ns, tf_message(t_ns, row))
            for ch in self._plots:
                self._add(ch.topic, t_ns, plot_message(ch, row))
            if self._crane_tip_n is not None:
                self._add(
                    WIRE_TOPIC, t_ns, wire_message(row, self._crane_tip_n, self._wire_length_m)
                )
        if scene:
            self._add(
                SCENE_TOPIC,
                t_ns,
                scene_message(t_ns, row, self._geo, self._crane_tip_n, self._docking),
            )

    def event(self, t_s: float, kind: str, text: str, data: dict | None = None) -> None:
        """Record an event at simulation time ``t_s`` on ``/events`` (and ``/log`` for
        Foxglove's Log panel). ``kind``: e.g. leg, alarm, gains, landing."""
        if not math.isfinite(t_s) or t_s < 0.0:
            raise ValueError(f"event time must be a finite number of seconds >= 0, got {t_s}")
        if not kind:
            raise ValueError("event kind must not be empty")
        message = event_message(t_s, kind, text, data)
        try:
            json_bytes(message)
        except (TypeError, ValueError) as err:
            raise ValueError(f"event data cannot be written as JSON: {err}") from None
        t_ns = self._origin_ns + round(t_s * 1e9)
        with self._lock:
            self._check_open()
            self._note_time(t_s)
            self._add(EVENTS_TOPIC, t_ns, message)
            self._add(LOG_TOPIC, t_ns, log_message(t_ns, kind, text))
            self._maybe_flush()

    # ------------------------------------------------------------------ flushing and closing
    def _note_time(self, t_s: float) -> None:
        if self._flushed_t_s == -math.inf:
            self._flushed_t_s = t_s  # the first chunk counts from the first message
        self._written_t_s = max(self._written_t_s, t_s)

    def _maybe_flush(self) -> None:
        """Flush (lock held) when flush_interval_s of wall time or flush_interval_sim_s of
        simulated time has passed since the last flush."""
        if not self._dirty:
            return
        wall_due = self._clock() - self._last_flush >= self._flush_interval_s
        sim_due = self._written_t_s - self._flushed_t_s >= self._flush_interval_sim_s
        if wall_due or sim_due:
            self._flush_locked()

    def _flush_locked(self) -> None:
        self._writer.flush()
        self._dirty = False
        self._last_flush = self._clock()
        self._flushed_t_s = self._written_t_s

    def flush(self) -> None:
        """Close the chunk in progress and hand everything to the operating system now."""
        with self._lock:
            self._check_open()
            self._flush_locked()

    def _flush_loop(self) -> None:
        poll = min(self._flush_interval_s / 4.0, 0.1)
        while not self._stop.wait(poll):
            with self._lock:
                if self._closed:
                    return
                self._maybe_flush()

    def close(self) -> None:
        """Write the summary and footer and close the file. Idempotent."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            try:
                self._writer.finish()
            finally:
                self._file.close()
        self._stop.set()
        if self._flusher is not None and self._flusher is not threading.current_thread():
            self._flusher.join()

    def __enter__(self) -> SessionRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
