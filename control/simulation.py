"""``Simulation``: the one owner of a running simulation, which steps it.

It holds what changes while a simulation runs: the plant state and the held sensor values,
the environment's moving parts (``site``: current, waves, the vessel's crane tip, the winch,
the wire, the docking frame; ``control.site_motion``), the injected faults (``injector``;
``control.fault_injection``), and, with control on, the control system's state (observer,
reference and controller (``controller_state``), signal checks) with its compiled
configuration. ``control.building`` builds all of it; this steps it and takes every command
through its own methods; nothing outside writes its arrays.

    sim = Simulation(ps, tree_depth_m=400.0)     # closed loop (chapter 3 on chapter 2)
    rows = sim.step(100)                          # LogRows: rows["tree_eta_n"] ...
    sim.set_target(1.0, 1.0, math.radians(90))
    rows = sim.run_for(60.0)                      # a whole number of steps, or ValueError

With ``control=False`` it is the open-loop plant of ``rov-console simulate``: the thrusters
turn at ``set_thruster_speeds`` and the control columns of the rows stay zero.

Stepping goes in chunks of at most ``chunk_steps`` that end on whole seconds (``REFRESH_S``),
or of up to ``LONG_CHUNK_S`` while nothing but the wire's entries and the control model's
wire spring needs refreshing there (``_still``; both ride in the chunk's rows):
``_chunk_inputs`` makes the environment rows (``SiteMotion``) and the sensor noise for a
chunk, changed by the injected faults, then one compiled kernel advances the chunk
(``control.jobs``, ``control.loop``). Commands are applied between chunks. A state that stops
being finite raises ``SimulationDiverged`` naming the time and which part went non-finite.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from control import loop, model, refkernel
from control.building import LONG_CHUNK_S, Start, build, finite_vector
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
    system_thruster_config,
)
from control.controller_state import ControllerState
from control.fault_injection import FaultInjector
from control.faults import Fault
from control.jobs import ClosedChunk, SimulationDiverged, run_closed_chunk, run_qp_chunk
from control.site_motion import (
    REFRESH_S,
    WIRE_DAMPING_RATIO,
    WIRE_MODELS,
    SiteMotion,
    steady_current,
)
from control.startup import StartupReport, check_mount_vector, hookup_estimate
from sim import environment as envmod
from sim import plant, sensors
from sim import vessel as vesselmod
from sim.docking import DockingFrame
from sim.gnc import ssa
from sim.params import ParameterSet

__all__ = [
    "GRIP_REACH_DEG",
    "GRIP_REACH_M",
    "LONG_CHUNK_S",
    "REFRESH_S",
    "WIRE_LENGTH_RANGE_M",
    "WIRE_MODELS",
    "Simulation",
    "SimulationDiverged",
    "steady_current",
]

FloatArray = NDArray[np.float64]
WIRE_LENGTH_RANGE_M = (1.0, 5000.0)
WINCH_RATE_MAX_MPS = 2.0
VESSEL_SPEED_MAX_MPS = 5.0
HEAVE_FORCE_MAX_NEWTON = 1.0e5
GRIP_REACH_M = 0.3
"""Farthest the ROV's origin may be from its mount on the tree for the gripper to close [m]:
the reach of a work-class manipulator's jaw around the tree's grab bar is a few decimetres, and
the hook-up leg's tolerance (at most 1 m in the schema) is tighter in every library mission."""
GRIP_REACH_DEG = 10.0
"""Largest heading difference from the mount at which the gripper closes [deg]: beyond it the
spring would yank the tree round (12 deg from 100 deg off, in the console defect report)."""


def _in_range(
    name: str, value: float, lo: float, hi: float, unit: str, lo_open: bool = False
) -> float:
    ok = math.isfinite(value) and (lo < value if lo_open else lo <= value) and value <= hi
    if not ok:
        bracket = "(" if lo_open else "["
        raise ValueError(f"{name} must be in {bracket}{lo:g}, {hi:g}] {unit}, got {value}")
    return float(value)


