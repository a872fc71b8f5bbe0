"""The lift wire as a lumped-mass line (MoorDyn), to check the quasi-static wire against.

MoorDyn (PyPI ``moordyn``, MoorDyn-C v2; Hall and Goupee 2015) models the wire as point
masses joined by axial springs with internal damping, with weight, buoyancy and Morison drag
and added mass on each node. Here it carries the tree as a free point (its mass, its
displaced volume from W0, and an added-mass coefficient that gives the tree's A33) below a
crane tip that can move.

What it is used for (``tests/test_dynamic_wire.py``):

- the static hang: the load's horizontal stiffness at the end of the wire against the closed
  form k = w / ln((W0 + w L) / W0) (eq. 2.30, corrected) that the quasi-static plant uses;
- the static offset in a steady current (``current_offset_m``): the wire's own drag and the
  tree's against eq. 2.29 (corrected) with the tree's drag as F0, as the quasi-static plant
  holds the tree;
- the vertical natural period against T0 = 2 pi sqrt((M + A33 + m_wire L / 3) / (EA / L))
  (the spring-mass estimate with a third of the wire's mass, Rayleigh's; MODEL_NOTES takes it
  from DNV's recommended practice for marine operations, not checked here against the text).

``CoupledWire`` is the same line with both ends driven from outside (the crane tip and the
tree's attachment point): ``wire = "moordyn"`` in ``control.simulation``, which steps it
beside the compiled plant (``sim.plant``) one step at a time and hands its force to the plant
(``E_FWIRE``, ``E_WEXT``). Optional: the module imports ``moordyn`` only when called.

The water: MoorDyn-C 2.7 takes it as external kinematics (``WaveKin 1``; the coupler sets the
water velocity at every node through ``ExternalWaveKinSet``, held until set again). Its
initial-condition solver runs in still water whatever the options (2.7.2 sets the water up
only after it), so a line in a current starts from the still hang and settles in time. The
current is uniform over depth and horizontal, the one the quasi-static wire's offset
(eq. 2.29, ``sim.site.wire_environment``) assumes; the waves act on the tree only, as with the
quasi-static wire.

Printing: MoorDyn logs through its own verbosity, set to errors only right after creation
(``SetVerbosity``), and ``disableOutTime`` stops the time it otherwise prints on every step.
Only the banner it prints while reading the input file, before any verbosity can be set,
still goes to standard output: ``_quiet`` sends it to /dev/null, once per line.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sim import site
from sim import wire as wire_mod
from sim.params import ParameterSet

CURRENT_RANGE_MPS = 5.0
"""Largest current speed the MoorDyn line takes [m/s] (the plant's current model: 0 to a few
m/s)."""
WAVE_SPEED_FRACTION = 0.04
"""MoorDyn's internal step as a fraction of the time an axial wave needs to cross one segment
[-]. Its explicit integrator diverged at 0.16 (100 m, 20 segments); 0.04 is stable from 100 m
to 1000 m."""


@dataclass(frozen=True)
class HangingLine:
    """One wire with the tree at its end, as MoorDyn is given it."""

    ps: ParameterSet
    length_m: float
    """Unstretched wire length L [m]."""
    n_segments: int = 20
    """Segments of the lumped-mass line [-]."""
    pull_newton: float = 0.0
    """Steady horizontal pull on the tree, north [N] (through a soft, weightless line to a
    far anchor; 0: none)."""
    relax_drag_area_m2: float = 0.0
    """Drag area C_D A of the tree's point [m^2]: damps the swing while MoorDyn relaxes to
    the static hang (statics do not depend on it in still water; in a current it is the
    tree's drag, ``tree_drag_area_m2``)."""
    current_mps: float = 0.0
    """Steady current towards north, uniform over depth [m/s] (0: still water). MoorDyn's
    initial-condition solver ignores it: ``current_offset_m`` lets the line settle in it."""

    def __post_init__(self) -> None:
        if not (math.isfinite(self.length_m) and 1.0 <= self.length_m <= 4000.0):
            raise ValueError(f"length_m must lie in [1, 4000], got {self.length_m!r}")
        if not 2 <= self.n_segments <= 500:
            raise ValueError(f"n_segments must lie in [2, 500], got {self.n_segments!r}")
        if not (math.isfinite(self.current_mps) and abs(self.current_mps) <= CURRENT_RANGE_MPS):
            raise ValueError(
                f"current_mps must lie in [-{CURRENT_RANGE_MPS:g}, {CURRENT_RANGE_MPS:g}], "
                f"got {self.current_mps!r}"
            )

    @property
    def time_step_s(self) -> float:
        """MoorDyn's internal step [s] (see ``WAVE_SPEED_FRACTION``)."""
        w = self.ps.wire
        speed = math.sqrt(w.axial_stiffness_newton / w.mass_per_length_kg_m)
        return WAVE_SPEED_FRACTION * self.length_m / self.n_segments / speed

    def static_depth_m(self) -> float:
        """Depth of the load below the crane tip in the static hang [m]: L stretched by the
        load and by the wire's own submerged weight (W0 L + w L^2 / 2) / EA."""
        w = self.ps.wire.submerged_weight_per_length()
        ea = self.ps.wire.axial_stiffness_newton
        w0 = self.ps.tree.submerged_weight_newton
        return self.length_m + (w0 * self.length_m + 0.5 * w * self.length_m**2) / ea

    def input_text(self, relax_s: float) -> str:
        """The MoorDyn input file (v2 format). ``relax_s``: time MoorDyn's initial-condition
        solver may take to find the static hang (0: start from the stretched straight line)."""
        ps = self.ps
        rho, g = wire_mod.RHO_WATER, wire_mod.GRAVITY
        m = ps.tree.mass_kg
        w0 = ps.tree.submerged_weight_newton
        volume = max((m * g - w0) / (rho * g), 1e-6)
        ca = ps.tree.M_a[2, 2] / (rho * volume)
        depth = self.static_depth_m()
        lines = _line_type_header(ps)
        far = 1000.0 * self.length_m
        stretch = far  # the pull line is stretched by its own length: force ~ EA, soft
        if self.pull_newton > 0.0:
            lines.append(f"pull 1e-5 1e-6 {self.pull_newton} -0.001 0.0 0.0 0.0 0.0 0.0")
        lines += [
            "---------------------- POINTS --------------------------------",
            "ID Attachment X Y Z Mass Volume CdA Ca",
            "(#) (-) (m) (m) (m) (kg) (m^3) (m^2) (-)",
            "1 Coupled 0.0 0.0 0.0 0.0 0.0 0.0 0.0",
            f"2 Free 0.0 0.0 {-depth} {m} {volume} {self.relax_drag_area_m2} {ca}",
        ]
        if self.pull_newton > 0.0:
            lines.append(f"3 Fixed {far + stretch} 0.0 {-depth} 0.0 0.0 0.0 0.0")
        lines += [
            "---------------------- LINES ---------------------------------",
            "ID LineType AttachA AttachB UnstrLen NumSegs Outputs",
            "(#) (name) (#) (#) (m) (-) (-)",
            f"1 wire 1 2 {self.length_m} {self.n_segments} -",
        ]
        if self.pull_newton > 0.0:
            lines.append(f"2 pull 2 3 {far} 4 -")
        lines += [
            "---------------------- OPTIONS -------------------------------",
            f"{self.time_step_s} dtM",
            f"{g} g",
            f"{rho} rho",
            f"{depth + 1000.0} WtrDpth",
            "0 writeLog",
            *_WATER_AND_QUIET_OPTIONS,
            f"{relax_s} TmaxIC",
            "1 ICgenDynamic",
            "8.0 CdScaleIC",
            "1e-5 threshIC",
            "--------------------------------------------------------------",
        ]
        return "\n".join(lines) + "\n"


_WATER_AND_QUIET_OPTIONS = ("1 WaveKin", "1 disableOutTime")
"""Input options: the water's velocity from the coupler (``_set_current``), and no time
printed on each step."""


def _line_type_header(ps: ParameterSet, internal_damping: float = -0.001) -> list[str]:
    """The input file's head and its ``wire`` line type (the parameter set's wire: diameter,
    mass per metre, EA, drag coefficient; added mass 1, no bending stiffness). Internal
    damping as MoorDyn reads it: > 0, BA [N s] (axial force per unit strain rate); < 0, a
    damping ratio of each segment's own vibration (default 0.1 %)."""
    wire = ps.wire
    return [
        "--------------------- MoorDyn Input File ---------------------",
        "rov-console lift wire (sim.dynamic_wire)",
        "---------------------- LINE TYPES ----------------------------",
        "TypeName Diam Mass/m EA BA/-zeta EI Cd Ca CdAx CaAx",
        "(name) (m) (kg/m) (N) (N-s/-) (N-m^2) (-) (-) (-) (-)",
        f"wire {wire.diameter_m} {wire.mass_per_length_kg_m} "
        f"{wire.axial_stiffness_newton} {internal_damping} 0.0 {wire.drag_coefficient} 1.0 0.0 0.0",
    ]


def _quiet(fn: Callable[..., Any], *args: Any) -> Any:
    """Call ``fn`` with the process's standard output sent to /dev/null: only for
    ``moordyn.Create``, whose banner comes before any verbosity can be set."""
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    try:
        return fn(*args)
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


def _create(path: Path) -> Any:
    """A MoorDyn system from the input file at ``path``, logging errors only."""
    import moordyn  # type: ignore[import-untyped]

    system = _quiet(moordyn.Create, str(path))
    moordyn.SetVerbosity(system, moordyn.LEVEL_ERR)
    return system


def _set_current(system: Any, current_md: list[float], t_s: float) -> int:
    """Give every point MoorDyn asks water kinematics for (its line nodes and points) the
    water velocity ``current_md`` (MoorDyn's axes) and no acceleration; returns how many.
    Call after ``moordyn.Init``."""
    import moordyn

    if moordyn.ExternalWaveKinInit(system) != 0:
        raise RuntimeError("MoorDyn could not set up the external water kinematics")
    n = len(moordyn.ExternalWaveKinGetCoordinates(system))
    if moordyn.ExternalWaveKinSet(system, [current_md] * n, [[0.0, 0.0, 0.0]] * n, t_s) != 0:
        raise RuntimeError("MoorDyn did not take the current")
    return n


class _Run:
    """A MoorDyn system built from a ``HangingLine``; close it with ``close``."""

    def __init__(self, line: HangingLine, relax_s: float) -> None:
        import moordyn

        self._md = moordyn
        self._dir = tempfile.TemporaryDirectory()
        path = Path(self._dir.name) / "wire.txt"
        path.write_text(line.input_text(relax_s))
        self.system = _create(path)
        if moordyn.Init(self.system, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]) != 0:
            raise RuntimeError("MoorDyn could not initialise the wire")
        _set_current(self.system, [line.current_mps, 0.0, 0.0], 0.0)
        self.load = moordyn.GetPoint(self.system, 2)
        self.t_s = 0.0

    def load_position(self) -> np.ndarray:
        """The tree's point, MoorDyn axes (x, y, z up) from the crane tip [m]."""
        return np.asarray(self._md.GetPointPos(self.load), dtype=float)

    def step(self, top: list[float], top_velocity: list[float], dt_s: float) -> np.ndarray:
        """Advance by dt_s with the crane tip at ``top``; returns the force on the tip [N]."""
        force = self._md.Step(self.system, top, top_velocity, self.t_s, dt_s)
        self.t_s += dt_s
        return np.asarray(force, dtype=float)

    def close(self) -> None:
        self._md.Close(self.system)
        self._dir.cleanup()


