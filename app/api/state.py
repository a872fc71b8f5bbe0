"""The present state, once (GET) or as a stream (WebSocket); watching needs no token."""

from __future__ import annotations

import asyncio
import contextlib

from fastapi import APIRouter, Query, WebSocket, WebSocketDisconnect

from app.api.deps import SnapshotDep
from app.api.guards import MAX_TELEMETRY_CLIENTS, websocket_origin_allowed
from app.api.schemas import StateOut
from app.console import Console

router = APIRouter(prefix="/api", tags=["state"])
SEND_TIMEOUT_S = 5.0
"""A client that takes longer than this to accept one message is dropped."""


@router.get("/state", response_model=StateOut)
def state(snapshot: SnapshotDep) -> StateOut:
    """Simulation time, tree and ROV pose (degrees), controller mode, mission leg, alarms."""
    return StateOut.of(snapshot)


class StateJsonCache:
    """The JSON text of the latest snapshot, built once however many clients listen."""

    def __init__(self) -> None:
        self._seq = -1
        self._text = ""

    def text(self, console: Console) -> tuple[int, str]:
        snap = console.loop.snapshot
        if snap.seq != self._seq:
            self._text = StateOut.of(snap).model_dump_json()
            self._seq = snap.seq
        return self._seq, self._text


@router.websocket("/telemetry")
async def telemetry(
    websocket: WebSocket, rate_hz: float = Query(default=20.0, ge=0.5, le=100.0)
) -> None:
    """Stream of state messages (the body of GET /api/state) at up to ``rate_hz``. Each client
    gets the newest state when it is ready for one: a slow client skips states, it never
    holds up the loop or the other clients."""
    console: Console = websocket.app.state.console
    cache: StateJsonCache = websocket.app.state.state_cache
    state = websocket.app.state
    if not websocket_origin_allowed(websocket):
        await websocket.close(code=1008, reason="origin not allowed")  # policy violation
        return
    if state.telemetry_clients >= MAX_TELEMETRY_CLIENTS:
        await websocket.accept()  # then close with a reason the client can read: try later
        await websocket.close(code=1013, reason="too many telemetry clients")
        return
    state.telemetry_clients += 1
    try:
        await _stream(websocket, console, cache, rate_hz)
    finally:
        state.telemetry_clients -= 1


async def _stream(
    websocket: WebSocket, console: Console, cache: StateJsonCache, rate_hz: float
) -> None:
    await websocket.accept()
    receiver = asyncio.create_task(_drain_incoming(websocket))
    last = -1
    try:
        while not receiver.done():
            seq, text = cache.text(console)
            if seq != last:
                await asyncio.wait_for(websocket.send_text(text), SEND_TIMEOUT_S)
                last = seq
            # wait one send period, or less if the client goes: its place is free at once
            await asyncio.wait({receiver}, timeout=1.0 / rate_hz)
    except (TimeoutError, WebSocketDisconnect, RuntimeError, OSError):
        pass
    finally:
        receiver.cancel()
        with contextlib.suppress(Exception):
            await websocket.close()


async def _drain_incoming(websocket: WebSocket) -> None:
    """Read (and ignore) what the client sends, to notice when it goes away."""
    with contextlib.suppress(WebSocketDisconnect, RuntimeError):
        while True:
            await websocket.receive_text()
