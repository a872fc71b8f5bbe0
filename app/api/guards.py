"""What protects the server from careless and hostile clients, before a route runs:

- ``BodyLimit``: request bodies above ``MAX_BODY_BYTES`` are refused with 413 (by the declared
  length, and by counting when none is declared), so no upload is kept in memory whole.
- ``allowed_hosts``: the Host header must name this server (DNS rebinding: a web page on
  another name that resolves to 127.0.0.1 must not read the console).
- wrong tokens are counted per client (``app.console.tokens.GuessLimit``): after too many,
  that client is refused with 429 until its window has passed.
- ``origin_allowed``: a browser's WebSocket carries an Origin; only this server's own pages
  (or clients that send none, like scripts) may open the telemetry stream.
"""

from __future__ import annotations

import ipaddress
import json
from collections.abc import Awaitable, Callable, MutableMapping
from typing import Any
from urllib.parse import urlsplit

MAX_BODY_BYTES = 256 * 1024
"""Largest request body [bytes]: a mission file of 200 legs is about 30 kB."""
MAX_TELEMETRY_CLIENTS = 16
"""Telemetry WebSocket connections at once (the loop serves each one a snapshot stream)."""

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
App = Callable[[Scope, Receive, Send], Awaitable[None]]


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


def allowed_hosts(host: str, allow_remote: bool) -> list[str]:
    """Host names the server answers to: the loopback names and the bound address; with
    ``allow_remote`` and a wildcard bind, any (the operator chose to expose it)."""
    if allow_remote and host in ("0.0.0.0", "::"):
        return ["*"]
    names = {"127.0.0.1", "localhost", "::1", "[::1]", host, f"[{host}]"}
    return sorted(names)


def origin_allowed(origin: str | None, hosts: list[str]) -> bool:
    """A WebSocket's Origin (None for non-browser clients) must be one of our host names."""
    if origin is None or "*" in hosts:
        return True
    try:
        name = urlsplit(origin).hostname or ""
    except ValueError:
        return False
    return name in hosts or f"[{name}]" in hosts or _is_loopback_name(name)


def _is_loopback_name(name: str) -> bool:
    if name == "localhost":
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False