class Simulation:
    """Plant, environment, sensors and (with ``control``) the control system, stepped together.

    ``ps`` is what the control system is configured with; ``plant_ps`` (default: the same) is
    the physical truth the plant simulates, for robustness studies. ``wire`` is one of
    ``WIRE_MODELS``; ``vessel`` the vessel's wave-frequency motion at the crane tip (None: the
    tip stands still); ``start_gripping=False`` has the ROV wait free beside the tree."""

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
        start = build(
            ps,
            tree_depth_m=tree_depth_m,
            settings=settings,
            control=control,
            has_rov=has_rov,
            crane_tip_n=crane_tip_n,
            current=current,
            waves=waves,
            seed=seed,
            dt_s=dt_s,
            tree_heading_rad=tree_heading_rad,
            chunk_steps=chunk_steps,
            plant_ps=plant_ps,
            start_gripping=start_gripping,
            vessel=vessel,
            wire=wire,
            wire_damping_ratio=wire_damping_ratio,
        )
        self.ps = ps
        self._take_plant(start)
        self._take_control(start)
        self.injector = FaultInjector(self.n_thrusters)
        """The injected faults (control.faults), past, present and scheduled."""
        self.log_layout: Layout = LAYOUT
        """The columns of the rows ``step`` returns (``keep_log_columns``)."""
        self.log_keep: NDArray[np.intp] = np.arange(N_LOG, dtype=np.intp)
        """Their indices in the whole row (``LAYOUT``), in order."""

    def _take_plant(self, start: Start) -> None:
        """The plant's and the environment's parts of ``start``."""
        self.plant_ps = start.plant_ps
        self.dt_s = start.dt_s
        self.chunk_steps = start.chunk_steps
        self.refresh_steps = start.refresh_steps
        """Steps between refreshes of the slow parts of the environment (``REFRESH_S``)."""
        self.long_chunk_steps = start.long_chunk_steps
        """The longest chunk while the slow parts stand still (``LONG_CHUNK_S``)."""
        self.has_rov = start.has_rov
        self.site: SiteMotion = start.site
        """The environment's moving parts: current, waves, vessel, crane, winch, wire."""
        self.arrays = start.arrays
        self._healthy_arrays = start.arrays  # the plant's, before any thruster fault
        self._thrust_factors = np.ones(start.arrays.thr_T.shape[1])
        self.sensor_cfg = start.sensor_cfg
        self._noise_stream = start.noise_stream
        self.x = start.x
        self.held_y = start.held_y
        self.step_index = 0
        self.gripping = start.gripping
        self.thruster_speeds_rps = np.zeros(self.plant_ps.rov.thrusters.T.shape[1])
        self._last_env: FloatArray | None = None  # the last step's environment row

    def _take_control(self, start: Start) -> None:
        """The control system's parts of ``start``."""
        self.control_on = start.control_on
        self.settings = start.settings
        self.sysm = start.sysm
        self.gains = start.gains
        self.thruster_config = start.thruster_config
        self.C = start.C
        self.controller_state: ControllerState = start.controller_state
        """The controller's state (mode, reference, integrals, the pilot's demand) by name."""
        self.pilot_capacity = start.pilot_capacity
        """Full stick on [surge, sway, heave, yaw], (2, 4): backwards, forwards [N, N m]."""
        self.xhat, self.P_cov = start.xhat, start.P_cov
        self.Q = start.Q
        self.target = start.target
        self.startup = start.startup
        self._mount_flipped = False  # the control system's mounting vector mirrored (a fault)

    # ------------------------------------------------------------------ what it is now
    @property
    def t_s(self) -> float:
        return self.step_index * self.dt_s

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
    def wire_length_m(self) -> float:
        """The winch's present payout (unstretched) [m]."""
        return self.site.wire_length_m

    @property
    def crane_tip_n(self) -> FloatArray:
        """Where the vessel keeps the crane tip, NED [m] (without its wave motion)."""
        return self.site.crane_tip_n

    @property
    def crane_target_n(self) -> FloatArray:
        """Where the vessel is taking the crane tip (``move_vessel``), NED [m]."""
        return self.site.crane_target_n

    @property
    def docking_frame(self) -> DockingFrame | None:
        return self.site.docking_frame

    @property
    def wire_model(self) -> str:
        """``quasi-static``, ``elastic`` or ``moordyn`` (``WIRE_MODELS``)."""
        return self.site.wire_model

    @property
    def wave_field(self) -> envmod.WaveField | None:
        return self.site.wave_field

    @property
    def vessel_ramp_s(self) -> float:
        """The vessel's motion grows in over this long from t = 0 [s] (``SiteMotion``)."""
        return self.site.vessel_ramp_s

    @property
    def current_speed_mps(self) -> float:
        """The current's set speed [m/s] (what the instructor or the mission set; injected
        surges are not in it: ``current_flowing``)."""
        return float(self.site.current_state.speed_mps)

    @property
    def current_direction_rad(self) -> float:
        """The direction the current's set speed flows towards [rad]."""
        return float(self.site.current_state.direction_rad)

    def current_flowing(self) -> tuple[float, float]:
        """The current as it flows now, (speed [m/s], direction it flows towards [rad]): the
        set current with the injected surges and turns active at this time, what the plant's
        next step gets. The landing's planners plan in it (the trial crew judged by what the
        ROV had to hold against, not by the forecast)."""
        t = np.array([self.t_s])
        speeds, dirs = self.injector.current(
            t, np.array([self.current_speed_mps]), np.array([self.current_direction_rad])
        )
        return float(speeds[0]), float(dirs[0])

    @property
    def winch_idle(self) -> bool:
        """The winch has reached its commanded payout."""
        return self.site.winch_idle

    @property
    def winch_target_m(self) -> float:
        """The payout the winch is going to [m] (``winch_to``)."""
        return float(self.site.wire_target_m)

    @property
    def winch_rate_mps(self) -> float:
        """The speed the winch pays out or hauls in at while it moves [m/s]."""
        return float(self.site.wire_rate_mps)

    @property
    def heave_compensation(self) -> bool | None:
        """The crane's active heave compensation is on (or fading in); None when the crane
        tip does not heave (no sea or no vessel motion in this run)."""
        return self.site.heave_compensation

    def set_heave_compensation(self, on: bool) -> None:
        """Turn the crane's heave compensation on or off: it fades in or out over two peak
        periods of the sea from now (``SiteMotion.set_heave_compensation``); ValueError when
        the crane tip does not heave in this run (no sea or no vessel motion)."""
        self.site.set_heave_compensation(bool(on), self.t_s)

    @property
    def thruster_health(self) -> FloatArray:
        """Each thruster's share of the thrust its speed should give, as its drive reports it
        (1 healthy, 0 lost; an injected thruster fault): the pilot's thruster telemetry. The
        control system does not read it (it goes on allocating to a lost thruster)."""
        return self._thrust_factors.copy()

    def winch_steps_busy(self) -> int:
        """Steps from now after each of which the winch is certainly still moving
        (``winch_idle`` false; ``SiteMotion.winch_steps_busy``); 0 with any fault scheduled
        (a winch slip moves the payout)."""
        return 0 if self.faults else self.site.winch_steps_busy()

    def vessel_at(self, target_n: FloatArray, tol_m: float = 1e-6) -> bool:
        return bool(np.linalg.norm(self.crane_tip_n - np.asarray(target_n, float)) <= tol_m)

    def wire_length_for_depth(self, tree_depth_m: float) -> float:
        """Unstretched payout that hangs the tree's centre at ``tree_depth_m`` in the present
        current (the plant's wire and tree)."""
        return self.site.wire_length_for_depth(tree_depth_m)

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
            self.current_speed_mps,
        )

    def present_row(self) -> FloatArray:
        """A log row for the present state (before the next step): time, plant, reference,
        estimate, mode and site (the site of the last step's environment row, as logged)."""
        row = np.zeros(N_LOG)
        env = self._last_env if self._last_env is not None else self.site.at_rest_row()
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
        the mounting vector r (``control.startup.hookup_estimate``)."""
        last_fix_s = float(self.Q.last_t[sensors.POSITION])
        self.xhat, self.P_cov = hookup_estimate(self.held_y, self.C, self.ps, self.t_s, last_fix_s)

    # ------------------------------------------------------------------ plant commands
    def set_thruster_speeds(self, n_rps: FloatArray) -> None:
        """Propeller speeds while control is off [rev/s]."""
        self.thruster_speeds_rps = finite_vector(
            "thruster speed command [rev/s]", n_rps, self.thruster_speeds_rps.shape[0]
        )

    def set_push(self, force_newton: FloatArray) -> None:
        """A steady external force on the tree's centre, NED [N]."""
        self.site.push_newton = finite_vector("push force [N]", force_newton, 3)

    def winch_to(self, length_m: float, rate_mps: float) -> None:
        """Pay out (or haul in) the wire smoothly to ``length_m`` at ``rate_mps``."""
        length = _in_range("wire length", length_m, *WIRE_LENGTH_RANGE_M, "m")
        rate = _in_range("winch rate", rate_mps, 0.0, WINCH_RATE_MAX_MPS, "m/s", lo_open=True)
        self.site.winch_to(length, rate)

    def move_vessel(self, target_n: FloatArray, speed_mps: float) -> None:
        """Move the vessel (the crane tip) smoothly to ``target_n`` at ``speed_mps``."""
        target = finite_vector("crane tip target", target_n, 3)
        speed = _in_range("vessel speed", speed_mps, 0.0, VESSEL_SPEED_MAX_MPS, "m/s", lo_open=True)
        self.site.crane_target_n = target
        self.site.crane_speed_mps = speed

    def set_current(self, params: envmod.CurrentParams) -> None:
        """A new current (and its random walk), starting from its nominal speed and
        direction."""
        self.site.set_current(params)

    def set_docking_frame(self, frame: DockingFrame | None) -> None:
        """Put a docking frame (and the seabed) under the tree, or take it away."""
        self.site.docking_frame = frame

    # ------------------------------------------------------------------ injected faults
    @property
    def faults(self) -> list[Fault]:
        """Injected faults, past, present and scheduled (control.faults)."""
        return self.injector.faults

    @property
    def fault_events(self) -> list[tuple[float, str]]:
        """Every fault start and end so far, (time [s], what), oldest first (unlike
        ``take_fault_log``, never emptied: the console reads it from where it got to)."""
        return self.injector.events

    def inject_fault(self, fault: Fault) -> None:
        """Schedule a fault (control.faults); one that starts in the past starts now."""
        self.injector.inject(fault)

    def clear_faults(self) -> None:
        """End every fault now (a slipped winch stays where it slipped to)."""
        self.injector.clear(self.t_s)
        self._apply_mount_sign(False)
        self._apply_thrust_factors(np.ones(self.n_thrusters))

    def take_fault_log(self) -> list[tuple[float, str]]:
        """Faults that started or ended since the last call: (time [s], what)."""
        return self.injector.take_log()

    def active_faults(self) -> list[Fault]:
        """Faults whose window covers the present time."""
        return self.injector.active(self.t_s)

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
            k = self._next_chunk(int(n) - done)
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

    def _next_chunk(self, left: int) -> int:
        """The steps of the next chunk, with ``left`` steps of the request to go: up to the
        next fault's start or end and the next whole second, or past whole seconds while the
        slow parts stand still (``_still``)."""
        k = min(
            self.chunk_steps,
            left,
            self.injector.steps_to_edge(self.t_s, self.dt_s, self.chunk_steps),
            self.refresh_steps - self.step_index % self.refresh_steps,
        )
        if self.site.mdwire is not None:
            return 1  # MoorDyn and the plant take turns, one step each
        if k == self.refresh_steps and self._still():
            # whole seconds with nothing to refresh but the wire's entries (which the rows
            # refresh themselves): one chunk over several, ending on a whole second
            whole = min(left, self.long_chunk_steps) // self.refresh_steps
            k = self.refresh_steps * max(1, whole)
        return k

    def _still(self) -> bool:
        """Nothing refreshed on a whole second needs Python for seconds to come: the site
        stands still (``SiteMotion.still``) and no fault was ever injected. Then a chunk may
        run past whole seconds (``LONG_CHUNK_S``) and give the same numbers as chunks of a
        second."""
        qp = self.control_on and self.C.alloc_kind == loop.ALLOC_EXTERNAL
        return not self.faults and self.site.still(qp)

    def _sync_site(self) -> None:
        """The vessel's position and the wire length are known on board: the control plant
        model's wire spring (equilibrium point and stiffness) as at the last refresh, put
        into its configuration again if anything (new gains, a new mode) replaced it."""
        k_h, p_eq, now = self.site.spring_k_h, self.site.spring_p_eq, self.C.p_eq
        if k_h != self.C.k_h or now[0] != p_eq[0] or now[1] != p_eq[1]:
            self.C = self.C._replace(k_h=k_h, p_eq=p_eq.copy())

    def _environment_chunk(self, n: int) -> FloatArray:
        """(n, N_ENV) environment rows of the next n steps (``SiteMotion.rows``), the
        current changed by the injected faults; advances the site to the chunk's end."""
        change = self.injector.current if self.faults else None
        return self.site.rows(n, self.step_index, self.x, self.gripping, change)

    def _chunk_inputs(self, n: int) -> tuple[FloatArray, sensors.NoiseChunk]:
        """Environment rows and sensor noise for the next n steps, with the injected faults
        (sensor dropouts, biases, winch slip, current surges, a drifting vessel) applied
        before the kernel runs."""
        if self.faults:
            flipped, factors = self.injector.before_chunk(self.t_s, self.site)
            self._apply_mount_sign(flipped)
            self._apply_thrust_factors(factors)
        env = self._environment_chunk(n)
        noise = self._noise_stream.take(self.sensor_cfg, self.step_index, n)
        if self.faults:
            t = self.site.times(self.step_index, n)
            self.injector.in_chunk(env, noise, t, self.dt_s, self.site)
        self.site.wire_rows(env, self.step_index, self.x, self.arrays.tree_r_att)
        return env, noise

    def _chunk(self, n: int, out: FloatArray | None = None) -> FloatArray:
        """Advance n steps in one chunk; returns their rows: ``out`` (n, the log's width)
        filled, when given, else a new array. The kernels make whole rows, whose kept
        columns are taken here (``keep_log_columns``)."""
        env, noise = self._chunk_inputs(n)
        whole = self.log_keep.shape[0] == N_LOG
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
        else:
            self._sync_site()
            chunk = ClosedChunk(
                self.step_index, self.x, self.held_y, self.xhat, self.P_cov, self.cs,
                self.target, env, noise.noise, noise.fresh, self.arrays, self.C, self.Q,
                self.dt_s, self.log_keep, self.site.spring_rows, out,
            )  # fmt: skip
            if self.C.alloc_kind == loop.ALLOC_EXTERNAL:
                res = run_qp_chunk(chunk, self.thruster_config)
            else:
                res = run_closed_chunk(chunk)
            x, held, log, ok = res.x, res.held_y, res.rows, res.steps_done
            self.xhat, self.P_cov, self.controller_state.vector = res.xhat, res.P_cov, res.cs
            # the control model's spring of the chunk's last whole second
            self.site.take_spring()
            self._sync_site()
        if not whole and log.shape[1] == N_LOG:
            log = log[:, self.log_keep]
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
