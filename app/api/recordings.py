"""Session recording to MCAP: start, stop, list, download."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, HTTPException, status
from fastapi import Path as FastApiPath
from fastapi.responses import FileResponse

from app.api.deps import UNPROCESSABLE, ConsoleDep, SnapshotDep, TokenDep, run_command
from app.api.schemas import RecordingInfoOut, RecordingListOut, RecordingOut, RecordingStartIn
from app.console import (
    RECORDING_NAME,
    Console,
    ConsoleError,
    Snapshot,
    list_recordings,
    recording_path,
)
from app.console.commands import StartRecording, StopRecording

router = APIRouter(prefix="/api/recordings", tags=["recordings"])


def finished_recording(name: str, console: Console, snapshot: Snapshot) -> Path:
    """The file of a recording that exists and is not being written, else the HTTP error
    (422 a name that is not a recording's, 404 none such, 409 still being written)."""
    try:
        path = recording_path(console.settings.recordings_dir, name)
    except ConsoleError as err:
        raise HTTPException(UNPROCESSABLE, f"name: {err}") from None
    if not path.is_file():
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no recording named {name!r}")
    if name == snapshot.recording:
        raise HTTPException(
            status.HTTP_409_CONFLICT, f"{name} is being written; stop the recording first"
        )
    return path


@router.get("", response_model=RecordingListOut)
def get_recordings(console: ConsoleDep, snapshot: SnapshotDep) -> RecordingListOut:
    return RecordingListOut(
        recordings=[
            RecordingInfoOut(**r) for r in list_recordings(console.settings.recordings_dir)
        ],
        recording=snapshot.recording,
    )


@router.post("/start", response_model=RecordingOut)
async def start(body: RecordingStartIn, console: ConsoleDep, _: TokenDep) -> RecordingOut:
    result = await run_command(console, StartRecording(body.label))
    return RecordingOut(name=result["name"])  # type: ignore[index]


@router.post("/stop", response_model=RecordingOut)
async def stop(console: ConsoleDep, _: TokenDep) -> RecordingOut:
    result = await run_command(console, StopRecording())
    return RecordingOut(name=result["name"])  # type: ignore[index]


@router.get(
    "/{name}",
    response_class=FileResponse,
    responses={200: {"content": {"application/octet-stream": {}}}},
)
def download(
    name: Annotated[
        str, FastApiPath(pattern=RECORDING_NAME.pattern, description="a recording's file name")
    ],
    console: ConsoleDep,
    snapshot: SnapshotDep,
) -> FileResponse:
    """The MCAP file (not while it is being written)."""
    path = finished_recording(name, console, snapshot)
    return FileResponse(path, media_type="application/octet-stream", filename=name)
