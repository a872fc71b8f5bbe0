"""``ConsoleSettings``: the options of ``rov-console serve``, checked when made."""

from __future__ import annotations

import ipaddress
import math
import socket
from collections.abc import Collection
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import urlsplit

from app.console.commands import SPEED_MAX, SPEED_MIN
from app.console.tokens import (
    CREW_TOKEN_FIELDS,
    MIN_INSTRUCTOR_TOKEN_CHARS,
    MIN_TOKEN_CHARS,
    check_crew_tokens,
    check_token,
)


@dataclass(frozen=True)
class ConsoleSettings:
    """Options of ``rov-console serve``."""

    host: str = "127.0.0.1"
    """Address the HTTP API and the 3D view bind to."""
    port: int = 8000
    """HTTP port (API, OpenAPI, telemetry WebSocket)."""
    viser_port: int = 8080
    """Port of the 3D view (viser)."""
    token: str | None = None
    """Token for actions that change the run; None: one is generated at start."""
    instructor_token: str | None = None
    """Token of the instructor (faults); None: the instructor's features are off (the API
    answers 403 saying how to turn them on; the page's instructor tab says the same)."""
    winch_token: str | None = None
    """Token of the winch station (GET /winch); None: only the console token opens it."""
    supervisor_token: str | None = None
    """Token of the supervisor's station (GET /supervisor: watch, pause, resume); None: only
    the console token opens it."""
    params: str = "full-scale"
    """Parameter set when no mission is given."""
    mission: str | None = None
    """Library mission (or file) to load and start."""
    depth_m: float = 400.0
    """Tree depth when no mission is given [m]."""
    recordings_dir: Path = Path("recordings")
    """Where session recordings (MCAP) go."""
    allow_remote: bool = False
    """Binding to a non-loopback address must be asked for explicitly."""
    view: bool = True
    """Start the 3D view (viser); the API alone for tests."""
    paused: bool = False
    """Start paused."""
    speed: float = 1.0
    """Start speed (simulated s per wall-clock s)."""
    announce: bool = False
    """Print the addresses and the token once serving (the serve command)."""
    foxglove_port: int | None = None
    """Also serve the session live over the Foxglove WebSocket protocol on this port
    (read-only; on ``host``, so loopback unless ``allow_remote``); None: not."""
    behind_proxy: bool = False
    """A reverse proxy on this machine stands in front of the console: its X-Forwarded-For
    and X-Forwarded-Proto headers are believed (the client address the token lockout counts
    and the operations log names). Off: those headers are ignored, whoever sends them."""

    def __post_init__(self) -> None:
        if isinstance(self.recordings_dir, str):
            # a path given as text (a script's settings): a Path, as the CLI makes it
            object.__setattr__(self, "recordings_dir", Path(self.recordings_dir))
        if not isinstance(self.recordings_dir, Path):
            raise ValueError(
                f"recordings_dir must be a folder's path, got "
                f"{type(self.recordings_dir).__name__} {self.recordings_dir!r}"
            )
        if not is_loopback(self.host) and not self.allow_remote:
            raise ValueError(
                f"host {self.host!r} is not a loopback address: binding to it "
                f"exposes the console to the network; pass allow_remote "
                f"(--allow-remote) to do it on purpose"
            )
        for name in ("port", "viser_port"):
            value = getattr(self, name)
            if not 0 <= value <= 65535:
                raise ValueError(f"{name} must be in [0, 65535], got {value}")
        if self.view and self.port == self.viser_port and self.port != 0:
            raise ValueError(f"port and viser_port must differ, both are {self.port}")
        if self.foxglove_port is not None:
            if not 1 <= self.foxglove_port <= 65535:
                raise ValueError(f"foxglove_port must be in [1, 65535], got {self.foxglove_port}")
            if self.foxglove_port in (self.port, self.viser_port):
                raise ValueError(
                    f"foxglove_port must differ from port and viser_port, got {self.foxglove_port}"
                )
        check_token("token", self.token, MIN_TOKEN_CHARS)
        check_token("instructor_token", self.instructor_token, MIN_INSTRUCTOR_TOKEN_CHARS)
        if self.instructor_token is not None and self.instructor_token == self.token:
            raise ValueError("instructor_token must differ from the console token")
        check_crew_tokens(
            {n: getattr(self, n) for n in ("token", "instructor_token", *CREW_TOKEN_FIELDS)}
        )
        if not (math.isfinite(self.speed) and SPEED_MIN <= self.speed <= SPEED_MAX):
            raise ValueError(f"speed must be in [{SPEED_MIN}, {SPEED_MAX}], got {self.speed}")
        if not (math.isfinite(self.depth_m) and 5.0 < self.depth_m <= 4000.0):
            raise ValueError(f"depth_m must be in (5, 4000] m, got {self.depth_m}")


def is_loopback(host: str) -> bool:
    """localhost, or an address in 127.0.0.0/8 or ::1, in any spelling the system accepts
    (127.1 is 127.0.0.1)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        pass
    try:
        return ipaddress.ip_address(socket.inet_aton(host)).is_loopback
    except OSError:
        return False


def allowed_hosts(host: str, allow_remote: bool) -> list[str]:
    """Host names the server answers to: the loopback names and the bound address; with
    ``allow_remote`` and a wildcard bind, any (the operator chose to expose it)."""
    if allow_remote and host in ("0.0.0.0", "::"):
        return ["*"]
    names = {"127.0.0.1", "localhost", "::1", "[::1]", host, f"[{host}]"}
    return sorted(names)


def origin_allowed(origin: str | None, hosts: list[str], ports: Collection[int]) -> bool:
    """A WebSocket's Origin (None for non-browser clients) must be one of the console's own
    pages: one of our host names and one of the ``ports`` it serves pages on (the API's and
    the 3D view's), so another web server on this machine (``http://localhost:9999``) does
    not pass."""
    if origin is None or "*" in hosts:
        return True
    try:
        parts = urlsplit(origin)
        name = parts.hostname or ""
        port = parts.port or DEFAULT_PORTS.get(parts.scheme)
    except ValueError:
        return False
    named = name in hosts or f"[{name}]" in hosts or is_loopback(name)
    return named and parts.scheme in DEFAULT_PORTS and port in ports


DEFAULT_PORTS = {"http": 80, "https": 443}
"""The port an Origin without one means, by its scheme (the only schemes a page has here)."""


PILOT_VIEW_PATH = "/pilot-view"
"""The path of the 3D view's socket when the pilot page embeds the view: that browser's
console panel starts minimised (the pilot flies from the pilot page's own side panel, and
the console's panel covered a third of the view)."""
