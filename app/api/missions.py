"""Missions: the library, uploads, validation, start and abort."""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, HTTPException, status

from app.api.deps import UNPROCESSABLE, ConsoleDep, SnapshotDep, TokenDep, run_command
from app.api.schemas import (
    CommandOut,
    MissionListOut,
    MissionOut,
    MissionStatusOut,
    MissionSummaryOut,
    MissionTextIn,
    StartMissionIn,
    UploadOut,
    ValidationOut,
)
from app.console import prepare_run
from app.console.commands import AbortMission, StartRun
from app.console.instance import check_sent_mission
from app.console.texts import quoted
from missions import schema

router = APIRouter(prefix="/api/missions", tags=["missions"])


def _summary(m: schema.Mission, source: str) -> MissionSummaryOut:
    return MissionSummaryOut(
        name=m.name,
        description=m.description,
        legs=len(m.legs),
        params=m.setup.params,
        source=source,
    )


def parse_text(body: MissionTextIn) -> schema.Mission:
    """The mission in a request; MissionError names the field (and the line of a TOML), or
    refuses a parameter set named by a server path (``check_sent_mission``)."""
    if (body.toml is None) == (body.mission is None):
        raise schema.MissionError("give exactly one of 'toml' (text) or 'mission' (object)")
    if body.toml is not None:
        mission = schema.parse_text(body.toml, "toml")
    else:
        mission = schema.parse_mission(body.mission or {}, "<upload>")
    check_sent_mission(mission)
    return mission


@router.get("", response_model=MissionListOut)
def list_missions(console: ConsoleDep) -> MissionListOut:
    library, uploaded = console.mission_names()
    return MissionListOut(
        library=[_summary(schema.load_mission(n), "library") for n in library],
        uploaded=[_summary(console.find_mission(n), "upload") for n in uploaded],
        leg_types=list(schema.leg_models()),
    )


@router.get("/current", response_model=MissionStatusOut)
def current_mission(snapshot: SnapshotDep) -> MissionStatusOut:
    """The running mission and leg, or the last one's result."""
    return MissionStatusOut.of(snapshot.mission)


@router.get("/leg-types", response_model=dict[str, dict])
def leg_types() -> dict[str, dict]:
    """JSON schema of each leg type (what the mission builder offers)."""
    return {name: model.model_json_schema() for name, model in schema.leg_models().items()}


@router.get("/{name}", response_model=MissionOut)
def get_mission(name: str, console: ConsoleDep) -> MissionOut:
    try:
        m = console.find_mission(name)
    except KeyError:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no mission named {quoted(name)}") from None
    return MissionOut(name=m.name, mission=m.model_dump(mode="json"), toml=schema.dump_mission(m))


@router.post("/validate", response_model=ValidationOut)
def validate(body: MissionTextIn) -> ValidationOut:
    """Check a mission without keeping it; the errors name the field and the allowed range."""
    try:
        m = parse_text(body)
    except schema.MissionError as err:
        lines = [ln.strip() for ln in str(err).splitlines()]
        return ValidationOut(valid=False, errors=lines[1:] if len(lines) > 1 else lines)
    return ValidationOut(valid=True, errors=[], name=m.name, legs=len(m.legs))


@router.post("/uploads", response_model=UploadOut, status_code=status.HTTP_201_CREATED)
def upload(body: MissionTextIn, console: ConsoleDep, _: TokenDep) -> UploadOut:
    """Keep a mission (in memory) to start it by name."""
    try:
        name = console.add_upload(parse_text(body))
    except schema.MissionError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
    except ValueError as err:
        raise HTTPException(status.HTTP_409_CONFLICT, str(err)) from None
    return UploadOut(name=name)


@router.post("/start", response_model=CommandOut)
async def start(body: StartMissionIn, console: ConsoleDep, _: TokenDep) -> CommandOut:
    """Build the mission's set-up and run its legs (or only load the set-up)."""
    try:
        mission = console.find_mission(body.name)
    except KeyError:
        raise HTTPException(
            status.HTTP_404_NOT_FOUND, f"name: no mission named {quoted(body.name)}"
        ) from None
    try:
        run = await asyncio.to_thread(prepare_run, mission, body.run_legs)
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
    return CommandOut(result=await run_command(console, StartRun(run)))


@router.post("/abort", response_model=CommandOut)
async def abort(console: ConsoleDep, _: TokenDep) -> CommandOut:
    return CommandOut(result=await run_command(console, AbortMission()))
