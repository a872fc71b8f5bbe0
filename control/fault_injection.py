"""``FaultInjector``: the injected faults of one run (``control.faults``) and what they do to
a chunk's inputs.

Before a chunk (``before_chunk``) it notes the faults that started or ended, lets the winch
slip once at a slip's start, and says whether the mounting vector is mirrored and how much
thrust each thruster still gives (the owner reconfigures the control system and the plant
with those). Over the chunk's steps it changes the current (``current``: surges and turns)
and, once the rows are made, the sensors' samples and the crane tip (``in_chunk``: dropouts,
wild points, a biased or frozen compass, the vessel's drift). Chunks end where a fault starts
or ends (``steps_to_edge``), so a fault acts from its own step however the run is cut.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from control.faults import THRUSTER_KINDS, Fault
from control.site_motion import SiteMotion
from sim import plant, sensors
from sim.sensors import SENSOR_NAMES

FloatArray = NDArray[np.float64]


class FaultInjector:
    """The faults injected into a run with ``n_thrusters`` thrusters: past, present and
    scheduled, and the log of their starts and ends."""

    def __init__(self, n_thrusters: int) -> None:
        self.n_thrusters = n_thrusters
        self.faults: list[Fault] = []
        """Injected faults, past, present and scheduled."""
        self.events: list[tuple[float, str]] = []
        """Every fault start and end so far, (time [s], what), oldest first (unlike
        ``take_log``, never emptied: the console reads it from where it got to)."""
        self._log: list[tuple[float, str]] = []
        self._on: set[int] = set()
        self._slipped: set[int] = set()

    def inject(self, fault: Fault) -> None:
        """Schedule a fault; one that starts in the past starts now."""
        if not isinstance(fault, Fault):
            raise ValueError(f"fault must be a control.faults.Fault, got {type(fault).__name__}")
        if fault.kind in THRUSTER_KINDS and fault.thruster > self.n_thrusters:
            raise ValueError(
                f"fault thruster must be in [1, {self.n_thrusters}] (this ROV's thrusters), "
                f"got {fault.thruster}"
            )
        self.faults.append(fault)

    def clear(self, t_s: float) -> None:
        """End every fault at ``t_s`` (a slipped winch stays where it slipped to)."""
        for k in sorted(self._on):
            self._note(t_s, f"fault cleared: {self.faults[k].kind}")
        self.faults, self._on, self._slipped = [], set(), set()

    def _note(self, t_s: float, text: str) -> None:
        self._log.append((t_s, text))
        self.events.append((t_s, text))

    def take_log(self) -> list[tuple[float, str]]:
        """Faults that started or ended since the last call: (time [s], what)."""
        out, self._log = self._log, []
        return out

    def active(self, t_s: float) -> list[Fault]:
        """Faults whose window covers ``t_s``."""
        return [f for f in self.faults if f.active(t_s)]

    def steps_to_edge(self, t_s: float, dt_s: float, most: int) -> int:
        """Steps from ``t_s`` until the next fault starts or ends, ``most`` when none does
        (chunks end there, so a fault acts from its own step)."""
        edges = [e for f in self.faults for e in (f.start_s, f.end_s) if e > t_s + 1e-9]
        if not edges:
            return most
        return max(1, round((min(edges) - t_s) / dt_s))

    def before_chunk(self, t_s: float, site: SiteMotion) -> tuple[bool, FloatArray]:
        """At a chunk's start ``t_s``: note the faults that started or ended, slip the winch
        at a slip's start (the tree drops at once). Returns whether the control system's
        mounting vector is mirrored now, and each thruster's share of the thrust its speed
        would give (a lost thruster 0)."""
        t = t_s + 1e-9
        active = {k for k, f in enumerate(self.faults) if f.active(t)}
        for k in sorted(active - self._on):
            self._note(t_s, f"fault: {self.faults[k].describe()}")
        for k in sorted(self._on - active):
            self._note(t_s, f"fault over: {self.faults[k].kind}")
        self._on = active
        for k, f in enumerate(self.faults):
            if f.kind == "winch_slip" and f.active(t) and k not in self._slipped:
                self._slipped.add(k)
                site.slip_winch(f.value)
        flipped = any(f.kind == "mount_sign" and f.active(t) for f in self.faults)
        factors = np.ones(self.n_thrusters)
        for f in self.faults:
            if f.kind in THRUSTER_KINDS and f.active(t):
                i = f.thruster - 1
                factors[i] = min(factors[i], 0.0 if f.kind == "thruster_lost" else f.value)
        return flipped, factors

    def current(
        self, t: FloatArray, speeds: FloatArray, dirs: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The current's speed and direction at the steps' times ``t`` with surges and turns
        added."""
        speeds, dirs = np.array(speeds, float), np.array(dirs, float)
        for f in self.faults:
            on = (t >= f.start_s - 1e-9) & (t < f.end_s - 1e-9)
            if f.kind == "current_surge":
                speeds[on] = np.maximum(speeds[on] + f.value, 0.0)
            elif f.kind == "current_turn":
                dirs[on] += math.radians(f.value)
        return speeds, dirs

    def in_chunk(
        self,
        env: FloatArray,
        noise: sensors.NoiseChunk,
        t: FloatArray,
        dt_s: float,
        site: SiteMotion,
    ) -> None:
        """Sensor and environment faults over the chunk's steps at times ``t``: ``noise``'s
        samples and ``env``'s crane tip changed in place; a drifting vessel leaves the crane
        tip (``site``) where the drift took it."""
        for f in self.faults:
            on = (t >= f.start_s - 1e-9) & (t < f.end_s - 1e-9)
            if not on.any():
                continue
            if f.kind == "dvl_lost":
                noise.fresh[on, SENSOR_NAMES.index("dvl")] = False
            elif f.kind == "position_dropout":
                noise.fresh[on, SENSOR_NAMES.index("position")] = False
            elif f.kind == "position_wild_points":
                fixes = np.flatnonzero(on & noise.fresh[:, SENSOR_NAMES.index("position")])
                noise.noise[fixes[::2], 0] += f.value  # every second fix jumps north
            elif f.kind == "compass_bias":
                noise.noise[on, 4] += math.radians(f.value)
            elif f.kind == "compass_freeze":
                noise.noise[on, 4] = np.nan  # sim.sensors.sample: a NaN repeats the held value
            elif f.kind == "vessel_drift":
                _drift(env, on, f, dt_s)
                site.hold_crane_at(env[-1, plant.E_CT : plant.E_CT + 3])


def _drift(env: FloatArray, on: NDArray[np.bool_], f: Fault, dt_s: float) -> None:
    """The crane tip in ``env`` moved by the vessel's drift over the steps ``on``."""
    d = math.radians(f.direction_deg)
    step = f.value * dt_s * np.array([math.cos(d), math.sin(d), 0.0])
    tips = env[:, plant.E_CT : plant.E_CT + 3]
    moves = np.vstack([tips[0:1], on[:, None] * step[None, :]])
    if np.all(tips == tips[0]):
        # the crane holds still (the fault holds it): a step at a time from where the tip is
        # (add.accumulate sums in order), the same whatever the chunks
        tips[:] = np.add.accumulate(moves, axis=0)[1:]
    else:  # the crane was moving when the drift began
        moves[0] = 0.0
        tips += np.add.accumulate(moves, axis=0)[1:]
