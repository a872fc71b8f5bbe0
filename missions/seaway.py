"""Landing in a seaway: slack wire and snap loads on the lift wire (issue 14).

Criteria (DNV's recommended practice for marine operations, DNV-RP-H103, "Modelling and
analysis of marine operations"; the criteria's form as the issue states them, section numbers
not checked here):

- **slack wire**: the dynamic drop of the tension exceeds 90 % of the static tension, i.e. the
  tension falls below ``SLACK_FRACTION`` (0.1) of the static tension. The static tension at
  the tree is the tree's submerged weight W0 (what the log's ``wire_tension`` reads at rest).
- **snap load**: when the wire tightens again after going slack. Its size is taken two ways:
  simulated, the largest tension in the ``SNAP_WINDOW_S`` after the slack ends (the elastic
  wire of ``control.simulation.WIRE_MODELS`` simulates it); and estimated by the spring-mass
  snap formula F_snap = v_snap sqrt(K M) (the load's kinetic energy at the snap velocity
  stored in the wire's spring, 1/2 M v^2 = 1/2 F^2 / K; the form DNV-RP-H103 gives for
  snap forces), with K = k_z the wire's axial stiffness, M = M + A33 + m_wire L / 3 and
  v_snap the speed at which the tree and the wire's top separate along the wire when it
  tightens (the tree's vertical velocity less the crane tip's heave and the pay-out rate).

The contact speed of a landing is the tree's own vertical speed when its bottom reaches the
post tops: with the vessel moving, it carries the crane tip's heave that the wire passes on.

``WireWatch`` finds the events in a stream of log rows (the mission driver feeds it when the
plant's wire is elastic); ``land_in_seaway`` lowers the tree onto a docking frame from a
moving vessel and reports; ``landing_limit`` steps the sea state up until a landing is no
longer within the limits (``rov-console study landing-limit``).
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from control.columns import LogRows
from control.simulation import Simulation
from missions import schema
from missions.setup import current_params, vary_tree
from sim import environment as envmod
from sim import params as params_mod
from sim import site
from sim import vessel as vesselmod
from sim.docking import DockingFrame

FloatArray = NDArray[np.float64]

SLACK_FRACTION = 0.1
"""Slack when the tension is below this share of the static tension (a dynamic drop of more
than 90 % of it; DNV-RP-H103's slack criterion as the issue states it)."""
HOVER_S = 40.0
"""How long the tree hovers at its start depth before the lowering [s]: the vessel's motion
grows in over two peak periods (``sim.vessel.RAMP_PEAK_PERIODS``, 20 s at Tp 10 s) and the
tree's response builds up, so the lowering meets the full sea. The wire is judged from t = 0,
the hover included: with the ramp nothing there needs leaving out. Measured, tree alone at
100 m, head sea, no compensation, elastic wire (MoorDyn's alike): no slack in the first
120 s in Hs 4, 8 and 6 m (Tp 10, 10, 12 s), the lowest tension in the first 40 s 0.95, 0.89,
0.91 W0 against 0.92, 0.85, 0.88 W0 from 40 to 120 s. Before the ramp the tip jumped to its
displaced place at t = 0: 8 or 9 slack episodes in the first 40 s, snaps up to 5.9 W0, so
the first 40 s were left out of the judgement."""
HOVER_M = 5.0
"""How high the tree's bottom hovers over the post tops before the lowering [m]."""
SNAP_WINDOW_S = 2.0
"""How long after the slack ends the snap's peak tension is looked for [s] (longer than the
wire's axial period, 0.8 to 2.6 s from 100 to 1000 m at full scale)."""


@dataclass(frozen=True)
class WireEvent:
    """A slack wire or a snap load."""

    kind: str
    """``slack`` or ``snap``."""
    t_s: float
    tension_newton: float
    """Slack: the lowest tension in the episode; snap: the peak after it [N]."""
    duration_s: float = 0.0
    """Slack: how long the tension stayed below the limit [s]."""

    def text(self, static_newton: float) -> str:
        ratio = self.tension_newton / static_newton
        if self.kind == "slack":
            return (
                f"slack wire at {self.t_s:.2f} s for {self.duration_s:.2f} s: tension down to "
                f"{self.tension_newton / 1e3:.1f} kN ({100 * ratio:.0f} % of the static "
                f"{static_newton / 1e3:.0f} kN, limit {100 * SLACK_FRACTION:.0f} %)"
            )
        return (
            f"snap load at {self.t_s:.2f} s: {self.tension_newton / 1e3:.1f} kN "
            f"({ratio:.2f} x the static tension)"
        )


@dataclass
class WireWatch:
    """Finds slack and snap events in the log's wire tension as rows arrive."""

    static_newton: float
    """Static tension at the tree: its submerged weight W0 [N]."""
    events: list[WireEvent] = field(default_factory=list)
    _slack_from: float | None = None
    _slack_min: float = math.inf
    _snap_until: float | None = None
    _snap_peak: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.static_newton) and self.static_newton > 0.0):
            raise ValueError(f"static tension must be > 0 N, got {self.static_newton!r}")

    def feed(self, t_s: FloatArray, tension_newton: FloatArray) -> list[WireEvent]:
        """Look at the next rows (time, tension); returns the events completed in them."""
        new: list[WireEvent] = []
        limit = SLACK_FRACTION * self.static_newton
        for t, f in zip(np.asarray(t_s, float), np.asarray(tension_newton, float), strict=True):
            if self._snap_until is not None:
                if f > self._snap_peak[1]:
                    self._snap_peak = (float(t), float(f))
                if t >= self._snap_until or f < limit:
                    new.append(WireEvent("snap", self._snap_peak[0], self._snap_peak[1]))
                    self._snap_until = None
            if f < limit:
                if self._slack_from is None:
                    self._slack_from, self._slack_min = float(t), float(f)
                self._slack_min = min(self._slack_min, float(f))
            elif self._slack_from is not None:
                new.append(
                    WireEvent(
                        "slack", self._slack_from, self._slack_min, float(t) - self._slack_from
                    )
                )
                self._slack_from = None
                self._snap_until = float(t) + SNAP_WINDOW_S
                self._snap_peak = (float(t), float(f))
        self.events.extend(new)
        return new

    def count(self, kind: str) -> int:
        return sum(1 for e in self.events if e.kind == kind)


