"""The running session, live, for Foxglove and Lichtblick: ``serve --foxglove-port PORT``.

The server is the Foxglove SDK's own (``foxglove-sdk``: the WebSocket protocol
``foxglove.websocket.v1``, kept by Foxglove), not ours. It advertises the channels a recording
has, with the same JSON schemas (``app.recording.stream.SessionStream``), and sends the same
messages a recording holds: the plot channels, ``/tf``, ``/scene``, ``/wire``,
``/session/log``, ``/events`` and ``/log``. A Foxglove layout made for a recording works live.

Read-only: no capability that lets a client publish, set parameters or call services is
advertised, and the console's controls are not reachable through it. It binds to loopback
unless the console itself is allowed to serve remote hosts (``--allow-remote``).

The paced loop only hands rows over (``rows``: a bounded queue, the oldest hand-over dropped
when a slow reader falls behind); a thread of its own decimates, encodes and sends them, and
does nothing but decimate while no client is subscribed. The rows are decimated as a
recording's are (20 Hz and 5 Hz of simulated time), and at most ``WALL_RATE_HZ`` hand-overs a
wall-clock second are sent: fast-forwarded, a live view shows the newest rows, not all.
"""

from __future__ import annotations

import queue
import threading
import time
from dataclasses import dataclass

import numpy as np

from app.recording.messages import json_bytes
from app.recording.stream import SessionStream
from control.columns import LAYOUT
from sim.docking import DockingFrame
from sim.params import ParameterSet

NUMERIC_RATE_HZ = 20.0
"""As a recording's (``SessionRecorder``'s default), in simulated time."""
SCENE_RATE_HZ = 5.0
WALL_RATE_HZ = 20.0
"""Batches of rows sent a wall-clock second at most: at 50x the recording's rates would be
13 000 messages a second, more than a viewer draws or a socket should carry; a live view
takes the newest rows of each 1/20 s and drops the rest (a recording keeps them all)."""
MAX_QUEUED = 32
"""Hand-overs waiting for the sending thread at most (the console hands over a tick's rows,
some 0.01-0.5 s of simulation each); the oldest is dropped beyond."""


@dataclass(frozen=True)
class _Rows:
    rows: np.ndarray
    crane_tip_n: np.ndarray
    wire_length_m: float
    docking: DockingFrame | None
    wall_ns: int
    """When they were handed over: the wall clock had simulated up to their last row."""


@dataclass(frozen=True)
class _Event:
    t_s: float
    kind: str
    text: str
    data: dict | None
    wall_ns: int


@dataclass(frozen=True)
class _NewRun:
    params: ParameterSet
    n_thrusters: int
    origin_ns: int


class LiveFeed:
    """A Foxglove WebSocket server on ``host:port`` sending the session's channels."""

    def __init__(
        self,
        params: ParameterSet,
        n_thrusters: int,
        origin_ns: int,
        port: int,
        host: str = "127.0.0.1",
        name: str = "rov-console",
    ) -> None:
        import foxglove  # the SDK loads its native library: only when asked for

        self._foxglove = foxglove
        self._context = foxglove.Context()
        self._channels: dict[str, foxglove.Channel] = {}
        self._stream = self._open_channels(params, n_thrusters, origin_ns)
        self._server = foxglove.start_server(
            name=name, host=host, port=port, context=self._context, capabilities=[]
        )
        self.port = int(self._server.port)
        self._queue: queue.Queue[object] = queue.Queue(MAX_QUEUED)
        self._closed = threading.Event()
        self.dropped = 0
        """Hand-overs dropped because the sending thread fell behind."""
        self._last_sent = -float("inf")
        self._anchor: tuple[float, int] | None = None
        """(simulation time [s], wall clock [ns]) of the last hand-over."""
        self._thread = threading.Thread(target=self._send_loop, name="foxglove-live", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ the loop's side
    def rows(
        self,
        rows: np.ndarray,
        crane_tip_n: np.ndarray,
        wire_length_m: float,
        docking: DockingFrame | None,
    ) -> None:
        """Hand over a tick's log rows (never waits)."""
        crane = np.asarray(crane_tip_n, float).copy()
        self._put(_Rows(rows, crane, wire_length_m, docking, time.time_ns()))

    def event(self, t_s: float, kind: str, text: str, data: dict | None = None) -> None:
        self._put(_Event(t_s, kind, text, dict(data) if data else None, time.time_ns()))

    def new_run(self, params: ParameterSet, n_thrusters: int, origin_ns: int) -> None:
        """A new run: its time starts again, its thrusters may differ (channels renewed)."""
        self._put(_NewRun(params, n_thrusters, origin_ns))

    def close(self) -> None:
        self._closed.set()
        self._thread.join(timeout=5.0)
        self._server.stop()

    def _put(self, item: object) -> None:
        if self._closed.is_set():
            return
        while True:
            try:
                self._queue.put_nowait(item)
                return
            except queue.Full:
                try:
                    self._queue.get_nowait()
                    self.dropped += 1
                except queue.Empty:
                    pass

    # ------------------------------------------------------------------ the sending thread
    def _open_channels(
        self, params: ParameterSet, n_thrusters: int, origin_ns: int
    ) -> SessionStream:
        stream = SessionStream(params, n_thrusters, NUMERIC_RATE_HZ, SCENE_RATE_HZ, origin_ns)
        specs = stream.channels()
        wanted = {spec.topic for spec in specs}
        for topic in [t for t in self._channels if t not in wanted]:
            self._channels.pop(topic).close()
        for spec in specs:
            old = self._channels.pop(spec.topic, None)
            if old is not None:
                old.close()
            self._channels[spec.topic] = self._foxglove.Channel(
                spec.topic,
                schema=self._foxglove.Schema(
                    name=str(spec.schema["title"]),
                    encoding="jsonschema",
                    data=json_bytes(spec.schema),
                ),
                message_encoding="json",
                context=self._context,
                metadata=spec.metadata,
            )
        return stream

    def _watched(self) -> bool:
        return any(ch.has_sinks() for ch in self._channels.values())

    def _send_loop(self) -> None:
        while not self._closed.is_set():
            try:
                item = self._queue.get(timeout=0.1)
            except queue.Empty:
                continue
            try:
                self._send(item)
            except Exception:  # a live view must never stop the console: drop what failed
                self.dropped += 1

    def _send(self, item: object) -> None:
        if isinstance(item, _NewRun):
            self._stream = self._open_channels(item.params, item.n_thrusters, item.origin_ns)
            self._anchor = None
            return
        if isinstance(item, _Event):
            messages = self._stream.event_messages(
                item.t_s, item.kind, item.text, item.data, wall_ns=item.wall_ns
            )
        else:
            assert isinstance(item, _Rows)
            t = LAYOUT.take(item.rows, "t_s")
            # log times: the wall clock when the rows were simulated, as a console
            # recording's (between the hand-over before and this one)
            anchor = (float(t[-1]), item.wall_ns)
            wall = [self._anchor, anchor] if self._anchor is not None else [anchor]
            self._anchor = anchor
            batch = self._stream.keep(
                item.rows, t, item.crane_tip_n, item.wire_length_m, item.docking, wall
            )
            if batch is None or not self._watched():
                return
            now = time.monotonic()
            if now - self._last_sent < 1.0 / WALL_RATE_HZ:
                return
            self._last_sent = now
            messages = list(self._stream.row_messages(batch))
        for topic, t_ns, data in messages:
            self._channels[topic].log(data, log_time=t_ns)
