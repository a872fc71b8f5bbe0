"""Reading a session: ``load_session``, ``check_session`` and ``SessionData``.

The file is scanned record by record; the reader stops at the first record that is cut off or
damaged and returns everything before it, with ``complete=False`` and where it stopped. Reading
never changes the file.

Since format 3 ``/session/log`` holds only the columns no plot channel carries exactly; the
reader puts each row back together from it and the plot messages of the same log time (the
channel's ``carried`` metadata says where each other column is), so ``rows`` are whole rows
whichever format the file has.

The rows are read by block name whatever layout they were recorded in: ``data.log`` is a
``LogRows`` over the file's own columns (``Layout.from_names``), so ``data.log["tree_eta_n"]``
works on files written before the log row was declared in ``control.columns`` too.
"""

from __future__ import annotations

import io
import json
import math
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import zstandard
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Header, Message, Metadata, Schema, Statistics
from mcap.stream_reader import StreamReader, breakup_chunk
from numpy.typing import NDArray

from app.recording.channels import (
    COLUMNS,
    EVENTS_TOPIC,
    RUN_RECORD_PREFIX,
    SESSION_TOPIC,
    SETUP_RECORD,
)
from control.columns import M_MAX, Layout, LogRows

FloatArray = NDArray[np.float64]

MCAP_MAGIC = bytes([137, 77, 67, 65, 80, 48, 13, 10])


@dataclass(frozen=True)
class SessionData:
    """A session log as read back (complete or cut off)."""

    metadata: dict
    """The setup record, decoded."""
    columns: list[str]
    """Flat names of the row's columns, as recorded."""
    t_s: FloatArray
    """(n,) simulation time of each row [s]."""
    rows: FloatArray
    """(n, len(columns)) the whole rows (``/session/log`` and, since format 3, the columns
    the plot channels carry), in the recorded column order."""
    events: list[dict]
    complete: bool
    """Footer present and every record intact."""
    message_counts: dict[str, int]
    end_time_s: float
    """Latest message time [s] (nan when there is none)."""
    file_bytes: int = 0
    intact_bytes: int = 0
    """Bytes of whole, valid records from the start; the rest is cut off or damaged."""
    problem: str = ""
    """Why the file is not complete ('' when it is)."""
    runs: list[dict] = field(default_factory=list)
    """The set-up of each run in the file, in order: the ``setup`` record's keys, then each
    ``run.N`` record's (a run started while recording); ``start_t_s`` is where each starts on
    the recording's time axis. Empty for a file with no setup record."""

    def run_index_at(self, t_s: float) -> int:
        """Index in ``runs`` of the run going on at recording time ``t_s`` (0 before the
        second starts, and for a file with no runs)."""
        here = 0
        for k, run in enumerate(self.runs[1:], start=1):
            start = run.get("start_t_s")
            if isinstance(start, int | float) and start <= t_s + 1e-9:
                here = k
        return here

    def run_offset_s(self, index: int) -> float:
        """What run ``index``'s own clock (the simulation time the console showed) is behind
        the recording's time axis [s]: its ``time_offset_s`` (0 for the first run, and for a
        file that does not record it)."""
        run = self.runs[index] if 0 <= index < len(self.runs) else {}
        offset = run.get("time_offset_s", 0.0)
        return float(offset) if isinstance(offset, int | float) and math.isfinite(offset) else 0.0

    def run_time_s(self, t_s: float) -> float:
        """Recording time ``t_s`` on the clock of the run going on then [s]."""
        return t_s - self.run_offset_s(self.run_index_at(t_s))

    def run_at(self, t_s: float) -> dict:
        """The set-up of the run going on at recording time ``t_s`` (the first run before it
        starts; the setup record when the file has no runs)."""
        return self.runs[self.run_index_at(t_s)] if self.runs else self.metadata

    @property
    def n_thrusters(self) -> int:
        """Thrusters of the recorded ROV (the recorder's metadata; M_MAX when unknown)."""
        recorder = self.metadata.get("recorder")
        n = recorder.get("n_thrusters") if isinstance(recorder, dict) else None
        return int(n) if isinstance(n, int) and 1 <= n <= M_MAX else M_MAX

    @cached_property
    def log(self) -> LogRows:
        """The rows read by block name (``log["tree_eta_n"]`` is (n, 6)), laid out as recorded;
        a block the file does not hold raises KeyError naming the blocks it has."""
        return LogRows(self.rows, self.n_thrusters, layout=Layout.from_names(self.columns))