def snap_load_estimate_newton(snap_speed_mps: float, stiffness_newton_per_m: float, mass_kg: float):
    """F_snap = v_snap sqrt(K M) [N] (see the module's notes)."""
    return abs(snap_speed_mps) * math.sqrt(stiffness_newton_per_m * mass_kg)


@dataclass(frozen=True)
class SeawayLanding:
    """One landing from a moving vessel."""

    significant_height_m: float
    peak_period_s: float
    heave_compensation: bool
    static_newton: float
    min_tension_newton: float
    """Lowest tension while hovering and lowering, before the first contact [N]."""
    max_tension_newton: float
    """Highest tension over the whole run (snaps included) [N]."""
    slack_events: int
    snap_events: int
    snap_peak_newton: float
    """Largest simulated snap load (0: no snap) [N]."""
    snap_estimate_newton: float
    """F_snap = v_snap sqrt(K M) at the largest snap speed (0: no snap) [N]: the snap's
    dynamic part, to set beside the simulated peak less the static tension."""
    contact_speed_mps: float
    """The tree's vertical speed when its bottom reached the post tops (nan: no contact)."""
    max_contact_speed_mps: float
    """The docking frame's limit [m/s]."""
    events: tuple[WireEvent, ...]
    lowering_s: float
    """Start of the lowering, after the hover (``HOVER_S``) [s]."""
    contact_s: float
    """Time of the first contact (nan: none) [s]."""
    rows: LogRows = field(repr=False, compare=False)

    @property
    def within_limits(self) -> bool:
        """No slack wire and a contact no faster than the frame allows."""
        return (
            self.slack_events == 0
            and math.isfinite(self.contact_speed_mps)
            and self.contact_speed_mps <= self.max_contact_speed_mps
        )

    def words(self) -> str:
        comp = "on" if self.heave_compensation else "off"
        verdict = "within limits" if self.within_limits else "NOT within limits"
        dynamic = self.snap_peak_newton - self.static_newton
        # a wire taking up the load again after a slack need not reach the static tension
        # (the tree partly on the frame): then the peak is under it, not "static + -274 kN"
        over = (
            f"static + {dynamic / 1e3:.0f} kN"
            if dynamic >= 0.0
            else f"{-dynamic / 1e3:.0f} kN under the static"
        )
        snap = (
            f"{self.snap_events} snap loads, peak {self.snap_peak_newton / 1e3:.0f} kN "
            f"({over}; estimate + {self.snap_estimate_newton / 1e3:.0f} kN)"
            if self.snap_events
            else "no snap loads"
        )
        return (
            f"Hs {self.significant_height_m:.1f} m, Tp {self.peak_period_s:.1f} s, heave "
            f"compensation {comp}: tension {self.min_tension_newton / 1e3:.0f} to "
            f"{self.max_tension_newton / 1e3:.0f} kN (static {self.static_newton / 1e3:.0f} "
            f"kN), {self.slack_events} slack, {snap}, contact speed "
            f"{self.contact_speed_mps:.3f} m/s (limit {self.max_contact_speed_mps:.2f}): "
            f"{verdict}"
        )


