"""``Console``: one running console as one object — its settings, the paced loop (which owns
the session), uploaded missions and the token.

``create_app`` (app.server) builds one ``Console`` per application; routes reach it through a
typed dependency (``app.api.deps.ConsoleDep``), the 3D view gets it at start. Nothing is
created at import time.
"""

from __future__ import annotations

import secrets
import threading
from collections import OrderedDict
from dataclasses import dataclass, field

from app.console.loop import PacedLoop
from app.console.session import PreparedRun, Session, prepare_run, station_keeping_mission
from app.console.settings import ConsoleSettings
from app.console.tokens import GuessLimit
from missions import schema

MAX_UPLOADS = 50
"""Uploaded missions kept in memory (the oldest goes first)."""


@dataclass
class Console:
    """Everything one running console holds."""

    settings: ConsoleSettings
    loop: PacedLoop
    token: str
    uploads: OrderedDict[str, schema.Mission] = field(default_factory=OrderedDict)
    _uploads_lock: threading.Lock = field(default_factory=threading.Lock)
    guesses: GuessLimit = field(default_factory=GuessLimit)
    """Wrong tokens per client (HTTP address or 3D-view client)."""

    @staticmethod
    def build(settings: ConsoleSettings) -> Console:
        """Build the first simulation (the given mission's set-up, or station keeping)."""
        run = initial_run(settings)
        session = Session(run, settings.recordings_dir)
        loop = PacedLoop(session, speed=settings.speed, paused=settings.paused)
        token = settings.token or secrets.token_urlsafe(18)
        return Console(settings, loop, token)

    def is_token(self, candidate: str | None) -> bool:
        return candidate is not None and secrets.compare_digest(
            candidate.encode(), self.token.encode()
        )

    def check_token(self, candidate: str | None, client: str) -> tuple[bool, float]:
        """(is it the token, seconds the client must wait before trying again). A wrong token
        counts against the client; a locked-out client is refused even with the right one."""
        wait = self.guesses.retry_after_s(client)
        if wait > 0.0:
            return False, wait
        if self.is_token(candidate):
            return True, 0.0
        self.guesses.failed(client)
        return False, 0.0

    # ----------------------------------------------------------- the instructor
    @property
    def instructor_on(self) -> bool:
        """The instructor's features (faults) are on: an instructor token was set."""
        return self.settings.instructor_token is not None

    def check_instructor(self, candidate: str | None, client: str) -> tuple[str, float]:
        """('ok' | 'off' | 'missing' | 'console token' | 'wrong', seconds the client must wait).
        Wrong tokens count against the client as for the console token (one guess limit)."""
        wanted = self.settings.instructor_token
        if wanted is None:
            return "off", 0.0
        wait = self.guesses.retry_after_s(client)
        if wait > 0.0:
            return "wrong", wait
        if candidate is None or candidate == "":
            return "missing", 0.0
        if secrets.compare_digest(candidate.encode(), wanted.encode()):
            return "ok", 0.0
        if self.is_token(candidate):
            return "console token", 0.0
        self.guesses.failed(client)
        return "wrong", 0.0

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
            raise ValueError(
                f"name: {mission.name!r} is a library mission; give the upload another name"
            )
        with self._uploads_lock:
            self.uploads.pop(mission.name, None)
            self.uploads[mission.name] = mission
            while len(self.uploads) > MAX_UPLOADS:
                self.uploads.popitem(last=False)
        return mission.name


def initial_run(settings: ConsoleSettings) -> PreparedRun:
    if settings.mission is not None:
        return prepare_run(schema.load_mission(settings.mission), run_legs=True)
    return prepare_run(station_keeping_mission(settings.params, settings.depth_m), run_legs=False)
