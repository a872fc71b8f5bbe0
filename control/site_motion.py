"""``SiteMotion``: the environment's moving parts, and each chunk's environment rows.

It owns what moves around the tree and the ROV without being either: the current and its
random walk, the waves, the vessel's crane tip (kept on station, moved on command, and its
wave-frequency motion), the winch's payout, the lift wire (quasi-static, elastic or MoorDyn's
lumped-mass line), the docking frame under the tree and a steady push on it. ``rows`` makes
the (n, ``sim.plant.N_ENV``) environment rows of the next chunk and advances all of it to the
chunk's end; ``wire_rows`` adds the vessel's motion and the elastic or MoorDyn wire's entries
once the injected faults have moved the crane tip.

The slow parts (the quasi-static wire's stiffnesses and drag offset, the control model's wire
spring, where the waves and the vessel's motion are evaluated, the elastic wire's mass) are
refreshed on the whole seconds of the step grid (``REFRESH_S``); the current's walk, the
winch's payout and the crane's path go a step at a time from the step before, so a run gives
the same rows however it is cut into chunks.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from control.jobs import SimulationDiverged
from sim import dynamic_wire as dwire
from sim import environment as envmod
from sim import plant, site
from sim import vessel as vesselmod
from sim import wire as wm
from sim.docking import DockingFrame
from sim.gnc import Rzyx
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]
CurrentChange = Callable[[FloatArray, FloatArray, FloatArray], tuple[FloatArray, FloatArray]]
"""(times [s], speeds [m/s], directions [rad]) of a chunk's steps -> the changed speeds and
directions (the injected current faults)."""

REFRESH_S = 1.0
"""How often the slow parts of the environment are brought up to date [s]: the quasi-static
wire's stiffnesses and drag offset (from the current at that step, the payout and the crane
tip), the control model's wire spring (its stiffness for the payout, its equilibrium under
the crane tip), the point where the waves and the vessel's motion are evaluated, and the
elastic wire's lumped mass. On the whole seconds of the step grid (steps 0, 1/dt, 2/dt...),
and chunks end there (or, with only the wire's entries and the control model's spring to
refresh, run past them and refresh those at the rows of whole seconds:
``control.simulation.LONG_CHUNK_S``, ``control.jobs.ClosedChunk.spring``), so a run gives the
same numbers however it is cut into requests (the console's ticks, the command line's
requests). A second is short beside how fast any of them changes: the current walks by
millimetres a second, the winch pays out at most 2 m/s on a wire hundreds of metres long (its
horizontal stiffness moves by 1 % at most), and the tree moves centimetres against waves
hundreds of metres long."""
WIRE_MODELS = ("quasi-static", "elastic", "moordyn")
"""The lift wire in the plant. ``quasi-static``: the elastic pendulum of ``sim.plant`` (the
spring k_z of eq. 2.25 on the tree's own inertia, no damping). ``elastic``: the same spring
with the wire's first axial mode: a third of the wire's mass lumped at the tree (vertically)
and a dashpot beside the spring (``wire_damping_ratio``), so the lift wire's resonance
T0 = 2 pi sqrt((M + A33 + m_wire L / 3) / (EA / L)) and slack and snap are simulated.
``moordyn``: a lumped-mass line (MoorDyn, ``sim.dynamic_wire.CoupledWire``) from the crane tip
to the tree's attachment point, stepped beside the plant one step at a time (all its axial
modes, its own weight, mass and drag; the current, uniform over depth, on the wire as on the
quasi-static wire, the waves on the tree only)."""
WIRE_DAMPING_RATIO = 0.02
"""Damping ratio of the elastic wire's dashpot against its axial mode [-]: an assumed value
for the internal (strand friction) damping of a steel wire rope, small beside the tree's
hydrodynamic heave damping; a parameter (``wire_damping_ratio``), not a measured figure."""
MOORDYN_WATER_BELOW_M = 1000.0
"""MoorDyn's seabed this far below the tree's attachment point at the start [m]: the wire
never reaches it (the plant's own seabed and docking frame carry the tree)."""


def steady_current(speed_mps: float, direction_rad: float) -> envmod.CurrentParams:
    """A current of fixed speed and direction (no random walk)."""
    return envmod.CurrentParams(
        speed_mps=speed_mps,
        direction_rad=direction_rad,
        speed_min_mps=speed_mps,
        speed_max_mps=speed_mps,
        direction_min_rad=direction_rad,
        direction_max_rad=direction_rad,
    )


class SiteMotion:
    """Current, waves, vessel, crane, winch and wire of one run, stepped chunk by chunk.

    ``plant_ps`` is the physical truth; ``model_tree_weight_newton`` the tree's submerged
    weight the control system is configured with, for the control model's wire spring
    (``model_spring``: refreshed only with control on)."""

    def __init__(
        self,
        plant_ps: ParameterSet,
        *,
        tree_depth_m: float,
        crane_tip_n: FloatArray,
        current: envmod.CurrentParams,
        waves: envmod.WaveParams | None,
        vessel: vesselmod.VesselMotion | None,
        wire: str,
        wire_damping_ratio: float,
        dt_s: float,
        refresh_steps: int,
        rng_current: np.random.Generator,
        rng_waves: np.random.Generator,
        model_spring: bool,
        model_tree_weight_newton: float,
    ) -> None:
        self.plant_ps = plant_ps
        self.dt_s = dt_s
        self.refresh_steps = refresh_steps
        self.wire_model = wire
        """``quasi-static``, ``elastic`` or ``moordyn`` (see ``WIRE_MODELS``)."""
        self.wire_damping_ratio = float(wire_damping_ratio)
        self.model_spring = model_spring
        self.model_tree_weight_newton = model_tree_weight_newton
        self.wire_site = site.wire_site(plant_ps)
        """The wire's and the tree's numbers behind every chunk's wire entries."""
        self._frame_entries = np.zeros(5)  # site.chunk_rows_into's ``frame``
        self._chunk_out = np.zeros(6)  # and its ``out``
        self.wire_held = np.zeros(plant.N_ENV)
        """The wire's slow entries, held between refreshes (``REFRESH_S``)."""
        self.spring_k_h = 0.0
        """The control model's wire spring at the last refresh [N/m]."""
        self.spring_k_h_wire_m = math.nan
        """The payout ``spring_k_h`` is for [m]."""
        self.spring_p_eq = np.zeros(2)
        """The control model's wire spring's equilibrium, north and east [m]."""
        # the control model's spring as ``site.chunk_rows_into`` carries it through a chunk:
        # [k_h, p_eq north, east, the payout k_h is for], from the three above before each
        # chunk and back into them after it (the last whole second's, as a chunk ending there)
        self._spring_held = np.zeros(4)
        self.spring_rows = np.zeros((0, 3))
        """The control model's spring at each row of the chunk whose rows were made last."""
        self._refresh_point = np.zeros(5)  # tree north, east, depth; crane tip north, east
        self._pivot_tops = np.zeros((0, 3))  # the elastic wire's top, the last two steps
        self._refresh_wire_m = 0.0  # the payout at the last refresh [m]
        self.rng_current = rng_current
        self.current_params = current
        self.current_state = envmod.initial_current(current)
        self.wave_field = envmod.make_wave_field(waves, rng_waves) if waves is not None else None
        self.wave_load = waves.load if waves is not None else envmod.DEFAULT_WAVE_LOAD
        """How the waves load the bodies (sim.environment.WAVE_LOADS)."""
        self.vessel_motion = vessel
        """The vessel's wave-frequency motion at the crane tip (None: the tip stands still)."""
        self.compensation: vesselmod.CompensationRamp | None = None
        """The heave compensation as switched during the run (None: as the mission set it)."""
        self.vessel_ramp_s = (
            vesselmod.ramp_time_s(waves.peak_period_s)
            if vessel is not None and waves is not None
            else 0.0
        )
        """The vessel's motion grows in over this long from t = 0 [s] (``sim.vessel.ramp_in``,
        two peak periods of the sea; 0: no vessel motion or no ramp)."""
        self.compensation_ramp_s = (
            vesselmod.ramp_time_s(waves.peak_period_s) if waves is not None else 0.0
        )
        """The heave compensation fades in or out over this long when switched [s]: as the
        vessel's ramp-in, two peak periods, far slower than the wire's axial bounce."""
        self.crane_tip_n = crane_tip_n
        self.wire_length_m = self.wire_length_for_depth(tree_depth_m)
        self.crane_target_n = self.crane_tip_n.copy()
        self.crane_speed_mps = 0.0
        self.wire_target_m = self.wire_length_m
        self.wire_rate_mps = 0.0
        self.push_newton = np.zeros(3)
        self.docking_frame: DockingFrame | None = None
        self.mdwire: dwire.CoupledWire | None = None
        """The MoorDyn wire (``wire = "moordyn"``, once ``start_moordyn_wire`` ran), else
        None."""
        self._wire_current_n = np.zeros(3)
        """The current the MoorDyn wire feels over the present chunk, NED [m/s] (set with the
        chunk's environment rows)."""
        self._md_tip_n = self.crane_tip_n.copy()

    def start_moordyn_wire(self, x: FloatArray, tree_r_att: FloatArray) -> None:
        """The MoorDyn line between the crane tip and the tree's attachment point of plant
        state ``x`` (its initial-condition solver settles the wire's own weight)."""
        R_t = Rzyx(*x[3:6])
        p_att = x[0:3] + R_t @ tree_r_att
        self.mdwire = dwire.CoupledWire(
            self.plant_ps,
            self.wire_length_m,
            self.crane_tip_n,
            p_att,
            float(p_att[2] - self.crane_tip_n[2]) + MOORDYN_WATER_BELOW_M,
            self.wire_damping_ratio,
        )
        self._md_tip_n = self.crane_tip_n.copy()

    # ------------------------------------------------------------------ what it is now
    def times(self, k0: int, n: int) -> FloatArray:
        """The times of steps k0 .. k0 + n - 1 [s], each (step index) x dt: the same numbers
        whatever chunk they fall in."""
        return (k0 + np.arange(n, dtype=np.float64)) * self.dt_s

    @property
    def winch_idle(self) -> bool:
        """The winch has reached its commanded payout."""
        return abs(self.wire_length_m - self.wire_target_m) < 1e-6

    def winch_steps_busy(self) -> int:
        """Steps from now after each of which the winch is certainly still moving: its gap to
        the target over a step's travel, less two steps of margin for the rounding of the
        payout's sum (some 1e-13 m a step against a travel of 1e-4 m or more); 0 when the
        winch is idle or stopped."""
        travel_m = self.wire_rate_mps * self.dt_s
        gap_m = abs(self.wire_target_m - self.wire_length_m)
        if travel_m <= 0.0 or gap_m < 1e-6:
            return 0
        return max(0, int(gap_m / travel_m) - 2)

    def wire_length_for_depth(self, tree_depth_m: float) -> float:
        """Unstretched payout that hangs the tree's centre at ``tree_depth_m`` in the present
        current (the plant's wire and tree)."""
        return site.wire_length_for_depth(
            self.plant_ps, tree_depth_m, self.crane_tip_n[2], self.current_state.speed_mps
        )

    def at_rest_row(self) -> FloatArray:
        """An environment row of the site at rest as it stands (before any step)."""
        env = site.wire_environment(
            self.plant_ps,
            self.wire_length_m,
            self.crane_tip_n,
            self.current_state.speed_mps,
            self.current_state.direction_rad,
        )
        env[plant.E_LREST] = self.wire_length_m + site.self_weight_stretch(
            self.plant_ps, self.wire_length_m
        )
        return env

    def still(self, qp: bool) -> bool:
        """Nothing of the site refreshed on a whole second needs Python for seconds to come:
        no sea (the waves and the vessel's motion are evaluated where the tree was at the
        refresh), the quasi-static wire (whose entries and the control model's spring
        ``site.chunk_rows_into`` refreshes itself at the rows of whole seconds). With the QP
        allocation (``qp``: its steps in Python, on the control configuration as it is) or a
        wire paid out to nothing (the refresh refuses it) that holds only while the winch
        and the crane rest."""
        if self.wave_field is not None or self.wire_model != "quasi-static":
            return False
        winch_rests = self.wire_length_m == self.wire_target_m
        crane_rests = self.crane_speed_mps <= 0.0 or bool(
            np.array_equal(self.crane_tip_n, self.crane_target_n)
        )
        if winch_rests and crane_rests:
            return True
        return not qp and self.wire_length_m > 0.0 and self.wire_target_m > 0.0

    # ------------------------------------------------------------------ commands
    def winch_to(self, length_m: float, rate_mps: float) -> None:
        """Pay out (or haul in) the wire to ``length_m`` at ``rate_mps`` (both checked by the
        caller; the MoorDyn wire's own range here)."""
        if self.mdwire is not None:
            lo, hi = dwire.COUPLED_LENGTH_RANGE_M
            if not lo <= length_m <= hi:
                raise ValueError(
                    f"wire length must be in [{lo:g}, {hi:g}] m with the moordyn wire, "
                    f"got {length_m:g}"
                )
        self.wire_target_m = length_m
        self.wire_rate_mps = rate_mps

    def slip_winch(self, drop_m: float) -> None:
        """The winch slips: the payout and its target grow by ``drop_m`` at once."""
        self.wire_length_m += drop_m
        self.wire_target_m += drop_m

    def hold_crane_at(self, tip_n: FloatArray) -> None:
        """The crane tip is at ``tip_n`` and stays there."""
        self.crane_tip_n = tip_n.copy()
        self.crane_target_n = tip_n.copy()

    def set_current(self, params: envmod.CurrentParams) -> None:
        """A new current (and its random walk), from its nominal speed and direction."""
        self.current_params = params
        self.current_state = envmod.initial_current(params)

    # ------------------------------------------------------------------ a chunk's rows
    def _refresh(self, x: FloatArray) -> None:
        """Take the slow parts' inputs at this step (``REFRESH_S``): the payout, the tree's
        position in plant state ``x`` for the waves, the crane tip's for the vessel's motion,
        and, with ``model_spring``, the control model's wire spring."""
        tip = self.crane_tip_n
        self._refresh_wire_m = self.wire_length_m
        self._refresh_point[:] = (x[0], x[1], x[2], tip[0], tip[1])
        if self.model_spring:
            if self.wire_length_m != self.spring_k_h_wire_m:
                self.spring_k_h = float(
                    wm.horizontal_stiffness(
                        self.plant_ps.wire.submerged_weight_per_length(),
                        self.model_tree_weight_newton,
                        self.wire_length_m,
                    )
                )
                self.spring_k_h_wire_m = self.wire_length_m
            self.spring_p_eq = tip[0:2].copy()

    def rows(
        self,
        n: int,
        k0: int,
        x: FloatArray,
        gripping: bool,
        change_current: CurrentChange | None = None,
    ) -> FloatArray:
        """(n, N_ENV) environment rows (sim.plant.E_*) of steps k0 .. k0 + n - 1 from plant
        state ``x``; advances the current, the winch and the crane to the end of the chunk.
        A chunk that starts on a whole second refreshes the slow parts first (``REFRESH_S``);
        any other holds them. ``change_current`` alters the current's speed and direction
        over the steps (at the tree and along the wire alike)."""
        if k0 % self.refresh_steps == 0:
            self._refresh(x)
        self.current_state, speeds, dirs = envmod.advance_current(
            self.current_state, self.current_params, self.dt_s, n, self.rng_current
        )
        if change_current is not None:
            speeds, dirs = change_current(self.times(k0, n), speeds, dirs)
        env = np.empty((n, plant.N_ENV))
        spring = np.empty((n, 3))
        held = self._spring_held
        held[0] = self.spring_k_h
        held[1:3] = self.spring_p_eq
        held[3] = self.spring_k_h_wire_m
        frame = self._frame_entries
        frame[0] = 0.0
        if self.docking_frame is not None:
            frame[0] = 1.0
            frame[1:3] = self.docking_frame.center_n
            frame[3] = self.docking_frame.heading_rad
            frame[4] = self.docking_frame.landing_depth_m
        out = self._chunk_out
        site.chunk_rows_into(
            env,
            self.wire_site,
            speeds,
            dirs,
            self.wire_length_m,
            self.wire_target_m,
            self.wire_rate_mps,
            self.crane_tip_n,
            self.crane_target_n,
            self.crane_speed_mps,
            self.push_newton,
            1.0 if gripping else 0.0,
            frame,
            self.dt_s,
            self.wire_held,
            k0,
            self.refresh_steps,
            out,
            held,
            spring,
            self.plant_ps.wire.submerged_weight_per_length(),  # as ``_refresh``
            self.model_tree_weight_newton if self.model_spring else 0.0,
        )
        self.spring_rows = spring
        if self.mdwire is not None:
            # the current the MoorDyn wire sees over this chunk: uniform over depth, the mean
            # speed and direction the quasi-static wire's drag offset takes (no waves)
            self._wire_current_n = envmod.current_velocity_n(float(out[4]), float(out[5]))
        if self.wave_field is not None:
            self._add_waves(env, self.times(k0, n))
        self.wire_length_m = float(out[0])
        self.crane_tip_n = out[1:4].copy()
        return env

    def take_spring(self) -> None:
        """After the chunk ran: the control model's spring of its last whole second (as if
        the chunk had ended there: chunks past whole seconds carry it in their rows)."""
        spring = self._spring_held
        self.spring_k_h = float(spring[0])
        self.spring_p_eq = spring[1:3].copy()
        self.spring_k_h_wire_m = float(spring[3])

    def _add_waves(self, env: FloatArray, t: FloatArray) -> None:
        """The waves' velocity and acceleration added to the current's, at the tree's centre
        as at the last refresh, kept inside the water column (a tree in the seabed's contact
        spring sits a few centimetres into it)."""
        assert self.wave_field is not None
        north, east, down = self._refresh_point[0:3]
        depth = min(max(float(down), 0.0), self.wave_field.water_depth_m)
        v_w, a_w = envmod.wave_kinematics_n(self.wave_field, t, depth, float(north), float(east))
        env[:, plant.E_VC : plant.E_VC + 3] += v_w
        if self.wave_load != "drag":
            env[:, plant.E_AC : plant.E_AC + 3] += a_w

    def wire_rows(self, env: FloatArray, k0: int, x: FloatArray, tree_r_att: FloatArray) -> None:
        """The rest of a chunk's rows, once the crane tip's path is final: the vessel's
        motion at the crane tip, and the elastic or the MoorDyn wire's entries (MoorDyn
        stepped over the one step of ``env`` from plant state ``x``)."""
        self._vessel_in_chunk(env, k0)
        if self.wire_model == "elastic":
            self._elastic_wire_in_chunk(env)
        if self.mdwire is not None:
            self._moordyn_wire_in_step(env, k0, x, tree_r_att)

    def _vessel_in_chunk(self, env: FloatArray, k0: int) -> None:
        """Add the vessel's wave-frequency motion to the crane tip (sim.vessel), grown in over
        ``vessel_ramp_s``; the crane tip's mean position (``crane_tip_n``, where the vessel
        keeps station) is unchanged."""
        if self.vessel_motion is None or self.wave_field is None:
            return
        t = self.times(k0, len(env))
        tip = vesselmod.crane_tip_motion_n(
            self.wave_field,
            t,
            self.vessel_motion,
            float(self._refresh_point[3]),
            float(self._refresh_point[4]),
            self.vessel_ramp_s,
        )
        if self.compensation is not None:  # switched during the run: the motion is without
            tip[:, 2] *= self.compensation.z_factor(t)
        env[:, plant.E_CT : plant.E_CT + 3] += tip

    def set_heave_compensation(self, on: bool, t_s: float) -> None:
        """Fade the heave compensation in (``on``) or out from ``t_s`` over
        ``compensation_ramp_s`` (``sim.vessel.CompensationRamp``), from where it stands; the
        vessel's motion is from then on the uncompensated one, scaled by the ramp."""
        motion = self.vessel_motion
        if motion is None or self.wave_field is None:
            raise ValueError(
                "heave compensation: the crane tip does not heave in this run (no sea)"
            )
        if self.compensation is not None:
            share = float(self.compensation.share(t_s))
        else:
            share = 1.0 if motion.heave_compensation else 0.0
        self.vessel_motion = replace(motion, heave_compensation=False)
        self.compensation = vesselmod.CompensationRamp(
            t_s,
            share,
            1.0 if on else 0.0,
            self.compensation_ramp_s,
            motion.heave_compensation_efficiency,
        )

    @property
    def heave_compensation(self) -> bool | None:
        """On (switching on), off (switching off), or None: the crane tip does not heave."""
        if self.vessel_motion is None or self.wave_field is None:
            return None
        if self.compensation is not None:
            return self.compensation.to_share > 0.5
        return self.vessel_motion.heave_compensation

    def _elastic_wire_in_chunk(self, env: FloatArray) -> None:
        """The elastic wire's entries: the lumped wire mass m_wire L / 3 (L the payout at the
        last refresh, ``REFRESH_S``), the dashpot c = 2 zeta sqrt(k_z (M + A33 + m_wire L / 3)),
        and the velocity of the wire's top (the crane tip's motion and the winch's pay-out)
        from the rows by the second-order backward difference (3 p_j - 4 p_j-1 + p_j-2) / 2 dt,
        whose two earlier points carry over from the chunk before (the first step of a run
        takes the top as still before it), so the velocities do not depend on the cut."""
        ps = self.plant_ps
        m_wire = ps.wire.mass_per_length_kg_m * self._refresh_wire_m / 3.0
        m_heave = ps.tree.M_rb[2, 2] + ps.tree.M_a[2, 2] + m_wire
        k_z = env[:, plant.E_KZ]
        env[:, plant.E_WMASS] = m_wire
        env[:, plant.E_WDAMP] = 2.0 * self.wire_damping_ratio * np.sqrt(k_z * m_heave)
        top = env[:, plant.E_CT : plant.E_CT + 3].copy()
        top[:, 2] += env[:, plant.E_LREST]
        before = self._pivot_tops
        if len(before) == 0:
            before = np.vstack([top[0], top[0]])
        tops = np.vstack([before, top])
        vel = (3.0 * tops[2:] - 4.0 * tops[1:-1] + tops[:-2]) / (2.0 * self.dt_s)
        self._pivot_tops = tops[-2:].copy()
        env[:, plant.E_VPIV : plant.E_VPIV + 3] = vel

    def _moordyn_wire_in_step(
        self, env: FloatArray, k0: int, x: FloatArray, tree_r_att: FloatArray
    ) -> None:
        """Step MoorDyn's wire over the coming plant step and give the plant its force.

        MoorDyn starts from the tree's attachment point as it is now (position and velocity
        from the plant's state) and the crane tip where it was, moves both at constant
        velocity to the end of the step (the crane tip to this step's row), and returns the
        force on the attachment point at the end. The plant then holds the mean of the force
        at the start and the predicted force at the end over its RK4 step (trapezoidal).
        Explicit: the wire does not see the tree's acceleration within the step, so its
        force lags the tree by O(dt^2) (the attachment point's path is predicted to first
        order) and the next step starts MoorDyn from the true position again. Against the
        shortest period of the coupled system, the wire's axial bounce T0 (0.76 s at 100 m,
        76 steps of 0.01 s), the error per cycle is of order (2 pi dt / T0)^2 ~ 0.7 %; a
        plain one-step lag (the force at the step's start held over it) would act as a
        negative damping ratio of about pi dt / (2 T0) ~ 2 %, the size of the wire's own
        damping, which is why the trapezoid is used. Checked in
        ``tests/test_moordyn_wire.py``: the bounce's period is T0 within 5 %."""
        wire = self.mdwire
        assert wire is not None and env.shape[0] == 1
        tip_n = env[0, plant.E_CT : plant.E_CT + 3].copy()
        tip_v = (tip_n - self._md_tip_n) / self.dt_s
        R_t = Rzyx(*x[3:6])
        p_att = x[0:3] + R_t @ tree_r_att
        v_att = plant.attachment_velocity_n(x, R_t, tree_r_att)
        f_start = wire.wire_force_n.copy()
        try:
            wire.set_length(self.wire_length_m)
            wire.set_current(self._wire_current_n)
            f_end = wire.step(self._md_tip_n, tip_v, p_att, v_att, self.dt_s)
        except (FloatingPointError, RuntimeError) as e:
            t_s = k0 * self.dt_s
            raise SimulationDiverged(f"MoorDyn wire failed at t = {t_s:.2f} s: {e}") from e
        self._md_tip_n = tip_n
        env[:, plant.E_FWIRE : plant.E_FWIRE + 3] = 0.5 * (f_start + f_end)
        env[:, plant.E_WEXT] = 1.0