def land_in_seaway(
    significant_height_m: float,
    peak_period_s: float,
    heave_compensation: bool,
    *,
    params: str = "full-scale",
    landing_depth_m: float = 110.0,
    hover_m: float = HOVER_M,
    lower_rate_mps: float = 0.05,
    hover_s: float = HOVER_S,
    settle_s: float = 20.0,
    seed: int = 0,
    wire: str = "elastic",
    frame_heading_rad: float = 0.0,
    wave_direction_rad: float = 0.0,
    wave_load: str = envmod.DEFAULT_WAVE_LOAD,
    water_depth_m: float | None = None,
    moving_vessel: bool = True,
    vessel_heading_rad: float | None = None,
    heave_compensation_efficiency: float | None = None,
    current: envmod.CurrentParams | None = None,
    mass_scale: float = 1.0,
    weight_scale: float = 1.0,
) -> SeawayLanding:
    """Lower the tree from ``hover_m`` above the post tops onto a docking frame below the
    crane tip, the vessel moving in a head sea (JONSWAP, ``sim.environment``), the tree alone
    on its wire (no ROV: what the wire and the vessel do to it). Calm sea: Hs 0.

    The vessel's motion grows in from t = 0 (``sim.vessel.ramp_in``) while the tree hovers
    ``hover_s`` at the start depth (``HOVER_S``). The wire is judged over the whole run: a
    slack episode counts when the wire takes the load again after it (the tree lifted off by
    the crane tip's heave, then the snap); the last one, the set-down the winch pays out for,
    never ends and is not a slack event.

    The installation (``LandingScenario.from_mission`` takes it from a mission): the frame's
    heading (the tree hangs turned to it), the waves' direction (towards, from north), load
    and water depth (None: the landing depth), the vessel (``moving_vessel`` False: the crane
    tip stands still; its heading, None: bow into the waves; the compensation's efficiency,
    None: ``VesselMotion``'s default), the current, and the tree's mass and submerged weight
    scaled (``missions.setup.vary_tree``). The crane tip stands over the frame's centre; the
    current pushes the tree off it. The defaults are the study's own scenario."""
    if not (math.isfinite(significant_height_m) and 0.0 <= significant_height_m <= 20.0):
        raise ValueError(f"significant_height_m must lie in [0, 20], got {significant_height_m}")
    ps = params_mod.load(params)
    if mass_scale != 1.0 or weight_scale != 1.0:
        ps = vary_tree(ps, mass_scale, weight_scale)  # no controller: the plant is the tree
    layout = ps.spec.docking.to_numeric()
    half_h = float(ps.tree.dimensions_m[2]) / 2.0
    frame = DockingFrame(np.zeros(2), frame_heading_rad, landing_depth_m)
    post_top = frame.post_top_depth_m(layout)
    waves = None
    vessel = None
    if significant_height_m > 0.0:
        waves = envmod.WaveParams(
            significant_height_m=significant_height_m,
            peak_period_s=peak_period_s,
            direction_rad=wave_direction_rad,
            load=wave_load,
            water_depth_m=landing_depth_m if water_depth_m is None else water_depth_m,
        )
        if moving_vessel:
            heading = vessel_heading_rad
            if heading is None:
                heading = wave_direction_rad + math.pi  # bow into the waves
            vessel = vesselmod.VesselMotion(
                heading_rad=heading, heave_compensation=heave_compensation
            )
            if heave_compensation_efficiency is not None:
                vessel = replace(
                    vessel, heave_compensation_efficiency=heave_compensation_efficiency
                )
    sim = Simulation(
        ps,
        tree_depth_m=post_top - hover_m - half_h,
        has_rov=False,
        control=False,
        crane_tip_n=(0.0, 0.0, 0.0),
        current=current,
        waves=waves,
        vessel=vessel,
        seed=seed,
        wire=wire,
        tree_heading_rad=frame_heading_rad,
    )
    sim.set_docking_frame(frame)
    static = float(ps.tree.submerged_weight_newton)
    watch = WireWatch(static)
    parts = [sim.run_for(hover_s)]  # see HOVER_S
    start_s = sim.t_s
    sim.winch_to(sim.wire_length_for_depth(landing_depth_m - half_h) + 0.3, lower_rate_mps)
    while not sim.winch_idle:
        parts.append(sim.run_for(1.0))
    parts.append(sim.run_for(settle_s))
    rows = LogRows.join(parts, sim.n_thrusters)
    t = rows.t_s
    tension = rows["wire_tension"]
    # the tree's vertical velocity, NED (from the body velocities)
    eta, nu = rows["tree_eta_n"], rows["tree_nu_b"]
    w_down = _down_velocity(eta, nu)
    bottom = eta[:, 2] + half_h
    hit = np.flatnonzero(bottom >= post_top)
    contact = float(w_down[hit[0]]) if hit.size else math.nan
    before = np.arange(len(t)) < (hit[0] if hit.size else len(t))
    watch.feed(t, tension)
    # the wire's top: the crane tip's heave (vessel) and the pay-out
    top_rate = np.gradient(rows["wire_rest_length"], t)
    if vessel is not None and sim.wave_field is not None:
        tip = vesselmod.crane_tip_motion_n(sim.wave_field, t, vessel, 0.0, 0.0, sim.vessel_ramp_s)
        top_rate = top_rate + np.gradient(tip[:, 2], t)
    snaps = [e for e in watch.events if e.kind == "snap"]
    slacks = [e for e in watch.events if e.kind == "slack"]
    estimate = 0.0
    if snaps:
        length = sim.wire_length_m
        k = site.vertical_stiffness(ps, length, 0.0)
        mass = ps.tree.M_rb[2, 2] + ps.tree.M_a[2, 2] + ps.wire.mass_per_length_kg_m * length / 3
        speeds = []
        for s in slacks:
            i = int(np.searchsorted(t, s.t_s + s.duration_s))
            i = min(i, len(t) - 1)
            speeds.append(abs(w_down[i] - top_rate[i]))
        estimate = snap_load_estimate_newton(max(speeds), k, mass)
    return SeawayLanding(
        significant_height_m=significant_height_m,
        peak_period_s=peak_period_s,
        heave_compensation=heave_compensation,
        static_newton=static,
        min_tension_newton=float(tension[before].min()),
        max_tension_newton=float(tension.max()),
        slack_events=len(slacks),
        snap_events=len(snaps),
        snap_peak_newton=max((e.tension_newton for e in snaps), default=0.0),
        snap_estimate_newton=estimate,
        contact_speed_mps=contact,
        max_contact_speed_mps=float(layout.max_landing_speed_mps),
        events=tuple(watch.events),
        lowering_s=start_s,
        contact_s=float(t[hit[0]]) if hit.size else math.nan,
        rows=rows,
    )


