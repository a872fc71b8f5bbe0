"""``ClosedLoop``: the control system of chapter 3 driving the plant of chapter 2.

Owns a ``sim.simulator.Simulator`` for the plant, environment and sensors, builds the compiled
control configuration (``control.loop.ControlArrays``) from a parameter set and
``ControlSettings``, and runs the compiled loop in chunks. Commands (targets, gains, modes,
allocation) are validated here and applied between chunks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from control import allocation as alloc
from control import loop, model, quality, reference, refkernel
from control.startup import StartupReport, check_mount_vector
from sim import environment as envmod
from sim import sensors
from sim import wire as wm
from sim.gnc import ssa
from sim.params import ParameterSet
from sim.simulator import SimulationDiverged, Simulator

FloatArray = NDArray[np.float64]
Feedback = Literal["perfect", "ekf"]
Allocation = Literal["pinv", "priority", "qp"]
Reference = Literal["first", "third"]
HeadingMode = Literal["shortest", "absolute"]

GAIN_LIMITS = {"kp": 1.0e7, "ki": 1.0e6, "kd": 1.0e8}
"""Largest accepted gain per term (same bounds as the parameter files)."""


@dataclass(frozen=True)
class Gains:
    """Tree-controller gains [surge, sway, yaw] (appendix B)."""

    kp: tuple[float, float, float]
    ki: tuple[float, float, float]
    kd: tuple[float, float, float]

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd"):
            values = getattr(self, name)
            if len(values) != 3:
                raise ValueError(f"gains.{name} must have 3 entries [surge, sway, yaw]")
            for i, v in enumerate(values):
                if not (math.isfinite(v) and 0.0 <= v <= GAIN_LIMITS[name]):
                    raise ValueError(f"gains.{name}[{i}] must be in [0, {GAIN_LIMITS[name]:g}],"
                                     f" got {v}")

    def heading_only(self) -> Gains:
        """Surge and sway gains at zero: the sea trial's heading-only mode."""
        return Gains((0.0, 0.0, self.kp[2]), (0.0, 0.0, self.ki[2]), (0.0, 0.0, self.kd[2]))


@dataclass(frozen=True)
class ControlSettings:
    """Choices of the control system."""

    feedback: Feedback = "perfect"
    allocation: Allocation = "priority"
    reference: Reference = "third"
    feedforward: bool = False
    heave_force_n: float = 0.0
    """Constant heave force of the ROV while on the tree (sea trial: small, downwards) [N]."""
    gains: Gains | None = None
    """None: the parameter set's gains."""
    r_mount_config_m: tuple[float, float, float] | None = None
    """The mounting vector the controller is configured with; None: the parameter set's."""

    def __post_init__(self) -> None:
        choices = {"feedback": ("perfect", "ekf"), "allocation": ("pinv", "priority", "qp"),
                   "reference": ("first", "third")}
        for name, allowed in choices.items():
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {', '.join(allowed)}, "
                                 f"got {getattr(self, name)!r}")
        if not math.isfinite(self.heave_force_n) or abs(self.heave_force_n) > 1e5:
            raise ValueError(f"heave_force_n must be in [-1e5, 1e5] N, got {self.heave_force_n}")


