"""Sea current and the vessel (crane tip) the wire hangs from."""

from __future__ import annotations

import math

from fastapi import APIRouter

from app.api.deps import ConsoleDep, SnapshotDep, TokenDep, run_command
from app.api.schemas import (
    CommandOut,
    CurrentIn,
    CurrentOut,
    EnvironmentOut,
    VesselIn,
    VisibilityIn,
    VisibilityOut,
)
from app.console.commands import ApplyVesselAdvice, MoveVessel, SetCurrent

router = APIRouter(prefix="/api/environment", tags=["environment"])


@router.get("", response_model=EnvironmentOut)
def get_environment(snapshot: SnapshotDep) -> EnvironmentOut:
    return EnvironmentOut(
        current=CurrentOut(
            speed_mps=snapshot.current_speed_mps,
            direction_deg=math.degrees(snapshot.current_direction_rad),
        ),
        crane_tip_n=list(snapshot.crane_tip_n),
        wire_length_m=snapshot.wire_length_m,
        wire_tension_newton=snapshot.wire_tension_newton,
    )


@router.put("/current", response_model=CommandOut)
async def set_current(body: CurrentIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    """A steady, uniform current."""
    return CommandOut(
        result=await run_command(console, SetCurrent(body.speed_mps, body.direction_deg))
    )


@router.put("/vessel", response_model=CommandOut)
async def move_vessel(body: VesselIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    """Move the vessel (and the crane tip) to a position at a speed."""
    return CommandOut(
        result=await run_command(console, MoveVessel(body.north_m, body.east_m, body.speed_mps))
    )


@router.post("/vessel/apply-advice", response_model=CommandOut)
async def apply_vessel_advice(console: ConsoleDep, _: TokenDep) -> CommandOut:
    """Follow the running dock leg's advice to move the vessel (``vessel = "advise"``; the
    state's ``mission.vessel_advice``): the vessel goes to the advised crane tip at the
    speed the leg itself moves it. 409 when there is no advice to apply or it is applied
    already."""
    return CommandOut(result=await run_command(console, ApplyVesselAdvice()))


@router.get("/visibility", response_model=VisibilityOut)
def get_visibility(console: ConsoleDep) -> VisibilityOut:
    """How far the water lets one see (the 3D view's fog; the simulation is not changed)."""
    return VisibilityOut(visibility_m=console.water.visibility_m)


@router.put("/visibility", response_model=VisibilityOut)
def set_visibility(body: VisibilityIn, console: ConsoleDep, _: TokenDep) -> VisibilityOut:
    """Set the water's visibility, from turbid (2 m) to clear (30 m)."""
    return VisibilityOut(visibility_m=console.water.set_visibility_m(body.visibility_m))