def vertical_natural_period_s(line: HangingLine, duration_s: float = 20.0) -> float:
    """The tree's bounce on the wire [s]: MoorDyn from the static hang, the crane tip raised
    2 cm over 0.3 s (a raised cosine), then the spectral peak of the tree's depth over the
    rest of ``duration_s`` (Hann window, padded 16 times)."""
    run = _Run(line, relax_s=0.0)
    try:
        dt, ramp, rise = 0.005, 0.3, 0.02
        depths = []
        for _ in range(int(round(duration_s / dt))):
            t = run.t_s
            top = rise * 0.5 * (1.0 - math.cos(math.pi * min(t, ramp) / ramp))
            v = rise * math.pi / (2.0 * ramp) * math.sin(math.pi * t / ramp) if t < ramp else 0.0
            run.step([0.0, 0.0, top], [0.0, 0.0, v], dt)
            depths.append(run.load_position()[2])
    finally:
        run.close()
    z = np.asarray(depths[int(1.0 / dt) :])
    z = (z - z.mean()) * np.hanning(z.shape[0])
    n = 16 * z.shape[0]
    spectrum = np.abs(np.fft.rfft(z, n=n))
    freqs = np.fft.rfftfreq(n, dt)
    return float(1.0 / freqs[1 + int(np.argmax(spectrum[1:]))])


