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
    console: ConsoleDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """Actions that change the run need the token; watching does not."""
    if credentials is None or not console.is_token(credentials.credentials):
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "this action needs the console token: send the header "
            "'Authorization: Bearer <token>' (printed at start-up)",
            headers={"WWW-Authenticate": "Bearer"},
        )


TokenDep = Annotated[None, Depends(require_token)]


async def run_command(console: Console, command: Command) -> object:
    """Queue a command for the loop and wait for it; its failure becomes a 4xx/503."""
    try:
        return await console.loop.call(command)
    except FileNotFoundError as err:
        raise HTTPException(status.HTTP_404_NOT_FOUND, str(err).strip("'\"")) from None
    except ConsoleError as err:
        raise HTTPException(status.HTTP_409_CONFLICT, str(err)) from None
    except ValueError as err:
        raise HTTPException(UNPROCESSABLE, str(err)) from None
    except TimeoutError:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE, "the simulation loop did not answer in time"
        ) from None
