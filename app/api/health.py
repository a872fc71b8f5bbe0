"""Liveness: answers without a token; 503 when the simulation loop is not ticking."""

from fastapi import APIRouter, Response, status

from app.api.deps import ConsoleDep
from app.api.schemas import HealthOut

router = APIRouter(prefix="/api/health", tags=["health"])


@router.get(
    "",
    response_model=HealthOut,
    responses={503: {"model": HealthOut, "description": "the loop is stopped or stalled"}},
)
def health(console: ConsoleDep, response: Response) -> HealthOut:
    loop = console.loop
    state = loop.health()
    if state != "ok":
        response.status_code = status.HTTP_503_SERVICE_UNAVAILABLE
    snap = loop.snapshot
    return HealthOut(
        status=state,
        t_s=snap.t_s,
        loop_running=loop.running,
        ticks=loop.ticks,
        run_error=snap.error,
        faults=loop.faults,
    )