@dataclass
class FileScan:
    """Everything found in the intact part of a file."""

    file_bytes: int
    intact_bytes: int = 8
    complete: bool = False
    problem: str = ""
    header: Header | None = None
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    messages: dict[str, list[Message]] = field(default_factory=dict)
    in_order: list[Message] = field(default_factory=list)
    """Every message, in the order of the file."""
    statistics: Statistics | None = None

    def channels_in_order(self) -> list[Channel]:
        return sorted(self.channels.values(), key=lambda c: c.id)


_READ_ERRORS = (McapError, ValueError, struct.error, zstandard.ZstdError, EOFError)


def _record_spans(buf: bytes) -> Iterator[tuple[int, int, int]]:
    """(start, end, opcode) of each whole top-level record after the magic."""
    pos = len(MCAP_MAGIC)
    while pos + 9 <= len(buf):
        opcode = buf[pos]
        (length,) = struct.unpack_from("<Q", buf, pos + 1)
        end = pos + 9 + length
        if end > len(buf):
            return
        yield pos, end, opcode
        pos = end


def _parse_record(buf: bytes, start: int, end: int) -> list:
    """The record at buf[start:end], a chunk broken up into its records (CRC checked)."""
    reader = StreamReader(
        io.BytesIO(buf[start:end]), skip_magic=True, emit_chunks=True, validate_crcs=True
    )
    record = next(iter(reader.records))
    if isinstance(record, Chunk):
        return breakup_chunk(record, validate_crc=True)
    return [record]


def _take(scan: FileScan, record: object) -> None:
    if isinstance(record, Header):
        scan.header = record
    elif isinstance(record, Schema):
        scan.schemas[record.id] = record
    elif isinstance(record, Channel):
        scan.channels[record.id] = record
    elif isinstance(record, Metadata):
        scan.metadata[record.name] = dict(record.metadata)
    elif isinstance(record, Message):
        channel = scan.channels.get(record.channel_id)
        if channel is None:
            raise ValueError(f"message on unknown channel {record.channel_id}")
        scan.messages.setdefault(channel.topic, []).append(record)
        scan.in_order.append(record)
    elif isinstance(record, Statistics):
        scan.statistics = record


def scan_file(path: Path) -> FileScan:
    """Read every intact record; stop at the first cut-off or damaged one."""
    try:
        buf = path.read_bytes()
    except OSError as err:
        raise ValueError(f"{path}: cannot read: {err.strerror or err}") from None
    if buf[: len(MCAP_MAGIC)] != MCAP_MAGIC:
        what = "empty" if not buf else "does not start with the MCAP magic bytes"
        raise ValueError(f"{path}: not an MCAP file ({what})")
    scan = FileScan(file_bytes=len(buf))
    _scan_records(buf, scan)
    if scan.header is None:
        raise ValueError(
            f"{path}: MCAP file without a readable header record "
            f"({len(buf)} bytes): {scan.problem or 'nothing to read'}"
        )
    return scan


def _scan_records(buf: bytes, scan: FileScan) -> None:
    """Fill ``scan`` from the records of ``buf`` up to the footer or the first bad record."""
    known = {int(op) for op in Opcode}
    for start, end, opcode in _record_spans(buf):
        if opcode not in known:  # a newer writer's record: skipped, as the MCAP spec asks
            scan.intact_bytes = end
            continue
        try:
            for record in _parse_record(buf, start, end):
                _take(scan, record)
        except _READ_ERRORS as err:
            scan.problem = f"damaged record (opcode {opcode:#04x}) at byte {start}: {err}"
            return
        scan.intact_bytes = end
        if opcode == Opcode.FOOTER:
            scan.complete = buf[end:] == MCAP_MAGIC
            if scan.complete:
                scan.intact_bytes = len(buf)
            else:
                scan.problem = f"footer at byte {start} is not followed by the closing magic"
            return
    scan.problem = (
        f"cut off at byte {scan.intact_bytes} of {len(buf)}: no footer "
        "(the writer did not finish: killed or still writing)"
    )


def _check_statistics(scan: FileScan) -> None:
    """A complete file's statistics must agree with the messages read."""
    if not scan.complete or scan.statistics is None:
        return
    for cid, n in scan.statistics.channel_message_counts.items():
        topic = scan.channels[cid].topic if cid in scan.channels else f"#{cid}"
        if len(scan.messages.get(topic, [])) != n:
            scan.complete = False
            scan.problem = (
                f"statistics say {n} messages on {topic}, found {len(scan.messages.get(topic, []))}"
            )