@dataclass(frozen=True)
class LoopLog:
    """Recorded closed-loop run: one row per plant step (columns: ``control.loop.L_*``)."""

    data: FloatArray
    n_thrusters: int
    quality_counters: NDArray[np.int64] = field(default_factory=lambda: np.zeros((5, 4), int))

    def col(self, start: int, width: int = 1) -> FloatArray:
        return self.data[:, start] if width == 1 else self.data[:, start:start + width]

    @property
    def t_s(self) -> FloatArray:
        return self.data[:, loop.L_T]

    @property
    def tree_eta_n(self) -> FloatArray:
        return self.col(loop.L_TREE, 6)

    @property
    def rov_eta_n(self) -> FloatArray:
        return self.col(loop.L_ROV, 6)

    @property
    def eta_d(self) -> FloatArray:
        """Reference [north, east, psi]."""
        return self.col(loop.L_ETA_D, 3)

    @property
    def eta_hat(self) -> FloatArray:
        return self.col(loop.L_ETA_HAT, 3)

    @property
    def utilisation(self) -> FloatArray:
        return self.col(loop.L_UTIL, self.n_thrusters)

    @property
    def tau_tree(self) -> FloatArray:
        return self.col(loop.L_TAU_TREE, 3)

    @property
    def tau_rov(self) -> FloatArray:
        return self.col(loop.L_TAU_ROV, 6)

    @property
    def tau_achieved(self) -> FloatArray:
        return self.col(loop.L_TAU_ACH, 6)

    def concat(self, other: LoopLog) -> LoopLog:
        return LoopLog(np.vstack([self.data, other.data]), self.n_thrusters,
                       other.quality_counters)


def _ref_params(ps: ParameterSet, kind: Reference) -> FloatArray:
    """The parameter set's reference limits as the packed array of control.refkernel."""
    r = ps.spec.reference
    speed = [r.max_speed_mps, r.max_speed_mps, math.radians(r.max_yaw_rate_deg_s)]
    if kind == "first":
        # thesis fig. 3.5: first-order low pass (time constant 1 / omega) with saturated rate
        return refkernel.pack_first_order(reference.FirstOrderParams(
            time_constant_s=1.0 / r.bandwidth_rad_s, max_rate=speed))
    return refkernel.pack_third_order(reference.ThirdOrderParams(
        natural_frequency_rad_s=r.bandwidth_rad_s, damping_ratio=r.damping_ratio,
        max_speed=speed,
        max_accel=[r.max_accel_mps2, r.max_accel_mps2, math.radians(r.max_yaw_accel_deg_s2)]))


def _free_gains(ps: ParameterSet) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Free-ROV station keeping in [north, east, down, psi]: critically damped at 0.5 rad/s on
    the ROV's own mass (the thesis leaves this controller open; section 3.4)."""
    m = np.diag(ps.rov.M_rb + ps.rov.M_a)[[0, 1, 2, 5]]
    omega = 0.5
    kp = m * omega**2
    kd = 2.0 * omega * m
    ki = kp * omega / 10.0
    return kp, ki, kd


def system_thruster_config(ps: ParameterSet, sysm: model.SystemModel) -> alloc.ThrusterConfig:
    """The ROV's thrusters seen from the tree's origin: T_sys = H(r)^T J(r) T.

    Allocating on these rows makes the priority (yaw > sway > surge) a priority on the TREE's
    motion, which is what must be kept: in the ROV's own frame a sway force on the tree needs
    a yaw moment of |r| times it at the ROV, so a saturated ROV-frame allocation turns the
    tree. The pseudo-inverse allocation is the same in either frame (T_sys = W T with W
    invertible on the allocated rows, so T_sys^+ = T^+ W^-1)."""
    thr = ps.rov.thrusters
    return alloc.ThrusterConfig(T=sysm.rov_to_tree @ thr.T, k_pos=thr.k_pos, k_neg=thr.k_neg,
                                n_max_rps=thr.n_max_rps)


