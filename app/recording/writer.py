"""Writing a session: ``SessionRecorder`` (one MCAP file; what it writes on each channel is
``stream.SessionStream``'s, shared with the live feed for Foxglove).

Decimation
    Log rows (one per plant step) are decimated by their *simulation* time, never by wall time,
    so the same seeded run gives the same messages. A row is kept when it is the first one at or
    after a multiple of 1/rate. Every kept row of the numeric rate feeds the named plot
    channels, ``/wire`` and ``/tf``, and ``/session/log`` gets, exactly, the row's columns that
    no plot channel carries exactly (``channels.session_columns``; the channel's ``carried``
    metadata says which topic and field holds each of the others, and the reader puts the whole
    row back together); the rows of the (slower) scene rate feed ``/scene``.

The writer thread
    ``write_log`` and ``event`` only check their input, decimate, and put the kept rows (or the
    event) on a bounded queue; a thread of the recorder encodes the messages (the numeric ones
    from templates, ``encoding.RowEncoder``), compresses and writes them. The caller (the
    console's paced loop) is never held by encoding, compression or the disk, unless the
    writer falls ``MAX_QUEUED`` batches behind: then ``write_log`` waits for room, so memory
    stays bounded. A failure in the thread (e.g. a full disk) is raised by the next call, as
    ``RecordingError`` naming the cause.

Crash safety
    Messages are grouped in zstd-compressed chunks, each closed between two batches (so a row
    never spans two chunks) once it holds ``CHUNK_BYTES``. The writer thread also closes the
    chunk in progress, hands it to the operating system and fsyncs the file once
    ``flush_interval_s`` of wall time (``clock``) has passed since it last did and it has
    something new (it looks after each batch and at least every 0.1 s), and at ``flush`` and
    ``close``. What a SIGKILL loses is therefore what the caller handed over in the last
    ``flush_interval_s`` + 0.1 s of wall time (0.6 s by default), plus what was still queued
    (nothing while the writer keeps up; at most ``MAX_QUEUED`` batches when it falls behind).
    This is a bound in wall time: in simulated time it is the run's speed times as much, about
    12 s at 20x and 30 s at 50x (a caller that gathers rows before handing them over, as the
    console does, loses what it gathered too). The killed file has no summary and no footer:
    the product's reader (``load_session``) reads it up to the last whole record, and
    ``rov-console log recover`` (``recover.recover_session``) rewrites it as a complete MCAP
    that stock readers open (``mcap``'s ``make_reader`` is tested). The fsync makes a synced
    chunk survive the machine losing power too.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import queue
import sys
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

from app import software_version
from app.recording.channels import (
    COLUMNS,
    FORMAT_VERSION,
    RESERVED_SETUP_KEYS,
    RUN_RECORD_PREFIX,
    SETUP_RECORD,
)
from app.recording.messages import json_bytes
from app.recording.stream import Decimator as Decimator  # re-exported
from app.recording.stream import RowBatch, SessionStream, WallAnchors
from control.columns import COLUMN_NAMES, LAYOUT, M_MAX, N_LOG, LogRows
from sim.docking import DockingFrame
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]

MAX_QUEUED = 64
"""Batches (one ``write_log`` or ``event`` call each) waiting for the writer thread at most;
``write_log`` waits for room beyond (the console hands over 0.5 s of simulation a batch)."""
CHUNK_BYTES = 1 << 20
"""A chunk is closed once it holds this many bytes of messages (uncompressed), at the end of a
batch, so that a row's messages are always in one chunk (a cut file holds whole rows)."""


