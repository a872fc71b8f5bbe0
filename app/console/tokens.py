"""The console token: generated or chosen, compared in constant time, and guarded against
guessing (wrong tokens are counted per client, over HTTP and in the 3D view alike)."""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable

MIN_TOKEN_CHARS = 16
"""Shortest token an operator may choose (a generated one has 24 characters)."""
MIN_INSTRUCTOR_TOKEN_CHARS = 8
"""Shortest instructor token (typed by hand at a training console; guessing is limited as for
the console token)."""
INSTRUCTOR_TOKEN_ENV = "ROV_CONSOLE_INSTRUCTOR_TOKEN"
"""Environment variable ``rov-console serve`` reads the instructor token from."""
CREW_ROLES = ("winch", "supervisor")
"""The crew's stations with a token of their own (``serve --winch-token``,
``--supervisor-token``): each opens its station and nothing else."""
CREW_TOKEN_FIELDS = tuple(f"{role}_token" for role in CREW_ROLES)
"""Their fields in ``ConsoleSettings``."""
CREW_TOKEN_ENV = {role: f"ROV_CONSOLE_{role.upper()}_TOKEN" for role in CREW_ROLES}
"""Environment variables ``rov-console serve`` reads the crew's tokens from."""
GUESS_LIMIT = 10
"""Wrong tokens one client may send within the window before it is locked out."""
GUESS_WINDOW_S = 60.0


class GuessLimit:
    """Counts wrong tokens per client (thread-safe: routes and viser callbacks use it)."""

    def __init__(
        self,
        limit: int = GUESS_LIMIT,
        window_s: float = GUESS_WINDOW_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.limit = limit
        self.window_s = window_s
        self._clock = clock
        self._failures: dict[str, deque[float]] = {}
        self._lock = threading.Lock()

    def retry_after_s(self, client: str) -> float:
        """0 when the client may try; otherwise the seconds until it may."""
        with self._lock:
            failures = self._recent(client)
            if len(failures) < self.limit:
                return 0.0
            return max(failures[0] + self.window_s - self._clock(), 0.0)

    def failed(self, client: str) -> None:
        with self._lock:
            self._recent(client).append(self._clock())
            if len(self._failures) > 10_000:  # forget the oldest clients, bounded memory
                self._failures.pop(next(iter(self._failures)))

    def _recent(self, client: str) -> deque[float]:
        failures = self._failures.setdefault(client, deque(maxlen=self.limit))
        while failures and failures[0] < self._clock() - self.window_s:
            failures.popleft()
        return failures


def check_token(field: str, token: str | None, min_chars: int) -> None:
    """ValueError naming ``field`` when ``token`` (None: not set) is shorter than
    ``min_chars`` or has spaces or unprintable characters."""
    if token is not None and (len(token) < min_chars or not token.isprintable() or " " in token):
        raise ValueError(
            f"{field} must have at least {min_chars} printable characters and no spaces"
        )


def check_crew_tokens(tokens: dict[str, str | None]) -> None:
    """ValueError naming the field when a crew token (``{role}_token``) is too short, has
    spaces or unprintable characters, or equals another of the console's ``tokens`` (each
    token must open one thing only)."""
    for role in CREW_ROLES:
        check_token(f"{role}_token", tokens.get(f"{role}_token"), MIN_INSTRUCTOR_TOKEN_CHARS)
    given = [(name, t) for name, t in tokens.items() if t is not None]
    for i, (name, t) in enumerate(given):
        for other, u in given[i + 1 :]:
            if t == u and (name in CREW_TOKEN_FIELDS or other in CREW_TOKEN_FIELDS):
                raise ValueError(f"{name} and {other} must differ")
