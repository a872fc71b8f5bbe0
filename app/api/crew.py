"""The crew's stations: the winch page (GET /winch, socket /api/winch) and the supervisor's
page (GET /supervisor, socket /api/supervisor), each with its own token (``serve
--winch-token``, ``--supervisor-token``; the console token opens them too). What they show
is built in ``app.console.crew``; what they change goes through the typed commands of
``app.console.commands`` (``WinchPayOut``, ``WinchHaulIn``, ``WinchStop``,
``HeaveCompensation``, ``Pause``, ``Resume``), logged as "winch (Name)" or "supervisor (Name)".

Protocol (JSON text messages), as the pilot's socket: the page first sends
``{"type": "hello", "token": ..., "name": ...}``; a wrong token, a bad name, another station's
token or a second winch operator gets ``{"type": "error", "message": ...}`` and the socket
closes. Then the winch station sends

- ``{"type": "pay_out" | "haul_in", "speed_mps": v, "distance_m": d}`` (no distance: until
  stopped), ``{"type": "stop"}``, ``{"type": "compensation", "on": bool}``;

and the supervisor ``{"type": "pause"}`` or ``{"type": "resume"}``. Each command is answered
with ``{"type": "done", "result": ...}`` or an error message naming the field and its range;
the status comes every ``STATUS_PERIOD_S`` as ``{"type": "status", "status": {...}}``.

Over HTTP, the same winch commands (``Authorization: Bearer <winch token>``, or the console
token): ``POST /api/winch/pay-out`` and ``/haul-in`` with ``{"speed_mps", "distance_m"}``,
``POST /api/winch/stop``, ``PUT /api/winch/compensation`` with ``{"on"}``, logged as
"winch (API <address>)"; ``GET /api/winch`` (no token) reads the station's status.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

from fastapi import (
    APIRouter,
    Depends,
    HTTPException,
    Request,
    WebSocket,
    WebSocketDisconnect,
    status,
)
from fastapi.responses import HTMLResponse
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from pydantic import Field

from app.api.deps import ConsoleDep, SnapshotDep, run_command
from app.api.guards import websocket_origin_allowed
from app.api.schemas import CommandOut, Finite, _In
from app.api.stations import COMMAND_TIMEOUT_S, Refused, read_hello, read_message, refuse, send
from app.console import Console, ConsoleError
from app.console.commands import (
    WINCH_DISTANCE_MAX_M,
    WINCH_SPEED_MAX_MPS,
    Command,
    HeaveCompensation,
    Pause,
    Resume,
    WinchHaulIn,
    WinchPayOut,
    WinchStop,
)
from app.console.crew import (
    SlipWatch,
    station_actor,
    station_name,
    supervisor_status,
    winch_status,
)
from app.console.operations import ACTOR

router = APIRouter(tags=["crew"])
WINCH_PAGE = (Path(__file__).parent / "winch_page.html").read_text(encoding="utf-8")
SUPERVISOR_PAGE = (Path(__file__).parent / "supervisor_page.html").read_text(encoding="utf-8")
STATUS_PERIOD_S = 0.2
PAGE_HEADERS = {
    "Content-Security-Policy": "default-src 'self'; script-src 'unsafe-inline'; "
    "style-src 'unsafe-inline'; connect-src 'self'; frame-ancestors 'self'",
    "X-Content-Type-Options": "nosniff",
}
"""The stations' pages load nothing from elsewhere and talk only to their own server."""


@router.get("/winch", response_class=HTMLResponse)
def winch_page() -> HTMLResponse:
    """The winch operator's station: pay out, haul in, stop, heave compensation; the
    tension, the tree's height over the posts and its vertical speed, the wire alarms."""
    return HTMLResponse(WINCH_PAGE, headers=PAGE_HEADERS)


@router.get("/supervisor", response_class=HTMLResponse)
def supervisor_page() -> HTMLResponse:
    """The supervisor's station: the state, the alarms, the crew and the operations log;
    pause and resume."""
    return HTMLResponse(SUPERVISOR_PAGE, headers=PAGE_HEADERS)


