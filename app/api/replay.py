"""The API's replay of a recorded session: open, play, pause, seek, close.

One replay for API clients (session-level), played beside the live run on the loop's clock:
``GET /api/replay`` (and ``replay`` in ``/api/state``) reports where it is, while
``/api/state`` keeps reporting the live run, which goes on stepping. It never changes what a
browser in the page shows: each browser opens replays of its own in the page.
"""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, HTTPException, status

from app.api.deps import UNPROCESSABLE, ConsoleDep, SnapshotDep, TokenDep, run_command
from app.api.schemas import ReplayOpenIn, ReplayOut, ReplaySeekIn, ReplayStateOut
from app.console import ConsoleError, load_replay
from app.console.commands import CloseReplay, OpenReplay, PlayReplay, SeekReplay

router = APIRouter(prefix="/api/replay", tags=["replay"])


def _out(status: object) -> ReplayStateOut:
    return ReplayStateOut(replay=ReplayOut.of(status))  # type: ignore[arg-type]


@router.get("", response_model=ReplayStateOut)
def get_replay(snapshot: SnapshotDep) -> ReplayStateOut:
    return ReplayStateOut(replay=ReplayOut.of(snapshot.replay) if snapshot.replay else None)


@router.post("/open", response_model=ReplayStateOut)
async def open_replay(body: ReplayOpenIn, console: ConsoleDep, _: TokenDep) -> ReplayStateOut:
    """Open a recording beside the live run (which goes on; the page does not show it)."""
    try:
        data = await asyncio.to_thread(load_replay, console.settings.recordings_dir, body.name)
    except FileNotFoundError as err:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"name: {err}") from None
    except ConsoleError as err:
        raise HTTPException(UNPROCESSABLE, f"name: {err}") from None
    except Exception as err:
        raise HTTPException(UNPROCESSABLE, f"name: cannot read {body.name}: {err}") from None
    return _out(await run_command(console, OpenReplay(body.name, data)))


@router.post("/play", response_model=ReplayStateOut)
async def play(console: ConsoleDep, _: TokenDep) -> ReplayStateOut:
    return _out(await run_command(console, PlayReplay(True)))


@router.post("/pause", response_model=ReplayStateOut)
async def pause(console: ConsoleDep, _: TokenDep) -> ReplayStateOut:
    return _out(await run_command(console, PlayReplay(False)))


@router.put("/seek", response_model=ReplayStateOut)
async def seek(body: ReplaySeekIn, console: ConsoleDep, _: TokenDep) -> ReplayStateOut:
    return _out(await run_command(console, SeekReplay(body.t_s)))


@router.post("/close", response_model=ReplayStateOut)
async def close(console: ConsoleDep, _: TokenDep) -> ReplayStateOut:
    await run_command(console, CloseReplay())
    return ReplayStateOut(replay=None)
