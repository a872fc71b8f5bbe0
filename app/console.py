"""The console as one object: settings, the loop, uploaded missions and the token.

``create_app`` (app.server) builds one ``Console`` per application; routes reach it through a
typed dependency (``app.api.deps.ConsoleDep``), the 3D view gets it at start. Nothing is
created at import time.
"""

from __future__ import annotations

import ipaddress
import math
import secrets
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

from app.console_engine import ConsoleEngine, PreparedRun, prepare_run, station_keeping_mission
from app.console_loop import SPEED_MAX, SPEED_MIN, ConsoleLoop
from missions import schema

MAX_UPLOADS = 50
"""Uploaded missions kept in memory (the oldest goes first)."""


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

    def __post_init__(self) -> None:
        if not is_loopback(self.host) and not self.allow_remote:
            raise ValueError(f"host {self.host!r} is not a loopback address: binding to it "
                             f"exposes the console to the network; pass allow_remote "
                             f"(--allow-remote) to do it on purpose")
        for name in ("port", "viser_port"):
            value = getattr(self, name)
            if not 0 <= value <= 65535:
                raise ValueError(f"{name} must be in [0, 65535], got {value}")
        if self.view and self.port == self.viser_port and self.port != 0:
            raise ValueError(f"port and viser_port must differ, both are {self.port}")
        if self.token is not None and len(self.token) < 8:
            raise ValueError("token must have at least 8 characters")
        if not (math.isfinite(self.speed) and SPEED_MIN <= self.speed <= SPEED_MAX):
            raise ValueError(f"speed must be in [{SPEED_MIN}, {SPEED_MAX}], got {self.speed}")
        if not (math.isfinite(self.depth_m) and 5.0 < self.depth_m <= 4000.0):
            raise ValueError(f"depth_m must be in (5, 4000] m, got {self.depth_m}")


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass
class Console:
    """Everything one running console holds."""

    settings: ConsoleSettings
    loop: ConsoleLoop
    token: str
    uploads: OrderedDict[str, schema.Mission] = field(default_factory=OrderedDict)
    _uploads_lock: threading.Lock = field(default_factory=threading.Lock)

    @staticmethod
    def build(settings: ConsoleSettings) -> Console:
        """Build the first closed loop (the given mission's set-up, or station keeping)."""
        run = initial_run(settings)
        engine = ConsoleEngine(run, settings.recordings_dir)
        loop = ConsoleLoop(engine, speed=settings.speed, paused=settings.paused)
        token = settings.token or secrets.token_urlsafe(18)
        return Console(settings, loop, token)

    def is_token(self, candidate: str | None) -> bool:
        return candidate is not None and secrets.compare_digest(candidate.encode(),
                                                                self.token.encode())

    # ----------------------------------------------------------- missions
    def mission_names(self) -> tuple[list[str], list[str]]:
        """(library names, uploaded names)."""
        with self._uploads_lock:
            return schema.library_names(), list(self.uploads)

    def find_mission(self, name: str) -> schema.Mission:
        """An uploaded or library mission by name (never a path); KeyError if unknown."""
        with self._uploads_lock:
            if name in self.uploads:
                return self.uploads[name]
        if name in schema.library_names():
            return schema.load_mission(name)
        raise KeyError(name)

    def add_upload(self, mission: schema.Mission) -> str:
        if mission.name in schema.library_names():
            raise ValueError(f"name: {mission.name!r} is a library mission; give the upload "
                             f"another name")
        with self._uploads_lock:
            self.uploads.pop(mission.name, None)
            self.uploads[mission.name] = mission
            while len(self.uploads) > MAX_UPLOADS:
                self.uploads.popitem(last=False)
        return mission.name


def initial_run(settings: ConsoleSettings) -> PreparedRun:
    if settings.mission is not None:
        return prepare_run(schema.load_mission(settings.mission), run_legs=True)
    return prepare_run(station_keeping_mission(settings.params, settings.depth_m),
                       run_legs=False)
