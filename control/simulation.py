"""``Simulation``: the one owner of a running simulation.

It holds everything that changes while a simulation runs: the plant state and the held sensor
values, the environment (current, waves, the vessel's crane tip, the winch, the docking frame),
and, with control on, the control system's state (observer, reference, controller, signal
checks) with its compiled configuration. It steps all of it and takes every command through
its own methods; nothing outside writes its arrays.

    sim = Simulation(ps, tree_depth_m=400.0)     # closed loop (chapter 3 on chapter 2)
    rows = sim.step(100)                          # LogRows: rows["tree_eta_n"] ...
    sim.set_target(1.0, 1.0, math.radians(90))
    rows = sim.run_for(60.0)                      # a whole number of steps, or ValueError

With ``control=False`` it is the open-loop plant of ``rov-console simulate``: the thrusters
turn at ``set_thruster_speeds`` and the control columns of the rows stay zero.

Stepping goes in chunks of at most ``chunk_steps`` that end on whole seconds (``REFRESH_S``),
or of up to ``LONG_CHUNK_S`` while nothing but the wire's entries and the control model's
wire spring needs refreshing there (``_still``; both ride in the chunk's rows):
``_chunk_inputs`` makes the environment and sensor noise for a chunk (the place where
injected faults will change what the plant and the sensors see), then one compiled kernel
advances the chunk (``control.loop``). Commands are applied between chunks. A state
that stops being finite raises ``SimulationDiverged`` naming the time and which part went
non-finite.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from control import allocation as alloc
from control import loop, model, quality, refkernel
from control.columns import LAYOUT, N_LOG, Layout, LogRows
from control.config import (
    ALLOCATIONS,
    HEADING_MODES,
    MODES,
    Allocation,
    ControlSettings,
    Gains,
    HeadingMode,
    Mode,
    control_arrays,
    pilot_capacity,
    system_thruster_config,
)
from control.controller_state import ControllerState
from control.faults import THRUSTER_KINDS, Fault
from control.jobs import ClosedChunk, run_closed_chunk
from control.startup import StartupReport, check_mount_vector
from sim import dynamic_wire as dwire
from sim import environment as envmod
from sim import plant, sensors, site
from sim import vessel as vesselmod
from sim import wire as wm
from sim.docking import DockingFrame
from sim.gnc import Rzyx, ssa
from sim.params import ParameterSet
from sim.sensors import SENSOR_NAMES

FloatArray = NDArray[np.float64]
DT_RANGE_S = (1e-4, 0.05)
"""Plant step sizes accepted [s] (RK4 on the 2.5 Hz gripper mode is stable below 0.18 s)."""
WIRE_LENGTH_RANGE_M = (1.0, 5000.0)
WINCH_RATE_MAX_MPS = 2.0
VESSEL_SPEED_MAX_MPS = 5.0
HEAVE_FORCE_MAX_NEWTON = 1.0e5
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
GRIP_REACH_M = 0.3
"""Farthest the ROV's origin may be from its mount on the tree for the gripper to close [m]:
the reach of a work-class manipulator's jaw around the tree's grab bar is a few decimetres, and
the hook-up leg's tolerance (at most 1 m in the schema) is tighter in every library mission."""
GRIP_REACH_DEG = 10.0
"""Largest heading difference from the mount at which the gripper closes [deg]: beyond it the
spring would yank the tree round (12 deg from 100 deg off, in the console defect report)."""


REFRESH_S = 1.0
"""How often the slow parts of the environment are brought up to date [s]: the quasi-static
wire's stiffnesses and drag offset (from the current at that step, the payout and the crane
tip), the control model's wire spring (its stiffness for the payout, its equilibrium under
the crane tip), the point where the waves and the vessel's motion are evaluated, and the
elastic wire's lumped mass. On the whole seconds of the step grid (steps 0, 1/dt, 2/dt...),
and chunks end there (or, with only the wire's entries and the control model's spring to
refresh, run past them and refresh those at the rows of whole seconds: ``LONG_CHUNK_S``,
``control.jobs.ClosedChunk.spring``), so a run gives the same numbers however
it is cut into requests (the console's ticks, the command line's requests). A second
is short beside how fast any of them changes: the current walks by millimetres a second, the
winch pays out at most 2 m/s on a wire hundreds of metres long (its horizontal stiffness moves
by 1 % at most), and the tree moves centimetres against waves hundreds of metres long."""


LONG_CHUNK_S = 5.0
"""The longest chunk while nothing but the quasi-static wire's entries needs a refresh
(``Simulation._still``: winch and crane at rest, no sea, no faults) [s]. Each chunk costs some
Python besides its steps; longer chunks share it over more steps, and much longer ones gain
little while their rows outgrow the processor's cache (docs/performance.md)."""


class SimulationDiverged(RuntimeError):
    """The plant state stopped being finite."""


def initial_state(
    ps: ParameterSet,
    tree_position_n: FloatArray,
    tree_heading_rad: float = 0.0,
    has_rov: bool = True,
) -> FloatArray:
    """Tree at rest at the given position and heading, ROV (if any) exactly on its mount."""
    x = np.zeros(plant.N_STATE)
    x[0:3] = tree_position_n
    x[5] = tree_heading_rad
    R_t = Rzyx(0.0, 0.0, tree_heading_rad)
    x[12:15] = tree_position_n + R_t @ ps.mount.r_rov_from_tree_tree_m
    x[17] = tree_heading_rad + ps.mount.psi_rov_from_tree_rad if has_rov else 0.0
    return x