def _down_velocity(eta: FloatArray, nu: FloatArray) -> FloatArray:
    """The down component of R(phi, theta, psi) v_b for each row."""
    phi, theta = eta[:, 3], eta[:, 4]
    u, v, w = nu[:, 0], nu[:, 1], nu[:, 2]
    return -np.sin(theta) * u + np.cos(theta) * np.sin(phi) * v + np.cos(theta) * np.cos(phi) * w


def landing_limit(
    peak_period_s: float,
    heave_compensation: bool,
    hs_step_m: float = 0.5,
    hs_max_m: float = 12.0,
    **kwargs: object,
) -> tuple[float, list[SeawayLanding]]:
    """Step Hs up from ``hs_step_m`` until a landing is not within the limits (slack wire or
    a contact faster than the frame allows). Returns (the last Hs within the limits, 0 if the
    first fails; the landings run)."""
    if not (0.0 < hs_step_m <= hs_max_m):
        raise ValueError(f"hs_step_m must lie in (0, {hs_max_m}], got {hs_step_m}")
    landings: list[SeawayLanding] = []
    last_ok = 0.0
    n = int(math.floor(hs_max_m / hs_step_m + 1e-9))
    for i in range(1, n + 1):
        hs = i * hs_step_m
        landing = land_in_seaway(hs, peak_period_s, heave_compensation, **kwargs)  # type: ignore[arg-type]
        landings.append(landing)
        if not landing.within_limits:
            break
        last_ok = hs
    return last_ok, landings


