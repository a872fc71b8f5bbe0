"""Controller mode (tree / free ROV), grip, thrust allocation and the tree's target."""

from __future__ import annotations

from fastapi import APIRouter

from app.api.deps import ConsoleDep, SnapshotDep, TokenDep, run_command
from app.api.schemas import (
    AllocationIn,
    CommandOut,
    ControlOut,
    GripIn,
    ModeIn,
    PoseOut,
    TargetIn,
)
from app.console.commands import SetAllocation, SetGrip, SetMode, SetTarget

router = APIRouter(prefix="/api/control", tags=["control"])


@router.get("", response_model=ControlOut)
def get_control(snapshot: SnapshotDep) -> ControlOut:
    return ControlOut(
        mode=snapshot.mode,
        allocation=snapshot.allocation,
        grip=snapshot.grip,
        reference=PoseOut.of(snapshot.eta_ref),
    )


@router.put("/mode", response_model=CommandOut)
async def set_mode(body: ModeIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    return CommandOut(result=await run_command(console, SetMode(body.mode)))


@router.put("/allocation", response_model=CommandOut)
async def set_allocation(body: AllocationIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    return CommandOut(result=await run_command(console, SetAllocation(body.allocation)))


@router.put("/grip", response_model=CommandOut)
async def set_grip(body: GripIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    return CommandOut(result=await run_command(console, SetGrip(body.grip)))


@router.put("/target", response_model=CommandOut)
async def set_target(body: TargetIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    """Where the tree should go (when no mission is running)."""
    return CommandOut(
        result=await run_command(console, SetTarget(body.north_m, body.east_m, body.heading_deg))
    )