def control_arrays(ps: ParameterSet, sysm: model.SystemModel, settings: ControlSettings,
                   gains: Gains, p_eq: FloatArray, dt: float) -> loop.ControlArrays:
    """Compile the control configuration."""
    thr = ps.rov.thrusters
    cfg = system_thruster_config(ps, sysm)
    pinv_plan = alloc._pinv_plan(cfg, alloc.DEFAULT_DOFS)
    prio_plan = alloc._priority_plan(cfg, alloc.DEFAULT_PRIORITY)
    dof3 = model.DOF3
    A = sysm.tree_to_rov[np.ix_(dof3, dof3)]
    scfg = sensors.sensor_config(ps.sensors, dt)
    qcfg = quality.quality_config(scfg.noise_std, dt)
    obs = ps.spec.observer
    m_inv = np.linalg.inv(sysm.M)
    gqg = np.zeros((9, 9))
    force_std = np.asarray(obs.process_force_std)
    cov_nu = m_inv @ np.diag(force_std**2) @ m_inv.T
    gqg[3:6, 3:6] = dt * cov_nu
    gqg[6:9, 6:9] = dt * np.diag(np.asarray(obs.bias_drive_std) ** 2)
    noise = scfg.noise_std
    r_lever = float(np.linalg.norm(sysm.r_rov_from_tree_tree_m))
    fkp, fki, fkd = _free_gains(ps)
    kinds = {"pinv": loop.ALLOC_PINV, "priority": loop.ALLOC_PRIORITY, "qp": loop.ALLOC_EXTERNAL}
    return loop.ControlArrays(
        feedback_ekf=settings.feedback == "ekf", use_ff=settings.feedforward,
        ref_kind=loop.REF_FIRST if settings.reference == "first" else loop.REF_THIRD,
        ref_params=_ref_params(ps, settings.reference),
        Kp=np.array(gains.kp, float), Ki=np.array(gains.ki, float), Kd=np.array(gains.kd, float),
        M=sysm.M.copy(), M_inv=m_inv, D_l=sysm.D_l.copy(), D_nl=sysm.D_nl.copy(),
        k_h=float(sysm.k_h), p_eq=np.asarray(p_eq, float).copy(), A=A.copy(),
        A_inv=np.linalg.inv(A), i_limit=0.9 * model.dof_capacity(cfg.T, cfg.f_max_neg,
                                                                      cfg.f_max_pos),
        heave_n=float(settings.heave_force_n), r_mount=sysm.r_rov_from_tree_tree_m.copy(),
        psi_rel=float(sysm.psi_rov_from_tree_rad), alloc_kind=kinds[settings.allocation],
        pinv_T=np.ascontiguousarray(pinv_plan.T_pinv),
        pinv_rows=np.asarray(pinv_plan.layout.dofs, np.int64),
        prio_A=prio_plan.A, prio_D=prio_plan.D, prio_R=prio_plan.R,
        prio_rows=np.asarray(prio_plan.layout.dofs, np.int64),
        f_lo=prio_plan.layout.f_lo.copy(), f_hi=prio_plan.layout.f_hi.copy(),
        alloc_tol=float(prio_plan.layout.tol), k_pos=thr.k_pos.copy(), k_neg=thr.k_neg.copy(),
        n_max=thr.n_max_rps.copy(), T6=np.ascontiguousarray(thr.T),
        rov_to_tree=np.ascontiguousarray(sysm.rov_to_tree),
        GQG=gqg, T_b=np.asarray(obs.bias_time_constant_s, float),
        r_pos=float(max(noise[0], 1e-3) ** 2), r_psi=float(max(noise[4], 1e-4) ** 2),
        r_dvl=float(max(noise[5], 1e-3) ** 2 + (noise[10] * r_lever) ** 2),
        r_gyro=float(max(noise[10], 1e-4) ** 2),
        q_lo=qcfg.lo, q_hi=qcfg.hi, q_wild=qcfg.wild_jump, q_rate=qcfg.max_rate,
        q_frozen=qcfg.frozen_count, q_var=qcfg.variance_limit,
        free_Kp=fkp, free_Ki=fki, free_Kd=fkd)


