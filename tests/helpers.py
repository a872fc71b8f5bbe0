"""Small builders shared by the tests."""

import math

from control.simulation import steady_current as steady_current_rad
from sim import environment as envmod


def steady_current(speed_mps: float = 0.1, direction_deg: float = 225.0) -> envmod.CurrentParams:
    """A current that does not wander (default: the thesis's 0.1 m/s towards 225 deg)."""
    return steady_current_rad(speed_mps, math.radians(direction_deg))
