"""What protects the server from careless and hostile clients, before a route runs:

- ``BodyLimit``: request bodies above ``MAX_BODY_BYTES`` are refused with 413 (by the declared
  length, and by counting when none is declared), so no larger upload is kept in memory; a
  body that is not JSON gets 415 and a JSON object with a key given twice 422. It also names
  the request's sender ("API <address>") for the console's operations log.
- ``MethodGuard``: a path that only takes POST answers GET with 405 (not another route's
  422 or 404), and OPTIONS lists every method of the path in ``Allow``.
- the Host header must name this server (``app.console.allowed_hosts``; DNS rebinding: a web
  page on another name that resolves to 127.0.0.1 must not read the console).
- wrong tokens are counted per client (``app.console.tokens.GuessLimit``): after too many,
  that client is refused with 429 until its window has passed.
- a browser's WebSocket carries an Origin (``app.console.origin_allowed``): only this
  server's own pages, on the API's port or the 3D view's (or clients that send none, like
  scripts), may open the telemetry, plots and pilot sockets (``websocket_origin_allowed``).
"""

from __future__ import annotations

import json
from collections.abc import Awaitable, Callable, MutableMapping, Sequence
from typing import Any

from fastapi.routing import APIRoute
from starlette.datastructures import State
from starlette.routing import BaseRoute, Match, Route
from starlette.websockets import WebSocket

from app.console import allowed_hosts, origin_allowed
from app.console.operations import ACTOR

MAX_BODY_BYTES = 256 * 1024
"""Largest request body [bytes]: a mission file of 200 legs is about 30 kB."""
MAX_TELEMETRY_CLIENTS = 16
"""Telemetry WebSocket connections at once (the loop serves each one a snapshot stream)."""

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
App = Callable[[Scope, Receive, Send], Awaitable[None]]


def page_ports(state: State) -> set[int]:
    """The ports the console serves its pages on: the API's, and the 3D view's when it runs."""
    ports = {state.console.settings.port}
    if state.view is not None:
        ports.add(state.view.port)
    return ports


def websocket_origin_allowed(websocket: WebSocket) -> bool:
    """The socket was opened by one of the console's own pages, or by a client that sends no
    Origin (a script)."""
    state = websocket.app.state
    return origin_allowed(websocket.headers.get("origin"), state.allowed_hosts, page_ports(state))


class BodyLimit:
    """ASGI middleware reading a request's whole body before the route does (at most
    ``limit`` bytes, so nothing larger is ever held) and refusing, with the reason:

    - 413 a body over ``limit``, by its declared length or by counting a chunked one (read
      by the route, the overflow was FastAPI's 400 "error parsing the body");
    - 415 a body that is not JSON (every route with a body takes JSON; a ``text/plain``
      body was "Input should be a valid dictionary");
    - 422 a JSON object that gives one key twice (json.loads keeps the last one silently).
    """

    def __init__(self, app: App, limit: int = MAX_BODY_BYTES) -> None:
        self.app = app
        self.limit = limit

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        client = scope.get("client")
        ACTOR.set(f"API {client[0]}" if client else "API")  # the operations log's 'who'
        headers = dict(scope.get("headers") or [])
        declared = headers.get(b"content-length")
        if declared is not None and declared.isdigit() and int(declared) > self.limit:
            await _refuse(send, 413, f"request body too large: at most {self.limit} bytes")
            return
        body = await self._read(receive)
        if body is None:
            await _refuse(send, 413, f"request body too large: at most {self.limit} bytes")
            return
        problem = body_problem(body, headers.get(b"content-type"))
        if problem is not None:
            await _refuse(send, *problem)
            return
        await self.app(scope, _replay(body, receive), send)

    async def _read(self, receive: Receive) -> bytes | None:
        """The whole body, or None once it passes the limit (the rest is not read)."""
        parts: list[bytes] = []
        seen = 0
        while True:
            message = await receive()
            if message["type"] != "http.request":
                break  # the client went away: the route sees an empty body
            chunk = message.get("body", b"")
            seen += len(chunk)
            if seen > self.limit:
                return None
            parts.append(chunk)
            if not message.get("more_body", False):
                break
        return b"".join(parts)


