"""What protects the server from careless and hostile clients, before a route runs:

- ``BodyLimit``: request bodies above ``MAX_BODY_BYTES`` are refused with 413 (by the declared
  length, and by counting when none is declared), so no upload is kept in memory whole. It
  also names the request's sender ("API <address>") for the console's operations log.
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
from collections.abc import Awaitable, Callable, MutableMapping
from typing import Any

from starlette.datastructures import State
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


class BodyTooLarge(Exception):
    pass


class BodyLimit:
    """ASGI middleware: 413 for a body over ``limit`` bytes (the route never sees it)."""

    def __init__(self, app: App, limit: int = MAX_BODY_BYTES) -> None:
        self.app = app
        self.limit = limit

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        client = scope.get("client")
        ACTOR.set(f"API {client[0]}" if client else "API")  # the operations log's 'who'
        declared = dict(scope.get("headers") or []).get(b"content-length")
        if declared is not None and declared.isdigit() and int(declared) > self.limit:
            await self._refuse(send)
            return
        seen = 0
        started = False

        async def counting_receive() -> Message:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.limit:
                    raise BodyTooLarge
            return message

        async def tracking_send(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, counting_receive, tracking_send)
        except BodyTooLarge:
            if not started:
                await self._refuse(send)

    async def _refuse(self, send: Send) -> None:
        body = json.dumps(
            {"detail": f"request body too large: at most {self.limit} bytes"}
        ).encode()
        await send(
            {
                "type": "http.response.start",
                "status": 413,
                "headers": [
                    (b"content-type", b"application/json"),
                    (b"content-length", str(len(body)).encode()),
                ],
            }
        )
        await send({"type": "http.response.body", "body": body})


__all__ = [
    "MAX_BODY_BYTES",
    "MAX_TELEMETRY_CLIENTS",
    "BodyLimit",
    "allowed_hosts",
    "origin_allowed",
    "page_ports",
    "websocket_origin_allowed",
]
