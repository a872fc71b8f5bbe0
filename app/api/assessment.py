"""The assessment (issue 46): the criteria in force (anyone reads them; only the instructor
changes them), a trainee's trend over their runs, and a finished recording's logbook entry.

The console's criteria live in its recordings folder as ``criteria.toml`` (the file format
of ``rov-console logbook --criteria``, docs/formats.md), so they outlast a restart and the
command line reads the same file.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Annotated, Literal

from fastapi import APIRouter, HTTPException, Query, status
from fastapi import Path as FastApiPath
from fastapi.responses import Response
from pydantic import BaseModel, Field

from app import assessment as asmt
from app import scores as store
from app.api.deps import UNPROCESSABLE, ConsoleDep, ReviewerDep, SnapshotDep
from app.api.faults import InstructorDep
from app.api.recordings import finished_recording
from app.api.schemas import Finite, _In
from app.console import RECORDING_NAME, Console
from app.console import criteria as in_force
from app.console.session import SCORES_DB

router = APIRouter(tags=["assessment"])

MAX_LOGBOOK_RECORDING_BYTES = 256 * 1024 * 1024
"""Largest recording a logbook entry is written for over HTTP [bytes] (as the debrief's)."""
_writing = threading.Lock()
"""One logbook entry at a time (each reads and scores a whole recording: seconds)."""


class CriterionIn(_In):
    limit: Finite | None = Field(default=None, description="the limit; omitted: the default")
    zero_at: Finite | None = Field(default=None, description="where the score reaches 0")
    weight: Finite | None = Field(default=None, description=f"0 to {asmt.WEIGHT_MAX:g}")


class CriteriaIn(_In):
    """The criteria file's fields as JSON: criteria left out keep their defaults."""

    format_version: int = Field(default=asmt.FORMAT_VERSION)
    criteria: dict[Annotated[str, Field(max_length=40)], CriterionIn] = Field(
        default_factory=dict, max_length=len(asmt.DEFINITIONS)
    )


class CriterionOut(BaseModel):
    name: str
    title: str
    unit: str
    limit: float | None = Field(description="None: the parameter set's own")
    zero_at: float | None
    weight: float
    limit_max: float


class CriteriaOut(BaseModel):
    criteria: list[CriterionOut]
    toml: str = Field(description="the same as a criteria file")
    source: Literal["default", "instructor"]


class TrendPointOut(BaseModel):
    id: int
    utc: str
    mission: str
    flown_by: str
    faults: str
    total: float | None
    scores: dict[str, float | None]


def criteria_path(console: Console) -> Path:
    return in_force.criteria_path(console.settings.recordings_dir)


def console_criteria(console: Console) -> asmt.Criteria:
    """The criteria in force on this console (the defaults until the instructor sets any)."""
    try:
        return in_force.criteria_in_force(console.settings.recordings_dir)
    except asmt.CriteriaError as err:  # the file was edited by hand and broken
        raise HTTPException(UNPROCESSABLE, f"{asmt.CRITERIA_FILE}: {err}") from None


def _out(console: Console, criteria: asmt.Criteria) -> CriteriaOut:
    return CriteriaOut(
        criteria=[CriterionOut(**c) for c in criteria.as_dict()],
        toml=criteria.to_toml(),
        source="instructor" if criteria_path(console).exists() else "default",
    )


@router.get("/api/assessment/criteria", response_model=CriteriaOut)
def get_criteria(console: ConsoleDep) -> CriteriaOut:
    """The criteria in force: each one's limit, zero and weight."""
    return _out(console, console_criteria(console))


@router.put("/api/assessment/criteria", response_model=CriteriaOut)
def put_criteria(body: CriteriaIn, console: ConsoleDep, _: InstructorDep) -> CriteriaOut:
    """Set the criteria (the instructor token): those left out keep their defaults. A value
    out of range is refused with the field and its range named."""
    data = body.model_dump(exclude_none=True)
    try:
        criteria = in_force.apply_criteria(console.settings.recordings_dir, data, "the request")
    except asmt.CriteriaError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
    except OSError as err:
        raise HTTPException(
            status.HTTP_507_INSUFFICIENT_STORAGE, f"cannot write: {err.strerror or err}"
        ) from None
    return _out(console, criteria)


@router.delete("/api/assessment/criteria", response_model=CriteriaOut)
def reset_criteria(console: ConsoleDep, _: InstructorDep) -> CriteriaOut:
    """Back to the default criteria (the instructor token)."""
    return _out(console, in_force.reset_criteria(console.settings.recordings_dir))


@router.get("/api/scores/trend", response_model=list[TrendPointOut])
def get_trend(
    console: ConsoleDep,
    trainee: Annotated[str, Query(min_length=1, max_length=200)],
    mission: Annotated[str | None, Query(max_length=200)] = None,
) -> list[TrendPointOut]:
    """A trainee's runs, oldest first, each scored with the criteria in force."""
    criteria = console_criteria(console)
    try:
        points = store.trend(
            console.settings.recordings_dir / SCORES_DB, trainee, criteria, mission
        )
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
    return [TrendPointOut(**vars(p)) for p in points]


@router.get("/api/recordings/{name}/logbook")
def logbook(
    name: Annotated[
        str, FastApiPath(pattern=RECORDING_NAME.pattern, description="a recording's file name")
    ],
    console: ConsoleDep,
    snapshot: SnapshotDep,
    _: ReviewerDep,
    format: Annotated[Literal["pdf", "csv"], Query()] = "pdf",
) -> Response:
    """The logbook entry of a finished recording, PDF or CSV, scored with the criteria in
    force (the console or instructor token); 503 while another is being written."""
    from app import logbook as lb

    path = finished_recording(name, console, snapshot)
    if path.stat().st_size > MAX_LOGBOOK_RECORDING_BYTES:
        raise HTTPException(
            status.HTTP_413_REQUEST_ENTITY_TOO_LARGE,
            f"{name}: too large for the console (use 'rov-console logbook')",
        )
    criteria = console_criteria(console)
    if not _writing.acquire(blocking=False):
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            "another logbook entry is being written: try again in 10 s",
            headers={"Retry-After": "10"},
        )
    try:
        source = (
            "the console's (set by the instructor)"
            if criteria_path(console).exists()
            else ("the built-in defaults")
        )
        entry = lb.entry_of(path, criteria, None, source)
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, f"{name}: {err}".replace(str(path), name)) from None
    finally:
        _writing.release()
    stem = Path(name).stem
    if format == "csv":
        return Response(
            lb.csv_text(entry),
            media_type="text/csv",
            headers={"Content-Disposition": f'attachment; filename="{stem}-logbook.csv"'},
        )
    return Response(
        lb.pdf_bytes(entry),
        media_type="application/pdf",
        headers={"Content-Disposition": f'attachment; filename="{stem}-logbook.pdf"'},
    )
