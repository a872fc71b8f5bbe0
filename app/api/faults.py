"""The instructor's faults (inject now or later, list, clear) and the operations log, which
shows the instructor's commands only to the instructor.

Every fault route needs the instructor token (``Authorization: Bearer <instructor token>``), a
separate token from the console's: without one set (``serve --instructor-token`` or
``ROV_CONSOLE_INSTRUCTOR_TOKEN``) the routes answer 403 saying how to turn them on.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, HTTPException, Request, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from pydantic import BaseModel, Field

from app.api.deps import ConsoleDep, SnapshotDep, run_command
from app.api.schemas import CommandOut, Finite, _In
from app.console.faults import ClearFaults, InjectFault
from app.console.operations import Operation, trainee_view
from app.console.snapshot import FaultView
from app.console.tokens import INSTRUCTOR_TOKEN_ENV
from control.faults import DURATION_MAX_S, FAULT_KINDS

router = APIRouter(tags=["instructor"])
_bearer = HTTPBearer(auto_error=False, description="the instructor token")

OFF_TEXT = (
    "instructor features are off: start the console with --instructor-token "
    f"(or {INSTRUCTOR_TOKEN_ENV}) to inject faults"
)


def _client(request: Request) -> str:
    return f"http:{request.client.host if request.client else '?'}"


def require_instructor(
    request: Request,
    console: ConsoleDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """Only the instructor injects, lists and clears faults."""
    verdict, wait = console.check_instructor(
        credentials.credentials if credentials is not None else None, _client(request)
    )
    if verdict == "ok":
        return
    if verdict == "off":
        raise HTTPException(status.HTTP_403_FORBIDDEN, OFF_TEXT)
    if wait > 0.0:
        raise HTTPException(
            status.HTTP_429_TOO_MANY_REQUESTS,
            f"too many wrong tokens from this client: try again in {wait:.0f} s",
            headers={"Retry-After": str(max(int(wait + 0.999), 1))},
        )
    if verdict == "console token":
        raise HTTPException(
            status.HTTP_403_FORBIDDEN,
            "that is the console token: faults need the instructor token "
            "('Authorization: Bearer <instructor token>')",
        )
    raise HTTPException(
        status.HTTP_401_UNAUTHORIZED,
        "this action needs the instructor token: send the header "
        "'Authorization: Bearer <instructor token>'",
        headers={"WWW-Authenticate": "Bearer"},
    )


InstructorDep = Annotated[None, Depends(require_instructor)]


class FaultIn(_In):
    """A fault to inject. ``kind`` and ``value`` ranges: GET /api/faults/kinds."""

    kind: str = Field(max_length=40, description="one of control.faults.FAULT_KINDS")
    duration_s: Finite = Field(description=f"how long it lasts, (0, {DURATION_MAX_S:g}] s")
    value: Finite = Field(default=0.0, description="size in the kind's unit (see /kinds)")
    start_s: Finite | None = Field(
        default=None, description="simulation time it starts [s]; omitted: now"
    )
    thruster: int = Field(default=0, description="thruster faults: which thruster (1-based)")
    direction_deg: Finite = Field(default=0.0, description="vessel drift: towards [deg]")


class FaultEventOut(BaseModel):
    t_s: float
    text: str


class FaultsOut(BaseModel):
    t_s: float = Field(description="simulation time now [s]")
    active: list[FaultView]
    scheduled: list[FaultView]
    events: list[FaultEventOut] = Field(description="the latest fault starts and ends")


class FaultKindOut(BaseModel):
    kind: str
    unit: str
    min: float
    max: float
    takes_thruster: bool


class OperationOut(BaseModel):
    utc: str
    t_s: float
    who: str
    action: str
    outcome: str

    @staticmethod
    def of(op: Operation) -> OperationOut:
        return OperationOut(
            utc=op.utc, t_s=op.t_s, who=op.who, action=op.action, outcome=op.outcome
        )


@router.get("/api/faults/kinds", response_model=list[FaultKindOut])
def fault_kinds() -> list[FaultKindOut]:
    """Every fault kind with its value's unit and range (no token needed: it is the menu)."""
    from control.faults import THRUSTER_KINDS

    return [
        FaultKindOut(kind=k, unit=u, min=lo, max=hi, takes_thruster=k in THRUSTER_KINDS)
        for k, (u, lo, hi) in FAULT_KINDS.items()
    ]


@router.get("/api/faults", response_model=FaultsOut)
def get_faults(snapshot: SnapshotDep, _: InstructorDep) -> FaultsOut:
    """Faults active now and scheduled, and the latest starts and ends (instructor only)."""
    views = list(snapshot.faults)
    return FaultsOut(
        t_s=snapshot.t_s,
        active=[f for f in views if f.state == "active"],
        scheduled=[f for f in views if f.state == "scheduled"],
        events=[FaultEventOut(t_s=t, text=text) for t, text in snapshot.fault_log],
    )


@router.post("/api/faults", response_model=CommandOut)
async def inject_fault(body: FaultIn, console: ConsoleDep, _: InstructorDep) -> CommandOut:
    """Inject a fault now (no start_s) or at a later simulation time (instructor only)."""
    try:
        command = InjectFault(
            body.kind, body.duration_s, body.value, body.start_s, body.thruster, body.direction_deg
        )
    except ValueError as err:
        raise HTTPException(422, str(err)) from None
    return CommandOut(result=await run_command(console, command))


@router.delete("/api/faults", response_model=CommandOut)
async def clear_faults(console: ConsoleDep, _: InstructorDep) -> CommandOut:
    """End every fault now and drop the scheduled ones (instructor only)."""
    return CommandOut(result=await run_command(console, ClearFaults()))


@router.get("/api/operations", response_model=list[OperationOut])
def operations(
    request: Request,
    snapshot: SnapshotDep,
    console: ConsoleDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> list[OperationOut]:
    """The latest operations (who did what), oldest first. Watching needs no token; the
    instructor's own commands (faults) are listed only with the instructor token."""
    ops = snapshot.operations
    given = credentials.credentials if credentials is not None else None
    if given is None or console.check_instructor(given, _client(request))[0] != "ok":
        ops = trainee_view(ops)
    return [OperationOut.of(op) for op in ops]
