"""Pause, resume, single-step, speed and reset of the simulation."""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, HTTPException

from app.api.deps import UNPROCESSABLE, ConsoleDep, SnapshotDep, TokenDep, run_command
from app.api.schemas import CommandOut, LoopOut, ResetIn, SpeedIn, StateOut, StepIn
from app.console import prepare_run, station_keeping_mission
from app.console.commands import Pause, Resume, SetSpeed, StartRun, Step
from sim import params as params_mod

router = APIRouter(prefix="/api/run", tags=["run"])


@router.get("", response_model=LoopOut)
def get_run(snapshot: SnapshotDep) -> LoopOut:
    """Paused or running, speed, and how well the loop keeps its 100 Hz pace."""
    return StateOut.of(snapshot).loop


@router.post("/pause", response_model=CommandOut)
async def pause(console: ConsoleDep, _: TokenDep) -> CommandOut:
    return CommandOut(result=await run_command(console, Pause()))


@router.post("/resume", response_model=CommandOut)
async def resume(console: ConsoleDep, _: TokenDep) -> CommandOut:
    return CommandOut(result=await run_command(console, Resume()))


@router.post("/step", response_model=CommandOut)
async def step(body: StepIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    """Advance a paused run by ``steps`` plant steps."""
    return CommandOut(result=await run_command(console, Step(body.steps)))


@router.put("/speed", response_model=CommandOut)
async def speed(body: SpeedIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    return CommandOut(result=await run_command(console, SetSpeed(body.speed)))


@router.post("/reset", response_model=CommandOut)
async def reset(
    body: ResetIn, console: ConsoleDep, snapshot: SnapshotDep, _: TokenDep
) -> CommandOut:
    """Start again from a station-keeping set-up (a preset parameter set, a depth)."""
    params = body.params or snapshot.scene.params_name
    if params not in params_mod.available_presets():
        raise HTTPException(
            UNPROCESSABLE,
            f"params must be one of {', '.join(params_mod.available_presets())}, got {params!r}",
        )
    depth = body.depth_m or console.settings.depth_m
    run = await asyncio.to_thread(prepare_run, station_keeping_mission(params, depth), False)
    return CommandOut(result=await run_command(console, StartRun(run)))