def t0_estimate_s(ps: ParameterSet, length_m: float) -> float:
    """T0 = 2 pi sqrt((M + A33 + m_wire L / 3) / (EA / L)) [s]."""
    mass = ps.tree.mass_kg + ps.tree.M_a[2, 2] + ps.wire.mass_per_length_kg_m * length_m / 3.0
    return 2.0 * math.pi * math.sqrt(mass * length_m / ps.wire.axial_stiffness_newton)


def pulled_offset_m(line: HangingLine, relax_s: float = 300.0) -> float:
    """Horizontal offset of the tree [m] when pulled north with ``line.pull_newton``: the
    static equilibrium MoorDyn's initial-condition solver (dynamic relaxation) finds."""
    if line.pull_newton <= 0.0:
        raise ValueError(f"pull_newton must be > 0 N, got {line.pull_newton!r}")
    run = _Run(line, relax_s=relax_s)
    try:
        return float(run.load_position()[0])
    finally:
        run.close()


def tree_drag_area_m2(ps: ParameterSet, current_mps: float) -> float:
    """The drag area C_D A [m^2] that gives MoorDyn's tree point, still in the current
    ``current_mps``, the drag the plant gives the tree there: F0 = D_l v + D_nl v^2 (the
    tree's surge coefficients, ``sim.site.tree_drag_force``) = rho C_D A v^2 / 2. MoorDyn's
    point drag is quadratic only, so the two agree at this speed, not at others."""
    if not (math.isfinite(current_mps) and current_mps != 0.0):
        raise ValueError(f"current_mps must be a nonzero speed, got {current_mps!r}")
    f0 = site.tree_drag_force(ps, current_mps)
    return 2.0 * f0 / (wire_mod.RHO_WATER * current_mps**2)


