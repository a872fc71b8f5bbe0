"""Run a mission headless, as fast as the machine allows, and score it.

    result = run_mission(schema.load_mission("full-square-400"))
    result.summary()

The pieces: ``missions.setup`` builds the ``Simulation`` from the mission's set-up,
``missions.driver`` advances the mission on it (the same driver the console uses),
``missions.legs`` holds the leg executors and ``missions.scoring`` the figures.
"""

from __future__ import annotations

from collections.abc import Callable

from control.config import Allocation, Feedback
from missions import schema
from missions.driver import MissionDriver
from missions.scoring import LandingResult, LegResult, MissionResult
from missions.setup import build_simulation, charted_frame, vary_tree

__all__ = [
    "LandingResult",
    "LegResult",
    "MissionDriver",
    "MissionResult",
    "build_simulation",
    "charted_frame",
    "run_mission",
    "vary_tree",
]


def run_mission(
    mission: schema.Mission,
    seed: int | None = None,
    allocation: Allocation | None = None,
    feedback: Feedback | None = None,
    feedforward: bool | None = None,
    progress: Callable[[MissionDriver], None] | None = None,
) -> MissionResult:
    """Execute all legs and score them (``MissionDriver.run_to_end``); ``progress`` is called
    after each request."""
    sim = build_simulation(
        mission, seed=seed, allocation=allocation, feedback=feedback, feedforward=feedforward
    )
    return MissionDriver(mission, sim).run_to_end(progress=progress)
