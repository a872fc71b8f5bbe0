"""Mission files: a versioned TOML format, validated with pydantic.

A mission is a set-up (parameter set, depth, current, waves, sensors and control choices, seed)
and a sequence of legs. Legs are data: each has a ``type`` and its values, and the runner
(``missions.runner``) looks the type up in a registry. Angles are degrees in the file (the
interface), radians inside.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Annotated, Literal

import tomli_w
from pydantic import BaseModel, ConfigDict, Field, ValidationError

FORMAT_VERSION = 1
LIBRARY_DIR = Path(__file__).with_name("library")

Finite = Annotated[float, Field(allow_inf_nan=False)]


class MissionError(ValueError):
    """A mission file is invalid; the message names the file, the field and what is allowed."""


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class CurrentSetup(_Model):
    speed_mps: float = Field(ge=0.0, le=3.0, description="current speed [m/s]")
    direction_deg: float = Field(ge=-360.0, le=360.0,
                                 description="direction the current flows towards [deg]")
    speed_walk_mps_per_sqrt_s: float = Field(default=0.0, ge=0.0, le=0.1)
    direction_walk_deg_per_sqrt_s: float = Field(default=0.0, ge=0.0, le=10.0)
    speed_band_mps: float = Field(default=0.0, ge=0.0, le=1.0,
                                  description="random walk stays within speed +- band")
    direction_band_deg: float = Field(default=0.0, ge=0.0, le=180.0)


class WaveSetup(_Model):
    significant_height_m: float = Field(ge=0.0, le=30.0)
    peak_period_s: float = Field(gt=0.0, le=40.0)
    direction_deg: float = Field(ge=-360.0, le=360.0)


class PlantVariation(_Model):
    """Differences between the real tree and what the controller is configured with
    (thesis section 4.2.3)."""

    mass_scale: float = Field(default=1.0, ge=0.1, le=5.0,
                              description="tree rigid-body mass and inertia factor")
    weight_scale: float = Field(default=1.0, ge=0.1, le=5.0,
                                description="tree submerged weight factor")


class Setup(_Model):
    params: str = Field(description="parameter set name or file")
    depth_m: float = Field(gt=5.0, le=4000.0, description="tree depth [m]")
    crane_tip_n: Annotated[list[Finite], Field(min_length=2, max_length=2)] = [1.0, 1.0]
    heading_deg: float = Field(default=0.0, ge=-360.0, le=360.0, description="initial heading")
    current: CurrentSetup = CurrentSetup(speed_mps=0.0, direction_deg=0.0)
    waves: WaveSetup | None = None
    feedback: Literal["perfect", "ekf"] = "perfect"
    allocation: Literal["pinv", "priority", "qp"] = "priority"
    reference: Literal["first", "third"] = "third"
    feedforward: bool = False
    heave_force_n: float = Field(default=0.0, ge=-1.0e5, le=1.0e5)
    r_mount_config_m: Annotated[list[Finite], Field(min_length=3, max_length=3)] | None = Field(
        default=None, description="mount vector the controller is configured with "
                                  "(default: the parameter set's)")
    plant: PlantVariation = PlantVariation()
    seed: int = Field(default=0, ge=0, le=2**31 - 1)


class _Leg(_Model):
    name: str = ""
    score: bool = Field(default=False, description="count this leg in the mission's RMS")
    timeout_s: float = Field(default=3600.0, gt=0.0, le=86400.0)


class HoldLeg(_Leg):
    type: Literal["hold"]
    duration_s: float = Field(gt=0.0, le=86400.0)


class RotateLeg(_Leg):
    type: Literal["rotate"]
    angle_deg: float = Field(ge=-1080.0, le=1080.0,
                             description="positive = clockwise seen from above; 360 allowed")
    settle_s: float = Field(default=60.0, ge=0.0, le=3600.0)


class MoveLeg(_Leg):
    type: Literal["move"]
    north_m: float = Field(ge=-1000.0, le=1000.0)
    east_m: float = Field(ge=-1000.0, le=1000.0)
    heading_deg: float | None = Field(default=None, ge=-360.0, le=360.0)
    relative: bool = Field(default=True, description="relative to the present target")
    settle_s: float = Field(default=30.0, ge=0.0, le=3600.0)


class StepLeg(_Leg):
    type: Literal["step"]
    north_m: float = Field(ge=-1000.0, le=1000.0)
    east_m: float = Field(ge=-1000.0, le=1000.0)
    heading_deg: float = Field(ge=-360.0, le=360.0)
    relative: bool = True
    duration_s: float = Field(gt=0.0, le=86400.0)


class SquareLeg(_Leg):
    type: Literal["square"]
    side_m: float = Field(gt=0.0, le=100.0)
    heading_deg: float | None = Field(default=None, ge=-360.0, le=360.0,
                                      description="heading held along the square")
    clockwise: bool = True
    settle_s: float = Field(default=20.0, ge=0.0, le=3600.0)


class WaypointsLeg(_Leg):
    type: Literal["waypoints"]
    points_ne_m: list[Annotated[list[Finite], Field(min_length=2, max_length=2)]] = Field(
        min_length=1, max_length=200)
    relative: bool = True
    settle_s: float = Field(default=10.0, ge=0.0, le=3600.0)


class GainsLeg(_Leg):
    type: Literal["gains"]
    kp: Annotated[list[Annotated[float, Field(ge=0.0, le=1.0e7)]], Field(min_length=3,
                                                                         max_length=3)]
    ki: Annotated[list[Annotated[float, Field(ge=0.0, le=1.0e6)]], Field(min_length=3,
                                                                         max_length=3)]
    kd: Annotated[list[Annotated[float, Field(ge=0.0, le=1.0e8)]], Field(min_length=3,
                                                                         max_length=3)]


class ModeLeg(_Leg):
    type: Literal["mode"]
    mode: Literal["tree", "free"]
    grip: bool | None = Field(default=None, description="also grip (true) or release (false)")


Leg = Annotated[HoldLeg | RotateLeg | MoveLeg | StepLeg | SquareLeg | WaypointsLeg | GainsLeg |
                ModeLeg, Field(discriminator="type")]


class Mission(_Model):
    format_version: Literal[1] = Field(description="mission file format version")
    name: str
    description: str = ""
    setup: Setup
    legs: list[Leg] = Field(min_length=1, max_length=1000)


def _where(data: dict, loc: tuple) -> str:
    """Human-readable location: legs[3] (rotate).angle_deg."""
    parts: list[str] = []
    node: object = data
    for p in loc:
        if isinstance(p, int):
            kind = node[p].get("type") if isinstance(node, list) and p < len(node) and \
                isinstance(node[p], dict) else None
            parts[-1] = f"{parts[-1]}[{p + 1}]" + (f" ({kind})" if kind else "")
            node = node[p] if isinstance(node, list) and p < len(node) else None
        else:
            if str(p) in ("hold", "rotate", "move", "step", "square", "waypoints", "gains",
                          "mode"):
                continue  # discriminator tag, already shown
            parts.append(str(p))
            node = node.get(p) if isinstance(node, dict) else None
    return ".".join(parts)


def parse_mission(data: dict, source: str = "<mission>") -> Mission:
    """Validate a mission dictionary; raise MissionError naming file, field and range."""
    try:
        return Mission.model_validate(data)
    except ValidationError as err:
        lines = [f"invalid mission {source}:"]
        for e in err.errors():
            lines.append(f"  {_where(data, e['loc'])}: {e['msg']} (got {e.get('input')!r})")
        raise MissionError("\n".join(lines)) from None


def load_mission(path_or_name: str | Path) -> Mission:
    """Load a mission file, or a library mission by name."""
    path = Path(path_or_name)
    if not path.suffix:
        candidate = LIBRARY_DIR / f"{path_or_name}.toml"
        if not candidate.exists():
            raise MissionError(f"unknown mission {path_or_name!r}; the library has: "
                               f"{', '.join(library_names())}")
        path = candidate
    if not path.exists():
        raise MissionError(f"mission file not found: {path}")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as err:
        raise MissionError(f"cannot parse {path}: {err}") from None
    return parse_mission(data, str(path))


def dump_mission(mission: Mission) -> str:
    """The mission as TOML text (the same format load_mission reads)."""
    return tomli_w.dumps(mission.model_dump(mode="json", exclude_none=True))


def library_names() -> list[str]:
    """Missions in the library."""
    return sorted(p.stem for p in LIBRARY_DIR.glob("*.toml"))