def current_offset_m(line: HangingLine, settle_s: float = 200.0) -> float:
    """Horizontal offset of the tree's point downstream of the crane tip [m] in the line's
    steady current, the wire's own drag and the tree's (``line.relax_drag_area_m2``, see
    ``tree_drag_area_m2``) together. MoorDyn's initial-condition solver gives the still hang;
    the current is then switched on and the line integrated for ``settle_s``. The tree's swing
    is damped by its own drag in the current (linearised about the current: about 15 % of
    critical at 100 m, 30 % at 400 m, 0.5 m/s), so 200 s take it to the static offset within
    0.01 %."""
    if line.current_mps == 0.0:
        raise ValueError("current_mps must be nonzero for a current offset, got 0.0")
    if not (math.isfinite(settle_s) and settle_s > 0.0):
        raise ValueError(f"settle_s must be > 0 s, got {settle_s!r}")
    run = _Run(line, relax_s=RELAX_S)
    try:
        dt = 1.0
        for _ in range(int(math.ceil(settle_s / dt))):
            run.step([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], dt)
        return float(run.load_position()[0])
    finally:
        run.close()


def quasi_static_current_offset_m(ps: ParameterSet, length_m: float, current_mps: float) -> float:
    """The quasi-static wire's offset of the load in a uniform current [m]: eq. 2.29
    (corrected) with the wire's drag q and the tree's drag as F0, i.e. the wire's drag offset
    the plant's equilibrium point carries plus F0 / k_h (eq. 2.30) of its spring."""
    q = ps.wire.drag_per_length(current_mps)
    w = ps.wire.submerged_weight_per_length()
    f0 = site.tree_drag_force(ps, current_mps)
    return wire_mod.horizontal_offset(q, w, ps.tree.submerged_weight_newton, length_m, f0)


COUPLED_SEGMENTS = 20
"""Segments of the coupled wire [-] (as ``HangingLine``: its period is within 0.2 % of T0)."""
COUPLED_LENGTH_RANGE_M = (20.0, 4000.0)
"""Wire lengths the coupled wire takes [m]. MoorDyn's internal step is proportional to the
segment length (``WAVE_SPEED_FRACTION``): 5e-5 s at 100 m, 1e-5 s at 20 m, i.e. 1000 internal
steps per 0.01 s plant step below 20 m, slower than real time; above 4000 m the line has not
been checked (``HangingLine``'s range)."""
RELAX_S = 10.0
"""Time MoorDyn's initial-condition solver may take to settle the line between its two ends
at the start [s] (the line starts straight and stretched; its weight settles in a few axial
wave passages)."""