SLACK_WIRES = ("elastic", "moordyn")
"""Wire models that can go slack (``control.simulation.WIRE_MODELS``; the quasi-static wire
is a spring that pulls as well as pushes)."""


@dataclass(frozen=True)
class LandingScenario:
    """A planner's installation from a mission's set-up: everything about a landing in a
    seaway but the sea's height, which ``landing_limit`` sweeps. ``keywords()`` are
    ``land_in_seaway``'s arguments (its defaults are the study's own scenario)."""

    source: str
    """The mission's name (what the messages name)."""
    significant_height_m: float
    """The mission's own Hs [m], to report beside the limit."""
    peak_period_s: float
    heave_compensation: bool
    params: str
    mass_scale: float
    weight_scale: float
    landing_depth_m: float
    frame_heading_rad: float
    wave_direction_rad: float
    wave_load: str
    water_depth_m: float | None
    moving_vessel: bool
    vessel_heading_rad: float | None
    heave_compensation_efficiency: float | None
    current: envmod.CurrentParams
    wire: str
    seed: int
    hover_m: float = HOVER_M
    """Clearance of the tree's bottom over the post tops where it hovers, then is lowered
    from [m]: the mission's dock leg's (``from_mission``), else the study's own."""
    lower_rate_mps: float = 0.05
    """The winch's speed down [m/s]: the mission's dock leg's, else the study's own."""

    @classmethod
    def from_mission(cls, mission: schema.Mission) -> LandingScenario:
        """``from_setup`` for the mission's ``[setup]``, flown as its first dock leg flies the
        landing (its hover height and lowering rate); the study's own procedure when the
        mission has no dock leg."""
        scenario = cls.from_setup(mission.setup, mission.name)
        dock = next((leg for leg in mission.legs if isinstance(leg, schema.DockLeg)), None)
        if dock is None:
            return scenario
        return replace(scenario, hover_m=dock.hover_m, lower_rate_mps=dock.lower_rate_mps)

    @classmethod
    def from_setup(cls, setup: schema.Setup, source: str = "the mission") -> LandingScenario:
        """The scenario a mission's ``[setup]`` describes; ValueError naming the field when it
        has nothing to land on, no sea to sweep or a wire that cannot go slack."""
        frame, waves, vessel = setup.docking_frame, setup.waves, setup.vessel
        if frame is None:
            raise ValueError(
                f"{source}: setup.docking_frame is missing: the landing-limit study needs a "
                "docking frame to land on ([setup.docking_frame] with center_ne_m, heading_deg "
                "and landing_depth_m)"
            )
        if waves is None:
            raise ValueError(
                f"{source}: setup.waves.peak_period_s is missing: the landing-limit study "
                "sweeps Hs at the mission's peak period, so it needs [setup.waves] with "
                "peak_period_s (> 0, at most 40 s), significant_height_m and direction_deg"
            )
        if setup.wire not in SLACK_WIRES:
            raise ValueError(
                f"{source}: setup.wire is {setup.wire!r}: the quasi-static wire cannot go slack "
                "(a spring on the tree that pulls and pushes alike), so no landing would ever "
                'fail the slack criterion; set setup.wire to "elastic" or "moordyn"'
            )
        params_mod.load(setup.params)  # a ParameterError (ValueError) naming the set
        return cls(
            source=source,
            significant_height_m=waves.significant_height_m,
            peak_period_s=waves.peak_period_s,
            heave_compensation=vessel is not None and vessel.heave_compensation,
            params=setup.params,
            mass_scale=setup.plant.mass_scale,
            weight_scale=setup.plant.weight_scale,
            landing_depth_m=frame.landing_depth_m,
            frame_heading_rad=math.radians(frame.heading_deg),
            wave_direction_rad=math.radians(waves.direction_deg),
            wave_load=waves.load,
            water_depth_m=waves.water_depth_m,
            moving_vessel=vessel is not None,
            vessel_heading_rad=None
            if vessel is None or vessel.heading_deg is None
            else math.radians(vessel.heading_deg),
            heave_compensation_efficiency=None
            if vessel is None
            else vessel.heave_compensation_efficiency,
            current=current_params(setup.current),
            wire=setup.wire,
            seed=setup.seed,
        )

    def keywords(self) -> dict[str, object]:
        """``land_in_seaway``'s (and ``landing_limit``'s) keyword arguments."""
        skip = ("source", "significant_height_m", "peak_period_s", "heave_compensation")
        return {k: v for k, v in vars(self).items() if k not in skip}

    def limit(
        self, hs_step_m: float, hs_max_m: float, seed: int | None = None
    ) -> tuple[float, list[SeawayLanding]]:
        """``landing_limit`` for this installation (``seed``: instead of the mission's)."""
        kw = self.keywords()
        if seed is not None:
            kw["seed"] = seed
        try:
            return landing_limit(
                self.peak_period_s, self.heave_compensation, hs_step_m, hs_max_m, **kw
            )
        except ValueError as err:
            raise ValueError(
                f"{self.source}: cannot land on the frame at setup.docking_frame."
                f"landing_depth_m = {self.landing_depth_m:g} m with the {self.wire} wire "
                f"(the tree starts {self.hover_m:g} m above the post tops): {err}"
            ) from None

    def words(self, seed: int | None = None) -> str:
        """The installation in one paragraph."""
        deg = math.degrees
        if not self.moving_vessel:
            vessel = "no [setup.vessel]: the crane tip stands still"
        else:
            heading = (
                "bow into the waves"
                if self.vessel_heading_rad is None
                else f"heading {deg(self.vessel_heading_rad):g} deg"
            )
            eff = self.heave_compensation_efficiency
            comp = (
                f"heave compensation on ({100 * eff:.0f} %)"
                if self.heave_compensation and eff is not None
                else "heave compensation off"
            )
            vessel = f"vessel {heading}, {comp}"
        c = self.current
        return (
            f"{self.source}: {self.params} (tree mass x{self.mass_scale:g}, submerged weight "
            f"x{self.weight_scale:g}), frame at {self.landing_depth_m:g} m heading "
            f"{deg(self.frame_heading_rad):g} deg; sea Tp {self.peak_period_s:g} s towards "
            f"{deg(self.wave_direction_rad):g} deg ({self.wave_load} load); {vessel}; "
            f"{self.wire} wire; current {c.speed_mps:g} m/s towards "
            f"{deg(c.direction_rad):g} deg; lowered from {self.hover_m:g} m over the post "
            f"tops at {self.lower_rate_mps:g} m/s; seed {self.seed if seed is None else seed}"
        )


