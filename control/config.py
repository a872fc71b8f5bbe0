"""The control system's configuration: the choices (``ControlSettings``), the gains, and the
compiled arrays (``control.loop.ControlArrays``) built from a parameter set and those choices.

The choices each have one list of allowed values here (``FEEDBACKS``, ``ALLOCATIONS``,
``REFERENCES``, ``HEADING_MODES``, ``LAWS``, ``MODES``) and the gains one set of limits
(``GAIN_LIMITS``): the mission schema, the command line and the console's API use these.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from control import allocation as alloc
from control import loop, model, quality, reference, refkernel
from sim import sensors
from sim.params import GAIN_LIMITS, ParameterSet

FloatArray = NDArray[np.float64]
Feedback = Literal["perfect", "ekf"]
Allocation = Literal["pinv", "priority", "qp"]
Reference = Literal["first", "third"]
HeadingMode = Literal["shortest", "absolute"]
Law = Literal["thesis", "feedforward"]
Mode = Literal["tree", "free", "manual"]
FEEDBACKS: tuple[Feedback, ...] = ("perfect", "ekf")
ALLOCATIONS: tuple[Allocation, ...] = ("pinv", "priority", "qp")
REFERENCES: tuple[Reference, ...] = ("first", "third")
HEADING_MODES: tuple[HeadingMode, ...] = ("shortest", "absolute")
LAWS: tuple[Law, ...] = ("thesis", "feedforward")
"""thesis: eq. 3.9 alone; feedforward: with reference feedforward through the plant model."""
MODES: tuple[Mode, ...] = ("tree", "free", "manual")
"""Supervisor modes, by their code in the log (0 tree controller, 1 free-ROV station keeping,
2 flown by hand: the pilot's demand, ``Simulation.set_pilot_demand``)."""


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
                    raise ValueError(
                        f"gains.{name}[{i}] must be in [0, {GAIN_LIMITS[name]:g}], got {v}"
                    )

    @staticmethod
    def of(kp: Sequence[float], ki: Sequence[float], kd: Sequence[float]) -> Gains:
        """Gains from three [surge, sway, yaw] sequences (checked like the constructor)."""
        for name, v in (("kp", kp), ("ki", ki), ("kd", kd)):
            if len(v) != 3:
                raise ValueError(
                    f"gains.{name} must have 3 entries [surge, sway, yaw], got {len(v)}"
                )
        return Gains(
            (float(kp[0]), float(kp[1]), float(kp[2])),
            (float(ki[0]), float(ki[1]), float(ki[2])),
            (float(kd[0]), float(kd[1]), float(kd[2])),
        )

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
    heave_force_newton: float = 0.0
    """Constant heave force of the ROV while on the tree (sea trial: small, downwards) [N]."""
    gains: Gains | None = None
    """None: the parameter set's gains."""
    r_mount_config_m: tuple[float, float, float] | None = None
    """The mounting vector the controller is configured with; None: the parameter set's."""

    def __post_init__(self) -> None:
        choices = {"feedback": FEEDBACKS, "allocation": ALLOCATIONS, "reference": REFERENCES}
        for name, allowed in choices.items():
            if getattr(self, name) not in allowed:
                raise ValueError(
                    f"{name} must be one of {', '.join(allowed)}, got {getattr(self, name)!r}"
                )
        if not math.isfinite(self.heave_force_newton) or abs(self.heave_force_newton) > 1e5:
            raise ValueError(
                f"heave_force_newton must be in [-1e5, 1e5] N, got {self.heave_force_newton}"
            )


def _ref_params(ps: ParameterSet, kind: Reference) -> FloatArray:
    """The parameter set's reference limits as the packed array of control.refkernel."""
    r = ps.spec.reference
    speed = np.array([r.max_speed_mps, r.max_speed_mps, math.radians(r.max_yaw_rate_deg_s)])
    if kind == "first":
        # thesis fig. 3.5: first-order low pass (time constant 1 / omega) with saturated rate
        return refkernel.pack_first_order(
            reference.FirstOrderParams(
                time_constant_s=np.full(3, 1.0 / r.bandwidth_rad_s), max_rate=speed
            )
        )
    return refkernel.pack_third_order(
        reference.ThirdOrderParams(
            natural_frequency_rad_s=np.full(3, r.bandwidth_rad_s),
            damping_ratio=np.full(3, r.damping_ratio),
            max_speed=speed,
            max_accel=np.array(
                [r.max_accel_mps2, r.max_accel_mps2, math.radians(r.max_yaw_accel_deg_s2)]
            ),
        )
    )


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
    return alloc.ThrusterConfig(
        T=sysm.rov_to_tree @ thr.T, k_pos=thr.k_pos, k_neg=thr.k_neg, n_max_rps=thr.n_max_rps
    )


def pilot_capacity(ps: ParameterSet) -> FloatArray:
    """Full stick on each pilot axis [X, Y, Z, N] in the ROV's own axes, row 0 the negative
    direction and row 1 the positive, as magnitudes [N, N, N, N m]: the largest force
    (moment) that axis can have ALONE (the other three zero) within the thrusters' force box
    (a small linear program, as ``model.dof_capacity``; roll and pitch are left to restoring).
    Several axes at full stick together ask for more than the thrusters give: the allocation
    saturates them in its priority order."""
    thr = ps.rov.thrusters
    return _pilot_capacity(thr.T, thr.f_max_neg, thr.f_max_pos)


@model.memo_by_arrays
def _pilot_capacity(T: FloatArray, f_max_neg: FloatArray, f_max_pos: FloatArray) -> FloatArray:
    rows = T[[0, 1, 2, 5]]
    bounds = list(zip(-f_max_neg, f_max_pos, strict=True))
    out = np.zeros((2, 4))
    for k in range(4):
        others = [i for i in range(4) if i != k]
        for j, sign in enumerate((-1.0, 1.0)):
            res = linprog(
                -sign * rows[k], A_eq=rows[others], b_eq=np.zeros(3), bounds=bounds, method="highs"
            )
            out[j, k] = sign * float(rows[k] @ res.x) if res.success else 0.0
    return out


def control_arrays(
    ps: ParameterSet,
    sysm: model.SystemModel,
    settings: ControlSettings,
    gains: Gains,
    p_eq: FloatArray,
    dt: float,
) -> loop.ControlArrays:
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
        feedback_ekf=settings.feedback == "ekf",
        use_ff=settings.feedforward,
        ref_kind=loop.REF_FIRST if settings.reference == "first" else loop.REF_THIRD,
        ref_params=_ref_params(ps, settings.reference),
        Kp=np.array(gains.kp, float),
        Ki=np.array(gains.ki, float),
        Kd=np.array(gains.kd, float),
        M=sysm.M.copy(),
        M_inv=m_inv,
        D_l=sysm.D_l.copy(),
        D_nl=sysm.D_nl.copy(),
        k_h=float(sysm.k_h),
        p_eq=np.asarray(p_eq, float).copy(),
        A=A.copy(),
        A_inv=np.linalg.inv(A),
        i_limit=0.9 * model.dof_capacity(cfg.T, cfg.f_max_neg, cfg.f_max_pos),
        heave_newton=float(settings.heave_force_newton),
        r_mount=sysm.r_rov_from_tree_tree_m.copy(),
        psi_rel=float(sysm.psi_rov_from_tree_rad),
        alloc_kind=kinds[settings.allocation],
        pinv_T=np.ascontiguousarray(pinv_plan.T_pinv),
        pinv_rows=np.asarray(pinv_plan.layout.dofs, np.int64),
        prio_A=prio_plan.A,
        prio_D=prio_plan.D,
        prio_R=prio_plan.R,
        prio_rows=np.asarray(prio_plan.layout.dofs, np.int64),
        f_lo=prio_plan.layout.f_lo.copy(),
        f_hi=prio_plan.layout.f_hi.copy(),
        alloc_tol=float(prio_plan.layout.tol),
        k_pos=thr.k_pos.copy(),
        k_neg=thr.k_neg.copy(),
        n_max=thr.n_max_rps.copy(),
        T6=np.ascontiguousarray(thr.T),
        rov_to_tree=np.ascontiguousarray(sysm.rov_to_tree),
        GQG=gqg,
        T_b=np.asarray(obs.bias_time_constant_s, float),
        r_pos=float(max(noise[0], 1e-3) ** 2),
        r_psi=float(max(noise[4], 1e-4) ** 2),
        r_dvl=float(max(noise[5], 1e-3) ** 2 + (noise[10] * r_lever) ** 2),
        r_gyro=float(max(noise[10], 1e-4) ** 2),
        q_lo=qcfg.lo,
        q_hi=qcfg.hi,
        q_wild=qcfg.wild_jump,
        q_rate=qcfg.max_rate,
        q_frozen=qcfg.frozen_count,
        q_var=qcfg.variance_limit,
        free_Kp=fkp,
        free_Ki=fki,
        free_Kd=fkd,
    )
