"""The console server: ``create_app(settings)`` builds the FastAPI application (HTTP API,
OpenAPI at /openapi.json, telemetry WebSocket) around one ``Console``; its lifespan starts the
loop task and the 3D view (viser) and stops both. ``serve`` runs it with uvicorn (the
``rov-console serve`` command); ``serve_in_thread`` runs it in the background for tests and
benchmarks.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import sys
import threading
import time
from collections.abc import AsyncIterator, Iterator
from dataclasses import dataclass, replace
from typing import Any

import uvicorn
from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.middleware.trustedhost import TrustedHostMiddleware

from app.api import (
    assessment,
    control,
    crew,
    environment,
    faults,
    gains,
    health,
    missions,
    notes,
    pilot,
    plots,
    recordings,
    replay,
    run,
    scores,
    state,
)
from app.api.guards import MAX_BODY_BYTES, BodyLimit, MethodGuard, allowed_hosts
from app.api.schemas import ErrorOut
from app.api.state import StateJsonCache
from app.console import Console, ConsoleSettings
from app.console.commands import gain_band
from app.console.texts import without_server_paths

GIL_SWITCH_INTERVAL_S = 0.001
"""How long a Python thread may hold the GIL before another runnable one gets it (5 ms by
default): the loop's tick waits at most about this long for the server's and the 3D view's
threads."""

LOOP_JOIN_TIMEOUT_S = 10.0
"""How long shutdown waits for the loop's thread to finish its tick and close the session."""

ROUTERS = (
    health.router,
    state.router,
    run.router,
    missions.router,
    gains.router,
    control.router,
    environment.router,
    recordings.router,
    notes.router,
    replay.router,
    faults.router,
    scores.router,
    assessment.router,
    pilot.router,
    plots.router,
    crew.router,
)


def create_app(settings: ConsoleSettings) -> FastAPI:
    """The application for one console (nothing is shared between two apps)."""
    console = Console.build(settings)

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        # the loop on its own thread and event loop: HTTP handlers and telemetry sends on the
        # server's event loop do not delay its ticks; a shorter GIL switch interval (5 ms by
        # default) bounds how long another thread can keep it from waking up
        switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(GIL_SWITCH_INTERVAL_S)
        loop_thread = threading.Thread(
            target=asyncio.run, args=(console.loop.run(),), name="console-loop", daemon=True
        )
        loop_thread.start()
        view = None
        try:
            if settings.view:
                view = await asyncio.to_thread(_start_view, console, settings)
            app.state.view = view
            if settings.announce:
                print(addresses(settings, console.token, view.port if view else None), flush=True)
                print(instructor_line(settings), flush=True)
                print(crew_line(settings), flush=True)
            yield
        finally:
            console.loop.stop()
            await asyncio.to_thread(loop_thread.join, LOOP_JOIN_TIMEOUT_S)
            sys.setswitchinterval(switch_interval)
            if view is not None:
                await asyncio.to_thread(view.stop)

    app = FastAPI(
        title="ROV console",
        version="0.1.0",
        lifespan=lifespan,
        description="Simulator, control system and operator console for an ROV "
        "that positions a subsea tree hanging from a vessel's wire. "
        "Watching needs no token; actions that change the run need "
        "'Authorization: Bearer <token>'.",
    )
    _openapi_with_gain_band(app, console)
    app.state.console = console
    app.state.state_cache = StateJsonCache()
    app.state.reports = scores.ReportCache()
    app.state.view = None
    app.state.allowed_hosts = allowed_hosts(settings.host, settings.allow_remote)
    app.state.telemetry_clients = 0
    app.state.pilot_name = None  # the pilot flying from the pilot page (one at a time)
    app.state.winch_name = None  # the winch operator on the winch station (one at a time)
    for router in ROUTERS:
        app.include_router(router, responses=ERROR_RESPONSES)
    app.add_exception_handler(RequestValidationError, _validation_error)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(RecursionError, _too_deep)
    app.add_middleware(MethodGuard, routes=[r for router in ROUTERS for r in router.routes])
    app.add_middleware(TrustedHostMiddleware, allowed_hosts=app.state.allowed_hosts)
    app.add_middleware(BodyLimit, limit=MAX_BODY_BYTES)
    return app


