"""Flying by hand from the console: the pilot's commands (applied by the loop between ticks,
like every other command) and the status the pilot page shows.

The pilot page (``app/api/pilot.py``) sends the stick as ``PilotDemand`` many times a second;
those are ``quiet``: the operations log and the recording do not get one entry per key press
(the log rows carry the commanded thrust). Taking over, handing back, the holds and the
pilot's arrival and departure are logged with the pilot's name.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from app.console.commands import LoopControls, number
from app.console.texts import compass_heading_deg
from control.simulation import Simulation

AXES = ("surge", "sway", "heave", "yaw")
"""The pilot's axes, in the ROV's own frame: forward, starboard, down, clockwise from above."""
DEMAND_TIMEOUT_S = 0.5
"""A pilot page that sends nothing for this long (page closed, socket lost, tab asleep) has
its demand set to zero (the page sends its stick every 50 ms while connected)."""
NAME_MAX_CHARS = 40


def pilot_name(name: object) -> str:
    """A pilot's name as the operations log shows it, or ValueError naming the field."""
    if not isinstance(name, str):
        raise ValueError(f"pilot name must be text, got {type(name).__name__}")
    text = " ".join(name.split())
    if not text or len(text) > NAME_MAX_CHARS or not text.isprintable():
        raise ValueError(f"pilot name must be 1 to {NAME_MAX_CHARS} printable characters")
    return text


def pilot_status(sim: Simulation) -> dict[str, object]:
    """What the pilot page shows of the simulation (read on the loop task)."""
    heading, depth = sim.pilot_holds
    rov = sim.rov_eta_n
    return {
        "mode": sim.mode,
        "holds": {"heading": heading, "depth": depth},
        "demand": dict(zip(AXES, (float(v) for v in sim.pilot_demand), strict=True)),
        "heading_deg": compass_heading_deg(float(rov[5])),
        "depth_m": float(rov[2]),
        "surge_mps": float(sim.plant_state[18]),
        "t_s": sim.t_s,
        "thrusters_out": thrusters_out(sim),
    }


THRUSTER_WEAK_SHARE = 0.95
"""A thruster giving less than this share of its thrust shows on the pilot page [-]."""


def thrusters_out(sim: Simulation) -> list[dict[str, float]]:
    """The thrusters whose drives report less thrust than their speed should give (a lost
    or weakened thruster, an instructor's fault), 1-based, with the share they give: what a
    work-class ROV's thruster telemetry tells its pilot (the control system is not told)."""
    return [
        {"number": i + 1, "share": round(float(share), 2)}
        for i, share in enumerate(sim.thruster_health)
        if share < THRUSTER_WEAK_SHARE
    ]


def autopilot_mode(sim: Simulation) -> str:
    """The autopilot a pilot hands back to: the tree controller while the ROV grips the tree,
    station keeping of the ROV alone otherwise."""
    return "tree" if sim.gripping else "free"


@dataclass(frozen=True)
class PilotDemand:
    """The stick: each axis a fraction in [-1, 1] of its full thrust (see
    ``Simulation.set_pilot_demand``)."""

    surge: float
    sway: float
    heave: float
    yaw: float
    quiet: ClassVar[bool] = True

    def __post_init__(self) -> None:
        for axis in AXES:
            number(f"pilot {axis}", getattr(self, axis), -1.0, 1.0)

    def apply(self, loop: LoopControls) -> object:
        eng = loop.session
        eng.require_live("pilot")
        eng.sim.set_pilot_demand(self.surge, self.sway, self.heave, self.yaw)
        return pilot_status(eng.sim)


@dataclass(frozen=True)
class PilotHolds:
    """Auto-heading and auto-depth on or off."""

    heading: bool
    depth: bool

    def __post_init__(self) -> None:
        for name in ("heading", "depth"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} hold must be true or false")

    def apply(self, loop: LoopControls) -> object:
        eng = loop.session
        eng.require_live("pilot holds")
        eng.sim.set_pilot_holds(self.heading, self.depth)
        eng.note("command", "pilot holds", {"heading": self.heading, "depth": self.depth})
        return pilot_status(eng.sim)


@dataclass(frozen=True)
class PilotTakeOver:
    """``pilot`` True: fly by hand (mode "manual", from a zero stick); False: hand back to the
    autopilot (``autopilot_mode``), which holds where the pilot left the tree (its target
    becomes the present estimate) or the ROV (free mode starts at the present pose). Both
    bumpless (the kernel starts the new controller from the last commanded thrust). Not while
    a mission runs its legs: abort it first."""

    pilot: bool

    def __post_init__(self) -> None:
        if not isinstance(self.pilot, bool):
            raise ValueError("pilot must be true or false")

    def apply(self, loop: LoopControls) -> object:
        eng = loop.session
        eng.require_live("pilot")
        eng.require_no_mission("pilot")
        sim = eng.sim
        if self.pilot:
            sim.set_pilot_demand(0.0, 0.0, 0.0, 0.0)
            sim.set_mode("manual")
        else:
            mode = autopilot_mode(sim)
            if mode == "tree":  # hold the tree where the pilot left it, not the old target
                north, east, psi = sim.eta_estimate
                sim.set_target(north, east, psi)
            sim.set_mode(mode)  # type: ignore[arg-type]
        eng.note("command", f"mode {sim.mode}", {"mode": sim.mode})
        return pilot_status(sim)


@dataclass(frozen=True)
class PilotConnected:
    """A pilot page signed in (logged with the pilot's name); changes nothing."""

    def apply(self, loop: LoopControls) -> object:
        return pilot_status(loop.session.sim)


@dataclass(frozen=True)
class PilotDisconnected:
    """The pilot page went away or fell silent: the stick goes to zero (the holds keep
    station as when it is let go)."""

    reason: str

    def apply(self, loop: LoopControls) -> object:
        sim = loop.session.sim
        sim.set_pilot_demand(0.0, 0.0, 0.0, 0.0)
        return pilot_status(sim)
