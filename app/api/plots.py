"""The plots page (GET /plots) and its WebSocket (/api/plots): the tree against the reference
(north, east, heading) over the last ``WINDOW_S`` seconds, sent once and then only what is new.

viser's uPlot handle has no append (its data is replaced whole at each assignment), so the
console's plots went out whole 2.7 times a second (about 48 kB/s). The console now serves its
plots from this small page of its own (no library, drawn on <canvas>), embedded in the viser
page's "Plots" folder by an iframe; the page keeps the window in a ring buffer and draws the
fixed window (-120 s to now).

Read-only: no token; the Host header (the app's TrustedHostMiddleware) and the Origin are
checked as for the other sockets. ``?viewer=<viser client id>`` follows that browser: its own
replay when it has one open (``web.view.ConsoleView.shown_snapshot``), else the live run.

Protocol (JSON text messages, server to page only). Rows are
``[t_s, north_m, east_m, heading_deg, north_ref_m, east_ref_m, heading_ref_deg]``, thinned
to ``POINTS_PER_S`` a second (the first trend row of each 1/POINTS_PER_S-second bin):

- ``{"type": "window", "source": "live"|"replay", "name": ..., "rows": [...]}`` first, and
  again whenever what is shown changes (a replay opened or closed, the run reset: time went
  back); the page drops what it had.
- ``{"type": "append", "rows": [...]}``: only rows newer than the last one sent, at most
  every ``PERIOD_S``, and nothing at all while nothing is new (paused).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from fastapi.responses import HTMLResponse

from app.api.guards import websocket_origin_allowed
from app.console import Snapshot, compass_degrees

router = APIRouter(tags=["plots"])
PAGE = (Path(__file__).parent / "plots_page.html").read_text(encoding="utf-8")
WINDOW_S = 120.0
"""The window the page draws [s before now]."""
POINTS_PER_S = 2.0
"""Rows a second of simulated time sent (a trace a few hundred pixels wide needs no more)."""
PERIOD_S = 0.5
"""How often the socket looks for new rows [s of wall time]."""
SEND_TIMEOUT_S = 5.0
NDIGITS = 4
"""Decimals sent (0.1 mm, 1e-4 deg: far below a pixel)."""


@router.get("/plots", response_class=HTMLResponse)
def plots_page() -> HTMLResponse:
    """The console's plots: tree and reference north, east and heading, last 120 s."""
    return HTMLResponse(PAGE)


def bins(t_s: np.ndarray) -> np.ndarray:
    """The thinning bin of each time (``POINTS_PER_S`` bins a second)."""
    return np.floor(np.asarray(t_s) * POINTS_PER_S + 1e-9).astype(np.int64)


def thinned(trend: np.ndarray, after_bin: int | None) -> np.ndarray:
    """The first row of each bin later than ``after_bin`` (all of the last ``WINDOW_S`` when
    None), in time order; rows of a bin already sent are never sent again."""
    if len(trend) == 0:
        return trend
    if after_bin is None:
        trend = trend[trend[:, 0] >= trend[-1, 0] - WINDOW_S]
        b = bins(trend[:, 0])
    else:
        b = bins(trend[:, 0])
        trend, b = trend[b > after_bin], b[b > after_bin]
    if len(trend) == 0:
        return trend
    first = np.unique(b, return_index=True)[1]
    return trend[np.sort(first)]


def rows_json(rows: np.ndarray) -> list[list[float]]:
    """Rows in the page's units, rounded to ``NDIGITS``: the headings in compass degrees,
    [0, 360), as the rest of the page prints them (the page draws them across north
    unbroken)."""
    out = np.array(rows[:, :7], dtype=float)
    out[:, [3, 6]] = compass_degrees(out[:, [3, 6]], NDIGITS)
    return [[round(float(v), NDIGITS) if math.isfinite(v) else 0.0 for v in r] for r in out]


class PlotFeed:
    """What one page has been sent: the next message for a snapshot (None: nothing new)."""

    def __init__(self) -> None:
        self.key: tuple[str, str] | None = None
        self.last_bin: int | None = None
        self.last_t: float = -math.inf

    def message(self, snap: Snapshot) -> dict[str, Any] | None:
        trend = snap.trend
        if len(trend) == 0:
            return None
        name = snap.replay.name if snap.replay is not None else ""
        key = (snap.source, name)
        if key != self.key or float(trend[-1, 0]) < self.last_t:
            rows = thinned(trend, None)
            self.key = key
            kind: dict[str, Any] = {"type": "window", "source": snap.source, "name": name}
        else:
            rows = thinned(trend, self.last_bin)
            if len(rows) == 0:
                return None
            kind = {"type": "append"}
        if len(rows):
            self.last_bin = int(bins(rows[-1:, 0])[0])
            self.last_t = float(rows[-1, 0])
        return {**kind, "rows": rows_json(rows)}


def _viewer(text: str | None) -> int | None:
    try:
        return int(text) if text is not None else None
    except ValueError:
        return None


@router.websocket("/api/plots")
async def plots_socket(websocket: WebSocket) -> None:
    """The plots' rows (see the module's protocol)."""
    if not websocket_origin_allowed(websocket):
        await websocket.close(code=1008, reason="origin not allowed")
        return
    await websocket.accept()
    viewer = _viewer(websocket.query_params.get("viewer"))
    sender = asyncio.create_task(_feed(websocket, viewer))
    try:
        # the page sends nothing: a receive returns when it goes (a paused run sends nothing,
        # so the sender alone would not notice)
        while not sender.done():
            if (await websocket.receive())["type"] == "websocket.disconnect":
                break
    except (WebSocketDisconnect, RuntimeError):
        pass
    finally:
        sender.cancel()
        with contextlib.suppress(asyncio.CancelledError, Exception):
            await sender


async def _feed(websocket: WebSocket, viewer: int | None) -> None:
    state = websocket.app.state
    feed = PlotFeed()
    with contextlib.suppress(WebSocketDisconnect, RuntimeError, OSError, TimeoutError):
        while True:
            view = state.view
            live = state.console.loop.snapshot
            snap = view.shown_snapshot(viewer, live) if view is not None else live
            message = feed.message(snap)
            if message is not None:
                text = json.dumps(message, separators=(",", ":"))
                await asyncio.wait_for(websocket.send_text(text), SEND_TIMEOUT_S)
            await asyncio.sleep(PERIOD_S)
