"""What the stations' sockets share (the pilot page's, the winch's, the supervisor's): the
sign-in hello, a page's message read as JSON, and refusing with the reason."""

from __future__ import annotations

import asyncio
import contextlib
import json
from typing import Any

from fastapi import WebSocket

HELLO_TIMEOUT_S = 30.0
"""A page must sign in within this long after opening the socket."""
COMMAND_TIMEOUT_S = 5.0
MAX_MESSAGE_CHARS = 1000


class Refused(Exception):
    """The page is told why and the socket closes."""


async def send(websocket: WebSocket, message: dict[str, Any]) -> None:
    await asyncio.wait_for(websocket.send_json(message), COMMAND_TIMEOUT_S)


async def refuse(websocket: WebSocket, why: str) -> None:
    """Tell the page why, and close (policy violation)."""
    with contextlib.suppress(Exception):
        await send(websocket, {"type": "error", "message": why})
        await websocket.close(code=1008, reason=why[:120])


async def read_hello(websocket: WebSocket) -> tuple[dict, str | None, str]:
    """The page's first message, ``{type: hello, token, name}``: (the hello, its token, the
    client as the token guard counts it), else Refused with the reason."""
    try:
        hello = await asyncio.wait_for(websocket.receive_json(), HELLO_TIMEOUT_S)
    except TimeoutError:
        raise Refused(f"sign in within {HELLO_TIMEOUT_S:g} s of connecting") from None
    except ValueError:
        raise Refused("the first message must be JSON: {type: hello, token, name}") from None
    if not isinstance(hello, dict) or hello.get("type") != "hello":
        raise Refused("the first message must be {type: hello, token, name}")
    client = f"ws:{websocket.client.host if websocket.client else '?'}"
    token = hello.get("token")
    return hello, token if isinstance(token, str) else None, client


def read_message(text: str) -> object:
    """A page's message as JSON, or ValueError saying what is wrong (too long, not JSON)."""
    if len(text) > MAX_MESSAGE_CHARS:
        raise ValueError(f"message longer than {MAX_MESSAGE_CHARS} characters")
    try:
        return json.loads(text)
    except ValueError:
        raise ValueError("message is not JSON") from None
