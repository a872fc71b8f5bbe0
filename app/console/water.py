"""The water the scene is seen through: its visibility, a setting of the session (from clear to
turbid). It changes nothing of the simulation: the 3D view's fog, the water's colour and the
ROV camera's picture follow it."""

from __future__ import annotations

import math
import threading

from app.console.errors import ConsoleError

VISIBILITY_MIN_M = 2.0
"""Turbid water: a black target is lost at 2 m."""
VISIBILITY_MAX_M = 30.0
"""Clear open water."""
VISIBILITY_DEFAULT_M = 20.0
"""A clear day at the site."""


def check_visibility_m(visibility_m: float) -> float:
    """``visibility_m`` as a float if it is a number in [VISIBILITY_MIN_M, VISIBILITY_MAX_M];
    a ``ConsoleError`` that says the range otherwise."""
    value = float(visibility_m)
    if not (math.isfinite(value) and VISIBILITY_MIN_M <= value <= VISIBILITY_MAX_M):
        raise ConsoleError(
            f"visibility must be between {VISIBILITY_MIN_M:g} and {VISIBILITY_MAX_M:g} m"
            f" (turbid to clear), got {visibility_m}"
        )
    return value


class Water:
    """The session's water (read by any thread, set by the page or the API)."""

    def __init__(self, visibility_m: float = VISIBILITY_DEFAULT_M) -> None:
        self._lock = threading.Lock()
        self._visibility_m = check_visibility_m(visibility_m)

    @property
    def visibility_m(self) -> float:
        """Distance at which the water hides a dark object [m]."""
        return self._visibility_m

    def set_visibility_m(self, visibility_m: float) -> float:
        """Set the visibility (range-checked, ``check_visibility_m``); returns it."""
        value = check_visibility_m(visibility_m)
        with self._lock:
            self._visibility_m = value
        return value