def ned_to_moordyn(v_n: np.ndarray) -> list[float]:
    """NED vector to MoorDyn's axes (x north, y west, z up: a half turn about north)."""
    return [float(v_n[0]), -float(v_n[1]), -float(v_n[2])]


def moordyn_to_ned(v: np.ndarray) -> np.ndarray:
    """MoorDyn's axes (x north, y west, z up) to NED."""
    return np.array([v[0], -v[1], -v[2]], dtype=float)


def internal_damping_ns(ps: ParameterSet, length_m: float, damping_ratio: float) -> float:
    """MoorDyn's BA [N s] that gives the tree's bounce on the wire the damping ratio
    ``damping_ratio``: the whole line's dashpot is BA / L, made equal to the elastic wire's
    c = 2 zeta sqrt(k_z (M + A33 + m_wire L / 3)) with k_z = EA / L, so both wire models damp
    the bounce alike. (It also damps the line's own axial modes, e.g. 30 % of critical for
    the first one with both ends held at 100 m, so the start-up transient dies at once.)"""
    k_z = ps.wire.axial_stiffness_newton / length_m
    m_heave = ps.tree.mass_kg + ps.tree.M_a[2, 2] + ps.wire.mass_per_length_kg_m * length_m / 3.0
    return 2.0 * damping_ratio * math.sqrt(k_z * m_heave) * length_m


def coupled_input_text(
    ps: ParameterSet, length_m: float, water_depth_m: float, damping_ratio: float
) -> str:
    """MoorDyn input (v2 format) for the wire between two coupled points: 1, the crane tip,
    and 2, the tree's attachment point, both moved by the caller. The points have no mass or
    volume: the tree (its mass, added mass and W0) stays in the plant, MoorDyn carries the
    wire's own mass, weight, elasticity and drag (``internal_damping_ns``: damping)."""
    n = COUPLED_SEGMENTS
    speed = math.sqrt(ps.wire.axial_stiffness_newton / ps.wire.mass_per_length_kg_m)
    ba = internal_damping_ns(ps, length_m, damping_ratio)
    lines = _line_type_header(ps, ba if ba > 0.0 else -0.001)
    lines += [
        "---------------------- POINTS --------------------------------",
        "ID Attachment X Y Z Mass Volume CdA Ca",
        "(#) (-) (m) (m) (m) (kg) (m^3) (m^2) (-)",
        "1 Coupled 0.0 0.0 0.0 0.0 0.0 0.0 0.0",
        f"2 Coupled 0.0 0.0 {-length_m} 0.0 0.0 0.0 0.0",
        "---------------------- LINES ---------------------------------",
        "ID LineType AttachA AttachB UnstrLen NumSegs Outputs",
        "(#) (name) (#) (#) (m) (-) (-)",
        f"1 wire 1 2 {length_m} {n} -",
        "---------------------- OPTIONS -------------------------------",
        f"{WAVE_SPEED_FRACTION * length_m / n / speed} dtM",
        f"{wire_mod.GRAVITY} g",
        f"{wire_mod.RHO_WATER} rho",
        f"{water_depth_m} WtrDpth",
        "0 writeLog",
        *_WATER_AND_QUIET_OPTIONS,
        f"{RELAX_S} TmaxIC",
        "1 ICgenDynamic",
        "8.0 CdScaleIC",
        "1e-5 threshIC",
        "--------------------------------------------------------------",
    ]
    return "\n".join(lines) + "\n"


