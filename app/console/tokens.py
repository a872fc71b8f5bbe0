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