def _decode_record(record: dict[str, str]) -> dict:
    out = {}
    for key, text in record.items():
        try:
            out[key] = json.loads(text)
        except json.JSONDecodeError:
            out[key] = text
    return out


def _decode_setup(scan: FileScan) -> dict:
    return _decode_record(scan.metadata.get(SETUP_RECORD, {}))


def _decode_runs(scan: FileScan, setup: dict) -> list[dict]:
    """The setup record, then the ``run.N`` records in the order of N."""

    def number(name: str) -> int:
        tail = name.removeprefix(RUN_RECORD_PREFIX)
        return int(tail) if tail.isdigit() else 0

    later = sorted(
        (name for name in scan.metadata if name.startswith(RUN_RECORD_PREFIX) and number(name)),
        key=number,
    )
    first = [setup] if setup else []
    return first + [_decode_record(scan.metadata[name]) for name in later]


def _session_channel_metadata(scan: FileScan) -> dict[str, str]:
    for ch in scan.channels.values():
        if ch.topic == SESSION_TOPIC:
            return dict(ch.metadata)
    return {}


@dataclass(frozen=True)
class RowSources:
    """Where each column of the recorded row is: on ``/session/log`` or on a plot channel."""

    columns: list[str]
    """The row's flat names, in row order."""
    written: list[str]
    """The columns ``/session/log`` holds, in its order (all of them before format 3)."""
    carried: dict[str, tuple[str, str]]
    """Column -> (topic, field) of the plot channel holding it (empty before format 3)."""


def _row_sources(path: Path | str, setup: dict, scan: FileScan) -> RowSources:
    meta = _session_channel_metadata(scan)
    written = json.loads(meta["columns"]) if "columns" in meta else None
    carried = {
        str(k): (str(v[0]), str(v[1])) for k, v in json.loads(meta.get("carried", "{}")).items()
    }
    fallback = written if written is not None and not carried else COLUMNS
    columns = list(setup.get("columns") or fallback)
    written = columns if written is None else list(written)
    if carried:
        unknown = sorted((set(written) | set(carried)) ^ set(columns))
        if unknown or len(written) + len(carried) != len(columns):
            raise ValueError(
                f"{path}: {SESSION_TOPIC} and its carried columns do not make up the "
                f"recorded row (differ in {', '.join(unknown) or 'duplicates'})"
            )
    return RowSources(columns, written, carried)


def _rebuilt_rows(scan: FileScan, written_rows: FloatArray, sources: RowSources) -> FloatArray:
    """The whole rows: ``/session/log``'s columns, and each carried column from the message of
    its plot channel with the same log time (NaN where that message is missing)."""
    msgs = scan.messages.get(SESSION_TOPIC, [])
    where = {c: i for i, c in enumerate(sources.columns)}
    rows = np.full((len(msgs), len(sources.columns)), math.nan)
    rows[:, [where[c] for c in sources.written]] = written_rows
    by_topic: dict[str, list[tuple[int, str]]] = {}
    for column, (topic, name) in sources.carried.items():
        by_topic.setdefault(topic, []).append((where[column], name))
    for topic, fields in by_topic.items():
        at_time = {m.log_time: m for m in scan.messages.get(topic, [])}
        for i, m in enumerate(msgs):
            other = at_time.get(m.log_time)
            if other is None:
                continue
            values = json.loads(other.data)
            for k, name in fields:
                v = values.get(name)
                rows[i, k] = math.nan if v is None else v
    return rows


def _rows(messages: list[Message], width: int) -> FloatArray:
    """(n, width) rows of ``/session/log`` messages (null read as NaN)."""
    rows = np.empty((len(messages), width))
    for i, m in enumerate(messages):
        values = json.loads(m.data)["row"]
        if len(values) != width:
            raise ValueError(
                f"{SESSION_TOPIC} message {i} has {len(values)} values for {width} columns"
            )
        rows[i] = [math.nan if v is None else v for v in values]
    return rows


def time_origin_ns(setup: dict) -> int:
    """Log time of simulation time zero in a file (0 for files before it was recorded)."""
    recorder = setup.get("recorder")
    value = recorder.get("time_origin_ns", 0) if isinstance(recorder, dict) else 0
    return int(value) if isinstance(value, int | float) else 0


def wall_log_times(setup: dict) -> bool:
    """Whether a file's log times are the wall clock's (a console's recording since issue 47:
    when each row was simulated, each event happened), not its origin plus simulation time."""
    recorder = setup.get("recorder")
    return isinstance(recorder, dict) and recorder.get("log_time") == "wall"