class CoupledWire:
    """The lift wire as a MoorDyn line between the crane tip and the tree's attachment point,
    both driven from outside (``control.simulation`` with ``wire = "moordyn"``), in the
    current given by ``set_current`` (still water until then).

    ``step`` advances the line by one plant step with both ends moving at constant velocity
    from where they are now, and returns the wire's force on the tree's attachment point at
    the end of the step, NED [N]. Close it with ``close``."""

    def __init__(
        self,
        ps: ParameterSet,
        length_m: float,
        tip_n: np.ndarray,
        attachment_n: np.ndarray,
        water_depth_m: float,
        damping_ratio: float,
    ) -> None:
        lo, hi = COUPLED_LENGTH_RANGE_M
        if not (math.isfinite(length_m) and lo <= length_m <= hi):
            raise ValueError(
                f"wire length for the moordyn wire must lie in [{lo:g}, {hi:g}] m, "
                f"got {length_m:.1f} m"
            )
        import moordyn

        self._md = moordyn
        self.ps = ps
        self.length_m = float(length_m)
        self._speed = math.sqrt(ps.wire.axial_stiffness_newton / ps.wire.mass_per_length_kg_m)
        self._dir = tempfile.TemporaryDirectory()
        path = Path(self._dir.name) / "wire.txt"
        path.write_text(coupled_input_text(ps, length_m, water_depth_m, damping_ratio))
        self.system: Any = None
        self.system = _create(path)
        self.line = moordyn.GetLine(self.system, 1)
        x = ned_to_moordyn(tip_n) + ned_to_moordyn(attachment_n)
        if moordyn.Init(self.system, x, [0.0] * 6) != 0:
            raise RuntimeError("MoorDyn could not initialise the wire")
        self.current_n = np.zeros(3)
        """The water's velocity along the whole line, NED [m/s] (``set_current``)."""
        self._n_water_points = _set_current(self.system, [0.0, 0.0, 0.0], 0.0)
        self.t_s = 0.0
        self.wire_force_n = self._point_force(2)
        """Wire force on the tree's attachment point at ``t_s``, NED [N]."""

    def _point_force(self, point_id: int) -> np.ndarray:
        """The wire's force on MoorDyn's point ``point_id`` now, NED [N]."""
        point = self._md.GetPoint(self.system, point_id)
        return moordyn_to_ned(np.asarray(self._md.GetPointForce(point), dtype=float))

    def top_tension_newton(self) -> float:
        """Tension at the crane tip [N]."""
        return float(np.linalg.norm(self._point_force(1)))

    def set_current(self, current_n: np.ndarray) -> None:
        """The current along the whole line from now on, NED [m/s]: uniform over depth, as
        the quasi-static wire's drag offset (eq. 2.29) takes it."""
        current_n = np.asarray(current_n, dtype=float)
        if current_n.shape != (3,) or not np.all(np.isfinite(current_n)):
            raise ValueError(f"current_n must be 3 finite numbers, got {current_n!r}")
        if np.array_equal(current_n, self.current_n):
            return
        u = ned_to_moordyn(current_n)
        n = self._n_water_points
        if self._md.ExternalWaveKinSet(self.system, [u] * n, [[0.0] * 3] * n, self.t_s) != 0:
            raise RuntimeError("MoorDyn did not take the current")
        self.current_n = current_n.copy()

    def set_length(self, length_m: float) -> None:
        """Pay out or haul in to the unstretched length ``length_m``; MoorDyn's internal step
        follows the segment length (``WAVE_SPEED_FRACTION``)."""
        lo, hi = COUPLED_LENGTH_RANGE_M
        if not (math.isfinite(length_m) and lo <= length_m <= hi):
            raise ValueError(
                f"wire length for the moordyn wire must lie in [{lo:g}, {hi:g}] m, "
                f"got {length_m:.1f} m"
            )
        if length_m == self.length_m:
            return
        self._md.SetLineUnstretchedLength(self.line, float(length_m))
        self._md.SetDt(self.system, WAVE_SPEED_FRACTION * length_m / COUPLED_SEGMENTS / self._speed)
        self.length_m = float(length_m)

    def step(
        self,
        tip_n: np.ndarray,
        tip_velocity_n: np.ndarray,
        attachment_n: np.ndarray,
        attachment_velocity_n: np.ndarray,
        dt_s: float,
    ) -> np.ndarray:
        """Advance dt_s from the ends' present positions and velocities; returns the force on
        the attachment point at the end of the step, NED [N] (also kept as ``wire_force_n``)."""
        x = ned_to_moordyn(tip_n) + ned_to_moordyn(attachment_n)
        v = ned_to_moordyn(tip_velocity_n) + ned_to_moordyn(attachment_velocity_n)
        f = np.asarray(self._md.Step(self.system, x, v, self.t_s, dt_s), dtype=float)
        self.t_s += dt_s
        if not np.all(np.isfinite(f)):
            raise FloatingPointError(f"MoorDyn's wire force is not finite at t = {self.t_s:.2f} s")
        self.wire_force_n = moordyn_to_ned(f[3:6])
        return self.wire_force_n

    def close(self) -> None:
        """Free MoorDyn's system (also done when the object is collected)."""
        if self.system is not None:
            self._md.Close(self.system)
            self.system = None
            self._dir.cleanup()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # interpreter shutdown: MoorDyn may be gone already
            pass
