"""Small builders shared by the tests."""

import math

from sim import environment as envmod


def steady_current(speed_mps: float = 0.1, direction_deg: float = 225.0) -> envmod.CurrentParams:
    """A current that does not wander (default: the thesis's 0.1 m/s towards 225 deg)."""
    d = math.radians(direction_deg)
    return envmod.CurrentParams(speed_mps=speed_mps, direction_rad=d, speed_min_mps=speed_mps,
                                speed_max_mps=speed_mps, direction_min_rad=d, direction_max_rad=d)