SEEDS_MAX = 50
"""Most seeds one landing-limit study sweeps (each is a whole sweep of Hs, 1-3 s)."""


@dataclass(frozen=True)
class SeedLimit:
    """One sea's sweep: its seed, the last Hs within the limits, the landings run."""

    seed: int
    limit_m: float
    landings: list[SeawayLanding] = field(compare=False, repr=False)


def limits_over_seeds(
    sweep: Callable[[int], tuple[float, list[SeawayLanding]]], first_seed: int, seeds: int
) -> list[SeedLimit]:
    """``sweep(seed)`` for ``seeds`` seeds from ``first_seed`` on, lowest limit first (ties:
    the lower seed). One seed's limit is one sea's: at Tp 10 s in 2 m steps, twelve seeds gave
    limits from 2 to 6 m, so a margin is judged on the lowest of several."""
    if isinstance(seeds, bool) or not isinstance(seeds, int) or not 1 <= seeds <= SEEDS_MAX:
        raise ValueError(f"seeds must be a whole number in [1, {SEEDS_MAX}], got {seeds!r}")
    out = []
    for seed in range(first_seed, first_seed + seeds):
        hs, landings = sweep(seed)
        out.append(SeedLimit(seed, hs, landings))
    return sorted(out, key=lambda r: (r.limit_m, r.seed))


