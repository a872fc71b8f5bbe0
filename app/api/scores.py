"""Scores of flown missions (history, best runs, hand against autopilot), as the page and any
client read them (watching: no token), and the debrief of a finished recording (the console
or instructor token, or the 3D view's ticket: a report takes seconds of work; one is written
at a time, and each recording's is kept while the file is unchanged)."""

from __future__ import annotations

import threading
from collections import OrderedDict
from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, HTTPException, Query, Request, status
from fastapi import Path as FastApiPath
from fastapi.responses import HTMLResponse

from app import scores as store
from app.api.deps import UNPROCESSABLE, ConsoleDep, ReviewerDep, SnapshotDep
from app.api.recordings import finished_recording
from app.console import RECORDING_NAME
from app.console.session import SCORES_DB

router = APIRouter(tags=["scores"])

MAX_REPORT_RECORDING_BYTES = 256 * 1024 * 1024
"""Largest recording debriefed over HTTP [bytes] (a 24 MB one took 11-17 s); the command line
(``rov-console report``) has no limit."""
REPORT_RETRY_S = 15
"""Retry-After of a debrief asked for while another is being written [s]."""
REPORTS_KEPT = 8
"""Debrief pages kept (a few hundred kB each, figures inline)."""


class ReportCache:
    """Debrief pages by recording (path, modification time, size): a recording is read and
    drawn once, and again only when its file changes. One report is written at a time."""

    def __init__(self, kept: int = REPORTS_KEPT) -> None:
        self.kept = kept
        self.written = 0
        """Reports written (not served from the cache)."""
        self._pages: OrderedDict[tuple[str, int, int], str] = OrderedDict()
        self._lock = threading.Lock()
        self._writing = threading.Lock()

    def page(self, path: Path) -> str | None:
        """The debrief of ``path``; None when another report is being written now."""
        stat = path.stat()
        key = (str(path), stat.st_mtime_ns, stat.st_size)
        with self._lock:
            if key in self._pages:
                self._pages.move_to_end(key)
                return self._pages[key]
        if not self._writing.acquire(blocking=False):
            return None
        try:
            from app.report import debrief, render_html

            page = render_html(debrief(path))
            with self._lock:
                self._pages[key] = page
                while len(self._pages) > self.kept:
                    self._pages.popitem(last=False)
            self.written += 1
            return page
        finally:
            self._writing.release()


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
    request: Request,
    _: ReviewerDep,
) -> HTMLResponse:
    """The debrief of a finished recording (``rov-console report``'s page): scores per leg,
    landings, pose, track and forces, events with who. Needs the console or instructor token
    (or ``ticket``, the 3D view's); 503 with Retry-After while another report is written."""
    path = finished_recording(name, console, snapshot)
    size = path.stat().st_size
    if size > MAX_REPORT_RECORDING_BYTES:
        raise HTTPException(
            status.HTTP_413_REQUEST_ENTITY_TOO_LARGE,
            f"{name}: {size} bytes; the console debriefs recordings of at most "
            f"{MAX_REPORT_RECORDING_BYTES} bytes (use 'rov-console report' for larger ones)",
        )
    cache: ReportCache = request.app.state.reports
    try:
        page = cache.page(path)
    except ValueError as err:
        # the error names the file by its name, never by its place on the server
        raise HTTPException(UNPROCESSABLE, f"{name}: {err}".replace(str(path), name)) from None
    if page is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            f"another debrief is being written: try again in {REPORT_RETRY_S} s",
            headers={"Retry-After": str(REPORT_RETRY_S)},
        )
    return HTMLResponse(page)
