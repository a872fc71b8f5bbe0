"""Scores of flown missions (history, best runs, hand against autopilot) and the debrief of a
finished recording, as the page and any client read them (watching: no token)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, HTTPException, Query, status
from fastapi import Path as FastApiPath
from fastapi.responses import HTMLResponse
from pydantic import BaseModel

from app import scores as store
from app.api.deps import UNPROCESSABLE, ConsoleDep, SnapshotDep
from app.console import RECORDING_NAME, ConsoleError, recording_path
from app.console.session import SCORES_DB

router = APIRouter(tags=["scores"])


class ScoreOut(BaseModel):
    id: int
    utc: str
    trainee: str
    mission: str
    source: str
    log_file: str | None
    passed: bool
    landed: bool | None
    time_to_dock_s: float | None
    miss_m: float | None
    heading_error_deg: float | None
    contact_speed_mps: float | None
    rms_north_m: float
    rms_east_m: float
    rms_heading_deg: float
    saturated_s: float
    thrust_newton_s: float | None
    faults: str
    manual_share: float
    flown_by: str


def _history(console: ConsoleDep, trainee: str | None, mission: str | None) -> list[store.Score]:
    try:
        return store.history(console.settings.recordings_dir / SCORES_DB, trainee, mission)
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None


@router.get("/api/scores", response_model=list[ScoreOut])
def get_scores(
    console: ConsoleDep,
    trainee: Annotated[str | None, Query(max_length=200)] = None,
    mission: Annotated[str | None, Query(max_length=200)] = None,
    best: bool = False,
) -> list[ScoreOut]:
    """Stored scores, newest first (``best``: the best run of each mission)."""
    rows = _history(console, trainee, mission)
    return [ScoreOut(**s.__dict__) for s in (store.best(rows) if best else rows)]


@router.get("/api/scores/compare", response_model=dict[str, ScoreOut])
def compare_scores(
    console: ConsoleDep,
    mission: Annotated[str, Query(min_length=1, max_length=200)],
    trainee: Annotated[str | None, Query(max_length=200)] = None,
) -> dict[str, ScoreOut]:
    """The best run of ``mission`` flown by the autopilot, by hand and mixed, side by side."""
    best = store.compare(_history(console, trainee, mission))
    return {how: ScoreOut(**s.__dict__) for how, s in best.items()}


@router.get("/api/recordings/{name}/report", response_class=HTMLResponse)
def report(
    name: Annotated[
        str, FastApiPath(pattern=RECORDING_NAME.pattern, description="a recording's file name")
    ],
    console: ConsoleDep,
    snapshot: SnapshotDep,
) -> HTMLResponse:
    """The debrief of a finished recording (``rov-console report``'s page): scores per leg,
    landings, pose, track and forces, events with who."""
    from app.report import debrief, render_html

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
    try:
        return HTMLResponse(render_html(debrief(path)))
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, f"{name}: {err}") from None
