"""Typed dependencies of the routes, and turning a command's failure into an HTTP answer."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, HTTPException, Request, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from app.console import Console, ConsoleError, Snapshot
from app.console.commands import Command

UNPROCESSABLE = 422
"""A request that is well-formed but names a value the console cannot use."""
_bearer = HTTPBearer(auto_error=False, description="the console token printed at start-up")


def get_console(request: Request) -> Console:
    return request.app.state.console


ConsoleDep = Annotated[Console, Depends(get_console)]


def get_snapshot(console: ConsoleDep) -> Snapshot:
    return console.loop.snapshot


SnapshotDep = Annotated[Snapshot, Depends(get_snapshot)]


def require_token(
    request: Request,
    console: ConsoleDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """Actions that change the run need the token; watching does not. A client that sent
    too many wrong tokens is refused (429) until its window has passed."""
    client = f"http:{request.client.host if request.client else '?'}"
    ok, wait = console.check_token(
        credentials.credentials if credentials is not None else None, client
    )
    if wait > 0.0:
        raise HTTPException(
            status.HTTP_429_TOO_MANY_REQUESTS,
            f"too many wrong tokens from this client: try again in {wait:.0f} s",
            headers={"Retry-After": str(max(int(wait + 0.999), 1))},
        )
    role = console.crew_role(credentials.credentials) if credentials is not None else None
    if not ok and role is not None:
        raise HTTPException(
            status.HTTP_403_FORBIDDEN,
            f"that is the {role} station's token: it opens GET /{role} only; this action "
            "needs the console token",
        )
    if not ok:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "this action needs the console token: send the header "
            "'Authorization: Bearer <token>' (printed at start-up)",
            headers={"WWW-Authenticate": "Bearer"},
        )


TokenDep = Annotated[None, Depends(require_token)]


def require_reviewer(
    request: Request,
    console: ConsoleDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
    ticket: str | None = None,
) -> None:
    """Debriefs are for the people who run the session: the console token, the instructor's
    token, or the ticket the 3D view puts in the links it gives unlocked browsers. Watchers
    (no token) read scores but do not start the report's seconds of work."""
    if console.is_debrief_ticket(ticket):
        return
    if credentials is not None and console.is_instructor_token(credentials.credentials):
        return
    require_token(request, console, credentials)  # the console token; wrong ones count


ReviewerDep = Annotated[None, Depends(require_reviewer)]


COMMAND_TIMEOUT_S = 10.0
"""How long an API request waits for the loop to apply its command [s]."""


async def run_command(console: Console, command: Command) -> object:
    """Queue a command for the loop and wait for it; its failure becomes a 4xx/503."""
    try:
        return await console.loop.call(command, COMMAND_TIMEOUT_S)
    except TimeoutError:  # before OSError: TimeoutError is one of its subclasses
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            f"the simulation loop did not answer within {COMMAND_TIMEOUT_S:g} s; "
            "it may be overloaded, and the command may still be applied",
        ) from None
    except FileNotFoundError as err:
        raise HTTPException(status.HTTP_404_NOT_FOUND, str(err).strip("'\"")) from None
    except ConsoleError as err:
        raise HTTPException(status.HTTP_409_CONFLICT, str(err)) from None
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
    except OSError as err:  # e.g. the recordings folder is read-only or the disk is full
        raise HTTPException(
            status.HTTP_507_INSUFFICIENT_STORAGE,
            f"cannot write: {err.strerror or err}" + (f" ({err.filename})" if err.filename else ""),
        ) from None
