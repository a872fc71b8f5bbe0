"""The pilot page (GET /pilot) and its WebSocket (/api/pilot): flying the ROV by hand with
the keyboard or a gamepad.

viser's page cannot pass keys or gamepads to the server (its client uses keys only for its own
pointer modifiers), so the console serves a small page of its own beside it, which embeds the
3D view and reads the keyboard and the browser's Gamepad API.

Protocol (JSON text messages). The page opens the socket and first sends
``{"type": "hello", "token": ..., "name": ...}``; a wrong token, a bad name or a second pilot
gets ``{"type": "error", "message": ...}`` and the socket closes. Then:

- ``{"type": "demand", "surge": s, "sway": s, "heave": s, "yaw": s}`` (each in [-1, 1]), sent
  every 50 ms and on every key change;
- ``{"type": "holds", "heading": bool, "depth": bool}``;
- ``{"type": "mode", "pilot": bool}`` (take over / hand back to the autopilot).

The console answers each with ``{"type": "status", "status": {...}}`` (or an error message)
and sends the status every 0.1 s. When nothing arrives for ``DEMAND_TIMEOUT_S`` or the socket
closes, the demand goes to zero.
"""

from __future__ import annotations

import asyncio
import contextlib
from pathlib import Path
from typing import Any

from fastapi import APIRouter, Request, WebSocket, WebSocketDisconnect
from fastapi.responses import HTMLResponse

from app.api.guards import websocket_origin_allowed
from app.api.stations import COMMAND_TIMEOUT_S, Refused, read_hello, read_message, refuse, send
from app.console import PILOT_VIEW_PATH, Console, ConsoleError, Snapshot
from app.console.pilot import (
    DEMAND_TIMEOUT_S,
    PilotConnected,
    PilotDemand,
    PilotDisconnected,
    PilotHolds,
    PilotTakeOver,
    compass_heading_deg,
    pilot_name,
)
from app.console.snapshot import advice_line

router = APIRouter(tags=["pilot"])
PAGE = (Path(__file__).parent / "pilot_page.html").read_text(encoding="utf-8")
STATUS_PERIOD_S = 0.1


@router.get("/pilot", response_class=HTMLResponse)
def pilot_page(request: Request) -> HTMLResponse:
    """The pilot's page: the 3D view beside the pilot's readout; keys and gamepad fly."""
    view = request.app.state.view
    port = view.port if view is not None else 0  # 0: the page says the 3D view is off
    page = PAGE.replace("__VIEW_PORT__", str(port)).replace("__VIEW_PATH__", PILOT_VIEW_PATH)
    return HTMLResponse(page)


async def _command(console: Console, command: object, who: str) -> Any:
    future = console.loop.submit(command, who)  # type: ignore[arg-type]
    return await asyncio.wait_for(asyncio.wrap_future(future), COMMAND_TIMEOUT_S)


def snapshot_status(snap: Snapshot, last: dict[str, Any]) -> dict[str, Any]:
    """The published state ``snap``, with the holds and demand the loop last confirmed, and
    a dock leg's advice to move the vessel (the pilot cannot apply it: the console's operator
    does, as the sea trial's crew asked the captain)."""
    rov = snap.rov_eta_n
    return {
        **last,
        "mode": snap.mode,
        "heading_deg": compass_heading_deg(float(rov[5])),
        "depth_m": rov[2],
        "t_s": snap.t_s,
        "vessel_advice": advice_line(snap),
    }


async def _sign_in(websocket: WebSocket, console: Console) -> str:
    """The pilot's name once the hello checks out, else Refused with the reason."""
    hello, token, client = await read_hello(websocket)
    ok, wait = console.check_token(token, client)
    if wait > 0.0:
        raise Refused(f"too many wrong tokens from this client: try again in {wait:.0f} s")
    if not ok:
        raise Refused("wrong token: flying needs the console token (printed at start-up)")
    try:
        return pilot_name(hello.get("name"))
    except ValueError as err:
        raise Refused(str(err)) from None


def _parse(text: str) -> object:
    """One message from the page as a command, or ValueError saying what is wrong."""
    m: Any = read_message(text)
    kind = m.get("type") if isinstance(m, dict) else None
    if kind == "demand":
        return PilotDemand(*(m.get(axis, 0.0) for axis in ("surge", "sway", "heave", "yaw")))
    if kind == "holds":
        return PilotHolds(m.get("heading"), m.get("depth"))
    if kind == "mode":
        return PilotTakeOver(m.get("pilot"))
    raise ValueError("message type must be demand, holds or mode")


