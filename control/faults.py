"""Injected faults: what went wrong at sea, to rehearse and to train on (thesis chapter 5 and
appendix C: the DVL's broken cable, position-fix dropouts and wild points, the mounting vector
entered with the wrong sign, the winch that slipped and dropped the tree, a current that
changes, a vessel that drifts off).

A fault has a kind, a start and a duration in simulation time, and one value whose meaning
depends on the kind (``FAULT_KINDS``). ``control.fault_injection.FaultInjector`` applies the
faults whose window covers a step when the simulation makes that chunk's inputs
(``Simulation._chunk_inputs``): sensor faults change the sensor samples and noise, environment
faults the water and the crane tip, the winch slip pays the wire out at once, and the
mount-sign fault hands the control system the mirrored mounting vector. The control system is
not told: it sees only the effects, through its own checks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

FAULT_KINDS: dict[str, tuple[str, float, float]] = {
    "dvl_lost": ("-", 0.0, 0.0),
    "position_dropout": ("-", 0.0, 0.0),
    "position_wild_points": ("m", 0.5, 100.0),
    "compass_bias": ("deg", -180.0, 180.0),
    "mount_sign": ("-", 0.0, 0.0),
    "winch_slip": ("m", 0.05, 5.0),
    "current_surge": ("m/s", -2.0, 2.0),
    "current_turn": ("deg", -180.0, 180.0),
    "vessel_drift": ("m/s", 0.01, 2.0),
    "thruster_lost": ("-", 0.0, 0.0),
    "thruster_weakened": ("factor", 0.0, 1.0),
    "compass_freeze": ("-", 0.0, 0.0),
}
"""Kind -> (unit of its value, smallest value, largest value). The value: the size of a wild
point (the position fix jumps this far, every second sample); the compass's bias; how far the
winch slips (the tree drops that much at once; 0.5 to 1 m at sea); the current's added speed;
its turn; the vessel's drift speed (towards ``direction_deg``); a weakened thruster's efficiency
(the thrust it still gives for the speed it turns at: 0 gives nothing, 1 all of it). Kinds with
no value take 0. The thruster kinds name their thruster (``thruster``, 1-based); a lost
thruster gives no thrust whatever it is told; a frozen compass goes on sending, at its rate,
the heading it measured when it froze."""
THRUSTER_KINDS = ("thruster_lost", "thruster_weakened")
THRUSTERS_MAX = 32
"""Highest thruster number a fault may name (the ROV's own count is checked when injected)."""
DURATION_MAX_S = 48 * 3600.0


@dataclass(frozen=True)
class Fault:
    """One fault: ``kind`` from ``start_s`` for ``duration_s`` (a winch slip happens at its
    start; its duration only says how long it is shown as active)."""

    kind: str
    start_s: float
    duration_s: float
    value: float = 0.0
    direction_deg: float = 0.0
    """Vessel drift: the direction it drifts towards [deg]."""
    thruster: int = 0
    """Thruster faults: which thruster (1-based); 0 for the other kinds."""

    def __post_init__(self) -> None:
        if self.kind not in FAULT_KINDS:
            raise ValueError(
                f"fault kind must be one of {', '.join(FAULT_KINDS)}, got {self.kind!r}"
            )
        for name, v, lo, hi in (
            ("start_s", self.start_s, 0.0, DURATION_MAX_S),
            ("duration_s", self.duration_s, 0.0, DURATION_MAX_S),
            ("direction_deg", self.direction_deg, -360.0, 360.0),
        ):
            if not (isinstance(v, int | float) and math.isfinite(v) and lo <= v <= hi):
                raise ValueError(f"fault {name} must be in [{lo:g}, {hi:g}], got {v!r}")
        if self.duration_s <= 0.0:
            raise ValueError(f"fault duration_s must be more than 0, got {self.duration_s!r}")
        if self.kind in THRUSTER_KINDS:
            if (
                isinstance(self.thruster, bool)
                or not isinstance(self.thruster, int)
                or not 1 <= self.thruster <= THRUSTERS_MAX
            ):
                raise ValueError(
                    f"fault thruster must be a thruster number in [1, {THRUSTERS_MAX}], "
                    f"got {self.thruster!r}"
                )
        elif self.thruster != 0:
            raise ValueError(f"fault {self.kind} names no thruster, got thruster {self.thruster!r}")
        unit, lo, hi = FAULT_KINDS[self.kind]
        if unit == "-":
            if self.value != 0.0:
                raise ValueError(f"fault {self.kind} takes no value, got {self.value!r}")
        elif not (math.isfinite(self.value) and lo <= self.value <= hi):
            raise ValueError(
                f"fault {self.kind} value must be in [{lo:g}, {hi:g}] {unit}, got {self.value!r}"
            )

    @property
    def end_s(self) -> float:
        return self.start_s + self.duration_s

    def active(self, t_s: float) -> bool:
        return self.start_s <= t_s < self.end_s

    def describe(self) -> str:
        unit = FAULT_KINDS[self.kind][0]
        value = "" if unit == "-" else f" {self.value:g} {unit}"
        which = f" {self.thruster}" if self.kind in THRUSTER_KINDS else ""
        return (
            f"{self.kind.replace('_', ' ')}{which}{value} from {self.start_s:g} s "
            f"for {self.duration_s:g} s"
        )