def simulation_times(scan: FileScan, t_s: FloatArray) -> dict[int, float]:
    """Simulation time [s] of each log time of a file of wall-clock log times: a row's (all
    its channels share one log time; ``t_s``: the rows', in ``/session/log``'s order) and an
    event's."""
    session = scan.messages.get(SESSION_TOPIC, [])
    out = {m.log_time: float(t) for m, t in zip(session, t_s, strict=True)}
    for m in scan.messages.get(EVENTS_TOPIC, []):
        t = json.loads(m.data).get("t_s")
        if isinstance(t, int | float):
            out.setdefault(m.log_time, float(t))
    return out


def read_scan(path: str | Path) -> tuple[FileScan, SessionData]:
    """The raw scan of a file and what it holds (for check_session and export_csv)."""
    scan = scan_file(Path(path))
    _check_statistics(scan)
    setup = _decode_setup(scan)
    sources = _row_sources(path, setup, scan)
    columns = sources.columns
    layout = Layout.from_names(columns)
    if not layout.has("t_s"):
        raise ValueError(f"{path}: the recorded columns have no t_s")
    rows = _rows(scan.messages.get(SESSION_TOPIC, []), len(sources.written))
    if sources.carried:
        rows = _rebuilt_rows(scan, rows, sources)
    events = [json.loads(m.data) for m in scan.messages.get(EVENTS_TOPIC, [])]
    t_s = layout.take(rows, "t_s").copy()
    if wall_log_times(setup):
        times = [float(t) for t in t_s if math.isfinite(t)]
        times += [float(e["t_s"]) for e in events if isinstance(e.get("t_s"), int | float)]
        end_s = max(times) if times else math.nan
    else:
        ends = [m.log_time for msgs in scan.messages.values() for m in msgs]
        end_s = (max(ends) - time_origin_ns(setup)) / 1e9 if ends else math.nan
    data = SessionData(
        metadata=setup,
        columns=columns,
        t_s=t_s,
        rows=rows,
        events=events,
        complete=scan.complete,
        message_counts={t: len(m) for t, m in sorted(scan.messages.items())},
        end_time_s=end_s,
        file_bytes=scan.file_bytes,
        intact_bytes=scan.intact_bytes,
        problem=scan.problem,
        runs=_decode_runs(scan, setup),
    )
    return scan, data


def load_session(path: str | Path) -> SessionData:
    """Read a session log, complete or cut off (up to its last intact record).

    Raises ValueError naming the file when it is not an MCAP file at all."""
    return read_scan(path)[1]


def _channel_report(
    scan: FileScan, ch: Channel, origin: int, sim_at: dict[int, float] | None = None
) -> dict:
    """A channel's counts and simulation-time range [s] (``sim_at``: the simulation time of
    each log time, for a file of wall-clock log times)."""
    msgs = scan.messages.get(ch.topic, [])
    schema = scan.schemas.get(ch.schema_id)

    def sim_s(log_time: int) -> float | None:
        if sim_at is None:
            return (log_time - origin) / 1e9
        return sim_at.get(log_time)

    return {
        "topic": ch.topic,
        "schema": schema.name if schema else "",
        "encoding": ch.message_encoding,
        "messages": len(msgs),
        "first_s": sim_s(min(m.log_time for m in msgs)) if msgs else None,
        "last_s": sim_s(max(m.log_time for m in msgs)) if msgs else None,
    }


def check_session(path: str | Path) -> dict:
    """What a file holds: status, where it stops, channels with counts, time range, metadata.

    Raises ValueError naming the file when it is not an MCAP file at all."""
    scan, data = read_scan(path)
    origin = time_origin_ns(data.metadata)
    sim_at = simulation_times(scan, data.t_s) if wall_log_times(data.metadata) else None
    channels = [_channel_report(scan, ch, origin, sim_at) for ch in scan.channels_in_order()]
    starts = [c["first_s"] for c in channels if c["first_s"] is not None]
    return {
        "file": str(path),
        "status": "complete" if data.complete else "truncated",
        "complete": data.complete,
        "problem": data.problem,
        "file_bytes": data.file_bytes,
        "intact_bytes": data.intact_bytes,
        "writer": scan.header.library if scan.header else "",
        "time_range_s": [min(starts), data.end_time_s] if starts else None,
        "rows": len(data.rows),
        "events": len(data.events),
        "metadata_records": sorted(scan.metadata),
        "metadata_keys": sorted(data.metadata),
        "channels": channels,
    }
