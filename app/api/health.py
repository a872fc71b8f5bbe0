"""Liveness: answers without a token."""

from fastapi import APIRouter

from app.api.deps import ConsoleDep
from app.api.schemas import HealthOut

router = APIRouter(prefix="/api/health", tags=["health"])


@router.get("", response_model=HealthOut)
def health(console: ConsoleDep) -> HealthOut:
    return HealthOut(status="ok", t_s=console.loop.snapshot.t_s, loop_running=console.loop.running)