class ClosedLoop:
    """The controlled system, stepped in compiled chunks (default 1 s of 100 steps)."""

    def __init__(self, ps: ParameterSet, *, tree_depth_m: float,
                 settings: ControlSettings | None = None,
                 crane_tip_n: FloatArray = (1.0, 1.0, 0.0),
                 current: envmod.CurrentParams | None = None,
                 waves: envmod.WaveParams | None = None, seed: int = 0, dt_s: float = 0.01,
                 tree_heading_rad: float = 0.0, chunk_steps: int = 100,
                 plant_ps: ParameterSet | None = None, start_gripping: bool = True) -> None:
        """``ps`` is what the control system is configured with; ``plant_ps`` (default: the
        same) is the physical truth the plant simulates, for robustness studies."""
        self.ps = ps
        self.settings = settings or ControlSettings()
        self.sim = Simulator(plant_ps or ps, tree_depth_m=tree_depth_m, crane_tip_n=crane_tip_n,
                             current=current, waves=waves, has_rov=True,
                             tree_heading_rad=tree_heading_rad, seed=seed, dt_s=dt_s,
                             chunk_steps=chunk_steps)
        self.dt_s = dt_s
        self.chunk_steps = chunk_steps
        r_cfg = self.settings.r_mount_config_m
        self.sysm = model.system_model(ps, self.sim.wire_length_m,
                                       None if r_cfg is None else np.asarray(r_cfg, float))
        self.gains = self.settings.gains or Gains(tuple(ps.gains.kp), tuple(ps.gains.ki),
                                                  tuple(ps.gains.kd))
        self.thruster_config = system_thruster_config(ps, self.sysm)
        self.C = control_arrays(ps, self.sysm, self.settings, self.gains,
                                self.sim.crane_tip_n[0:2], dt_s)
        if not start_gripping:
            # the ROV waits free, 3 m further back and 1 m above its mount (a hook-up to come)
            x = self.sim.x.copy()
            c, s = math.cos(x[5]), math.sin(x[5])
            x[12:15] += np.array([-3.0 * c, -3.0 * s, -1.0])
            self.sim.x = x
            self.sim.held_y = sensors.true_outputs(x)
            self.sim.gripping = False
        self.cs = np.zeros(loop.N_CS)
        self.cs[loop.CS_MODE] = loop.MODE_TREE if start_gripping else loop.MODE_FREE
        self.cs[loop.CS_LAST_MODE] = -1.0  # first step initialises the reference bumplessly
        self.xhat, self.P_cov = self._initial_estimate()
        w = quality.WINDOW
        self.Q = loop.QualityState(np.zeros(sensors.N_Y), -np.ones(5), np.zeros(5, np.int64),
                                   np.zeros((sensors.N_Y, w)), np.zeros((5, 4), np.int64))
        eta0 = self.xhat[0:3] if self.settings.feedback == "ekf" else self.sim.x[[0, 1, 5]]
        self.target = np.array(eta0, float)
        self.startup = self.check_mount() if start_gripping else StartupReport(False, 0.0, 0.0)

    # ------------------------------------------------------------------ set-up helpers
    def _initial_estimate(self) -> tuple[FloatArray, FloatArray]:
        """EKF start: the first measurements moved to the tree origin, at rest, no bias."""
        y = self.sim.held_y
        ne, psi, _, _ = loop.tree_measurements(y, y[4] - self.C.psi_rel, self.C)
        x0 = np.zeros(9)
        x0[0:2] = ne
        x0[2] = psi
        p0 = np.diag([1.0, 1.0, 0.01, 0.01, 0.01, 1e-4,
                      *(np.asarray(self.ps.spec.observer.process_force_std) ** 2)])
        return x0, p0

    @property
    def t_s(self) -> float:
        return self.sim.t_s

    @property
    def eta_estimate(self) -> FloatArray:
        """What the controller believes: tree [north, east, psi]."""
        if self.settings.feedback == "ekf":
            return self.xhat[0:3].copy()
        return self.sim.x[[0, 1, 5]].copy()

    # ------------------------------------------------------------------ commands
    def set_target(self, north_m: float, east_m: float, psi_rad: float,
                   heading_mode: HeadingMode = "shortest") -> None:
        """Where the tree should go. ``shortest``: the heading target is reached the short way
        round from the present reference; ``absolute``: ``psi_rad`` is taken as it stands,
        unwrapped, so +2 pi from 0 is a full turn."""
        for name, v in (("north_m", north_m), ("east_m", east_m), ("psi_rad", psi_rad)):
            if not math.isfinite(v):
                raise ValueError(f"target {name} must be finite, got {v}")
        psi_ref = self.cs[loop.CS_REF + 2] if self.cs[loop.CS_LAST_MODE] >= 0 else \
            self.eta_estimate[2]
        if heading_mode == "shortest":
            psi = psi_ref + ssa(psi_rad - psi_ref)
        elif heading_mode == "absolute":
            psi = psi_rad
        else:
            raise ValueError(f"heading_mode must be 'shortest' or 'absolute', got {heading_mode!r}")
        self.target = np.array([north_m, east_m, psi])

    def set_gains(self, gains: Gains) -> None:
        """New tree-controller gains, bumpless: the jump of the P and D terms at this instant
        is moved into the integral, so the commanded force does not change."""
        e = self.cs[loop.CS_E:loop.CS_E + 3]
        de = self.cs[loop.CS_DE:loop.CS_DE + 3]
        old_pd = -self.C.Kp * e - self.C.Kd * de
        new_kp, new_kd = np.array(gains.kp), np.array(gains.kd)
        new_pd = -new_kp * e - new_kd * de
        self.cs[loop.CS_I:loop.CS_I + 3] += old_pd - new_pd
        self.gains = gains
        self.C = self.C._replace(Kp=new_kp, Ki=np.array(gains.ki), Kd=new_kd)

    def set_mode(self, mode: Literal["tree", "free"]) -> None:
        """Supervisor switch (section 3.4): tree controller or free-ROV station keeping. The
        new controller starts from the last commanded thrust (no jump)."""
        modes = {"tree": loop.MODE_TREE, "free": loop.MODE_FREE}
        if mode not in modes:
            raise ValueError(f"mode must be 'tree' or 'free', got {mode!r}")
        self.cs[loop.CS_MODE] = modes[mode]

    def set_grip(self, gripping: bool) -> None:
        """Physically grip (True) or release (False) the tree."""
        self.sim.gripping = bool(gripping)

    def set_heave_force(self, force_n: float) -> None:
        """Constant heave force of the ROV while on the tree (positive = down) [N]."""
        if not (math.isfinite(force_n) and abs(force_n) <= 1e5):
            raise ValueError(f"heave force must be in [-1e5, 1e5] N, got {force_n}")
        self.C = self.C._replace(heave_n=float(force_n))
        self.settings = replace(self.settings, heave_force_n=float(force_n))

    def set_free_setpoint(self, north_m: float, east_m: float, down_m: float,
                          psi_rad: float) -> None:
        """Where the free-flying ROV should hold station (supervisor's free mode)."""
        values = np.array([north_m, east_m, down_m, psi_rad], float)
        if not np.all(np.isfinite(values)):
            raise ValueError(f"free-ROV set point must be finite, got {values.tolist()}")
        self.cs[loop.CS_FSP:loop.CS_FSP + 4] = values

    def check_mount(self) -> StartupReport:
        """The start-up check of the mount vector against the measured geometry."""
        return check_mount_vector(self.sim.held_y, self.sysm.r_rov_from_tree_tree_m,
                                  self.sim.crane_tip_n, self.sim.wire_length_m, self.ps,
                                  self.sim.current_state.speed_mps)

    def reset_observer(self) -> None:
        """Restart the EKF from the present measurements (after hook-up)."""
        self.xhat, self.P_cov = self._initial_estimate()

    def mount_pose_n(self) -> FloatArray:
        """Where the ROV's origin belongs on the tree now: [north, east, down, psi] (truth of
        the tree's pose, as the pilot sees it on the camera, and the configured r)."""
        x = self.sim.x
        c, s = math.cos(x[5]), math.sin(x[5])
        r = self.sysm.r_rov_from_tree_tree_m
        return np.array([x[0] + c * r[0] - s * r[1], x[1] + s * r[0] + c * r[1], x[2] + r[2],
                         x[5] + self.sysm.psi_rov_from_tree_rad])

    def set_allocation(self, kind: Allocation) -> None:
        kinds = {"pinv": loop.ALLOC_PINV, "priority": loop.ALLOC_PRIORITY,
                 "qp": loop.ALLOC_EXTERNAL}
        if kind not in kinds:
            raise ValueError(f"allocation must be one of pinv, priority, qp, got {kind!r}")
        self.settings = replace(self.settings, allocation=kind)
        self.C = self.C._replace(alloc_kind=kinds[kind])

    # ------------------------------------------------------------------ stepping
    def run(self, duration_s: float) -> LoopLog:
        """Advance by ``duration_s`` with the present target and return the log."""
        if not (math.isfinite(duration_s) and duration_s >= 0.0):
            raise ValueError(f"duration must be a finite number of seconds >= 0, got {duration_s}")
        total = int(round(duration_s / self.dt_s))
        out = np.empty((total, loop.N_LOG))
        done = 0
        while done < total:
            n = min(self.chunk_steps, total - done)
            out[done:done + n] = self._chunk(n)
            done += n
        m = self.ps.rov.thrusters.T.shape[1]
        return LoopLog(out, m, self.Q.counters.copy())

    def _sync_site(self) -> None:
        """The vessel's position and the wire length are known on board: keep the control
        plant model's wire spring (equilibrium point and stiffness) up to date."""
        sim = self.sim
        k_h = wm.horizontal_stiffness(sim.ps.wire.submerged_weight_per_length(),
                                      self.ps.tree.submerged_weight_n, sim.wire_length_m)
        if (k_h != self.C.k_h) or np.any(self.C.p_eq != sim.crane_tip_n[0:2]):
            self.C = self.C._replace(k_h=float(k_h), p_eq=sim.crane_tip_n[0:2].copy())

    def _chunk(self, n: int) -> FloatArray:
        sim = self.sim
        self._sync_site()
        env, _ = sim.environment_chunk(n)
        noise = sensors.draw_noise(sim.sensor_cfg, sim.rng, sim.step_index, n)
        if self.C.alloc_kind == loop.ALLOC_EXTERNAL:
            result = self._chunk_python(env, noise)
        else:
            result = loop.run_chunk(sim.step_index, sim.x, sim.held_y, self.xhat, self.P_cov,
                                    self.cs, self.target, env, noise.noise, noise.fresh,
                                    sim.arrays, self.C, self.Q, self.dt_s)
        x, held, self.xhat, self.P_cov, self.cs, log, ok = result
        if ok < n:
            raise SimulationDiverged(f"plant state not finite at t = "
                                     f"{(sim.step_index + ok + 1) * self.dt_s:.2f} s")
        sim.x, sim.held_y = x, held
        sim.step_index += n
        return log

    def _chunk_python(self, env: FloatArray, noise: sensors.NoiseChunk):
        """Same steps as loop.run_chunk, with the QP allocation (not compiled) in the middle."""
        sim = self.sim
        x, held, xhat, pc, cs = sim.x, sim.held_y, self.xhat, self.P_cov, self.cs
        n = env.shape[0]
        log = np.zeros((n, loop.N_LOG))
        for j in range(n):
            k = sim.step_index + j
            held = sensors.sample(x, held, noise.noise[j], noise.fresh[j], sensors.Y_SENSOR)
            tau6, xhat, pc, cs = loop.control_step(k * self.dt_s, x, held, noise.fresh[j],
                                                   xhat, pc, cs, self.target, self.C, self.Q,
                                                   self.dt_s, log[j])
            f = np.asarray(alloc.allocate_qp(self.thruster_config, tau6).force_n)
            x, xhat, pc = loop.finish_step(x, f, env[j], xhat, pc, self.C, sim.arrays,
                                           self.dt_s, log[j])
            log[j, loop.L_T] = (k + 1) * self.dt_s
            log[j, loop.L_TREE:loop.L_TREE + 6] = x[0:6]
            log[j, loop.L_ROV:loop.L_ROV + 6] = x[12:18]
            log[j, loop.L_Y:loop.L_Y + 11] = held
            loop.log_site(log[j], x, env[j], sim.arrays)
            if not np.all(np.isfinite(x)):
                return x, held, xhat, pc, cs, log, j
        return x, held, xhat, pc, cs, log, n