def parse_winch(text: str) -> Command:
    """One message of the winch page as a command, or ValueError saying what is wrong."""
    m = _message(text)
    kind = m.get("type")
    if kind in ("pay_out", "haul_in"):
        unknown = set(m) - {"type", "speed_mps", "distance_m"}
        if unknown:
            raise ValueError(f"{kind} takes speed_mps and distance_m, not {sorted(unknown)[0]}")
        run = WinchPayOut if kind == "pay_out" else WinchHaulIn
        return run(m.get("speed_mps"), m.get("distance_m"))  # type: ignore[arg-type]
    if kind == "stop":
        return WinchStop()
    if kind == "compensation":
        return HeaveCompensation(m.get("on"))  # type: ignore[arg-type]
    raise ValueError("message type must be pay_out, haul_in, stop or compensation")


def parse_supervisor(text: str) -> Command:
    """One message of the supervisor's page: pause or resume, nothing else."""
    kind = _message(text).get("type")
    if kind == "pause":
        return Pause()
    if kind == "resume":
        return Resume()
    raise ValueError("the supervisor may pause and resume only: message type must be one of them")


def _message(text: str) -> dict[str, Any]:
    m = read_message(text)
    if not isinstance(m, dict):
        raise ValueError("message must be a JSON object with a type")
    return m


async def _sign_in(websocket: WebSocket, console: Console, role: str) -> str:
    """The crew member's name once the hello checks out, else Refused with the reason."""
    hello, token, client = await read_hello(websocket)
    verdict, wait = console.check_station(role, token, client)
    if wait > 0.0:
        raise Refused(f"too many wrong tokens from this client: try again in {wait:.0f} s")
    if verdict == "another":
        raise Refused(f"that token opens another station: the {role} page needs the {role} token")
    if verdict != "ok":
        raise Refused(f"wrong token: the {role} page needs the {role} token or the console token")
    try:
        return station_name(hello.get("name"), role)
    except ValueError as err:
        raise Refused(str(err)) from None


@router.websocket("/api/winch")
async def winch_socket(websocket: WebSocket) -> None:
    """The winch station (see the module's protocol); one winch operator at a time."""
    state = websocket.app.state
    if not websocket_origin_allowed(websocket):
        await websocket.close(code=1008, reason="origin not allowed")
        return
    await websocket.accept()
    try:
        name = await _sign_in(websocket, state.console, "winch")
        if state.winch_name is not None:
            raise Refused(f"{state.winch_name} is on the winch: one winch operator at a time")
    except Refused as err:
        await refuse(websocket, str(err))
        return
    except WebSocketDisconnect:
        return
    state.winch_name = name
    slips = SlipWatch()
    try:
        await _station(
            websocket, state.console, "winch", name, parse_winch, lambda s: winch_status(s, slips)
        )
    finally:
        state.winch_name = None


@router.websocket("/api/supervisor")
async def supervisor_socket(websocket: WebSocket) -> None:
    """The supervisor's station (see the module's protocol)."""
    state = websocket.app.state
    if not websocket_origin_allowed(websocket):
        await websocket.close(code=1008, reason="origin not allowed")
        return
    await websocket.accept()
    try:
        name = await _sign_in(websocket, state.console, "supervisor")
    except Refused as err:
        await refuse(websocket, str(err))
        return
    except WebSocketDisconnect:
        return

    def status(snap: Any) -> dict[str, object]:
        return supervisor_status(snap, {"pilot": state.pilot_name, "winch": state.winch_name})

    await _station(websocket, state.console, "supervisor", name, parse_supervisor, status)


async def _station(
    websocket: WebSocket,
    console: Console,
    role: str,
    name: str,
    parse: Callable[[str], Command],
    status: Callable[[Any], dict[str, object]],
) -> None:
    """Send the status every ``STATUS_PERIOD_S`` and apply the page's commands, each
    answered, until the page goes."""
    who = station_actor(role, name)

    async def report() -> None:
        while True:
            await send(websocket, {"type": "status", "status": status(console.loop.snapshot)})
            await asyncio.sleep(STATUS_PERIOD_S)

    try:
        await send(websocket, {"type": "welcome", "name": name, "role": role})
    except (WebSocketDisconnect, RuntimeError, OSError, TimeoutError):
        return
    reporter = asyncio.create_task(report())
    try:
        while not reporter.done():
            text = await websocket.receive_text()
            try:
                command = parse(text)
                future = console.loop.submit(command, who)
                result = await asyncio.wait_for(asyncio.wrap_future(future), COMMAND_TIMEOUT_S)
            except (ValueError, ConsoleError, TimeoutError) as err:
                await send(websocket, {"type": "error", "message": str(err) or "timed out"})
                continue
            await send(websocket, {"type": "done", "result": result})
    except (WebSocketDisconnect, RuntimeError, OSError, TimeoutError):
        pass
    finally:
        reporter.cancel()
        with contextlib.suppress(Exception):
            await websocket.close()


