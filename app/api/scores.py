"""Scores of flown missions (history, best runs, hand against autopilot) and the debrief of a
finished recording, as the page and any client read them (watching: no token)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, HTTPException, Query
from fastapi import Path as FastApiPath
from fastapi.responses import HTMLResponse

from app import scores as store
from app.api.deps import UNPROCESSABLE, ConsoleDep, SnapshotDep
from app.api.recordings import finished_recording
from app.console import RECORDING_NAME
from app.console.session import SCORES_DB

router = APIRouter(tags=["scores"])


def _history(console: ConsoleDep, trainee: str | None, mission: str | None) -> list[store.Score]:
    try:
        return store.history(console.settings.recordings_dir / SCORES_DB, trainee, mission)
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None


@router.get("/api/scores", response_model=list[store.Score])
def get_scores(
    console: ConsoleDep,
    trainee: Annotated[str | None, Query(max_length=200)] = None,
    mission: Annotated[str | None, Query(max_length=200)] = None,
    best: bool = False,
) -> list[store.Score]:
    """Stored scores, newest first (``best``: the best run of each mission)."""
    rows = _history(console, trainee, mission)
    return store.best(rows) if best else rows


@router.get("/api/scores/compare", response_model=dict[str, store.Score])
def compare_scores(
    console: ConsoleDep,
    mission: Annotated[str, Query(min_length=1, max_length=200)],
    trainee: Annotated[str | None, Query(max_length=200)] = None,
) -> dict[str, store.Score]:
    """The best run of ``mission`` flown by the autopilot, by hand and mixed, side by side."""
    return store.compare(_history(console, trainee, mission))


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

    path = finished_recording(name, console, snapshot)
    try:
        return HTMLResponse(render_html(debrief(path)))
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, f"{name}: {err}") from None