class RecordingError(RuntimeError):
    """The recorder was used wrongly (closed, bad input)."""


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
    (``started_utc`` at ``start_t_s``) when the metadata gives it, else now. Without
    ``wall_log_times``, message log times are this plus the simulation time, so Foxglove
    shows the date the session ran."""
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
    wall_log_times: bool = False,
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
        "times": (
            "log time = the wall clock when the row was simulated or the event happened; "
            "messages carry t_s (simulation)"
            if wall_log_times
            else "log time = time_origin_ns + simulation time; messages carry t_s (simulation)"
        ),
    } | rates
    if wall_log_times:
        recorder["log_time"] = "wall"
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


@dataclass(frozen=True)
class _Event:
    """An event's messages (topic, log time, bytes), encoded by the caller (which checks
    they can be)."""

    messages: list[tuple[str, int, bytes]]


@dataclass(frozen=True)
class _Record:
    """A metadata record written mid-file (a run's set-up)."""

    name: str
    values: dict[str, str]


@dataclass(frozen=True)
class _Flush:
    """Close the chunk, write and fsync now; ``done`` is set once that is done."""

    done: threading.Event


_CLOSE = object()
"""Put on the queue last: the writer thread writes the summary and footer and ends."""


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
        numeric_rate_hz: float = 20.0,
        scene_rate_hz: float = 5.0,
        clock: Callable[[], float] = time.monotonic,
        overwrite: bool = False,
        docking: DockingFrame | None = None,
        time_origin_ns: int | None = None,
        wall_log_times: bool = False,
    ) -> None:
        """Create ``path`` (refuses an existing file unless ``overwrite``), write the header,
        schemas, channels and the ``setup`` metadata record (``metadata``, e.g. from
        ``session_metadata``), and start the writer thread. ``docking``: the docking frame to
        draw from the start (``write_log`` can change it). ``wall_log_times``: the caller
        says when each hand-over of rows was simulated (``write_log``'s ``wall``) and when each
        event happened, and those wall-clock times are the log times (a console's session,
        run at 5x, stamped start plus simulated time ran minutes into the future); else log
        times are the start plus the simulated time (a headless run, simulated faster than
        real time, would squeeze into seconds)."""
        if not 1 <= n_thrusters <= M_MAX:
            raise ValueError(f"n_thrusters must be in [1, {M_MAX}], got {n_thrusters}")
        rates = {
            "numeric_rate_hz": numeric_rate_hz,
            "scene_rate_hz": scene_rate_hz,
            "flush_interval_s": flush_interval_s,
        }
        _check_rates(**rates)
        self._origin_ns = (
            int(time_origin_ns) if time_origin_ns is not None else time_origin_of(metadata)
        )
        self.wall_log_times = bool(wall_log_times)
        setup = _setup_record(
            metadata, params, n_thrusters, rates, self._origin_ns, self.wall_log_times
        )
        self._stream = SessionStream(
            params, n_thrusters, numeric_rate_hz, scene_rate_hz, self._origin_ns
        )
        self.path = Path(path)
        self._file: BinaryIO = open(self.path, "wb" if overwrite else "xb")
        try:
            # chunks are closed by the writer thread (CHUNK_BYTES, flush_interval_s), never
            # by mcap in the middle of a row
            self._writer = Writer(
                self._file, chunk_size=sys.maxsize, compression=CompressionType.ZSTD
            )
            self._writer.start(profile="", library=f"rov-console {software_version()}")
            self._start_file(setup)
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
        self._lock = threading.Lock()
        """Held by callers (the decimators, the last row time, closing)."""
        self._closed = False
        self._error: Exception | None = None
        """What went wrong in the writer thread (it then writes nothing more)."""
        self._queue: queue.Queue[object] = queue.Queue(MAX_QUEUED)
        self._chunk_bytes = 0
        """Bytes of messages in the chunk in progress (the writer thread's)."""
        self.runs = 1
        """Runs whose set-up the file holds (the ``setup`` record's, then ``add_run``'s)."""
        self._thread = threading.Thread(target=self._write_loop, name="mcap-writer", daemon=True)
        self._thread.start()

    def _start_file(self, setup: dict[str, str]) -> None:
        """Schemas, channels and the setup record, handed to the operating system."""
        self._channels = self._register_channels()
        self._sequence = dict.fromkeys(self._channels, 0)
        self._writer.add_metadata(SETUP_RECORD, setup)
        self._writer.flush()

    # ------------------------------------------------------------------ set-up
    def _register_channels(self) -> dict[str, int]:
        w = self._writer
        channels: dict[str, int] = {}
        for spec in self._stream.channels():
            sid = w.register_schema(spec.schema["title"], "jsonschema", json_bytes(spec.schema))
            channels[spec.topic] = w.register_channel(spec.topic, "json", sid, spec.metadata)
        return channels

    # ------------------------------------------------------------------ the caller's side
    def _check_open(self) -> None:
        if self._error is not None:
            raise RecordingError(f"{self.path}: writing failed: {self._error}")
        if self._closed:
            raise RecordingError(f"{self.path}: the recorder is closed")

    def write_log(
        self,
        data: FloatArray | LogRows,
        crane_tip_n: Sequence[float] | FloatArray | None = None,
        wire_length_m: float | None = None,
        docking: DockingFrame | None = None,
        wall: WallAnchors | None = None,
    ) -> None:
        """Record log rows (``LogRows`` or an (n, N_LOG) array in ``control.columns`` layout),
        later than every row recorded so far and in time order (else ValueError: a restarted
        simulation needs a new recorder). The rows kept go to the writer thread; this waits
        only when ``MAX_QUEUED`` batches are already waiting.

        ``crane_tip_n`` (NED, m), ``wire_length_m`` and ``docking``: None keeps the last value
        given; the wire is drawn and ``/wire`` written once a crane tip is known. ``wall``:
        (simulation time, wall clock [ns]) when the rows up to that time had been simulated,
        for a recorder of ``wall_log_times`` (ignored otherwise)."""
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
                self._crane_tip_n = _crane_tip(crane_tip_n).copy()
            if wire_length_m is not None:
                self._wire_length_m = float(wire_length_m)
            if docking is not None:
                self._docking = docking
            self._last_t_s = float(t[-1]) if len(t) else self._last_t_s
            batch = self._stream.keep(
                rows,
                t,
                self._crane_tip_n,
                self._wire_length_m,
                self._docking,
                wall if self.wall_log_times else None,
            )
            if batch is not None:
                self._put(batch)

    def event(
        self,
        t_s: float,
        kind: str,
        text: str,
        data: dict | None = None,
        wall_ns: int | None = None,
    ) -> None:
        """Record an event at simulation time ``t_s`` on ``/events`` (and ``/log`` for
        Foxglove's Log panel). ``kind``: e.g. leg, alarm, gains, landing. ``wall_ns``: when it
        happened on the wall clock (a recorder of ``wall_log_times`` logs it then; now when
        not given)."""
        if self.wall_log_times:
            wall_ns = time.time_ns() if wall_ns is None else int(wall_ns)
        else:
            wall_ns = None
        messages = self._stream.event_messages(t_s, kind, text, data, wall_ns)
        with self._lock:
            self._check_open()
            self._put(_Event(messages))

    def add_run(self, metadata: Mapping[str, Any]) -> str:
        """Record the set-up of a run started while recording (``session_metadata`` of the
        new run, its ``start_t_s`` on this recording's time axis) as the metadata record
        ``run.N`` (N = 2, 3, ...); returns the record's name. Readers take each run's
        mission, frame and current from these (``SessionData.runs``)."""
        try:
            values = {
                str(k): json.dumps(v, sort_keys=True, allow_nan=False) for k, v in metadata.items()
            }
        except (TypeError, ValueError) as err:
            raise ValueError(f"run metadata cannot be written as JSON: {err}") from None
        with self._lock:
            self._check_open()
            self.runs += 1
            name = f"{RUN_RECORD_PREFIX}{self.runs}"
            self._put(_Record(name, values))
        return name

    def flush(self) -> None:
        """Close the chunk in progress, write everything handed over so far and fsync, now
        (returns once it is on disk)."""
        done = threading.Event()
        with self._lock:
            self._check_open()
            self._put(_Flush(done))
        while not done.wait(0.1) and self._thread.is_alive():
            pass
        with self._lock:
            self._check_open()

    def _put(self, item: object) -> None:
        """Queue ``item``, waiting while the queue is full (never for a writer that ended)."""
        while True:
            try:
                self._queue.put(item, timeout=0.1)
                return
            except queue.Full:
                if not self._thread.is_alive():
                    raise RecordingError(f"{self.path}: the writer thread has ended") from None

    def close(self) -> None:
        """Write what is queued, the summary and footer, and close the file. Idempotent;
        raises ``RecordingError`` when the writer thread failed."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            with contextlib.suppress(RecordingError):  # a writer that ended needs no _CLOSE
                self._put(_CLOSE)
        self._thread.join()
        if self._error is not None:
            raise RecordingError(f"{self.path}: writing failed: {self._error}")

    def __enter__(self) -> SessionRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ the writer thread
    def _write_loop(self) -> None:
        """Write what comes off the queue; close the chunk, write and fsync every
        flush_interval_s of wall time while there is something new; finish at _CLOSE."""
        poll = min(self._flush_interval_s / 4.0, 0.1)
        last_sync, dirty = self._clock(), False
        try:
            while (item := self._next(poll)) is not _CLOSE:
                if self._error is None:  # after a failure the queue is only drained
                    try:
                        dirty = self._write_item(item) or dirty
                        if self._chunk_bytes >= CHUNK_BYTES:
                            self._close_chunk()
                        due = self._clock() - last_sync >= self._flush_interval_s
                        if isinstance(item, _Flush) or (dirty and due):
                            self._sync()
                            last_sync, dirty = self._clock(), False
                    except Exception as err:
                        self._error = err
                if isinstance(item, _Flush):
                    item.done.set()
        finally:
            self._finish()

    def _next(self, timeout_s: float) -> object:
        try:
            return self._queue.get(timeout=timeout_s)
        except queue.Empty:
            return None

    def _write_item(self, item: object) -> bool:
        """Write one queued item; True when it held messages."""
        if isinstance(item, RowBatch):
            self._write_rows(item)
            return True
        if isinstance(item, _Event):
            for topic, t_ns, data in item.messages:
                self._add(topic, t_ns, data)
            return True
        if isinstance(item, _Record):
            self._close_chunk()  # the rows before the record stay before it in the file
            self._writer.add_metadata(item.name, item.values)
            return True
        return False

    def _write_rows(self, batch: RowBatch) -> None:
        """Every message of a batch's kept rows, row by row in channel order."""
        for topic, t_ns, data in self._stream.row_messages(batch):
            self._add(topic, t_ns, data)

    def _add(self, topic: str, t_ns: int, data: bytes) -> None:
        self._chunk_bytes += len(data)
        self._sequence[topic] += 1
        self._writer.add_message(
            self._channels[topic],
            log_time=t_ns,
            publish_time=t_ns,
            data=data,
            sequence=self._sequence[topic],
        )

    def _close_chunk(self) -> None:
        """Close the chunk in progress and hand it to the operating system."""
        self._writer.flush()
        self._chunk_bytes = 0

    def _sync(self) -> None:
        """Close the chunk in progress, hand it to the operating system, fsync."""
        self._close_chunk()
        os.fsync(self._file.fileno())

    def _finish(self) -> None:
        """The summary and footer (unless writing failed), fsync'ed; the file closed."""
        try:
            if self._error is None:
                self._writer.finish()
                self._file.flush()
                os.fsync(self._file.fileno())
        except Exception as err:
            self._error = err
        finally:
            self._file.close()