def _openapi_with_gain_band(app: FastAPI, console: Console) -> None:
    """/openapi.json states the gains PUT /api/gains accepts now: each in [0, gain_band] of
    the running parameter set's gain (``app.console.commands.check_gain_band``), one range
    per axis (``prefixItems``), not the wider static limit every parameter file may use.
    The schema is built afresh on each request: the parameter set changes with a reset or a
    mission."""
    build = app.openapi

    def openapi() -> dict[str, Any]:
        app.openapi_schema = None
        schema = build()
        gains = console.loop.session.sim.ps.gains
        properties = schema["components"]["schemas"]["GainsIn"]["properties"]
        for term in ("kp", "ki", "kd"):
            bands = [gain_band(float(g)) for g in getattr(gains, term)]
            axes = [{"type": "number", "minimum": 0.0, "maximum": b} for b in bands]
            properties[term]["prefixItems"] = axes
            properties[term]["items"] = {"type": "number", "minimum": 0.0, "maximum": max(bands)}
        return schema

    app.openapi = openapi  # type: ignore[method-assign]


ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    code: {"model": ErrorOut, "description": text}
    for code, text in (
        (400, "malformed request (bad Host header, nesting too deep)"),
        (405, "the path does not take this method (the Allow header lists those it takes)"),
        (401, "this action needs the console token (faults: the instructor token)"),
        (403, "instructor features off, or the console token sent for an instructor action"),
        (404, "no such mission or recording"),
        (409, "cannot be done now (a mission is running, a replay is open ...)"),
        (413, "request body too large"),
        (415, "the body is not JSON"),
        (422, "a field is out of range or of the wrong type; the message names it"),
        (429, "too many wrong tokens from this client"),
        (503, "the simulation loop did not answer"),
    )
}
"""The error answers every route may give: ``{"detail": "<what is wrong>"}``."""


async def _http_error(request: Request, exc: Exception) -> Response:
    """FastAPI's answer to an HTTPException, its message without the server's paths (a
    recording's or the scores database's folder): ``without_server_paths``."""
    assert isinstance(exc, StarletteHTTPException)
    if isinstance(exc.detail, str):
        exc.detail = without_server_paths(exc.detail)
    return await http_exception_handler(request, exc)


async def _too_deep(request: Request, exc: Exception) -> JSONResponse:
    """A body nested deeper than the parser's recursion limit: a plain 400, no traceback."""
    return JSONResponse(status_code=400, content={"detail": "request nested too deeply to read"})


def _start_view(console: Console, settings: ConsoleSettings):
    from web.view import ConsoleView

    return ConsoleView(console, settings.host, settings.viser_port)


