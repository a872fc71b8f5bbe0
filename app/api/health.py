"""Liveness: answers without a token; 503 when the simulation loop is not ticking, or when
its state cannot be served (what /api/state and the telemetry sockets send)."""

from fastapi import APIRouter, Request, Response, status

from app.api.deps import ConsoleDep
from app.api.schemas import HealthOut
from app.api.state import StateJsonCache
from app.console import Console

router = APIRouter(prefix="/api/health", tags=["health"])


@router.get(
    "",
    response_model=HealthOut,
    responses={
        503: {
            "model": HealthOut,
            "description": "the loop is stopped or stalled, or its state cannot be served",
        }
    },
)
def health(console: ConsoleDep, request: Request, response: Response) -> HealthOut:
    loop = console.loop
    state = loop.health()
    state_error = None
    if state == "ok":
        state_error = unservable(request.app.state.state_cache, console)
        if state_error is not None:
            state = "broken"
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
        state_error=state_error,
    )


def unservable(cache: StateJsonCache, console: Console) -> str | None:
    """Why the latest state cannot be written as JSON (None: it can). The text is cached
    per snapshot, so this costs one serialisation per tick at most, shared with telemetry."""
    try:
        cache.text(console)
    except Exception as err:  # whatever breaks /api/state breaks health: say what
        return f"the state cannot be served: {type(err).__name__}: {str(err)[:200]}"
    return None
