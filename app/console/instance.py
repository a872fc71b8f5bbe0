"""``Console``: one running console as one object — its settings, the paced loop (which owns
the session), uploaded missions and the token.

``create_app`` (app.server) builds one ``Console`` per application; routes reach it through a
typed dependency (``app.api.deps.ConsoleDep``), the 3D view gets it at start. Nothing is
created at import time.
"""

from __future__ import annotations

import re
import secrets
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field

from app.console.errors import ConsoleError
from app.console.loop import PacedLoop
from app.console.session import PreparedRun, Session, prepare_run, station_keeping_mission
from app.console.settings import ConsoleSettings
from app.console.tokens import CREW_ROLES, GuessLimit
from app.console.water import Water
from missions import schema
from sim import params as params_mod

DEBRIEF_TICKET_S = 600.0
"""How long a debrief ticket (``Console.debrief_ticket``) opens debriefs [s]."""
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
    water: Water = field(default_factory=Water)
    """The water's visibility (the 3D view's fog)."""
    """Wrong tokens per client (HTTP address or 3D-view client)."""
    _ticket: tuple[str, float] = ("", 0.0)
    """The debrief ticket and when it expires (monotonic clock)."""

    @staticmethod
    def build(settings: ConsoleSettings) -> Console:
        """Build the first simulation (the given mission's set-up, or station keeping)."""
        run = initial_run(settings)
        session = Session(run, settings.recordings_dir)
        if settings.foxglove_port is not None:
            try:
                session.start_live_feed(settings.foxglove_port, settings.host)
            except Exception as err:  # the SDK's error (the port taken): one line, no trace
                session.close()
                raise ConsoleError(
                    f"cannot serve Foxglove on port {settings.foxglove_port}: {err}"
                ) from None
        loop = PacedLoop(session, speed=settings.speed, paused=settings.paused)
        token = settings.token or secrets.token_urlsafe(18)
        return Console(settings, loop, token)

    def is_token(self, candidate: str | None) -> bool:
        return candidate is not None and secrets.compare_digest(
            candidate.encode(), self.token.encode()
        )

    def check_token(self, candidate: str | None, client: str) -> tuple[bool, float]:
        """(is it the token, seconds the client must wait before trying again). A wrong guess
        costs the guesser, never the operator: no token at all is no guess (it counts for
        nothing), and the right token is accepted even while ``client`` is locked out (on
        loopback every local client shares one address, so locking the address locked the
        operator out too). Only a wrong token counts against the client; once locked out, its
        wrong tokens are refused with the wait."""
        if not candidate:
            return False, 0.0
        if self.is_token(candidate):
            return True, 0.0
        if self.crew_role(candidate) is not None:
            return False, 0.0  # a crew member's own token: refused, but no guess
        wait = self.guesses.retry_after_s(client)
        if wait > 0.0:
            return False, wait
        self.guesses.failed(client)
        return False, 0.0

    # ----------------------------------------------------------- the crew's stations
    def crew_role(self, candidate: str | None) -> str | None:
        """The crew station (``tokens.CREW_ROLES``) whose token this is, else None (each
        compared in constant time)."""
        found = None
        for role in CREW_ROLES:
            wanted = getattr(self.settings, f"{role}_token")
            if (
                candidate
                and wanted
                and secrets.compare_digest(str(candidate).encode(), str(wanted).encode())
            ):
                found = role
        return found

    def check_station(self, role: str, candidate: str | None, client: str) -> tuple[str, float]:
        """May ``candidate`` open the ``role`` station? ('ok' | 'missing' | 'another' | 'wrong',
        seconds the client must wait). The station's own token and the console token open it
        (the console token changes everything in the run already); another station's token,
        or the instructor's, is refused but no guess; anything else counts against the client,
        as for the console token, and the right token is accepted during a lockout."""
        if not candidate:
            return "missing", 0.0
        if self.crew_role(candidate) == role or self.is_token(candidate):
            return "ok", 0.0
        if self.crew_role(candidate) is not None or self.is_instructor_token(candidate):
            return "another", 0.0
        wait = self.guesses.retry_after_s(client)
        if wait > 0.0:
            return "wrong", wait
        self.guesses.failed(client)
        return "wrong", 0.0

    def debrief_ticket(self) -> str:
        """A ticket that opens debrief reports for ``DEBRIEF_TICKET_S``: the 3D view puts it
        in the report links it gives unlocked browsers (a link cannot carry a header)."""
        ticket, expires = self._ticket
        if time.monotonic() > expires - DEBRIEF_TICKET_S / 2:  # fresh for half its life
            ticket = secrets.token_urlsafe(18)
            self._ticket = (ticket, time.monotonic() + DEBRIEF_TICKET_S)
        return ticket

    def is_debrief_ticket(self, candidate: str | None) -> bool:
        ticket, expires = self._ticket
        return (
            bool(candidate and ticket)
            and time.monotonic() < expires
            and secrets.compare_digest(str(candidate).encode(), ticket.encode())
        )

    # ----------------------------------------------------------- the instructor
    @property
    def instructor_on(self) -> bool:
        """The instructor's features (faults) are on: an instructor token was set."""
        return self.settings.instructor_token is not None

    def is_instructor_token(self, candidate: str | None) -> bool:
        wanted = self.settings.instructor_token
        return bool(candidate and wanted) and secrets.compare_digest(
            str(candidate).encode(), str(wanted).encode()
        )

    def check_instructor(self, candidate: str | None, client: str) -> tuple[str, float]:
        """('ok' | 'off' | 'missing' | 'console token' | 'crew token' | 'wrong', seconds the
        client must wait). As for the console token: no token, the console token and the
        crew's tokens are no guesses, the right
        token is accepted during a lockout, and wrong ones count against the client (one
        guess limit for both tokens)."""
        wanted = self.settings.instructor_token
        if wanted is None:
            return "off", 0.0
        if not candidate:
            return "missing", 0.0
        if self.is_instructor_token(candidate):
            return "ok", 0.0
        if self.is_token(candidate):
            return "console token", 0.0
        if self.crew_role(candidate) is not None:
            return "crew token", 0.0  # a crew member's own token: refused, but no guess
        wait = self.guesses.retry_after_s(client)
        if wait > 0.0:
            return "wrong", wait
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
        """Keep a mission sent over the network (HTTP or the 3D view); MissionError when it
        names a server file (``check_sent_mission``), ValueError when its name is taken."""
        check_sent_mission(mission)
        taken = {n.casefold(): n for n in schema.library_names()}.get(mission.name.casefold())
        if taken is not None:
            raise ValueError(
                f"name: {mission.name!r} is the library mission {taken!r} (names are "
                "compared without regard to case); give the upload another name"
            )
        with self._uploads_lock:
            self.uploads.pop(mission.name, None)
            self.uploads[mission.name] = mission
            while len(self.uploads) > MAX_UPLOADS:
                self.uploads.popitem(last=False)
        return mission.name


PRESET_NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,40}$")


def check_sent_mission(mission: schema.Mission) -> None:
    """A mission that came over the network names one of the console's parameter sets; it
    never names a file on the server (which would be read, and its content quoted in the
    error). Only the command line, reading a local mission file, may point at a parameter
    file. MissionError names the field and the sets; it quotes no path."""
    params = mission.setup.params
    presets = params_mod.available_presets()
    if params in presets:
        return
    got = f" (got {params!r})" if PRESET_NAME_RE.match(params) else " (got a file path)"
    raise schema.MissionError(
        f"setup.params: a mission sent to the console must name one of its parameter sets: "
        f"{', '.join(presets)}{got}; parameter files are read only by the command line"
    )


def initial_run(settings: ConsoleSettings) -> PreparedRun:
    if settings.mission is not None:
        return prepare_run(schema.load_mission(settings.mission), run_legs=True)
    return prepare_run(station_keeping_mission(settings.params, settings.depth_m), run_legs=False)