async def _validation_error(request: Request, exc: Exception) -> JSONResponse:
    """422 whose message names each bad field: 'body.kp.1: Input should be <= 10000000'."""
    assert isinstance(exc, RequestValidationError)
    errors = exc.errors()
    message = "; ".join(f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']}" for e in errors[:20])
    return JSONResponse(
        status_code=422,
        content={
            "detail": message,
            "errors": [{"loc": list(e["loc"]), "msg": e["msg"], "type": e["type"]} for e in errors],
        },
    )


def addresses(settings: ConsoleSettings, token: str, viser_port: int | None = None) -> str:
    """What ``serve`` prints: where to open the console and the token."""
    host = f"[{settings.host}]" if ":" in settings.host else settings.host
    lines = [
        f"3D console:  http://{host}:{viser_port or settings.viser_port}/",
        f"HTTP API:    http://{host}:{settings.port}/docs  "
        f"(OpenAPI: /openapi.json, telemetry: ws://{host}:{settings.port}/api/telemetry)",
        f"pilot page:  http://{host}:{settings.port}/pilot  (keys and gamepad fly the ROV)",
        f"plots page:  http://{host}:{settings.port}/plots  (also in the 3D console's Plots)",
        f"winch page:  http://{host}:{settings.port}/winch  (the winch operator's station)",
        f"supervisor:  http://{host}:{settings.port}/supervisor  (watch, pause and resume)",
        f"token:       {token}   (needed to change the run; watching needs none)",
    ]
    return "\n".join(lines)


def instructor_line(settings: ConsoleSettings) -> str:
    """What ``serve`` prints about the instructor (never the instructor's token)."""
    if settings.instructor_token is None:
        return (
            "instructor:  off (faults cannot be injected; pass --instructor-token or set "
            "ROV_CONSOLE_INSTRUCTOR_TOKEN to turn it on)"
        )
    return "instructor:  on (faults need the instructor token, not the console token)"


def crew_line(settings: ConsoleSettings) -> str:
    """What ``serve`` prints about the crew's stations (never their tokens)."""
    given = [
        role for role in ("winch", "supervisor") if getattr(settings, f"{role}_token") is not None
    ]
    if not given:
        return "crew:        the winch and supervisor pages open with the console token"
    return (
        f"crew:        {' and '.join(given)} token{'s' if len(given) > 1 else ''} set "
        "(each opens its own page only; the console token opens them too)"
    )


def serve(settings: ConsoleSettings) -> None:
    """Run until interrupted (the ``rov-console serve`` command); prints where to go. Once
    the console is built (its first chunk's kernels compiled or loaded), the kernels of the
    commands it has not used yet are compiled into the cache by a process of low priority
    beside it (``app.precompile``: nothing to do when the cache has them)."""
    from app import precompile

    app = create_app(replace(settings, announce=True))
    warm = precompile.start_in_background()
    try:
        uvicorn.Server(uvicorn_config(app, settings)).run()
    finally:
        warm.terminate()


def uvicorn_config(app: FastAPI, settings: ConsoleSettings) -> uvicorn.Config:
    """How uvicorn serves the console. uvicorn believes X-Forwarded-For from 127.0.0.1 by
    default, so any local client could name itself anyone (escaping the token lockout, faking
    the operations log's 'who'); the headers are read only when the operator says a proxy
    stands in front (``behind_proxy``)."""
    return uvicorn.Config(
        app,
        host=settings.host,
        port=settings.port,
        log_level="warning",
        lifespan="on",
        proxy_headers=settings.behind_proxy,
        # behind a proxy: the addresses uvicorn trusts (FORWARDED_ALLOW_IPS, else loopback)
        forwarded_allow_ips=None if settings.behind_proxy else [],
    )


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port nobody listens on right now (for tests and benchmarks)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


@dataclass(frozen=True)
class RunningServer:
    """A console served in a background thread."""

    settings: ConsoleSettings
    app: FastAPI
    token: str

    @property
    def console(self) -> Console:
        return self.app.state.console

    @property
    def base_url(self) -> str:
        return f"http://{self.settings.host}:{self.settings.port}"

    @property
    def view_url(self) -> str:
        view = self.app.state.view
        return f"http://{self.settings.host}:{view.port if view else self.settings.viser_port}/"

    @property
    def auth(self) -> dict[str, str]:
        return {"Authorization": f"Bearer {self.token}"}


@contextlib.contextmanager
def serve_in_thread(settings: ConsoleSettings, timeout_s: float = 300.0) -> Iterator[RunningServer]:
    """Serve on free ports (port 0 in the settings) in a thread; stop on exit."""
    if settings.port == 0:
        settings = replace(settings, port=free_port(settings.host))
    if settings.view and settings.viser_port == 0:
        settings = replace(settings, viser_port=free_port(settings.host))
    app = create_app(settings)
    server = uvicorn.Server(uvicorn_config(app, settings))
    thread = threading.Thread(target=server.run, name="console-http", daemon=True)
    thread.start()
    deadline = time.monotonic() + timeout_s
    while not server.started:
        if not thread.is_alive() or time.monotonic() > deadline:
            server.should_exit = True
            raise RuntimeError("the console server did not start")
        time.sleep(0.05)
    try:
        yield RunningServer(settings, app, app.state.console.token)
    finally:
        server.should_exit = True
        thread.join(timeout=30.0)