def _replay(body: bytes, receive: Receive) -> Receive:
    """A receive that gives the body read once, then waits on the client (disconnect)."""
    sent = False

    async def replay() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await receive()

    return replay


def _is_json(content_type: bytes | None) -> bool:
    """No content type (scripts, curl -d) is read as JSON, as FastAPI does; else it must
    be application/json or application/*+json."""
    if content_type is None:
        return True
    mime = content_type.split(b";")[0].strip().lower()
    return mime == b"application/json" or (
        mime.startswith(b"application/") and mime.endswith(b"+json")
    )


class DuplicateKey(ValueError):
    pass


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise DuplicateKey(key)
        out[key] = value
    return out


def body_problem(body: bytes, content_type: bytes | None) -> tuple[int, str] | None:
    """(status, message) when a non-empty body is not JSON or names a key twice; None when
    it may go on (a body that does not parse is the route's to refuse, naming the place)."""
    if not body:
        return None
    if not _is_json(content_type):
        shown = (content_type or b"").decode("latin-1")[:60]
        return 415, f"the body must be JSON (Content-Type: application/json), got {shown!r}"
    try:
        json.loads(body, object_pairs_hook=_no_duplicates)
    except DuplicateKey as err:
        return 422, f"body: the key {_short(str(err.args[0]))} is given twice"
    except (ValueError, RecursionError):
        return None
    return None


def _short(text: str, limit: int = 40) -> str:
    return repr(text) if len(text) <= limit else repr(text[:limit]) + "..."


async def _refuse(send: Send, status_code: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status_code,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})


class MethodGuard:
    """ASGI middleware answering a method a path does not take before any route runs: a path
    written out in full (``/api/recordings/start``) is that route's, so GET on it is 405
    naming the methods it takes, not the 422 of ``GET /api/recordings/{name}`` that also
    matches it; OPTIONS answers 204 with every method of the path (Starlette's 405 named the
    first route's only)."""

    def __init__(self, app: App, routes: Sequence[BaseRoute]) -> None:
        self.app = app
        self.routes = routes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        allowed = self.methods(scope)
        method = scope["method"]
        if not allowed or (method in allowed and method != "OPTIONS"):
            await self.app(scope, receive, send)
            return
        allow = ", ".join(sorted(allowed | {"OPTIONS"}))
        if method == "OPTIONS":
            await send({"type": "http.response.start", "status": 204, "headers": _allow(allow)})
            await send({"type": "http.response.body", "body": b""})
            return
        detail = f"{method} is not allowed on this path; it takes {allow}"
        body = json.dumps({"detail": detail}).encode()
        headers = [*_allow(allow), (b"content-type", b"application/json")]
        headers.append((b"content-length", str(len(body)).encode()))
        await send({"type": "http.response.start", "status": 405, "headers": headers})
        await send({"type": "http.response.body", "body": body})

    def methods(self, scope: Scope) -> set[str]:
        """The methods of the routes written out as this path, else of every route whose
        pattern matches it (empty: no route has the path, a 404 for the router)."""
        literal: set[str] = set()
        patterned: set[str] = set()
        for route in self.routes:
            if not isinstance(route, Route | APIRoute):
                continue
            match, _ = route.matches(scope)
            if match == Match.NONE:
                continue
            methods = route.methods or set()
            (patterned if "{" in route.path else literal).update(methods)
        return literal or patterned


def _allow(allow: str) -> list[tuple[bytes, bytes]]:
    return [(b"allow", allow.encode())]


__all__ = [
    "MAX_BODY_BYTES",
    "MAX_TELEMETRY_CLIENTS",
    "BodyLimit",
    "MethodGuard",
    "allowed_hosts",
    "origin_allowed",
    "page_ports",
    "websocket_origin_allowed",
]