def finite_vector(name: str, value: object, length: int) -> FloatArray:
    """A command vector of the right length with finite entries, else ValueError naming it."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != (length,):
        raise ValueError(f"{name} must have {length} entries, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def _in_range(
    name: str, value: float, lo: float, hi: float, unit: str, lo_open: bool = False
) -> float:
    ok = math.isfinite(value) and (lo < value if lo_open else lo <= value) and value <= hi
    if not ok:
        bracket = "(" if lo_open else "["
        raise ValueError(f"{name} must be in {bracket}{lo:g}, {hi:g}] {unit}, got {value}")
    return float(value)


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


class Simulation:
    """Plant, environment, sensors and (with ``control``) the control system, stepped together.

    ``ps`` is what the control system is configured with; ``plant_ps`` (default: the same) is
    the physical truth the plant simulates, for robustness studies."""

    def __init__(
        self,
        ps: ParameterSet,
        *,
        tree_depth_m: float,
        settings: ControlSettings | None = None,
        control: bool = True,
        has_rov: bool = True,
        crane_tip_n: FloatArray | tuple[float, ...] = (1.0, 1.0, 0.0),
        current: envmod.CurrentParams | None = None,
        waves: envmod.WaveParams | None = None,
        seed: int = 0,
        dt_s: float = 0.01,
        tree_heading_rad: float = 0.0,
        chunk_steps: int = 100,
        plant_ps: ParameterSet | None = None,
        start_gripping: bool = True,
        vessel: vesselmod.VesselMotion | None = None,
        wire: str = "quasi-static",
        wire_damping_ratio: float = WIRE_DAMPING_RATIO,
    ) -> None:
        if wire not in WIRE_MODELS:
            raise ValueError(f"wire must be one of {', '.join(WIRE_MODELS)}, got {wire!r}")
        if not (math.isfinite(wire_damping_ratio) and 0.0 <= wire_damping_ratio <= 1.0):
            raise ValueError(f"wire_damping_ratio must lie in [0, 1], got {wire_damping_ratio!r}")
        self.wire_model = wire
        """``quasi-static`` or ``elastic`` (see ``WIRE_MODELS``)."""
        self.wire_damping_ratio = float(wire_damping_ratio)
        if not (DT_RANGE_S[0] <= dt_s <= DT_RANGE_S[1]):
            raise ValueError(
                f"dt_s must be in [{DT_RANGE_S[0]:g}, {DT_RANGE_S[1]:g}] s, got {dt_s}"
            )
        if control and not has_rov:
            raise ValueError("control needs the ROV (has_rov=True)")
        if not (isinstance(chunk_steps, int) and chunk_steps >= 1):
            raise ValueError(f"chunk_steps must be a whole number >= 1, got {chunk_steps}")
        self.ps = ps
        self.plant_ps = plant_ps or ps
        self.dt_s = dt_s
        self.chunk_steps = chunk_steps
        self.refresh_steps = max(1, round(REFRESH_S / dt_s))
        """Steps between refreshes of the slow parts of the environment (``REFRESH_S``)."""
        self.long_chunk_steps = (
            self.refresh_steps * round(LONG_CHUNK_S / REFRESH_S)
            if chunk_steps >= self.refresh_steps
            else chunk_steps
        )
        """The longest chunk while the slow parts stand still (``LONG_CHUNK_S``; a
        ``chunk_steps`` under a second keeps every chunk that short)."""
        self.has_rov = has_rov
        self.control_on = control
        self.vessel_motion = vessel
        """The vessel's wave-frequency motion at the crane tip (None: the tip stands still)."""
        self._init_plant(
            tree_depth_m,
            crane_tip_n,
            current,
            waves,
            seed,
            tree_heading_rad,
            has_rov and start_gripping,
        )
        self.vessel_ramp_s = (
            vesselmod.ramp_time_s(waves.peak_period_s)
            if vessel is not None and waves is not None
            else 0.0
        )
        """The vessel's motion grows in over this long from t = 0 [s] (``sim.vessel.ramp_in``,
        two peak periods of the sea; 0: no vessel motion or no ramp)."""
        self.mdwire: dwire.CoupledWire | None = None
        """The MoorDyn wire (``wire = "moordyn"``), else None."""
        self._wire_current_n = np.zeros(3)
        """The current the MoorDyn wire feels over the present chunk, NED [m/s] (set with the
        chunk's environment rows)."""
        if wire == "moordyn":
            self._init_moordyn_wire()
        self.settings = settings or ControlSettings()
        r_cfg = self.settings.r_mount_config_m
        self.sysm = model.system_model(
            ps, self.wire_length_m, None if r_cfg is None else np.asarray(r_cfg, float)
        )
        self.gains = self.settings.gains or Gains.of(ps.gains.kp, ps.gains.ki, ps.gains.kd)
        self.thruster_config = system_thruster_config(ps, self.sysm)
        self.C = control_arrays(
            ps, self.sysm, self.settings, self.gains, self.crane_tip_n[0:2], dt_s
        )
        if has_rov and not start_gripping:
            # the ROV waits free, 3 m further back and 1 m above its mount (a hook-up to come)
            c, s = math.cos(self.x[5]), math.sin(self.x[5])
            self.x[12:15] += np.array([-3.0 * c, -3.0 * s, -1.0])
            self.held_y = sensors.true_outputs(self.x)
        self.controller_state = ControllerState.start(
            loop.MODE_TREE if start_gripping else loop.MODE_FREE
        )
        self.pilot_capacity = pilot_capacity(ps)
        """Full stick on [surge, sway, heave, yaw], (2, 4): backwards, forwards [N, N m]."""
        self.xhat, self.P_cov = self._initial_estimate()
        w = quality.WINDOW
        self.Q = loop.QualityState(
            np.zeros(sensors.N_Y),
            -np.ones(5),
            np.zeros(5, np.int64),
            np.zeros((sensors.N_Y, w)),
            np.zeros((5, 4), np.int64),
        )
        eta0 = self.xhat[0:3] if self.settings.feedback == "ekf" else self.x[[0, 1, 5]]
        self.target = np.array(eta0, float)
        self.startup = (
            self.check_mount() if control and start_gripping else StartupReport(False, 0.0, 0.0)
        )

    def _init_plant(
        self,
        tree_depth_m: float,
        crane_tip_n: FloatArray | tuple[float, ...],
        current: envmod.CurrentParams | None,
        waves: envmod.WaveParams | None,
        seed: int,
        tree_heading_rad: float,
        gripping: bool,
    ) -> None:
        ps = self.plant_ps
        self.arrays = plant.plant_arrays(ps, has_rov=self.has_rov)
        self._wire_site = site.wire_site(ps)
        """The wire's and the tree's numbers behind every chunk's wire entries."""
        self._frame_entries = np.zeros(5)  # site.chunk_rows_into's ``frame``
        self._chunk_out = np.zeros(6)  # and its ``out``
        self._wire_held = np.zeros(plant.N_ENV)  # the wire's slow entries (REFRESH_S)
        self._site_k_h = 0.0  # the control model's wire spring at the last refresh
        self._refresh_wire_k_h_m = math.nan  # the payout _site_k_h is for
        self._site_p_eq = np.zeros(2)
        # the control model's spring as ``site.chunk_rows_into`` carries it through a chunk:
        # [k_h, p_eq north, east, the payout k_h is for], from the three above before each
        # chunk and back into them after it (the last whole second's, as a chunk ending there)
        self._spring_held = np.zeros(4)
        self._spring_rows = np.zeros((0, 3))  # the rows of the chunk whose inputs were made last
        self._refresh_point = np.zeros(5)  # tree north, east, depth; crane tip north, east
        self._pivot_tops = np.zeros((0, 3))  # the elastic wire's top, the last two steps
        self._last_env: FloatArray | None = None  # the last step's environment row
        self._refresh_wire_m = 0.0  # the payout at the last refresh [m]
        # One stream per purpose, each spawned from the seed and read in step order, so the
        # numbers a step gets do not depend on how the run is cut into chunks, nor on what
        # else draws (a current that walks leaves the sensors' noise as it is).
        streams = np.random.SeedSequence(seed).spawn(4)
        self.rng_current, self.rng_dropouts, self.rng_noise, rng_waves = (
            np.random.default_rng(s) for s in streams
        )
        self._noise_stream = sensors.NoiseStream(self.rng_dropouts, self.rng_noise)
        self.current_params = current or steady_current(0.0, 0.0)
        self.current_state = envmod.initial_current(self.current_params)
        self.wave_field = envmod.make_wave_field(waves, rng_waves) if waves is not None else None
        self.wave_load = waves.load if waves is not None else envmod.DEFAULT_WAVE_LOAD
        """How the waves load the bodies (sim.environment.WAVE_LOADS)."""
        self.crane_tip_n = finite_vector("crane_tip_n", crane_tip_n, 3)
        self.wire_length_m = site.wire_length_for_depth(
            ps, tree_depth_m, self.crane_tip_n[2], self.current_state.speed_mps
        )
        self.sensor_cfg = sensors.sensor_config(ps.sensors, self.dt_s)
        self.thruster_speeds_rps = np.zeros(ps.rov.thrusters.T.shape[1])
        self.push_newton = np.zeros(3)
        self.gripping = gripping
        self.crane_target_n = self.crane_tip_n.copy()
        self.crane_speed_mps = 0.0
        self.wire_target_m = self.wire_length_m
        self.wire_rate_mps = 0.0
        self.docking_frame: DockingFrame | None = None
        self.faults: list[Fault] = []
        """Injected faults, past, present and scheduled (control.faults)."""
        self.log_layout: Layout = LAYOUT
        """The columns of the rows ``step`` returns (``keep_log_columns``)."""
        self.log_keep: NDArray[np.intp] = np.arange(N_LOG, dtype=np.intp)
        """Their indices in the whole row (``LAYOUT``), in order."""
        self._slipped: set[int] = set()
        self._faults_on: set[int] = set()
        self._fault_log: list[tuple[float, str]] = []
        self.fault_events: list[tuple[float, str]] = []
        """Every fault start and end so far, (time [s], what), oldest first (unlike
        ``take_fault_log``, never emptied: the console reads it from where it got to)."""
        self._mount_flipped = False
        self._healthy_arrays = self.arrays
        self._thrust_factors = np.ones(ps.rov.thrusters.T.shape[1])
        tree_pos = np.array([self.crane_tip_n[0], self.crane_tip_n[1], tree_depth_m])
        self.x = initial_state(ps, tree_pos, tree_heading_rad, self.has_rov)
        self.held_y = sensors.true_outputs(self.x)
        self.step_index = 0

    def _init_moordyn_wire(self) -> None:
        """The MoorDyn line between the crane tip and the tree's attachment point as the
        plant starts (its initial-condition solver settles the wire's own weight)."""
        R_t = Rzyx(*self.x[3:6])
        p_att = self.x[0:3] + R_t @ self.arrays.tree_r_att
        self.mdwire = dwire.CoupledWire(
            self.plant_ps,
            self.wire_length_m,
            self.crane_tip_n,
            p_att,
            float(p_att[2] - self.crane_tip_n[2]) + MOORDYN_WATER_BELOW_M,
            self.wire_damping_ratio,
        )
        self._md_tip_n = self.crane_tip_n.copy()

    def _initial_estimate(self) -> tuple[FloatArray, FloatArray]:
        """EKF start: the first measurements moved to the tree origin, at rest, no bias."""
        y = self.held_y
        ne, psi, _, _ = loop.tree_measurements(y, y[4] - self.C.psi_rel, self.C)
        x0 = np.zeros(9)
        x0[0:2] = ne
        x0[2] = psi
        p0 = np.diag(
            [
                1.0,
                1.0,
                0.01,
                0.01,
                0.01,
                1e-4,
                *(np.asarray(self.ps.spec.observer.process_force_std) ** 2),
            ]
        )
        return x0, p0

    # ------------------------------------------------------------------ what it is now
    @property
    def t_s(self) -> float:
        return self.step_index * self.dt_s

    def _times(self, n: int) -> FloatArray:
        """The times of the next n steps [s], each (step index) x dt: the same numbers
        whatever chunk they fall in (t_s + j dt rounds with where the chunk starts)."""
        return (self.step_index + np.arange(n, dtype=np.float64)) * self.dt_s

    @property
    def n_thrusters(self) -> int:
        return int(self.ps.rov.thrusters.T.shape[1])

    @property
    def tree_eta_n(self) -> FloatArray:
        """True tree pose [north, east, down, roll, pitch, yaw] (a copy)."""
        return self.x[0:6].copy()

    @property
    def rov_eta_n(self) -> FloatArray:
        """True ROV pose (a copy)."""
        return self.x[12:18].copy()

    @property
    def plant_state(self) -> FloatArray:
        """The 24-number plant state (a copy; see sim.plant)."""
        return self.x.copy()

    @property
    def eta_estimate(self) -> FloatArray:
        """What the controller believes: tree [north, east, psi]."""
        if self.settings.feedback == "ekf":
            return self.xhat[0:3].copy()
        return self.x[[0, 1, 5]].copy()

    @property
    def reference(self) -> FloatArray:
        """The reference model's state: pose (3), rate (3), acceleration (3) [NED, m, rad]."""
        return self.controller_state.reference.copy()

    @property
    def cs(self) -> FloatArray:
        """The controller's state vector as the kernels take it (named: ``controller_state``)."""
        return self.controller_state.vector

    @property
    def mode(self) -> Mode:
        return MODES[self.controller_state.mode]

    @property
    def quality_counters(self) -> NDArray[np.int64]:
        """Signal-check counters: 5 sensors x (range, wild point, frozen, variance)."""
        return self.Q.counters.copy()

    @property
    def winch_idle(self) -> bool:
        """The winch has reached its commanded payout."""
        return abs(self.wire_length_m - self.wire_target_m) < 1e-6

    def keep_log_columns(self, layout: Layout) -> None:
        """From now on, log only ``layout``'s columns (blocks of ``LAYOUT``, in its order): the
        rows ``step`` returns have that layout. A campaign's runs keep the few columns their
        scores and legs read (``missions.driver.LEAN_LAYOUT``); the kernels still make the
        whole row, and only the kept columns are written out (a sixth of the bytes a step
        to memory)."""
        keep = layout.columns_in(LAYOUT)
        if np.any(np.diff(keep) <= 0) or len(keep) != layout.width:
            raise ValueError("keep_log_columns: the layout's blocks must be LAYOUT's, in its order")
        self.log_layout = layout
        self.log_keep = keep

    def winch_steps_busy(self) -> int:
        """Steps from now after each of which the winch is certainly still moving
        (``winch_idle`` false): its gap to the target over a step's travel, less two steps of
        margin for the rounding of the payout's sum (some 1e-13 m a step against a travel of
        1e-4 m or more). 0 when the winch is idle or stopped, and with any fault scheduled (a
        winch slip moves the payout)."""
        travel_m = self.wire_rate_mps * self.dt_s
        gap_m = abs(self.wire_target_m - self.wire_length_m)
        if self.faults or travel_m <= 0.0 or gap_m < 1e-6:
            return 0
        return max(0, int(gap_m / travel_m) - 2)

    def reference_polls_away(
        self, goal: FloatArray, tol: FloatArray, poll_steps: int, max_polls: int
    ) -> int:
        """How many polls of ``poll_steps`` steps from now certainly end with the reference
        model's pose and rate away from ``goal`` (6,) by more than ``tol`` (6,) in some entry
        (``control.refkernel.polls_still_away``: the reference steps towards the target as
        the closed-loop kernel steps it, and nothing but the target and the mode moves it).
        0 when nothing can be said: open loop (no reference is stepped), or a switch into
        tree mode not yet taken (its first step resets the reference to the estimate)."""
        cs = self.controller_state
        if not self.control_on or max_polls <= 0 or poll_steps <= 0 or cs.tree_mode_pending:
            return 0
        return int(
            refkernel.polls_still_away(
                int(self.C.ref_kind),
                cs.reference,
                np.ascontiguousarray(self.target, dtype=float),
                float(self.dt_s),
                self.C.ref_params,
                np.ascontiguousarray(goal, dtype=float),
                np.ascontiguousarray(tol, dtype=float),
                int(poll_steps),
                int(max_polls),
                np.empty(9),
            )
        )

    def vessel_at(self, target_n: FloatArray, tol_m: float = 1e-6) -> bool:
        return bool(np.linalg.norm(self.crane_tip_n - np.asarray(target_n, float)) <= tol_m)

    @property
    def current_speed_mps(self) -> float:
        return float(self.current_state.speed_mps)

    @property
    def current_direction_rad(self) -> float:
        return float(self.current_state.direction_rad)

    def wire_length_for_depth(self, tree_depth_m: float) -> float:
        """Unstretched payout that hangs the tree's centre at ``tree_depth_m`` in the present
        current (the plant's wire and tree)."""
        return site.wire_length_for_depth(
            self.plant_ps, tree_depth_m, self.crane_tip_n[2], self.current_state.speed_mps
        )

    def wire_tension_newton(self) -> float:
        """Present wire tension at the tree [N]: the logged tension of the last step (the
        same function on the same numbers, whatever the wire model), before any step the
        site's at rest."""
        return float(LAYOUT.take(self.present_row(), "wire_tension"))

    def mount_pose_n(self) -> FloatArray:
        """Where the ROV's origin belongs on the tree now: [north, east, down, psi] (truth of
        the tree's pose, as the pilot sees it on the camera, and the configured r)."""
        x = self.x
        c, s = math.cos(x[5]), math.sin(x[5])
        r = self.sysm.r_rov_from_tree_tree_m
        return np.array(
            [
                x[0] + c * r[0] - s * r[1],
                x[1] + s * r[0] + c * r[1],
                x[2] + r[2],
                x[5] + self.sysm.psi_rov_from_tree_rad,
            ]
        )

    @property
    def free_setpoint_n(self) -> FloatArray:
        """The free-flying ROV's set point [north, east, down, psi] (a copy)."""
        return self.controller_state.free_setpoint_n.copy()

    def check_mount(self) -> StartupReport:
        """The start-up check of the mount vector against the measured geometry."""
        return check_mount_vector(
            self.held_y,
            self.sysm.r_rov_from_tree_tree_m,
            self.crane_tip_n,
            self.wire_length_m,
            self.ps,
            self.current_state.speed_mps,
        )

    def present_row(self) -> FloatArray:
        """A log row for the present state (before the next step): time, plant, reference,
        estimate, mode and site (the site of the last step's environment row, as logged)."""
        row = np.zeros(N_LOG)
        env = self._last_env
        if env is None:  # no step yet: the site at rest
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
        loop.write_plant_row(
            row,
            self.t_s,
            self.x,
            self.held_y,
            env,
            self.arrays,
            plant.make_work(self.arrays.thr_T.shape[1]),
        )
        rows = LogRows(row[None, :])
        rows["eta_ref_n"][0] = self.target
        rows["eta_hat_n"][0] = self.eta_estimate
        rows["mode"][0] = self.controller_state.mode
        return row

    # ------------------------------------------------------------------ control commands
    def set_target(
        self, north_m: float, east_m: float, psi_rad: float, heading_mode: HeadingMode = "shortest"
    ) -> None:
        """Where the tree should go. ``shortest``: the heading target is reached the short way
        round from the present reference; ``absolute``: ``psi_rad`` is taken as it stands,
        unwrapped, so +2 pi from 0 is a full turn."""
        for name, v in (("north_m", north_m), ("east_m", east_m), ("psi_rad", psi_rad)):
            if not math.isfinite(v):
                raise ValueError(f"target {name} must be finite, got {v}")
        if heading_mode not in HEADING_MODES:
            raise ValueError(
                f"heading_mode must be one of {', '.join(HEADING_MODES)}, got {heading_mode!r}"
            )
        cs = self.controller_state
        psi_ref = cs.reference[2] if cs.stepped else self.eta_estimate[2]
        psi = psi_ref + ssa(psi_rad - psi_ref) if heading_mode == "shortest" else psi_rad
        self.target = np.array([north_m, east_m, psi])

    def set_gains(self, gains: Gains) -> None:
        """New tree-controller gains, bumpless: the jump of the P and D terms at this instant
        is moved into the integral, so the commanded force does not change."""
        new_kp, new_kd = np.array(gains.kp), np.array(gains.kd)
        self.controller_state.retune_tree(self.C.Kp, self.C.Kd, new_kp, new_kd)
        self.gains = gains
        self.C = self.C._replace(Kp=new_kp, Ki=np.array(gains.ki), Kd=new_kd)

    def set_mode(self, mode: Mode) -> None:
        """Supervisor switch (section 3.4): tree controller, free-ROV station keeping or flown
        by hand ("manual", log code 2). The new controller starts from the last commanded
        thrust (no jump)."""
        if mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
        self.controller_state.mode = MODES.index(mode)

    def set_pilot_demand(self, surge: float, sway: float, heave: float, yaw: float) -> None:
        """The pilot's stick in the ROV's own axes, each a fraction in [-1, 1] of that axis's
        full thrust alone (``pilot_capacity``: surge forward, sway to starboard, heave down,
        yaw clockwise seen from above, all positive; full is that direction's own capacity,
        ``pilot_capacity``). It acts in the "manual" mode; zero on an axis hands it to the
        holds (see ``control.loop.manual_step``). Held until changed."""
        values = []
        for name, v in (("surge", surge), ("sway", sway), ("heave", heave), ("yaw", yaw)):
            values.append(_in_range(f"pilot {name}", float(v), -1.0, 1.0, "(fraction of full)"))
        frac = np.array(values)
        full = np.where(frac >= 0.0, self.pilot_capacity[1], self.pilot_capacity[0])
        self.controller_state.pilot_demand[:] = frac * full

    @property
    def pilot_demand(self) -> FloatArray:
        """The pilot's demand as fractions [surge, sway, heave, yaw] (a copy)."""
        d = self.controller_state.pilot_demand
        return d / np.where(d >= 0.0, self.pilot_capacity[1], self.pilot_capacity[0])

    def set_pilot_holds(self, heading: bool, depth: bool) -> None:
        """Auto-heading and auto-depth in the manual mode: on, a released yaw (heave) stick
        holds the heading (depth) where it was let go; off, it is zero moment (force)."""
        for name, v in (("heading hold", heading), ("depth hold", depth)):
            if not isinstance(v, bool | np.bool_):
                raise ValueError(f"{name} must be true or false, got {v!r}")
        self.controller_state.heading_hold = bool(heading)
        self.controller_state.depth_hold = bool(depth)

    @property
    def pilot_holds(self) -> tuple[bool, bool]:
        """(auto-heading, auto-depth)."""
        return self.controller_state.heading_hold, self.controller_state.depth_hold

    def set_grip(self, gripping: bool) -> None:
        """Physically grip (True) or release (False) the tree."""
        if not isinstance(gripping, bool | np.bool_):
            raise ValueError(f"grip must be true or false, got {gripping!r}")
        if gripping and not self.gripping:
            miss_m, miss_deg = self.grip_miss()
            if miss_m > GRIP_REACH_M or miss_deg > GRIP_REACH_DEG:
                raise ValueError(
                    f"grip: the ROV is {miss_m:.2f} m and {miss_deg:.0f} deg from its mount on "
                    f"the tree; the gripper closes within {GRIP_REACH_M:g} m and "
                    f"{GRIP_REACH_DEG:g} deg (fly it there first: a hook-up leg does)"
                )
        self.gripping = bool(gripping)

    def grip_miss(self) -> tuple[float, float]:
        """How far the ROV is from its mount on the tree: (distance [m], heading [deg])."""
        mount = self.mount_pose_n()
        rov = self.x[12:18]
        miss_m = float(np.linalg.norm(rov[0:3] - mount[0:3]))
        return miss_m, abs(math.degrees(ssa(float(rov[5] - mount[3]))))

    def set_allocation(self, kind: Allocation) -> None:
        kinds = {
            "pinv": loop.ALLOC_PINV,
            "priority": loop.ALLOC_PRIORITY,
            "qp": loop.ALLOC_EXTERNAL,
        }
        if kind not in kinds:
            raise ValueError(f"allocation must be one of {', '.join(ALLOCATIONS)}, got {kind!r}")
        self.settings = replace(self.settings, allocation=kind)
        self.C = self.C._replace(alloc_kind=kinds[kind])

    def set_heave_force(self, force_newton: float) -> None:
        """Constant heave force of the ROV while on the tree (positive = down) [N]."""
        f = _in_range(
            "heave force", force_newton, -HEAVE_FORCE_MAX_NEWTON, HEAVE_FORCE_MAX_NEWTON, "N"
        )
        self.C = self.C._replace(heave_newton=f)
        self.settings = replace(self.settings, heave_force_newton=f)

    def set_free_setpoint(
        self, north_m: float, east_m: float, down_m: float, psi_rad: float
    ) -> None:
        """Where the free-flying ROV should hold station (supervisor's free mode). The step
        that switches to free mode holds the ROV where it is (bumpless), so a set point for
        the free ROV is given after that step."""
        values = finite_vector("free-ROV set point", [north_m, east_m, down_m, psi_rad], 4)
        self.controller_state.free_setpoint_n[:] = values

    def reset_observer(self) -> None:
        """Restart the EKF at hook-up from the ROV's own measurements moved to the tree with
        the mounting vector r (see ``_hookup_estimate``)."""
        self.xhat, self.P_cov = self._hookup_estimate()

    def _hookup_estimate(self) -> tuple[FloatArray, FloatArray]:
        """EKF start at the grip: the tree's pose and velocity are the ROV's, moved to the
        tree's origin through r (eq. 3.4-3.6), each with the variance of the sensor it comes
        from; the bias starts at zero with its configured spread.

        The held position fix can be up to one fix interval old: it is carried forward over
        its age with the DVL's velocity, and its variance grows by the DVL's over that age.
        A start with loose pose variances but the gyro's tight rate variance is what made the
        filter run away at the grip: the wire spring couples the position to the yaw
        acceleration (the tree and ROV's mass matrix has sway-yaw terms), so after a few steps
        the gyro's corrections moved the east estimate by metres."""
        C, y = self.C, self.held_y
        psi_hat = y[4] - C.psi_rel
        ne, psi, uv, rate = loop.tree_measurements(y, psi_hat, C)
        c, s = math.cos(psi), math.sin(psi)
        vel_n = np.array([c * uv[0] - s * uv[1], s * uv[0] + c * uv[1]])
        last_fix_s = float(self.Q.last_t[sensors.POSITION])
        age_s = max(self.t_s - last_fix_s, 0.0) if last_fix_s >= 0.0 else 0.0
        x0 = np.zeros(9)
        x0[0:2] = ne + age_s * vel_n
        x0[2] = psi
        x0[3:5] = uv
        x0[5] = rate
        pos_var = C.r_pos + age_s**2 * C.r_dvl
        p0 = np.diag(
            [
                pos_var,
                pos_var,
                C.r_psi,
                C.r_dvl,
                C.r_dvl,
                C.r_gyro,
                *(np.asarray(self.ps.spec.observer.process_force_std) ** 2),
            ]
        )
        return x0, p0

    # ------------------------------------------------------------------ plant commands
    def set_thruster_speeds(self, n_rps: FloatArray) -> None:
        """Propeller speeds while control is off [rev/s]."""
        self.thruster_speeds_rps = finite_vector(
            "thruster speed command [rev/s]", n_rps, self.thruster_speeds_rps.shape[0]
        )

    def set_push(self, force_newton: FloatArray) -> None:
        """A steady external force on the tree's centre, NED [N]."""
        self.push_newton = finite_vector("push force [N]", force_newton, 3)

    def winch_to(self, length_m: float, rate_mps: float) -> None:
        """Pay out (or haul in) the wire smoothly to ``length_m`` at ``rate_mps``."""
        length = _in_range("wire length", length_m, *WIRE_LENGTH_RANGE_M, "m")
        rate = _in_range("winch rate", rate_mps, 0.0, WINCH_RATE_MAX_MPS, "m/s", lo_open=True)
        if self.mdwire is not None:
            lo, hi = dwire.COUPLED_LENGTH_RANGE_M
            if not lo <= length <= hi:
                raise ValueError(
                    f"wire length must be in [{lo:g}, {hi:g}] m with the moordyn wire, "
                    f"got {length:g}"
                )
        self.wire_target_m = length
        self.wire_rate_mps = rate

    def move_vessel(self, target_n: FloatArray, speed_mps: float) -> None:
        """Move the vessel (the crane tip) smoothly to ``target_n`` at ``speed_mps``."""
        target = finite_vector("crane tip target", target_n, 3)
        speed = _in_range("vessel speed", speed_mps, 0.0, VESSEL_SPEED_MAX_MPS, "m/s", lo_open=True)
        self.crane_target_n = target
        self.crane_speed_mps = speed

    def set_current(self, params: envmod.CurrentParams) -> None:
        """A new current (and its random walk), starting from its nominal speed and
        direction."""
        self.current_params = params
        self.current_state = envmod.initial_current(params)

    def set_docking_frame(self, frame: DockingFrame | None) -> None:
        """Put a docking frame (and the seabed) under the tree, or take it away."""
        self.docking_frame = frame

    # ------------------------------------------------------------------ stepping
    def steps_in(self, duration_s: float) -> int:
        """The number of plant steps in ``duration_s``; ValueError unless it is a finite,
        non-negative, whole number of steps (to 1e-9 of a step)."""
        if not (math.isfinite(duration_s) and duration_s >= 0.0):
            raise ValueError(f"duration must be a finite number of seconds >= 0, got {duration_s}")
        steps = duration_s / self.dt_s
        n = round(steps)
        if abs(steps - n) > 1e-9 * max(1.0, steps):
            raise ValueError(
                f"duration {duration_s:g} s is not a whole number of "
                f"{self.dt_s:g} s steps ({steps:.6g} steps)"
            )
        return int(n)

    def run_for(self, duration_s: float) -> LogRows:
        """Advance by ``duration_s`` (a whole number of steps) and return its rows."""
        return self.step(self.steps_in(duration_s))

    def step(self, n: int) -> LogRows:
        """Advance ``n`` plant steps (commands held) and return their log rows."""
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 0:
            raise ValueError(f"steps must be a whole number >= 0, got {n!r}")
        out: FloatArray | None = None
        done = 0
        while done < n:
            k = min(
                self.chunk_steps,
                int(n) - done,
                self._steps_to_fault_edge(),
                self.refresh_steps - self.step_index % self.refresh_steps,
            )
            if self.mdwire is not None:
                k = 1  # MoorDyn and the plant take turns, one step each
            elif k == self.refresh_steps and self._still():
                # whole seconds with nothing to refresh but the wire's entries (which the
                # rows refresh themselves): one chunk over several, ending on a whole second
                whole = min(int(n) - done, self.long_chunk_steps) // self.refresh_steps
                k = self.refresh_steps * max(1, whole)
            if done == 0 and k == n:
                # most requests: one chunk, whose own fresh rows are the answer
                out = self._chunk(k)
            else:
                # several chunks: each writes its rows straight into the request's (the
                # kernels' ``*_into`` forms; no join of the parts)
                if out is None:
                    out = np.empty((n, self.log_layout.width))
                self._chunk(k, out[done : done + k])
            done += k
        if out is None:
            out = np.empty((0, self.log_layout.width))
        out.flags.writeable = False  # shared by the joins of whoever reads them (LogRows.join)
        return LogRows(out, self.n_thrusters, self.Q.counters.copy(), self.log_layout)

    def _still(self) -> bool:
        """Nothing refreshed on a whole second needs Python for seconds to come: the
        quasi-static wire's entries and the control model's wire spring, which
        ``site.chunk_rows_into`` refreshes at the rows of whole seconds itself (the spring's
        rows go with the chunk: ``ClosedChunk.spring``), no sea (the waves and the vessel's
        motion are evaluated where the tree was at the refresh), no elastic or MoorDyn wire,
        no faults. Then a chunk may run past whole seconds (``LONG_CHUNK_S``) and give the
        same numbers as chunks of a second. With the QP allocation (its steps in Python, on
        ``C`` as it is) or a wire paid out to nothing (the refresh refuses it) that holds
        only while the winch and the crane rest."""
        if self.faults or self.wave_field is not None or self.wire_model != "quasi-static":
            return False
        winch_rests = self.wire_length_m == self.wire_target_m
        crane_rests = self.crane_speed_mps <= 0.0 or bool(
            np.array_equal(self.crane_tip_n, self.crane_target_n)
        )
        if winch_rests and crane_rests:
            return True
        qp = self.control_on and self.C.alloc_kind == loop.ALLOC_EXTERNAL
        return not qp and self.wire_length_m > 0.0 and self.wire_target_m > 0.0

    def _refreshing(self) -> bool:
        """This chunk starts on a whole second of the step grid (``REFRESH_S``)."""
        return self.step_index % self.refresh_steps == 0

    def _refresh(self) -> None:
        """Take the slow parts' inputs at this step (``REFRESH_S``): the payout, the tree's
        position for the waves, the crane tip's for the vessel's motion, and, with control,
        the control model's wire spring."""
        x, tip = self.x, self.crane_tip_n
        self._refresh_wire_m = self.wire_length_m
        self._refresh_point[:] = (x[0], x[1], x[2], tip[0], tip[1])
        if self.control_on:
            if self.wire_length_m != self._refresh_wire_k_h_m:
                self._site_k_h = float(
                    wm.horizontal_stiffness(
                        self.plant_ps.wire.submerged_weight_per_length(),
                        self.ps.tree.submerged_weight_newton,
                        self.wire_length_m,
                    )
                )
                self._refresh_wire_k_h_m = self.wire_length_m
            self._site_p_eq = tip[0:2].copy()

    def _sync_site(self) -> None:
        """The vessel's position and the wire length are known on board: the control plant
        model's wire spring (equilibrium point and stiffness) as at the last refresh, put
        into its configuration again if anything (new gains, a new mode) replaced it."""
        k_h, p_eq, now = self._site_k_h, self._site_p_eq, self.C.p_eq
        if k_h != self.C.k_h or now[0] != p_eq[0] or now[1] != p_eq[1]:
            self.C = self.C._replace(k_h=k_h, p_eq=p_eq.copy())

    def _chunk_inputs(self, n: int) -> tuple[FloatArray, sensors.NoiseChunk]:
        """Environment rows and sensor noise for the next n steps. Injected faults (sensor
        dropouts, biases, winch slip, current surges) change these before the kernel runs."""
        if self.faults:
            self._faults_before_chunk()
        env = self._environment_chunk(n)
        noise = self._noise_stream.take(self.sensor_cfg, self.step_index, n)
        if self.faults:
            self._faults_in_chunk(env, noise)
        self._vessel_in_chunk(env, n)
        if self.wire_model == "elastic":
            self._elastic_wire_in_chunk(env)
        if self.mdwire is not None:
            self._moordyn_wire_in_step(env)
        return env, noise

    def _moordyn_wire_in_step(self, env: FloatArray) -> None:
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
        R_t = Rzyx(*self.x[3:6])
        r_att = self.arrays.tree_r_att
        p_att = self.x[0:3] + R_t @ r_att
        v_att = plant.attachment_velocity_n(self.x, R_t, r_att)
        f_start = wire.wire_force_n.copy()
        try:
            wire.set_length(self.wire_length_m)
            wire.set_current(self._wire_current_n)
            f_end = wire.step(self._md_tip_n, tip_v, p_att, v_att, self.dt_s)
        except (FloatingPointError, RuntimeError) as e:
            raise SimulationDiverged(f"MoorDyn wire failed at t = {self.t_s:.2f} s: {e}") from e
        self._md_tip_n = tip_n
        env[:, plant.E_FWIRE : plant.E_FWIRE + 3] = 0.5 * (f_start + f_end)
        env[:, plant.E_WEXT] = 1.0

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

    def _vessel_in_chunk(self, env: FloatArray, n: int) -> None:
        """Add the vessel's wave-frequency motion to the crane tip (sim.vessel), grown in over
        ``vessel_ramp_s``; the crane tip's mean position (``crane_tip_n``, where the vessel
        keeps station) is unchanged."""
        if self.vessel_motion is None or self.wave_field is None:
            return
        t = self._times(n)
        env[:, plant.E_CT : plant.E_CT + 3] += vesselmod.crane_tip_motion_n(
            self.wave_field,
            t,
            self.vessel_motion,
            float(self._refresh_point[3]),
            float(self._refresh_point[4]),
            self.vessel_ramp_s,
        )

    # ------------------------------------------------------------------ injected faults
    def inject_fault(self, fault: Fault) -> None:
        """Schedule a fault (control.faults); one that starts in the past starts now."""
        if not isinstance(fault, Fault):
            raise ValueError(f"fault must be a control.faults.Fault, got {type(fault).__name__}")
        if fault.kind in THRUSTER_KINDS and fault.thruster > self.n_thrusters:
            raise ValueError(
                f"fault thruster must be in [1, {self.n_thrusters}] (this ROV's thrusters), "
                f"got {fault.thruster}"
            )
        self.faults.append(fault)

    def clear_faults(self) -> None:
        """End every fault now (a slipped winch stays where it slipped to)."""
        for k in sorted(self._faults_on):
            self._log_fault(f"fault cleared: {self.faults[k].kind}")
        self.faults, self._faults_on, self._slipped = [], set(), set()
        self._apply_mount_sign(False)
        self._apply_thrust_factors(np.ones(self.n_thrusters))

    def _log_fault(self, text: str) -> None:
        self._fault_log.append((self.t_s, text))
        self.fault_events.append((self.t_s, text))

    def take_fault_log(self) -> list[tuple[float, str]]:
        """Faults that started or ended since the last call: (time [s], what)."""
        out, self._fault_log = self._fault_log, []
        return out

    def active_faults(self) -> list[Fault]:
        """Faults whose window covers the present time."""
        return [f for f in self.faults if f.active(self.t_s)]

    def _steps_to_fault_edge(self) -> int:
        """Steps until the next fault starts or ends (chunks end there, so a fault acts from
        its own step; without faults, chunks are as before)."""
        if not self.faults:
            return self.chunk_steps
        edges = [e for f in self.faults for e in (f.start_s, f.end_s) if e > self.t_s + 1e-9]
        if not edges:
            return self.chunk_steps
        return max(1, round((min(edges) - self.t_s) / self.dt_s))

    def _faults_before_chunk(self) -> None:
        """Faults that act once at their start (winch slip) and those that reconfigure the
        control system while active (mount sign)."""
        t = self.t_s + 1e-9
        active = {k for k, f in enumerate(self.faults) if f.active(t)}
        for k in sorted(active - self._faults_on):
            self._log_fault(f"fault: {self.faults[k].describe()}")
        for k in sorted(self._faults_on - active):
            self._log_fault(f"fault over: {self.faults[k].kind}")
        self._faults_on = active
        for k, f in enumerate(self.faults):
            if f.kind == "winch_slip" and f.active(t) and k not in self._slipped:
                self._slipped.add(k)
                self.wire_length_m += f.value  # the tree drops at once
                self.wire_target_m += f.value
        flipped = any(f.kind == "mount_sign" and f.active(t) for f in self.faults)
        self._apply_mount_sign(flipped)
        factors = np.ones(self.n_thrusters)
        for f in self.faults:
            if f.kind in THRUSTER_KINDS and f.active(t):
                i = f.thruster - 1
                factors[i] = min(factors[i], 0.0 if f.kind == "thruster_lost" else f.value)
        self._apply_thrust_factors(factors)

    def _apply_thrust_factors(self, factors: FloatArray) -> None:
        """Each thruster gives this share of the thrust its speed would give (a lost thruster
        0): the plant's thrust coefficients scaled; the control system's are left alone (it
        is not told, and goes on allocating to the thruster)."""
        if np.array_equal(factors, self._thrust_factors):
            return
        self._thrust_factors = factors.copy()
        base = self._healthy_arrays
        self.arrays = base._replace(
            thr_k_pos=base.thr_k_pos * factors, thr_k_neg=base.thr_k_neg * factors
        )

    def _apply_mount_sign(self, flipped: bool) -> None:
        """The control system's mounting vector: as configured, or mirrored."""
        if flipped == self._mount_flipped:
            return
        self._mount_flipped = flipped
        r = self.sysm.r_rov_from_tree_tree_m
        self.sysm = model.system_model(self.ps, self.wire_length_m, -r)
        self.thruster_config = system_thruster_config(self.ps, self.sysm)
        alloc, heave = self.C.alloc_kind, self.C.heave_newton
        self.C = control_arrays(
            self.ps, self.sysm, self.settings, self.gains, self.crane_tip_n[0:2], self.dt_s
        )._replace(alloc_kind=alloc, heave_newton=heave)

    def _faulted_current(
        self, speeds: FloatArray, dirs: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The current's speed and direction over the chunk's steps with surges and turns
        added (at the tree and along the wire alike)."""
        t = self._times(len(speeds))
        speeds, dirs = np.array(speeds, float), np.array(dirs, float)
        for f in self.faults:
            on = (t >= f.start_s - 1e-9) & (t < f.end_s - 1e-9)
            if f.kind == "current_surge":
                speeds[on] = np.maximum(speeds[on] + f.value, 0.0)
            elif f.kind == "current_turn":
                dirs[on] += math.radians(f.value)
        return speeds, dirs

    def _faults_in_chunk(self, env: FloatArray, noise: sensors.NoiseChunk) -> None:
        """Sensor and environment faults over the chunk's steps."""
        n = len(env)
        t = self._times(n)
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
                d = math.radians(f.direction_deg)
                step = f.value * self.dt_s * np.array([math.cos(d), math.sin(d), 0.0])
                tips = env[:, plant.E_CT : plant.E_CT + 3]
                moves = np.vstack([tips[0:1], on[:, None] * step[None, :]])
                if np.all(tips == tips[0]):
                    # the crane holds still (the fault holds it): a step at a time from where
                    # the tip is (add.accumulate sums in order), the same whatever the chunks
                    tips[:] = np.add.accumulate(moves, axis=0)[1:]
                else:  # the crane was moving when the drift began
                    moves[0] = 0.0
                    tips += np.add.accumulate(moves, axis=0)[1:]
                self.crane_tip_n = env[-1, plant.E_CT : plant.E_CT + 3].copy()
                self.crane_target_n = self.crane_tip_n.copy()

    def _chunk(self, n: int, out: FloatArray | None = None) -> FloatArray:
        """Advance n steps in one chunk; returns their rows: ``out`` (n, the log's width)
        filled, when given, else a new array. The kernels make whole rows, whose kept
        columns are taken here (``keep_log_columns``)."""
        env, noise = self._chunk_inputs(n)
        whole = self.log_keep.shape[0] == N_LOG
        if self.control_on:
            self._sync_site()
        if not self.control_on:
            args = (
                self.step_index,
                self.x,
                self.held_y,
                self.thruster_speeds_rps,
                env,
                noise.noise,
                noise.fresh,
                self.arrays,
                self.dt_s,
            )
            if out is None or not whole:
                x, held, log, ok = loop.run_open_chunk(*args)
            else:  # the rows straight into the request's (no copy of them afterwards)
                x, held, ok = loop.run_open_chunk_into(*args, out)
                log = out
        elif self.C.alloc_kind == loop.ALLOC_EXTERNAL:
            x, held, self.xhat, self.P_cov, cs, log, ok = self._chunk_qp(env, noise)
            self.controller_state.vector = cs
        else:
            chunk = ClosedChunk(
                self.step_index, self.x, self.held_y, self.xhat, self.P_cov, self.cs,
                self.target, env, noise.noise, noise.fresh, self.arrays, self.C, self.Q,
                self.dt_s, self.log_keep, self._spring_rows, out,
            )  # fmt: skip
            x, held, self.xhat, self.P_cov, cs, log, ok = run_closed_chunk(chunk)
            self.controller_state.vector = cs
        if not whole and log.shape[1] == N_LOG:
            log = log[:, self.log_keep]
        if self.control_on:
            # the control model's spring of the chunk's last whole second (as if the chunk
            # had ended there: chunks past whole seconds carry it in their rows)
            spring = self._spring_held
            self._site_k_h = float(spring[0])
            self._site_p_eq = spring[1:3].copy()
            self._refresh_wire_k_h_m = float(spring[3])
            self._sync_site()
        if ok < n:
            self._diverged(x, ok)
        self.x, self.held_y = x, held
        self._last_env = env[-1].copy()
        self.step_index += n
        if out is None:
            return log
        if log is not out:
            out[...] = log
        return out

    def _diverged(self, x: FloatArray, ok: int) -> None:
        parts = {
            "tree pose": x[0:6],
            "tree velocity": x[6:12],
            "ROV pose": x[12:18],
            "ROV velocity": x[18:24],
        }
        bad = [name for name, v in parts.items() if not np.all(np.isfinite(v))]
        raise SimulationDiverged(
            f"plant state not finite at t = "
            f"{(self.step_index + ok + 1) * self.dt_s:.2f} s "
            f"({', '.join(bad) or 'state'})"
        )

    def _chunk_qp(self, env: FloatArray, noise: sensors.NoiseChunk):
        """The compiled step body with the QP allocation (not compiled) in the middle."""
        x, held, xhat, pc, cs = self.x.copy(), self.held_y, self.xhat, self.P_cov, self.cs
        n = env.shape[0]
        log = np.zeros((n, N_LOG))
        work = plant.make_work(self.arrays.thr_T.shape[1])  # x is advanced in place
        for j in range(n):
            k = self.step_index + j
            held = sensors.sample(x, held, noise.noise[j], noise.fresh[j], sensors.Y_SENSOR)
            tau6, xhat, pc, cs = loop.control_step(
                k * self.dt_s,
                x,
                held,
                noise.fresh[j],
                xhat,
                pc,
                cs,
                self.target,
                self.C,
                self.Q,
                self.dt_s,
                log[j],
            )
            f = np.asarray(alloc.allocate_qp(self.thruster_config, tau6).force_newton)
            xhat, pc = loop.finish_step(
                x,
                f,
                env[j],
                xhat,
                pc,
                self.C,
                self.arrays,
                self.dt_s,
                (k + 1) * self.dt_s,
                held,
                log[j],
                work,
            )
            if not np.all(np.isfinite(x)):
                return x, held, xhat, pc, cs, log, j
        return x, held, xhat, pc, cs, log, n

    # ------------------------------------------------------------------ environment rows
    def _environment_chunk(self, n: int) -> FloatArray:
        """(n, N_ENV) environment rows (sim.plant.E_*); advances the current, the winch and
        the vessel to the end of the chunk. A chunk that starts on a whole second refreshes
        the slow parts first (``REFRESH_S``); any other holds them."""
        if self._refreshing():
            self._refresh()
        self.current_state, speeds, dirs = envmod.advance_current(
            self.current_state, self.current_params, self.dt_s, n, self.rng_current
        )
        if self.faults:
            speeds, dirs = self._faulted_current(speeds, dirs)
        env = np.empty((n, plant.N_ENV))
        spring = np.empty((n, 3))
        held = self._spring_held
        held[0] = self._site_k_h
        held[1:3] = self._site_p_eq
        held[3] = self._refresh_wire_k_h_m
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
            self._wire_site,
            speeds,
            dirs,
            self.wire_length_m,
            self.wire_target_m,
            self.wire_rate_mps,
            self.crane_tip_n,
            self.crane_target_n,
            self.crane_speed_mps,
            self.push_newton,
            1.0 if self.gripping else 0.0,
            frame,
            self.dt_s,
            self._wire_held,
            self.step_index,
            self.refresh_steps,
            out,
            held,
            spring,
            self.plant_ps.wire.submerged_weight_per_length(),  # as ``_refresh``
            self.ps.tree.submerged_weight_newton if self.control_on else 0.0,
        )
        self._spring_rows = spring
        if self.mdwire is not None:
            # the current the MoorDyn wire sees over this chunk: uniform over depth, the mean
            # speed and direction the quasi-static wire's drag offset takes (no waves)
            self._wire_current_n = envmod.current_velocity_n(float(out[4]), float(out[5]))
        if self.wave_field is not None:
            # the waves' velocity and acceleration added to the current's
            t = self._times(n)
            # at the tree's centre as at the last refresh, kept inside the water column (a
            # tree in the seabed's contact spring sits a few centimetres into it)
            north, east, down = self._refresh_point[0:3]
            depth = min(max(float(down), 0.0), self.wave_field.water_depth_m)
            v_w, a_w = envmod.wave_kinematics_n(
                self.wave_field, t, depth, float(north), float(east)
            )
            env[:, plant.E_VC : plant.E_VC + 3] += v_w
            if self.wave_load != "drag":
                env[:, plant.E_AC : plant.E_AC + 3] += a_w
        self.wire_length_m = float(out[0])
        self.crane_tip_n = out[1:4].copy()
        return env