def seeds_words(limits: list[SeedLimit]) -> str:
    """The limits of several seas in one line, lowest first."""
    low = limits[0]
    each = ", ".join(
        f"{r.limit_m:g} m (seed {r.seed})" for r in sorted(limits, key=lambda r: r.seed)
    )
    return (
        f"over {len(limits)} seeds the lowest limit is {low.limit_m:g} m (seed {low.seed}); "
        f"each: {each}"
    )


def hs_verdict(mission_hs_m: float, limit_m: float, landings: list[SeawayLanding]) -> str:
    """The mission's own Hs against the limit the sweep found, in words."""
    last = landings[-1]
    if mission_hs_m == 0.0:
        return f"your mission's sea is calm (Hs 0 m); the limit is {limit_m:g} m"
    if mission_hs_m <= limit_m:
        return f"your mission's Hs {mission_hs_m:g} m is within the limit {limit_m:g} m"
    if last.within_limits:
        return (
            f"your mission's Hs {mission_hs_m:g} m is above the largest Hs tried "
            f"({last.significant_height_m:g} m, within the limits): raise --hs-max"
        )
    failed = last.significant_height_m
    if mission_hs_m >= failed:
        return (
            f"your mission's Hs {mission_hs_m:g} m is NOT within the limit {limit_m:g} m "
            f"(a landing at Hs {failed:g} m already was not)"
        )
    return (
        f"your mission's Hs {mission_hs_m:g} m lies between the limit {limit_m:g} m and the "
        f"first Hs not within the limits ({failed:g} m): try a smaller --hs-step"
    )


def tension_figure(landing: SeawayLanding, path) -> object:
    """The wire's tension over the landing with the slack limit and the events marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = landing.rows
    fig, ax = plt.subplots(figsize=(9, 4))
    ax.plot(rows.t_s, rows["wire_tension"] / 1e3, lw=0.8, label="wire tension at the tree")
    ax.axhline(landing.static_newton / 1e3, color="0.5", ls="--", lw=0.8, label="static (W0)")
    ax.axhline(
        SLACK_FRACTION * landing.static_newton / 1e3,
        color="tab:red",
        ls=":",
        lw=1.0,
        label=f"slack limit ({100 * SLACK_FRACTION:.0f} % of static)",
    )
    ax.axvspan(rows.t_s[0], landing.lowering_s, color="0.9", lw=0, label="hover (vessel ramps in)")
    if math.isfinite(landing.contact_s):
        ax.axvline(landing.contact_s, color="k", lw=0.8, ls="-.", label="first contact")
    for e in landing.events:
        if e.kind == "slack":
            ax.axvspan(e.t_s, e.t_s + e.duration_s, color="tab:red", alpha=0.2, lw=0)
        else:
            ax.plot(e.t_s, e.tension_newton / 1e3, "v", color="tab:purple")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tension [kN]")
    ax.set_title("\n".join(textwrap.wrap(landing.words(), 120)), fontsize=8)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
