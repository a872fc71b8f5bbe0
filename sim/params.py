"""Parameter sets: validated files (pydantic) that build frozen numeric dataclasses.

A parameter set describes one physical configuration: the tree, the ROV and its thrusters, the
lifting wire, the ROV's mounting on the tree, the coupling spring, the sensors and the default
controller gains. Two sets ship with the product (``sim/presets/*.toml``):

- ``full-scale``: FMC EHXT tree (appendix B.1) with the work-class ROV (SF30k, B.3, thrust x10);
- ``model-scale``: the sea-trial module (B.2) with ROV Minerva (B.4).

Users load a set by name or from their own TOML/JSON file. Every number is checked on load; an
error names the field and the allowed range.
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Annotated

import numpy as np
from numpy.typing import NDArray
from pydantic import (
    AliasChoices,
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from sim import wire as wire_mod

PRESET_DIR = Path(__file__).with_name("presets")

FloatArray = NDArray[np.float64]
PositiveFloat = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]
FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
Vec3 = Annotated[list[FiniteFloat], Field(min_length=3, max_length=3)]
Vec6 = Annotated[list[FiniteFloat], Field(min_length=6, max_length=6)]
PositiveVec6 = Annotated[
    list[Annotated[float, Field(gt=0.0, allow_inf_nan=False)]], Field(min_length=6, max_length=6)
]
NonNegVec6 = Annotated[
    list[Annotated[float, Field(ge=0.0, allow_inf_nan=False)]], Field(min_length=6, max_length=6)
]


class ParameterError(ValueError):
    """A parameter file or value is invalid; the message names the field and allowed range."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def _matrix6(value: list[list[float]], name: str) -> list[list[float]]:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (6, 6):
        raise ValueError(f"{name} must be a 6x6 matrix, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    if not np.allclose(arr, arr.T, rtol=1e-9, atol=1e-9):
        raise ValueError(f"{name} must be symmetric")
    if np.min(np.linalg.eigvalsh(arr)) <= 0.0:
        raise ValueError(f"{name} must be positive definite")
    return value


class TreeSpec(_Strict):
    """The hanging module (Xmas tree)."""

    length_m: PositiveFloat = Field(le=20.0, description="box length along body x [m] (table B.1)")
    width_m: PositiveFloat = Field(le=20.0, description="box width along body y [m]")
    height_m: PositiveFloat = Field(le=20.0, description="box height along body z [m]")
    mass_kg: PositiveFloat = Field(le=5.0e5, description="mass in air [kg]")
    submerged_weight_newton: float | None = Field(
        default=None,
        gt=0.0,
        description="W0, weight in water [N]; default m g (1 - rho_w/rho_steel). The thesis "
        "never states it; two readings: a solid steel tree, 36 t x 9.81 x (1 - 1025/7850) = "
        "307.0 kN (the full-scale default, MODEL_NOTES), or the volume behind the thesis's "
        "added mass (15.7 m^3, eq. 2.18): 36 t x 9.81 - 1025 x 9.81 x 15.7 = 195.3 kN. W0 "
        "sets the wire's horizontal stiffness (eq. 2.30) and so how far the ROV can push the "
        "tree; it also gives the displaced water m - W0/g of the Froude-Krylov wave force",
        validation_alias=AliasChoices("submerged_weight_newton", "submerged_weight_n"),
    )
    attachment_height_m: PositiveFloat = Field(
        le=20.0, description="z_a: wire attachment above the centre of gravity [m] (eq. 2.22)"
    )
    rigid_body_inertia: PositiveVec6 = Field(description="diagonal of M_RB [kg, kg m^2] (B.1/B.5)")
    added_mass: PositiveVec6 = Field(description="diagonal of M_A [kg, kg m^2] (eq. 2.21/B.6)")
    linear_damping: NonNegVec6 | None = Field(
        default=None, description="diagonal of D_L; default from the drag rules (section 2.3.4)"
    )
    quadratic_damping: NonNegVec6 | None = Field(
        default=None, description="diagonal of D_NL; default from the drag rules"
    )


class ThrusterSpec(_Strict):
    """Thrusters: tau_b = T f, f_i = k_pos n^2 (n >= 0) or -k_neg n^2 (n < 0), |n| <= n_max."""

    configuration: list[Vec6] = Field(
        min_length=1,
        max_length=16,
        description="columns of the 6 x m thrust configuration matrix T, one row here per thruster",
    )
    k_pos: list[PositiveFloat] = Field(description="forward thrust coefficient [N/(rev/s)^2]")
    k_neg: list[PositiveFloat] = Field(description="reverse thrust coefficient [N/(rev/s)^2]")
    n_max_rps: list[Annotated[float, Field(gt=0.0, le=200.0)]] = Field(
        description="rated propeller speed [rev/s]"
    )

    @model_validator(mode="after")
    def _same_length(self) -> ThrusterSpec:
        m = len(self.configuration)
        for name in ("k_pos", "k_neg", "n_max_rps"):
            if len(getattr(self, name)) != m:
                raise ValueError(
                    f"{name} must have one entry per thruster ({m}), got {len(getattr(self, name))}"
                )
        return self


class RovSpec(_Strict):
    """The ROV (process plant model, section 2.2)."""

    name: str
    rigid_body_mass: list[Vec6] = Field(description="M_RB 6x6 [kg, kg m, kg m^2] (B.12/B.22)")
    added_mass: list[Vec6] = Field(description="M_A 6x6 (B.13/B.23)")
    linear_damping: NonNegVec6 = Field(description="diagonal of D_L (B.17/B.31)")
    quadratic_damping: NonNegVec6 = Field(description="diagonal of D_NL (B.16/B.30)")
    r_cg_m: Vec3 = Field(description="centre of gravity in body axes [m] (B.18/B.32)")
    r_cb_m: Vec3 = Field(description="centre of buoyancy in body axes [m]")
    buoyancy_ratio: float = Field(ge=0.9, le=1.1, description="B / W [-] (section 2.2.1)")
    thrusters: ThrusterSpec

    @field_validator("rigid_body_mass", "added_mass")
    @classmethod
    def _mass_matrix(cls, value: list[list[float]], info) -> list[list[float]]:
        return _matrix6(value, info.field_name)


class WireSpec(_Strict):
    """Lifting wire (MODEL_NOTES: not specified in the thesis)."""

    mass_per_length_kg_m: PositiveFloat = Field(le=500.0)
    diameter_m: PositiveFloat = Field(le=0.5)
    axial_stiffness_newton: PositiveFloat = Field(
        ge=1.0e4,
        le=1.0e11,
        description="EA [N]",
        validation_alias=AliasChoices("axial_stiffness_newton", "axial_stiffness_n"),
    )
    drag_coefficient: PositiveFloat = Field(le=3.0)

    @model_validator(mode="after")
    def _sinks(self) -> WireSpec:
        if self.to_numeric().submerged_weight_per_length() <= 0.0:
            raise ValueError(
                "mass_per_length_kg_m: the wire must be heavier than the water it "
                "displaces (submerged weight per metre > 0)"
            )
        return self

    def to_numeric(self) -> wire_mod.WireProperties:
        return wire_mod.WireProperties(
            self.mass_per_length_kg_m,
            self.diameter_m,
            self.axial_stiffness_newton,
            self.drag_coefficient,
        )


class MountSpec(_Strict):
    """Where the ROV grips the tree. The vector goes FROM the tree's origin TO the ROV's origin,
    in the tree's body axes (the sea trial entered it with the wrong sign, thesis 6.2.1)."""

    r_rov_from_tree_tree_m: Vec3 = Field(
        description="tree origin -> ROV origin, tree body axes [m]; thesis: [-2, 0, 0]"
    )
    psi_rov_from_tree_deg: float = Field(
        default=0.0, ge=-180.0, le=180.0, description="ROV heading relative to the tree [deg]"
    )


class CouplingSpec(_Strict):
    """The stiff gripper spring between ROV and tree (eq. 2.45-2.47)."""

    natural_frequency_hz: float = Field(
        default=2.5,
        gt=0.2,
        le=8.0,
        description="uncoupled ROV-on-spring frequency [Hz]; must stay well below 1/(2 pi dt)",
    )
    damping_ratio: float = Field(default=0.3, ge=0.0, le=2.0, description="structural damping [-]")


class SensorSpec(_Strict):
    """One sensor: white noise, zero-order hold at its own rate, random dropouts (sec. 2.6.4)."""

    rate_hz: float = Field(gt=0.0, le=100.0)
    noise_std: float = Field(
        ge=0.0, allow_inf_nan=False, description="1-sigma noise per axis [m, m/s, rad or rad/s]"
    )
    dropout_probability: float = Field(default=0.0, ge=0.0, lt=1.0)


class SensorsSpec(_Strict):
    """The ROV's sensor suite (section 2.6); noise in SI (the file may use the *_deg variants)."""

    position: SensorSpec = Field(description="USBL/LBL position of the ROV origin, NED [m]")
    depth: SensorSpec = Field(description="pressure depth of the ROV origin [m]")
    compass: SensorSpec = Field(description="heading [rad]")
    dvl: SensorSpec = Field(description="ROV body velocity [m/s]")
    gyro: SensorSpec = Field(description="ROV body angular rate [rad/s]")


GAIN_LIMITS = {"kp": 1.0e7, "ki": 1.0e6, "kd": 1.0e8}
"""Largest accepted controller gain per term; parameter files, missions, the console and the
control system all check against these."""
_THREE = Field(min_length=3, max_length=3)
KpVector = Annotated[
    list[Annotated[float, Field(ge=0.0, le=GAIN_LIMITS["kp"], allow_inf_nan=False)]], _THREE
]
"""[surge, sway, yaw] proportional gains, each in [0, GAIN_LIMITS["kp"]]."""
KiVector = Annotated[
    list[Annotated[float, Field(ge=0.0, le=GAIN_LIMITS["ki"], allow_inf_nan=False)]], _THREE
]
KdVector = Annotated[
    list[Annotated[float, Field(ge=0.0, le=GAIN_LIMITS["kd"], allow_inf_nan=False)]], _THREE
]


class GainsSpec(_Strict):
    """Nonlinear PID gains in the tree frame, [surge, sway, yaw] (B.9-B.11, B.19-B.21)."""

    kp: KpVector
    ki: KiVector
    kd: KdVector


class ReferenceSpec(_Strict):
    """Reference-model limits (section 3.3), [north/east, yaw]."""

    max_speed_mps: float = Field(gt=0.0, le=1.0, description="translation speed limit [m/s]")
    max_accel_mps2: float = Field(gt=0.0, le=1.0, description="translation accel limit [m/s^2]")
    max_yaw_rate_deg_s: float = Field(gt=0.0, le=30.0, description="turn rate limit [deg/s]")
    max_yaw_accel_deg_s2: float = Field(gt=0.0, le=10.0, description="turn accel limit [deg/s^2]")
    bandwidth_rad_s: float = Field(gt=0.0, le=5.0, description="omega of the models [rad/s]")
    damping_ratio: float = Field(
        default=1.0,
        ge=0.5,
        le=3.0,
        description="third order: relative damping (>= 1: no overshoot)",
    )


class ObserverSpec(_Strict):
    """EKF tuning (table 3.1), [surge, sway, yaw]."""

    process_force_std: Annotated[
        list[Annotated[float, Field(gt=0.0, le=1e7)]], Field(min_length=3, max_length=3)
    ] = Field(description="unmodelled force noise intensity [N, N, N m per sqrt(Hz)]")
    bias_drive_std: Annotated[
        list[Annotated[float, Field(gt=0.0, le=1e7)]], Field(min_length=3, max_length=3)
    ] = Field(description="bias random-walk intensity [N, N, N m per sqrt(s)]")
    bias_time_constant_s: Annotated[
        list[Annotated[float, Field(gt=1.0, le=1e6)]], Field(min_length=3, max_length=3)
    ] = Field(description="T_b of eq. 2.48b [s]")


class DockingSpec(_Strict):
    """Guideposts on the docking frame and funnels on the tree (thesis chapter 5)."""

    post_xy_m: list[Annotated[list[FiniteFloat], Field(min_length=2, max_length=2)]] = Field(
        min_length=1, max_length=8, description="post positions in the frame's axes [m]"
    )
    post_height_m: float = Field(gt=0.0, le=10.0)
    post_radius_m: float = Field(gt=0.0, le=1.0)
    funnel_mouth_radius_m: float = Field(gt=0.0, le=2.0)
    funnel_bore_radius_m: float = Field(
        gt=0.0,
        le=2.0,
        description="radius of the funnel's bore above its cone: a landed post can move this "
        "minus the post radius [m]",
    )
    funnel_cone_height_m: float = Field(
        gt=0.0,
        le=5.0,
        description="height of the cone from the mouth to the bore [m]; the cone must be no "
        "flatter than 45 deg (mouth minus bore radius at most this height)",
    )
    max_landing_speed_mps: float = Field(gt=0.0, le=2.0)
    frame_size_m: Annotated[
        list[Annotated[float, Field(gt=0.0, le=50.0)]], Field(min_length=2, max_length=2)
    ]

    @model_validator(mode="after")
    def _mouth_wider_than_post(self) -> DockingSpec:
        if self.funnel_mouth_radius_m <= self.post_radius_m:
            raise ValueError("funnel_mouth_radius_m must be larger than post_radius_m")
        if not self.post_radius_m < self.funnel_bore_radius_m <= self.funnel_mouth_radius_m:
            raise ValueError(
                "funnel_bore_radius_m must be larger than post_radius_m and at most "
                "funnel_mouth_radius_m"
            )
        # the contact model picks the nearer of the cone wall and the bottom plate at the
        # mouth's lip; the two agree there (no jump in contact energy) only if the wall's
        # horizontal run per metre of height is at most 1
        if self.funnel_mouth_radius_m - self.funnel_bore_radius_m > self.funnel_cone_height_m:
            raise ValueError(
                "funnel_cone_height_m must be at least funnel_mouth_radius_m - "
                "funnel_bore_radius_m (a cone no flatter than 45 deg)"
            )
        return self

    def to_numeric(self):
        from sim.docking import DockingLayout

        return DockingLayout(
            np.asarray(self.post_xy_m, float),
            self.post_height_m,
            self.post_radius_m,
            self.funnel_mouth_radius_m,
            self.funnel_bore_radius_m,
            self.funnel_cone_height_m,
            self.max_landing_speed_mps,
            np.asarray(self.frame_size_m, float),
        )


class ParameterSetSpec(_Strict):
    """A whole parameter set as it stands in a file."""

    name: str
    description: str = ""
    tree: TreeSpec
    rov: RovSpec
    wire: WireSpec
    mount: MountSpec
    coupling: CouplingSpec = CouplingSpec()
    sensors: SensorsSpec
    gains: GainsSpec
    reference: ReferenceSpec
    observer: ObserverSpec
    docking: DockingSpec


# --------------------------------------------------------------------------------------------
# Numeric dataclasses used by the core
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TreeParams:
    """Numeric tree model (section 2.3)."""

    dimensions_m: FloatArray
    """[length, width, height] of the box [m] (table B.1 / B.2)."""
    mass_kg: float
    """Mass in air [kg]."""
    submerged_weight_newton: float
    """W0 [N] (MODEL_NOTES: 307.0 kN at full scale)."""
    attachment_height_m: float
    """z_a [m], wire attachment above the centre of gravity (eq. 2.22)."""
    M_rb: FloatArray
    """Rigid-body mass matrix 6x6 (eq. 2.16 / B.1 / B.5)."""
    M_a: FloatArray
    """Added mass 6x6 (eq. 2.21 / B.6)."""
    D_l: FloatArray
    """Linear damping diagonal (6,) [N s/m, N m s/rad]."""
    D_nl: FloatArray
    """Quadratic damping diagonal (6,) [N s^2/m^2, N m s^2/rad^2]."""


@dataclass(frozen=True)
class ThrusterParams:
    """Thrusters (eq. 2.13 with u = n|n| and direction-dependent coefficients)."""

    T: FloatArray
    """Thrust configuration matrix 6 x m (B.15 / B.29)."""
    k_pos: FloatArray
    """Forward thrust coefficient (m,) [N/(rev/s)^2]."""
    k_neg: FloatArray
    """Reverse thrust coefficient (m,) [N/(rev/s)^2]."""
    n_max_rps: FloatArray
    """Rated propeller speed (m,) [rev/s]."""

    @property
    def f_max_pos(self) -> FloatArray:
        """Largest forward thrust per thruster [N]."""
        return self.k_pos * self.n_max_rps**2

    @property
    def f_max_neg(self) -> FloatArray:
        """Largest reverse thrust per thruster (positive number) [N]."""
        return self.k_neg * self.n_max_rps**2


@dataclass(frozen=True)
class RovParams:
    """Numeric ROV model (section 2.2)."""

    name: str
    """Which ROV."""
    M_rb: FloatArray
    """Rigid-body mass matrix 6x6 (B.12 / B.22)."""
    M_a: FloatArray
    """Added mass 6x6 (B.13 symmetrised / B.23 as read in MODEL_NOTES)."""
    D_l: FloatArray
    """Linear damping diagonal (6,) (B.17 / B.31)."""
    D_nl: FloatArray
    """Quadratic damping diagonal (6,) (B.16 / B.30)."""
    r_cg_m: FloatArray
    """Centre of gravity, body axes [m]."""
    r_cb_m: FloatArray
    """Centre of buoyancy, body axes [m]."""
    weight_newton: float
    """W = m g [N]."""
    buoyancy_newton: float
    """B [N], slightly more than W (section 2.2.1)."""
    thrusters: ThrusterParams
    """Thruster model."""


@dataclass(frozen=True)
class MountParams:
    """Mounting of the ROV on the tree."""

    r_rov_from_tree_tree_m: FloatArray
    """Tree origin -> ROV origin in tree body axes [m] (r_R^s of eq. 2.45)."""
    psi_rov_from_tree_rad: float
    """ROV heading relative to the tree [rad]."""


@dataclass(frozen=True)
class CouplingParams:
    """Gripper spring (eq. 2.46), diagonal in ROV body axes."""

    stiffness: FloatArray
    """(6,) [N/m, N m/rad]."""
    damping: FloatArray
    """(6,) [N s/m, N m s/rad]."""
    natural_frequency_hz: float
    """Frequency the stiffness was chosen for [Hz]."""


@dataclass(frozen=True)
class ParameterSet:
    """Everything the plant needs, numeric and frozen."""

    name: str
    tree: TreeParams
    rov: RovParams
    wire: wire_mod.WireProperties
    mount: MountParams
    coupling: CouplingParams
    sensors: SensorsSpec
    gains: GainsSpec
    spec: ParameterSetSpec = field(repr=False)


def tree_drag_coefficients(
    length_m: float, width_m: float, height_m: float, heave_linear_n_s_m: float
) -> tuple[FloatArray, FloatArray]:
    """Diagonal damping of the tree from the thesis's drag rules (section 2.3.4, eq. 2.39-2.40).

    Returns (D_l, D_nl), both (6,). Translational drag F = 1/2 rho A (C_l U + C_nl |U| U) with
    the fitted C_nl = 0.6285, C_l = 0.1433 per 1/2 rho A, times 1.2 in surge (the real tree is
    less open than the test model), sway = 1.8 x surge coefficients, heave quadratic = sway's,
    heave linear given (1 % of critical, computed by the caller from the wire stiffness).
    A is the projected area normal to the motion: surge W H, sway L H, heave L W.

    Rotation: strip theory on the box with C_d = 1.0. A face of extent b along the lever and
    h across it, turning about its centre, gives N = rho C_d h b^4 / 64 |w| w; both face pairs
    of the box are counted (e.g. yaw: H L^4 + H W^4). No linear rotational damping is given by
    the thesis for full scale; a small value (1 % of the quadratic coefficient per rad/s)
    keeps the model from ringing forever at zero speed.
    """
    rho = wire_mod.RHO_WATER
    c_nl_x, c_l_x = 1.2 * 0.6285, 1.2 * 0.1433
    c_nl_y, c_l_y = 1.8 * c_nl_x, 1.8 * c_l_x
    area = np.array([width_m * height_m, length_m * height_m, length_m * width_m])
    half_rho_a = 0.5 * rho * area
    d_nl = np.zeros(6)
    d_l = np.zeros(6)
    d_nl[0:3] = half_rho_a * np.array([c_nl_x, c_nl_y, c_nl_y])
    d_l[0:3] = half_rho_a * np.array([c_l_x, c_l_y, 0.0])
    d_l[2] = heave_linear_n_s_m
    cd_rot = 1.0
    L, W, H = length_m, width_m, height_m
    d_nl[3] = rho * cd_rot * L * (W**4 + H**4) / 64.0
    d_nl[4] = rho * cd_rot * W * (L**4 + H**4) / 64.0
    d_nl[5] = rho * cd_rot * H * (L**4 + W**4) / 64.0
    d_l[3:6] = 0.01 * d_nl[3:6]
    return d_l, d_nl


ADDED_MASS_VOLUME_M3 = 15.7
"""Volume of the full-scale tree behind its added mass in the thesis (eq. 2.18) [m^3]: the
second reading of its submerged weight (``submerged_weight_from_volume``)."""


def submerged_weight_from_volume(mass_kg: float, volume_m3: float) -> float:
    """W0 = m g - rho_w g V [N] of a body of mass m [kg] displacing V [m^3] (36 t and the
    15.7 m^3 of eq. 2.18: 195.3 kN)."""
    return mass_kg * wire_mod.GRAVITY - wire_mod.RHO_WATER * wire_mod.GRAVITY * volume_m3


def with_submerged_weight(ps: ParameterSet, weight_newton: float) -> ParameterSet:
    """The same parameter set with the tree's submerged weight W0 set to ``weight_newton``
    [N] (> 0; checked like a file's value)."""
    try:
        tree = TreeSpec.model_validate(
            {**ps.spec.tree.model_dump(), "submerged_weight_newton": weight_newton}
        )
    except ValidationError as err:
        raise ParameterError(_format_validation_error(f"{ps.name} tree", err)) from None
    return build(ps.spec.model_copy(update=dict(tree=tree)))


def _tree_params(spec: TreeSpec, wire: wire_mod.WireProperties) -> TreeParams:
    w0 = spec.submerged_weight_newton or wire_mod.submerged_weight(spec.mass_kg)
    m_rb = np.diag(np.asarray(spec.rigid_body_inertia, dtype=float))
    m_a = np.diag(np.asarray(spec.added_mass, dtype=float))
    # Heave linear damping: 1 % of critical with the wire's elastic stiffness at 400 m
    # (section 2.3.4): c = 2 * 0.01 * sqrt(k (m + m_a)).
    k_400 = wire.axial_stiffness_newton / 400.0
    c_heave = 2.0 * 0.01 * math.sqrt(k_400 * (m_rb[2, 2] + m_a[2, 2]))
    d_l, d_nl = tree_drag_coefficients(spec.length_m, spec.width_m, spec.height_m, c_heave)
    if spec.linear_damping is not None:
        d_l = np.asarray(spec.linear_damping, dtype=float)
    if spec.quadratic_damping is not None:
        d_nl = np.asarray(spec.quadratic_damping, dtype=float)
    return TreeParams(
        dimensions_m=np.array([spec.length_m, spec.width_m, spec.height_m]),
        mass_kg=spec.mass_kg,
        submerged_weight_newton=float(w0),
        attachment_height_m=spec.attachment_height_m,
        M_rb=m_rb,
        M_a=m_a,
        D_l=d_l,
        D_nl=d_nl,
    )


def _rov_params(spec: RovSpec) -> RovParams:
    m_rb = np.asarray(spec.rigid_body_mass, dtype=float)
    weight = float(m_rb[0, 0] * wire_mod.GRAVITY)
    thr = spec.thrusters
    return RovParams(
        name=spec.name,
        M_rb=m_rb,
        M_a=np.asarray(spec.added_mass, dtype=float),
        D_l=np.asarray(spec.linear_damping, dtype=float),
        D_nl=np.asarray(spec.quadratic_damping, dtype=float),
        r_cg_m=np.asarray(spec.r_cg_m, dtype=float),
        r_cb_m=np.asarray(spec.r_cb_m, dtype=float),
        weight_newton=weight,
        buoyancy_newton=weight * spec.buoyancy_ratio,
        thrusters=ThrusterParams(
            T=np.asarray(thr.configuration, dtype=float).T,
            k_pos=np.asarray(thr.k_pos, dtype=float),
            k_neg=np.asarray(thr.k_neg, dtype=float),
            n_max_rps=np.asarray(thr.n_max_rps, dtype=float),
        ),
    )


def _coupling_params(spec: CouplingSpec, rov: RovParams) -> CouplingParams:
    """Stiffness chosen so that the ROV alone on the spring rings at the given frequency:
    k_i = omega^2 (M_RB + M_A)_ii. Against the much heavier tree the coupled mode sits just
    above that frequency (measured in tests/test_plant.py)."""
    omega = 2.0 * math.pi * spec.natural_frequency_hz
    m_diag = np.diag(rov.M_rb + rov.M_a)
    return CouplingParams(
        stiffness=omega**2 * m_diag,
        damping=2.0 * spec.damping_ratio * omega * m_diag,
        natural_frequency_hz=spec.natural_frequency_hz,
    )


def build(spec: ParameterSetSpec) -> ParameterSet:
    """Turn a validated file model into the numeric parameter set."""
    wire = spec.wire.to_numeric()
    rov = _rov_params(spec.rov)
    return ParameterSet(
        name=spec.name,
        tree=_tree_params(spec.tree, wire),
        rov=rov,
        wire=wire,
        mount=MountParams(
            np.asarray(spec.mount.r_rov_from_tree_tree_m, dtype=float),
            math.radians(spec.mount.psi_rov_from_tree_deg),
        ),
        coupling=_coupling_params(spec.coupling, rov),
        sensors=spec.sensors,
        gains=spec.gains,
        spec=spec,
    )


def available_presets() -> list[str]:
    """Names of the parameter sets shipped with the product."""
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


def _format_validation_error(source: str, err: ValidationError) -> str:
    lines = [f"invalid parameter set {source}:"]
    for e in err.errors():
        loc = ".".join(str(p) for p in e["loc"])
        lines.append(f"  {loc}: {e['msg']} (got {e.get('input')!r})")
    return "\n".join(lines)


def parse_spec(data: dict, source: str = "<data>") -> ParameterSetSpec:
    """Validate a parameter-set dictionary; raises ParameterError naming field and range."""
    try:
        return ParameterSetSpec.model_validate(data)
    except ValidationError as err:
        raise ParameterError(_format_validation_error(source, err)) from None


def load_spec(name_or_path: str | Path) -> ParameterSetSpec:
    """Load a parameter set by preset name or from a .toml / .json file."""
    path = Path(name_or_path)
    if not path.suffix:
        preset = PRESET_DIR / f"{name_or_path}.toml"
        if not preset.exists():
            raise ParameterError(
                f"unknown parameter set {name_or_path!r}; "
                f"available: {', '.join(available_presets())}, or a file path"
            )
        path = preset
    if not path.exists():
        raise ParameterError(f"parameter file not found: {path}")
    return _spec_of_text(path.read_text(), path.suffix == ".json", str(path))


@lru_cache(maxsize=32)
def _spec_of_text(text: str, is_json: bool, source: str) -> ParameterSetSpec:
    """A parameter file's text parsed and validated, kept by its text (the spec is frozen):
    each run of a campaign loads its set again, and parsing the TOML cost some 2 ms a run.
    A file edited between runs is read again and parsed anew."""
    try:
        data = json.loads(text) if is_json else tomllib.loads(text)
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as err:
        raise ParameterError(f"cannot parse {source}: {err}") from None
    return parse_spec(data, source)


def load(name_or_path: str | Path) -> ParameterSet:
    """Load and build a parameter set."""
    return build(load_spec(name_or_path))


def froude_scale(spec: ParameterSetSpec, scale: float) -> ParameterSetSpec:
    """Froude-scale the tree of a parameter set by the length ratio lambda = model/full.

    Lengths x lambda, masses and forces x lambda^3, moments of inertia x lambda^5, linear
    damping (force/velocity) x lambda^2.5, quadratic damping (force/velocity^2) x lambda^2,
    rotational damping likewise with two more powers of length (eq. 2.37, 2.38, 2.43; same
    water density assumed). The ROV, wire and sensors are not scaled: a model test uses a real
    ROV and a real wire."""
    if not (0.0 < scale <= 10.0) or not math.isfinite(scale):
        raise ParameterError(f"scale must be in (0, 10], got {scale}")
    lam = scale
    t = spec.tree
    inertia = [v * lam**3 for v in t.rigid_body_inertia[:3]] + [
        v * lam**5 for v in t.rigid_body_inertia[3:]
    ]
    added = [v * lam**3 for v in t.added_mass[:3]] + [v * lam**5 for v in t.added_mass[3:]]

    def _damp(values: list[float] | None, trans: float, rot: float) -> list[float] | None:
        if values is None:
            return None
        return [v * trans for v in values[:3]] + [v * rot for v in values[3:]]

    tree = t.model_copy(
        update=dict(
            length_m=t.length_m * lam,
            width_m=t.width_m * lam,
            height_m=t.height_m * lam,
            mass_kg=t.mass_kg * lam**3,
            submerged_weight_newton=(
                None if t.submerged_weight_newton is None else t.submerged_weight_newton * lam**3
            ),
            attachment_height_m=t.attachment_height_m * lam,
            rigid_body_inertia=inertia,
            added_mass=added,
            linear_damping=_damp(t.linear_damping, lam**2.5, lam**4.5),
            quadratic_damping=_damp(t.quadratic_damping, lam**2, lam**5),
        )
    )
    return spec.model_copy(update=dict(name=f"{spec.name}-x{scale:g}", tree=tree))