# ---------------------------------------------------------------------- the winch over HTTP
_bearer = HTTPBearer(auto_error=False, description="the winch station's token")


def require_winch(
    request: Request,
    console: ConsoleDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """The winch token or the console token."""
    client = f"http:{request.client.host if request.client else '?'}"
    given = credentials.credentials if credentials is not None else None
    verdict, wait = console.check_station("winch", given, client)
    if wait > 0.0:
        raise HTTPException(
            status.HTTP_429_TOO_MANY_REQUESTS,
            f"too many wrong tokens from this client: try again in {wait:.0f} s",
            headers={"Retry-After": str(max(int(wait + 0.999), 1))},
        )
    if verdict == "another":
        raise HTTPException(
            status.HTTP_403_FORBIDDEN,
            "that token opens another station: the winch needs the winch token",
        )
    if verdict != "ok":
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "the winch needs the winch token (or the console token): send the header "
            "'Authorization: Bearer <token>'",
            headers={"WWW-Authenticate": "Bearer"},
        )


WinchDep = Annotated[None, Depends(require_winch)]


class WinchRunIn(_In):
    speed_mps: Finite = Field(description=f"winch speed, (0, {WINCH_SPEED_MAX_MPS:g}] m/s")
    distance_m: Finite | None = Field(
        default=None,
        description=f"how far, (0, {WINCH_DISTANCE_MAX_M:g}] m; omitted: until stopped",
    )


class CompensationIn(_In):
    on: bool = Field(description="the crane's heave compensation on or off")


def _command(make: Callable[[], Command]) -> Command:
    """The typed command (its range errors a 422); its sender is logged as the winch's."""
    ACTOR.set(station_actor("winch", ACTOR.get()))
    try:
        return make()
    except ValueError as err:
        raise HTTPException(422, str(err)) from None


@router.get("/api/winch")
def get_winch(snapshot: SnapshotDep) -> dict[str, object]:
    """The winch station's status (watching needs no token)."""
    return winch_status(snapshot, SlipWatch())


@router.post("/api/winch/pay-out", response_model=CommandOut)
async def pay_out(body: WinchRunIn, console: ConsoleDep, _: WinchDep) -> CommandOut:
    """Pay out (the tree goes down) at ``speed_mps``, ``distance_m`` or until stopped."""
    command = _command(lambda: WinchPayOut(body.speed_mps, body.distance_m))
    return CommandOut(result=await run_command(console, command))


@router.post("/api/winch/haul-in", response_model=CommandOut)
async def haul_in(body: WinchRunIn, console: ConsoleDep, _: WinchDep) -> CommandOut:
    """Haul in (the tree comes up) at ``speed_mps``, ``distance_m`` or until stopped."""
    command = _command(lambda: WinchHaulIn(body.speed_mps, body.distance_m))
    return CommandOut(result=await run_command(console, command))


@router.post("/api/winch/stop", response_model=CommandOut)
async def stop(console: ConsoleDep, _: WinchDep) -> CommandOut:
    """Stop the winch where it is (also while a mission runs)."""
    return CommandOut(result=await run_command(console, _command(WinchStop)))


@router.put("/api/winch/compensation", response_model=CommandOut)
async def compensation(body: CompensationIn, console: ConsoleDep, _: WinchDep) -> CommandOut:
    """The crane's heave compensation on or off (422 when the crane tip does not heave)."""
    command = _command(lambda: HeaveCompensation(body.on))
    return CommandOut(result=await run_command(console, command))
