"""Notes on the timeline: ``POST /api/notes`` (live, at the present time) and a finished
recording's notes (``GET``/``POST /api/recordings/NAME/notes``, added in review into the
side file beside it: ``app.recording.notes``)."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import APIRouter, Depends, HTTPException, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from pydantic import BaseModel, ConfigDict, Field

from app.api.deps import (
    UNPROCESSABLE,
    ConsoleDep,
    ReviewerDep,
    SnapshotDep,
    require_token,
    run_command,
)
from app.api.recordings import finished_recording
from app.console.commands import AddNote
from app.recording.notes import AUTHOR_MAX, TEXT_MAX, add_review_note, read_notes

router = APIRouter(tags=["notes"])
_bearer = HTTPBearer(auto_error=False)


def require_operator(
    request: Request,
    console: ConsoleDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """Notes are for those who have unlocked the controls (the console token) and the
    instructor (the instructor's token); wrong tokens count as for every action."""
    if credentials is not None and console.is_instructor_token(credentials.credentials):
        return
    require_token(request, console, credentials)


OperatorDep = Annotated[None, Depends(require_operator)]


class NoteIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    text: str = Field(max_length=4 * TEXT_MAX, description=f"at most {TEXT_MAX} characters")
    author: str = Field(default="", max_length=4 * AUTHOR_MAX)


class ReviewNoteIn(NoteIn):
    t_s: float = Field(description="time on the recording's axis [s]", allow_inf_nan=False)


class NoteOut(BaseModel):
    t_s: float
    author: str
    text: str
    source: str = Field(description="live (in the recording) or review (the side file)")


class NotesOut(BaseModel):
    notes: list[NoteOut]


@router.post("/api/notes")
async def add_note(body: NoteIn, console: ConsoleDep, _: OperatorDep) -> dict:
    """A note at the present time of the live run."""
    try:
        command = AddNote(body.text, body.author)
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
    result = await run_command(console, command)
    assert isinstance(result, dict)
    return result


@router.get("/api/recordings/{name}/notes", response_model=NotesOut)
async def recording_notes(
    name: str, console: ConsoleDep, snapshot: SnapshotDep, _: ReviewerDep
) -> NotesOut:
    path = finished_recording(name, console, snapshot)
    try:
        notes = await asyncio.to_thread(read_notes, path)
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, f"{name}: {err}") from None
    return NotesOut(notes=[NoteOut(**n.as_dict()) for n in notes])


@router.post("/api/recordings/{name}/notes", response_model=NoteOut)
async def add_recording_note(
    name: str, body: ReviewNoteIn, console: ConsoleDep, snapshot: SnapshotDep, _: OperatorDep
) -> NoteOut:
    """A note at ``t_s`` of a finished recording, into the side file beside it (the
    recording's own bytes are never rewritten)."""
    path = finished_recording(name, console, snapshot)

    def add() -> NoteOut:
        from app.recording import load_session

        t = load_session(path).log.t_s
        end = float(t[-1]) if len(t) else 0.0
        return NoteOut(
            **add_review_note(path, body.t_s, body.author or "reviewer", body.text, end).as_dict()
        )

    try:
        return await asyncio.to_thread(add)
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
