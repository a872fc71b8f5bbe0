"""Mission files: a versioned TOML format, validated with pydantic.

A mission is a set-up (parameter set, depth, current, waves, sensors and control choices, seed)
and a sequence of legs. Legs are data: each has a ``type`` and its values, and the runner
(``missions.runner``) looks the type up in a registry. Angles are degrees in the file (the
interface), radians inside.
"""

from __future__ import annotations

import functools
import re
import tomllib
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Literal

import tomli_w
from pydantic import (
    AfterValidator,
    AliasChoices,
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from control.config import Allocation, Feedback, Mode, Reference
from control.faults import Fault
from sim import dynamic_wire, site
from sim import params as params_mod
from sim.environment import DEFAULT_WAVE_LOAD
from sim.params import KdVector, KiVector, KpVector

WaveLoad = Literal["drag", "morison"]
"""sim.environment.WAVE_LOADS, as a type for the file's validation."""
VesselMode = Literal["auto", "advise", "fixed"]
"""A dock leg's vessel: moved by the leg to where the ROV holds the tree with thrust to spare
(``missions.assist``), advised to the operator, or left where it is."""
VESSEL_MODES: tuple[str, ...] = typing.get_args(VesselMode)

FORMAT_VERSION = 1
LIBRARY_DIR = Path(__file__).with_name("library")

Finite = Annotated[float, Field(allow_inf_nan=False)]


def within(lo: float, hi: float, unit: str) -> Callable[[float], float]:
    """A check whose error names the whole range ('must be in [-1000, 1000] m'), not one
    side of it as pydantic's ge/le do."""

    def check(value: float) -> float:
        if not lo <= value <= hi:
            raise ValueError(f"must be in [{lo:g}, {hi:g}] {unit}")
        return value

    return check


def _bounds(lo: float, hi: float) -> typing.Any:
    """A finite number whose JSON schema carries both ends of ``within``'s range."""
    return Field(allow_inf_nan=False, json_schema_extra={"minimum": lo, "maximum": hi})


SITE_RANGE_M = 1000.0
"""Horizontal positions on the site (crane tip, docking frame, waypoints) within +-this of
the origin [m]: the console's vessel and move legs reach as far (a tree hangs under its crane
tip; a frame a kilometre off it is already out of the ROV's reach)."""
SURVEY_ERROR_MAX_M = 50.0
"""Largest charted-to-real offset of a docking frame [m] (campaigns vary it by +-20 m)."""
MOUNT_RANGE_M = 20.0
"""Each component of a configured mount vector within +-this [m] (the full-scale ROV sits
2 m behind the tree's centre)."""
SiteM = Annotated[
    float,
    _bounds(-SITE_RANGE_M, SITE_RANGE_M),
    AfterValidator(within(-SITE_RANGE_M, SITE_RANGE_M, "m")),
]
SurveyM = Annotated[
    float,
    _bounds(-SURVEY_ERROR_MAX_M, SURVEY_ERROR_MAX_M),
    AfterValidator(within(-SURVEY_ERROR_MAX_M, SURVEY_ERROR_MAX_M, "m")),
]
MountM = Annotated[
    float,
    _bounds(-MOUNT_RANGE_M, MOUNT_RANGE_M),
    AfterValidator(within(-MOUNT_RANGE_M, MOUNT_RANGE_M, "m")),
]
_NE = Field(min_length=2, max_length=2)


class MissionError(ValueError):
    """A mission file is invalid; the message names the file, the field and what is allowed."""


MAX_LEGS = 200
"""Legs in one mission at most (the sea trial of appendix C has 19)."""
MAX_MISSION_S = 48 * 3600.0
"""Longest mission: the legs' timeouts added up [s] (two days; the sea trial takes 25 min)."""
NAME_CHARS = "letters, digits, spaces and - _ . , : ( ) +"
"""The characters of a name, as its error message lists them."""
NAME_RE = re.compile(r"^[\w .,:()+-]{1,80}$")
"""Mission names: 1 to 80 of ``NAME_CHARS`` (letters and digits of any script). Names label
recordings and are shown to every viewer, so nothing in them is markup, a path, a control
code, a direction override or an invisible character."""
LEG_NAME_RE = re.compile(r"^[\w .,:()+-]{0,80}$")


def _check_name(value: str, pattern: re.Pattern[str], what: str) -> str:
    if not pattern.fullmatch(value):
        raise ValueError(
            f"{what} must be 1 to 80 characters: {NAME_CHARS} (got {len(value)} characters)"
        )
    if value != " ".join(value.split()):
        raise ValueError(
            f"{what} must not start or end with a space or hold two in a row (names that "
            "differ only in spaces look alike in every list)"
        )
    return value


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class CurrentSetup(_Model):
    speed_mps: float = Field(ge=0.0, le=3.0, description="current speed [m/s]")
    direction_deg: float = Field(
        ge=-360.0, le=360.0, description="direction the current flows towards [deg]"
    )
    speed_walk_mps_per_sqrt_s: float = Field(default=0.0, ge=0.0, le=0.1)
    direction_walk_deg_per_sqrt_s: float = Field(default=0.0, ge=0.0, le=10.0)
    speed_band_mps: float = Field(
        default=0.0, ge=0.0, le=1.0, description="random walk stays within speed +- band"
    )
    direction_band_deg: float = Field(default=0.0, ge=0.0, le=180.0)


class WaveSetup(_Model):
    significant_height_m: float = Field(ge=0.0, le=30.0)
    peak_period_s: float = Field(gt=0.0, le=40.0)
    direction_deg: float = Field(ge=-360.0, le=360.0)
    load: WaveLoad = Field(
        default=typing.cast(WaveLoad, DEFAULT_WAVE_LOAD),
        description="how the waves load the tree and the ROV: 'morison' (relative-velocity "
        "drag, added mass and Froude-Krylov on the water's acceleration; the default, the "
        "complete load) or 'drag' (relative-velocity drag only, as table 4.1 of the thesis "
        "behaves)",
    )
    water_depth_m: float | None = Field(
        default=None,
        ge=1.0,
        le=11000.0,
        description="seabed depth for the wave kinematics [m]; default: the docking frame's "
        "landing depth if the mission has one, else deep water",
    )


class VesselSetup(_Model):
    """The installation vessel moving with the sea (sim.vessel: a typical 130 m construction
    vessel's RAOs; the crane tip moves with its heave, surge, sway, roll and pitch). Needs
    ``waves``; without them the crane tip stands still."""

    heading_deg: float | None = Field(
        default=None,
        ge=-360.0,
        le=360.0,
        description="vessel heading [deg]; default: bow into the waves (head sea)",
    )
    heave_compensation: bool = Field(
        default=False, description="the crane's active heave compensation is on"
    )
    heave_compensation_efficiency: float = Field(
        default=0.8,
        ge=0.0,
        le=1.0,
        description="fraction of the crane tip's vertical motion the compensation removes [-]",
    )


class PlantVariation(_Model):
    """Differences between the real tree and what the controller is configured with
    (thesis section 4.2.3)."""

    mass_scale: float = Field(
        default=1.0, ge=0.1, le=5.0, description="tree rigid-body mass and inertia factor"
    )
    weight_scale: float = Field(
        default=1.0, ge=0.1, le=5.0, description="tree submerged weight factor"
    )


class DockingFrameSetup(_Model):
    """Where the docking frame stands; its posts come from the parameter set."""

    center_ne_m: Annotated[list[SiteM], _NE] = Field(
        description=f"north, east of the frame's centre, each in +-{SITE_RANGE_M:g} [m]"
    )
    heading_deg: float = Field(ge=-360.0, le=360.0, description="heading the tree must land at")
    landing_depth_m: float = Field(
        gt=5.0, le=4000.0, description="depth of the landing surface (seabed) [m]"
    )
    survey_error_ne_m: Annotated[list[SurveyM], _NE] = Field(
        default=[0.0, 0.0],
        description="where the frame really is, relative to the charted "
        f"center_ne_m the operator aligns to, each in +-{SURVEY_ERROR_MAX_M:g} [m]",
    )


class Setup(_Model):
    params: str = Field(description="parameter set name or file")
    depth_m: float = Field(gt=5.0, le=4000.0, description="tree depth [m]")
    crane_tip_n: Annotated[list[SiteM], _NE] = Field(
        default=[1.0, 1.0],
        description=f"north, east of the crane tip, each in +-{SITE_RANGE_M:g} [m]",
    )
    heading_deg: float = Field(default=0.0, ge=-360.0, le=360.0, description="initial heading")
    current: CurrentSetup = CurrentSetup(speed_mps=0.0, direction_deg=0.0)
    waves: WaveSetup | None = None
    vessel: VesselSetup | None = None
    wire: Literal["quasi-static", "elastic", "moordyn"] = Field(
        default="quasi-static",
        description="lift wire in the plant: quasi-static (spring on the tree's inertia), "
        "elastic (with the wire's first axial mode: a third of its mass at the tree and "
        "axial damping; resonance, slack and snap loads) or moordyn (a lumped-mass line "
        "through MoorDyn, all its axial modes; tens of times slower)",
    )
    feedback: Feedback = "perfect"
    allocation: Allocation = "priority"
    reference: Reference = "third"
    feedforward: bool = False
    heave_force_newton: float = Field(
        default=0.0,
        ge=-1.0e5,
        le=1.0e5,
        description="ROV heave force while on the tree [N]",
        validation_alias=AliasChoices("heave_force_newton", "heave_force_n"),
    )
    r_mount_config_m: Annotated[list[MountM], Field(min_length=3, max_length=3)] | None = Field(
        default=None,
        description="mount vector the controller is configured with, each component in "
        f"+-{MOUNT_RANGE_M:g} m (default: the parameter set's)",
    )
    plant: PlantVariation = PlantVariation()
    docking_frame: DockingFrameSetup | None = None
    start_gripping: bool = Field(
        default=True,
        description="false: the ROV starts free, beside the tree, and a hookup leg brings it on",
    )
    seed: int = Field(default=0, ge=0, le=2**31 - 1)


class _Leg(_Model):
    name: str = Field(default="", description=f"0 to 80 characters: {NAME_CHARS}")
    score: bool = Field(default=False, description="count this leg in the mission's RMS")
    timeout_s: float = Field(default=3600.0, gt=0.0, le=86400.0)

    @field_validator("name")
    @classmethod
    def _name(cls, value: str) -> str:
        if not LEG_NAME_RE.fullmatch(value):
            raise ValueError(f"a leg's name holds 0 to 80 characters: {NAME_CHARS}")
        return value


class HoldLeg(_Leg):
    type: Literal["hold"]
    duration_s: float = Field(gt=0.0, le=86400.0)


class _Reaching(_Leg):
    """A leg that goes to a target and settles there: after settling, the tree (its true
    pose, as the camera shows it) must be within these tolerances of the target, or the leg
    fails (the mission goes on, and is reported failed)."""

    tolerance_m: float = Field(
        default=0.1, gt=0.0, le=100.0, description="horizontal distance allowed [m]"
    )
    tolerance_deg: float = Field(
        default=2.0, gt=0.0, le=180.0, description="heading error allowed [deg]"
    )


class RotateLeg(_Reaching):
    type: Literal["rotate"]
    angle_deg: float = Field(
        ge=-1080.0, le=1080.0, description="positive = clockwise seen from above; 360 allowed"
    )
    settle_s: float = Field(default=60.0, ge=0.0, le=3600.0)


class MoveLeg(_Reaching):
    type: Literal["move"]
    north_m: float = Field(ge=-1000.0, le=1000.0)
    east_m: float = Field(ge=-1000.0, le=1000.0)
    heading_deg: float | None = Field(default=None, ge=-360.0, le=360.0)
    relative: bool = Field(default=True, description="relative to the present target")
    settle_s: float = Field(default=30.0, ge=0.0, le=3600.0)


class StepLeg(_Reaching):
    """A step of the target (no settling wait: the response over ``duration_s`` is what is
    studied); at its end the tree must be within the tolerances of the stepped target."""

    type: Literal["step"]
    north_m: float = Field(ge=-1000.0, le=1000.0)
    east_m: float = Field(ge=-1000.0, le=1000.0)
    heading_deg: float = Field(ge=-360.0, le=360.0)
    relative: bool = True
    duration_s: float = Field(gt=0.0, le=86400.0)


class SquareLeg(_Reaching):
    type: Literal["square"]
    side_m: float = Field(gt=0.0, le=100.0)
    heading_deg: float | None = Field(
        default=None, ge=-360.0, le=360.0, description="heading held along the square"
    )
    clockwise: bool = True
    settle_s: float = Field(default=20.0, ge=0.0, le=3600.0)


class WaypointsLeg(_Reaching):
    type: Literal["waypoints"]
    points_ne_m: list[Annotated[list[SiteM], _NE]] = Field(
        min_length=1,
        max_length=200,
        description=f"[north, east] points, each coordinate in +-{SITE_RANGE_M:g} [m]",
    )
    relative: bool = True
    settle_s: float = Field(default=10.0, ge=0.0, le=3600.0)


class GainsLeg(_Leg):
    type: Literal["gains"]
    kp: KpVector
    ki: KiVector
    kd: KdVector


class ModeLeg(_Leg):
    type: Literal["mode"]
    mode: Mode
    grip: bool | None = Field(default=None, description="also grip (true) or release (false)")


class WaitLeg(_Leg):
    type: Literal["wait"]
    duration_s: float = Field(gt=0.0, le=86400.0)


class WireLeg(_Leg):
    """Lower (positive) or raise (negative) the tree with the winch."""

    type: Literal["wire"]
    change_m: float = Field(ge=-500.0, le=500.0, description="pay out (+) or haul in (-) [m]")
    rate_mps: float = Field(default=0.1, gt=0.0, le=1.0, description="winch speed [m/s]")
    settle_s: float = Field(default=20.0, ge=0.0, le=3600.0)


class VesselLeg(_Leg):
    """Move the vessel, and with it the crane tip the wire hangs from."""

    type: Literal["vessel"]
    north_m: float = Field(ge=-1000.0, le=1000.0)
    east_m: float = Field(ge=-1000.0, le=1000.0)
    relative: bool = True
    speed_mps: float = Field(default=0.1, gt=0.0, le=3.0)
    settle_s: float = Field(default=30.0, ge=0.0, le=3600.0)


class DockLeg(_Leg):
    """Land the tree on the docking frame: align over it at a hover height, lower, and check
    the funnels over the posts at contact."""

    type: Literal["dock"]
    hover_m: float = Field(
        default=1.0,
        gt=0.0,
        le=50.0,
        description="clearance of the tree's bottom over the post tops",
    )
    lower_rate_mps: float = Field(default=0.05, gt=0.0, le=0.5, description="winch speed down")
    align_tolerance_m: float = Field(
        default=0.05, gt=0.0, le=1.0, description="start lowering when aligned this well"
    )
    align_tolerance_deg: float = Field(default=1.0, gt=0.0, le=30.0)
    settle_s: float = Field(default=30.0, ge=0.0, le=3600.0)
    vessel: VesselMode = Field(
        default="auto",
        description=(
            "auto: the leg moves the vessel where the ROV can hold the tree over the frame; "
            "advise: it tells the operator where and waits; fixed: the vessel stays"
        ),
    )


class LiftLeg(_Leg):
    """Lift the tree off the frame (haul in) back to a hover height."""

    type: Literal["lift"]
    height_m: float = Field(
        default=1.0, gt=0.0, le=50.0, description="clearance of the bottom over the post tops"
    )
    rate_mps: float = Field(default=0.05, gt=0.0, le=0.5)
    settle_s: float = Field(default=30.0, ge=0.0, le=3600.0)


class HookupLeg(_Leg):
    """The free-flying ROV flies onto its mount on the tree, grips it, and the supervisor
    switches to the tree controller (appendix C step 4)."""

    type: Literal["hookup"]
    grip_tolerance_m: float = Field(default=0.05, gt=0.0, le=0.3)
    """How close the ROV must come to its mount before it grips [m]; at most the gripper's
    reach (control.simulation.GRIP_REACH_M)."""


class HeaveLeg(_Leg):
    """Set the ROV's constant heave force while on the tree (appendix C step 4.iii)."""

    type: Literal["heave"]
    force_newton: float = Field(
        ge=-1.0e5,
        le=1.0e5,
        description="positive = downwards [N]",
        validation_alias=AliasChoices("force_newton", "force_n"),
    )


Leg = Annotated[
    HoldLeg
    | RotateLeg
    | MoveLeg
    | StepLeg
    | SquareLeg
    | WaypointsLeg
    | GainsLeg
    | ModeLeg
    | WaitLeg
    | WireLeg
    | VesselLeg
    | DockLeg
    | LiftLeg
    | HookupLeg
    | HeaveLeg,
    Field(discriminator="type"),
]
LEG_TYPES = (
    "hold",
    "rotate",
    "move",
    "step",
    "square",
    "waypoints",
    "gains",
    "mode",
    "wait",
    "wire",
    "vessel",
    "dock",
    "lift",
    "hookup",
    "heave",
)


class FaultSpec(_Model):
    """A fault injected while the mission runs (control.faults: what each kind does and what
    its value means), e.g. the sea trial's broken DVL cable or the winch that slipped."""

    kind: str = Field(description="one of control.faults.FAULT_KINDS")
    start_s: Finite = Field(ge=0.0, le=MAX_MISSION_S, description="simulation time it starts [s]")
    duration_s: Finite = Field(gt=0.0, le=MAX_MISSION_S, description="how long it lasts [s]")
    value: Finite = Field(default=0.0, description="size, in the kind's unit")
    direction_deg: Finite = Field(default=0.0, ge=-360.0, le=360.0)
    thruster: int = Field(default=0, ge=0, description="thruster faults: which one (1-based)")

    @model_validator(mode="after")
    def _known(self) -> FaultSpec:
        self.fault()  # the kind and its value's range (ValueError names them)
        return self

    def fault(self) -> Fault:
        return Fault(
            self.kind, self.start_s, self.duration_s, self.value, self.direction_deg, self.thruster
        )


WIRE_LENGTH_RANGE_M = (1.0, 5000.0)
"""Unstretched wire the winch may pay out [m] (control.simulation.WIRE_LENGTH_RANGE_M)."""


@functools.lru_cache(maxsize=8)
def _preset(name: str) -> params_mod.ParameterSet:
    return params_mod.load(name)


def start_payout_m(setup: Setup) -> float:
    """Unstretched wire that hangs the tree at ``setup.depth_m`` [m]: the parameter set's
    equilibrium (``sim.site.wire_length_for_depth``: depth less the attachment height and
    the stretch) when it names one of the library's sets, else the depth itself. A path is
    never read here: a mission from the network is validated before its set is checked."""
    if setup.params not in params_mod.available_presets():
        return setup.depth_m
    ps = _preset(setup.params)
    return site.wire_length_for_depth(ps, setup.depth_m, 0.0, setup.current.speed_mps)


MAX_FAULTS = 50
MOORDYN_DEPTH_MIN_M = 25.0
"""Shallowest tree with the moordyn wire [m]: its centre hangs the attachment height (2.6 m
full scale) and the stretch below the wire's end, so 25 m leaves at least the 20 m of wire
``sim.dynamic_wire.COUPLED_LENGTH_RANGE_M`` asks for."""


class Mission(_Model):
    format_version: Literal[1] = Field(description="mission file format version")
    name: str = Field(description=f"1 to 80 characters: {NAME_CHARS}")
    description: str = Field(default="", max_length=2000)
    setup: Setup
    legs: list[Leg] = Field(min_length=1, max_length=MAX_LEGS)
    faults: list[FaultSpec] = Field(default_factory=list, max_length=MAX_FAULTS)

    @field_validator("name")
    @classmethod
    def _name(cls, value: str) -> str:
        return _check_name(value, NAME_RE, "name")

    @model_validator(mode="after")
    def _limits(self) -> Mission:
        total = sum(leg.timeout_s for leg in self.legs)
        if total > MAX_MISSION_S:
            raise ValueError(
                f"legs: their timeouts add up to {total:.0f} s; a mission may take at most "
                f"{MAX_MISSION_S:.0f} s (48 h)"
            )
        self._check_wire_payout()
        return self

    def _check_wire_payout(self) -> None:
        """Refuse a winch plan that hauls in more wire than there is (or pays out more than
        the winch holds), from the payout the set-up hangs the tree on (``start_payout_m``):
        the error gives the change the leg may ask for."""
        lo, hi = WIRE_LENGTH_RANGE_M
        if self.setup.wire == "moordyn":
            lo, hi = dynamic_wire.COUPLED_LENGTH_RANGE_M
            depth = self.setup.depth_m
            if not MOORDYN_DEPTH_MIN_M <= depth <= hi:
                raise ValueError(
                    f"setup.depth_m: the moordyn wire needs a tree depth in "
                    f"[{MOORDYN_DEPTH_MIN_M:g}, {hi:g}] m (at least {lo:g} m of wire), "
                    f"got {depth:g}"
                )
        if not any(leg.type == "wire" for leg in self.legs):
            return
        payout = start_payout_m(self.setup)
        for i, leg in enumerate(self.legs):
            if leg.type == "wire":
                if not lo <= payout + leg.change_m <= hi:
                    raise ValueError(
                        f"legs[{i + 1}] (wire).change_m: with about {payout:.1f} m of wire out "
                        f"there, change_m must be in [{lo - payout:.1f}, {hi - payout:.1f}] m "
                        f"(the wire stays in [{lo:g}, {hi:g}] m"
                        + (" with the moordyn wire)" if self.setup.wire == "moordyn" else ")")
                        + f", got {leg.change_m:g}"
                    )
                payout += leg.change_m
            elif leg.type in ("dock", "lift") and self.setup.docking_frame is not None:
                payout = self.setup.docking_frame.landing_depth_m

    @model_validator(mode="after")
    def _frame_for_docking(self) -> Mission:
        if self.setup.docking_frame is None:
            for i, leg in enumerate(self.legs):
                if leg.type in ("dock", "lift"):
                    raise ValueError(f"legs[{i + 1}] ({leg.type}) needs setup.docking_frame")
        if (
            self.setup.docking_frame is not None
            and self.setup.docking_frame.landing_depth_m <= self.setup.depth_m
        ):
            raise ValueError(
                "setup.docking_frame.landing_depth_m must be deeper than "
                "setup.depth_m (the tree starts above the frame)"
            )
        return self


def _where(data: dict, loc: tuple) -> str:
    """Human-readable location: legs[3] (rotate).angle_deg."""
    parts: list[str] = []
    node: object = data
    after_index = False
    for p in loc:
        was_index, after_index = after_index, isinstance(p, int)
        if isinstance(p, int):
            kind = (
                node[p].get("type")
                if isinstance(node, list) and p < len(node) and isinstance(node[p], dict)
                else None
            )
            parts[-1] = f"{parts[-1]}[{p + 1}]" + (f" ({kind})" if kind else "")
            node = node[p] if isinstance(node, list) and p < len(node) else None
        else:
            if was_index and str(p) in LEG_TYPES:
                continue  # a leg's discriminator tag, already shown (not setup.wire, .vessel)
            parts.append(str(p))
            node = node.get(p) if isinstance(node, dict) else None
    return ".".join(parts)


def _line_of(text: str, loc: tuple) -> int | None:
    """Line number (1-based) in a TOML text where the field at ``loc`` is written, if found."""
    lines = text.splitlines()
    start, end = 0, len(lines)
    keys = [p for p in loc if not (isinstance(p, str) and p in LEG_TYPES)]
    if keys and keys[0] == "legs" and len(keys) > 1 and isinstance(keys[1], int):
        headers = [i for i, ln in enumerate(lines) if ln.strip() == "[[legs]]"]
        if keys[1] >= len(headers):
            return None
        start = headers[keys[1]]
        end = headers[keys[1] + 1] if keys[1] + 1 < len(headers) else len(lines)
        keys = keys[2:]
        if not keys:
            return start + 1
    elif keys and isinstance(keys[0], str) and len(keys) > 1:
        section = "[" + ".".join(str(k) for k in keys[:-1] if isinstance(k, str)) + "]"
        for i, ln in enumerate(lines):
            if ln.strip() == section:
                start = i
                break
        keys = keys[-1:]
    for k in keys:
        if isinstance(k, str):
            for i in range(start, end):
                if lines[i].split("=")[0].strip() == k:
                    return i + 1
    return None


def parse_mission(data: dict, source: str = "<mission>", text: str | None = None) -> Mission:
    """Validate a mission dictionary; raise MissionError naming file, line (when the TOML text
    is given), field and allowed values."""
    try:
        return Mission.model_validate(data)
    except ValidationError as err:
        lines = [f"invalid mission {source}:"]
        for e in err.errors()[:MAX_ERRORS_SHOWN]:
            line = _line_of(text, e["loc"]) if text is not None else None
            where = f"line {line}: " if line else ""
            field = _where(data, e["loc"]) or "mission"
            msg = e["msg"].removeprefix("Value error, ")
            lines.append(f"  {where}{field}: {msg}{_got(e.get('input'))}")
        if err.error_count() > MAX_ERRORS_SHOWN:
            lines.append(f"  ... and {err.error_count() - MAX_ERRORS_SHOWN} more")
        raise MissionError("\n".join(lines)) from None


MAX_ERRORS_SHOWN = 20


def _got(value: object) -> str:
    """What was given, when it is a short scalar (an error never echoes a whole input back)."""
    if isinstance(value, bool | int | float) or (isinstance(value, str) and len(value) <= 40):
        text = repr(value)
        if text.isprintable():
            return f" (got {text})"
    return ""


def load_mission(path_or_name: str | Path) -> Mission:
    """Load a mission file, or a library mission by name."""
    path, text = read_named_file(
        path_or_name, LIBRARY_DIR, library_names, "mission", "a mission file", MissionError
    )
    return parse_text(text, str(path))


def read_named_file(
    path_or_name: str | Path,
    library_dir: Path,
    names: Callable[[], list[str]],
    what: str,
    kind: str,
    error: type[ValueError],
) -> tuple[Path, str]:
    """(path, text) of a file, or of ``library_dir/NAME.toml`` for a bare name; ``error``
    (naming the file, or listing the library's names) when it is missing, unreadable or larger
    than ``MAX_FILE_BYTES``. Shared by mission and campaign files."""
    path = Path(path_or_name)
    if not path.is_file():
        candidate = library_dir / f"{path_or_name}.toml"
        if candidate.is_file():
            path = candidate
        elif path.suffix == ".toml" or "/" in str(path_or_name):
            raise error(f"{what} file not found: {path}")
        else:
            raise error(
                f"unknown {what} {str(path_or_name)!r}; the library has: {', '.join(names())}"
            )
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise error(f"{path}: larger than {MAX_FILE_BYTES} bytes; not {kind}")
        return path, path.read_text()
    except (OSError, UnicodeDecodeError) as err:
        raise error(f"cannot read {path}: {err}") from None


MAX_FILE_BYTES = 256 * 1024
"""Largest mission file read (a mission of 200 legs is about 30 kB)."""


def parse_text(text: str, source: str) -> Mission:
    """A mission from TOML text; every malformed text is one MissionError, never a traceback
    (unparsable, nested too deeply, or invalid)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise MissionError(f"cannot parse {source}: {err}") from None
    except RecursionError:
        raise MissionError(f"cannot parse {source}: nested too deeply") from None
    try:
        return parse_mission(data, source, text)
    except RecursionError:
        raise MissionError(f"invalid mission {source}: nested too deeply") from None


def dump_mission(mission: Mission) -> str:
    """The mission as TOML text (the same format load_mission reads)."""
    return tomli_w.dumps(mission.model_dump(mode="json", exclude_none=True))


def library_names() -> list[str]:
    """Missions in the library."""
    return sorted(p.stem for p in LIBRARY_DIR.glob("*.toml"))


def leg_models() -> dict[str, type[BaseModel]]:
    """Leg type name -> its pydantic model, in the order of ``schema.Leg``."""
    union = typing.get_args(Leg)[0]
    out: dict[str, type[BaseModel]] = {}
    for model in typing.get_args(union):
        tag = typing.get_args(model.model_fields["type"].annotation)[0]
        out[str(tag)] = model
    return out
