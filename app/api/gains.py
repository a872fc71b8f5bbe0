"""Tree-controller gains: read, and set (validated, bumpless)."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException

from app.api.deps import UNPROCESSABLE, ConsoleDep, SnapshotDep, TokenDep, run_command
from app.api.schemas import GainsIn, GainsOut
from app.console import Gains
from app.console.commands import SetGains

router = APIRouter(prefix="/api/gains", tags=["gains"])


def gains_out(g: Gains) -> GainsOut:
    return GainsOut(kp=list(g.kp), ki=list(g.ki), kd=list(g.kd))


@router.get("", response_model=GainsOut)
def get_gains(console: ConsoleDep, snapshot: SnapshotDep) -> GainsOut:
    """The live controller's gains (also while a replay is shown)."""
    return gains_out(snapshot.gains or console.loop.session.sim.gains)


@router.put("", response_model=GainsOut)
async def set_gains(body: GainsIn, console: ConsoleDep, _: TokenDep) -> GainsOut:
    try:
        gains = Gains(tuple(body.kp), tuple(body.ki), tuple(body.kd))
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
    applied = await run_command(console, SetGains(gains))
    return gains_out(applied)  # type: ignore[arg-type]