@router.websocket("/api/pilot")
async def pilot_socket(websocket: WebSocket) -> None:
    """Fly by hand (see the module's protocol)."""
    state = websocket.app.state
    console: Console = state.console
    if not websocket_origin_allowed(websocket):
        await websocket.close(code=1008, reason="origin not allowed")
        return
    await websocket.accept()
    try:
        name = await _sign_in(websocket, console)
        flying = state.pilot_name
        if flying is not None:
            raise Refused(f"{flying} is flying: one pilot at a time")
    except Refused as err:
        await refuse(websocket, str(err))
        return
    except WebSocketDisconnect:
        return
    state.pilot_name = name
    who = f"pilot ({name})"
    reason = "page closed"
    try:
        last = await _command(console, PilotConnected(), who)
        await send(websocket, {"type": "welcome", "name": name, "status": last})
        reason = await _fly(websocket, console, who, last)
    except (WebSocketDisconnect, RuntimeError, OSError, TimeoutError):
        reason = "connection lost"
    finally:
        state.pilot_name = None
        with contextlib.suppress(Exception):
            console.loop.submit(PilotDisconnected(reason), who)
        with contextlib.suppress(Exception):
            await websocket.close()


def newest_stick_wins(commands: list[object]) -> list[object]:
    """The commands to apply of those that arrived since the last tick, in their order,
    with every stick but the newest dropped: a stick replaces the one before, so a page
    that sends faster than the loop ticks (a gamepad at 400 Hz) never builds a queue of
    stale sticks, and letting go applies on the next tick. Holds and take-overs are kept."""
    last = max((i for i, c in enumerate(commands) if isinstance(c, PilotDemand)), default=-1)
    return [c for i, c in enumerate(commands) if i == last or not isinstance(c, PilotDemand)]


async def _fly(websocket: WebSocket, console: Console, who: str, last: dict[str, Any]) -> str:
    """Apply the page's messages until it goes; returns why it went. A reader takes every
    message as it comes; each round applies what arrived meanwhile (``newest_stick_wins``)."""
    status = dict(last)
    inbox: list[str] = []
    arrived = asyncio.Event()

    async def report() -> None:
        with contextlib.suppress(WebSocketDisconnect, RuntimeError, OSError, TimeoutError):
            while True:
                await asyncio.sleep(STATUS_PERIOD_S)
                snap_status = snapshot_status(console.loop.snapshot, status)
                await send(websocket, {"type": "status", "status": snap_status})

    async def read() -> None:
        while True:
            inbox.append(await websocket.receive_text())
            arrived.set()

    reporter = asyncio.create_task(report())
    reader = asyncio.create_task(read())
    silent = False
    try:
        while not reporter.done():
            try:
                await asyncio.wait_for(_next(arrived, reader), DEMAND_TIMEOUT_S)
            except TimeoutError:
                if not silent:  # once per silence: zero the stick (logged)
                    silent = True
                    status.update(
                        await _command(
                            console, PilotDisconnected(f"no input for {DEMAND_TIMEOUT_S:g} s"), who
                        )
                    )
                continue
            silent = False
            texts, inbox[:] = list(inbox), []
            arrived.clear()
            await _apply(websocket, console, who, texts, status)
        return "status could not be sent"
    except WebSocketDisconnect:
        return "page closed"
    finally:
        reporter.cancel()
        reader.cancel()


async def _next(arrived: asyncio.Event, reader: asyncio.Task[None]) -> None:
    """Until a message has arrived; the reader's end (the page closed) is raised here."""
    waiter = asyncio.ensure_future(arrived.wait())
    try:
        await asyncio.wait({waiter, reader}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        waiter.cancel()
    if reader.done() and not arrived.is_set():
        reader.result()  # WebSocketDisconnect (or the error that ended it)
        raise WebSocketDisconnect


async def _apply(
    websocket: WebSocket, console: Console, who: str, texts: list[str], status: dict[str, Any]
) -> None:
    """Parse the messages that arrived (an error answered for each bad one) and apply them,
    the newest stick only; then send the status once."""
    commands: list[object] = []
    for text in texts:
        try:
            commands.append(_parse(text))
        except ValueError as err:
            await send(websocket, {"type": "error", "message": str(err)})
    applied = False
    for command in newest_stick_wins(commands):
        try:
            status.update(await _command(console, command, who))
            applied = True
        except (ValueError, ConsoleError) as err:
            await send(websocket, {"type": "error", "message": str(err)})
    if applied:
        await send(websocket, {"type": "status", "status": status})
