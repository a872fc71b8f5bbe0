"""Caps on the files browsers upload through the 3D view ("Upload mission file").

viser keeps every part of an upload in memory until the last part arrives, for any client,
before any callback of ours runs: a viewer that never entered the token could declare huge
files, send parts and never finish them (400 MB of parts raised the server's memory from 259
to 708 MB). ``UploadGuard`` stands in front of viser's two upload handlers of each browser and
refuses, before the token is asked for, a file larger than a mission file may be, more than
one unfinished upload a browser, unfinished uploads above ``MAX_IN_FLIGHT_BYTES`` over all
browsers, and parts beyond the declared size; then a browser that is not unlocked. What it
refuses is never buffered; what a browser leaves unfinished goes when it disconnects (viser
drops its parts; the guard forgets its share).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from missions.schema import MAX_FILE_BYTES

MAX_UPLOAD_BYTES = MAX_FILE_BYTES
"""Largest file a browser may upload [bytes]: a mission file (256 kB)."""
MAX_IN_FLIGHT_BYTES = 16 * MAX_UPLOAD_BYTES
"""Declared bytes of all unfinished uploads of all browsers together (4 MB)."""
VIEW_MESSAGE_MAX_BYTES = 1024 * 1024
"""Largest message a browser may send the view [bytes] (viser's own limit is 50 MB; an
upload part is at most 512 kB, the largest other message a few kB)."""


class UploadGuard:
    """The view's upload limits, over all browsers (thread-safe)."""

    def __init__(
        self, file_limit: int = MAX_UPLOAD_BYTES, total_limit: int = MAX_IN_FLIGHT_BYTES
    ) -> None:
        self.file_limit = file_limit
        self.total_limit = total_limit
        self.refused = 0
        """Uploads refused (and parts dropped)."""
        self._in_flight: dict[str, tuple[int, int]] = {}
        """transfer id -> (browser, declared bytes)"""
        self._lock = threading.Lock()

    @property
    def in_flight_bytes(self) -> int:
        with self._lock:
            return sum(size for _, size in self._in_flight.values())

    def guard(self, gui: Any, may_upload: Callable[[], bool], say: Callable[[str], None]) -> None:
        """Put the checks in front of viser's upload handlers of one browser's GUI (a
        ``viser.ClientHandle.gui``): ``may_upload`` tells whether it is unlocked, ``say``
        shows it why an upload was refused."""
        from viser import _messages  # viser's own message types (no public handle for these)

        interface = gui._websock_interface
        states: dict[str, Any] = gui._current_file_upload_states
        starts = interface._incoming_handlers.pop(_messages.FileTransferStartUpload, [])
        parts = interface._incoming_handlers.pop(_messages.FileTransferPart, [])

        def on_start(client_id: int, message: Any) -> None:
            why = self._admit(client_id, message, states, may_upload)
            if why:
                self.refused += 1
                say(f"upload refused: {why}")
                return
            for handler in starts:
                handler(client_id, message)
            self._forget_finished(message.transfer_uuid, states)

        def on_part(client_id: int, message: Any) -> None:
            state = states.get(message.transfer_uuid)
            with self._lock:
                ours = message.transfer_uuid in self._in_flight
            if state is None or not ours:
                return
            if state["transferred_bytes"] + len(message.content) > state["total_bytes"]:
                states.pop(message.transfer_uuid, None)  # more than it declared: dropped
                self._forget(message.transfer_uuid)
                self.refused += 1
                say("upload refused: the file is larger than it said")
                return
            for handler in parts:
                handler(client_id, message)
            self._forget_finished(message.transfer_uuid, states)

        interface.register_handler(_messages.FileTransferStartUpload, on_start)
        interface.register_handler(_messages.FileTransferPart, on_part)

    def _admit(
        self,
        client_id: int,
        message: Any,
        states: dict[str, Any],
        may_upload: Callable[[], bool],
    ) -> str:
        """'' when the upload may begin (and its size is reserved), else why not."""
        size, count = message.size_bytes, message.part_count
        if not 0 <= size <= self.file_limit:
            return f"a mission file has at most {self.file_limit} bytes"
        if not (0 <= count <= size and (count > 0) == (size > 0)):
            return "malformed upload"
        with self._lock:
            mine = [t for t, (who, _) in self._in_flight.items() if who == client_id]
            for transfer in mine:  # a browser's unfinished upload gives way to its next one
                self._in_flight.pop(transfer)
                states.pop(transfer, None)
            total = sum(s for _, s in self._in_flight.values())
            if total + size > self.total_limit:
                return "the console is receiving too many files now; try again shortly"
            if not may_upload():
                return "locked: enter the console token under Access"
            self._in_flight[message.transfer_uuid] = (client_id, size)
        return ""

    def _forget_finished(self, transfer: str, states: dict[str, Any]) -> None:
        if transfer not in states:  # finished (or dropped by viser)
            self._forget(transfer)

    def _forget(self, transfer: str) -> None:
        with self._lock:
            self._in_flight.pop(transfer, None)

    def forget_client(self, client_id: int) -> None:
        """A browser left: its unfinished uploads no longer count (viser drops their parts)."""
        with self._lock:
            for transfer in [t for t, (who, _) in self._in_flight.items() if who == client_id]:
                self._in_flight.pop(transfer)
