"""The mission builder's model: which leg types exist and what each one asks for, read from the
pydantic leg models of ``missions.schema`` (a new leg type appears in the panel by itself).

Pure: no viser here; ``web.builder_panel`` turns the field specs into inputs, and this module
also edits the set-up, reads uploaded files, words errors on one line and computes the preview.
"""

from __future__ import annotations

import functools
import json
import math
import re
import typing
from dataclasses import dataclass
from typing import Any, Literal

import annotated_types
from pydantic import BaseModel, ValidationError

from missions import schema

FieldKind = Literal["number", "integer", "bool", "tristate", "choice", "text", "json"]
TRISTATE = ("(unchanged)", "true", "false")
"""Choices of an optional yes/no field (None, True, False)."""
SKIPPED_FIELDS = ("type",)


@dataclass(frozen=True)
class FieldSpec:
    """One input of a leg in the builder."""

    name: str
    kind: FieldKind
    default: Any
    required: bool
    optional: bool
    """None is allowed (an empty input means None)."""
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] = ()
    description: str = ""
    lo_strict: bool = False
    """The lower bound itself is not allowed (``gt``)."""
    hi_strict: bool = False
    pairs: bool = False
    """A JSON field holding a list of [north, east] pairs (typed as "n, e; n, e")."""

    @property
    def label(self) -> str:
        """What the operator reads: "Duration [s]", from the field's name and unit suffix."""
        return label_of(self.name) + (" (optional)" if self.optional else "")

    @property
    def allowed(self) -> str:
        """The allowed range in words ("> 0 and <= 86400"), or "" when unbounded."""
        parts = []
        if self.lo is not None:
            parts.append(f"{'>' if self.lo_strict else '>='} {self.lo:g}")
        if self.hi is not None:
            parts.append(f"{'<' if self.hi_strict else '<='} {self.hi:g}")
        return " and ".join(parts)

    @property
    def hint(self) -> str:
        """The input's hover text: what the field means, how to type it, what is allowed."""
        parts = [self.description[:1].upper() + self.description[1:]] if self.description else []
        if self.pairs:
            parts.append(f"north, east pairs in metres separated by ';', e.g. {PAIRS_EXAMPLE}")
        elif self.kind == "json":
            parts.append(f"three numbers (surge, sway, yaw), e.g. {VECTOR_EXAMPLE}")
        if self.allowed:
            parts.append(f"allowed {self.allowed}" + (f" {self.unit}" if self.unit else ""))
        if self.optional:
            parts.append("leave empty for the default")
        parts.append(f"file key: {self.name}")
        return "; ".join(parts)

    @property
    def unit(self) -> str:
        return _split_unit(self.name)[1]


UNITS = (("_mps", "m/s"), ("_deg", "deg"), ("_newton", "N"), ("_s", "s"), ("_m", "m"))
"""Name suffix -> unit shown in the label (the project's naming rule: SI units in names)."""
LABELS = {
    "points_ne_m": "Waypoints north, east [m]",
    "kp": "Kp surge, sway, yaw",
    "ki": "Ki surge, sway, yaw",
    "kd": "Kd surge, sway, yaw",
    "score": "Count in the mission's RMS",
}
PAIRS_EXAMPLE = "0, 5; 5, 5"
VECTOR_EXAMPLE = "1e5, 1e5, 2e6"


def _split_unit(name: str) -> tuple[str, str]:
    for suffix, unit in UNITS:
        if name.endswith(suffix):
            return name.removesuffix(suffix), unit
    return name, ""


def label_of(name: str) -> str:
    """ "lower_rate_mps" -> "Lower rate [m/s]"."""
    if name in LABELS:
        return LABELS[name]
    stem, unit = _split_unit(name)
    words = stem.replace("_", " ").strip()
    words = words[:1].upper() + words[1:]
    return f"{words} [{unit}]" if unit else words


def _bounds(metadata: list) -> tuple[float | None, float | None, bool, bool]:
    """(lower, upper, lower excluded, upper excluded) from a field's constraints."""
    lo = hi = None
    lo_strict = hi_strict = False
    for m in metadata:
        if isinstance(m, annotated_types.Ge | annotated_types.Gt):
            lo_strict = isinstance(m, annotated_types.Gt)
            lo = float(m.gt if lo_strict else m.ge)  # type: ignore[union-attr,arg-type]
        if isinstance(m, annotated_types.Le | annotated_types.Lt):
            hi_strict = isinstance(m, annotated_types.Lt)
            hi = float(m.lt if hi_strict else m.le)  # type: ignore[union-attr,arg-type]
    return lo, hi, lo_strict, hi_strict


def _is_pairs(annotation: Any) -> bool:
    """A list of lists (waypoints), as opposed to a flat vector (gains)."""
    if typing.get_origin(annotation) is typing.Annotated:
        annotation = typing.get_args(annotation)[0]
    if typing.get_origin(annotation) is not list:
        return False
    inner = typing.get_args(annotation)[0]
    if typing.get_origin(inner) is typing.Annotated:
        inner = typing.get_args(inner)[0]
    return typing.get_origin(inner) is list


def _kind(annotation: Any) -> tuple[FieldKind, bool, tuple[str, ...]]:
    """(kind, optional, choices) of a field's annotation."""
    args = typing.get_args(annotation)
    optional = type(None) in args
    inner = [a for a in args if a is not type(None)] if optional else [annotation]
    base = inner[0] if len(inner) == 1 else annotation
    if typing.get_origin(base) is Literal:
        return "choice", optional, tuple(str(a) for a in typing.get_args(base))
    if base is bool:
        return ("tristate", True, TRISTATE) if optional else ("bool", False, ())
    if base is float:
        return "number", optional, ()
    if base is int:
        return "integer", optional, ()
    if base is str:
        return "text", optional, ()
    return "json", optional, ()


def common_fields() -> set[str]:
    """Fields every leg type has (name, score, timeout): shown after the leg's own."""
    fields = [set(m.model_fields) for m in schema.leg_models().values()]
    return set.intersection(*fields) if fields else set()


def field_specs(model: type[BaseModel]) -> list[FieldSpec]:
    """The inputs a leg model asks for (bounds from its ``Field`` constraints): the leg's own
    fields first, then the ones all legs share."""
    specs = []
    common = common_fields()
    names = [n for n in model.model_fields if n not in common] + [
        n for n in model.model_fields if n in common
    ]
    for name in names:
        info = model.model_fields[name]
        if name in SKIPPED_FIELDS:
            continue
        kind, optional, choices = _kind(info.annotation)
        lo, hi, lo_strict, hi_strict = _bounds(info.metadata)
        required = info.is_required()
        default = None if required else info.get_default(call_default_factory=True)
        specs.append(
            FieldSpec(
                name,
                kind,
                default,
                required,
                optional,
                lo,
                hi,
                choices,
                info.description or "",
                lo_strict,
                hi_strict,
                kind == "json" and _is_pairs(info.annotation),
            )
        )
    return specs


def initial_value(spec: FieldSpec) -> Any:
    """What the input shows before the operator types: the default, or a value in range (an
    example route for waypoints)."""
    if spec.default is not None:
        return spec.default
    if spec.pairs and spec.required:
        return parse_pairs(spec, PAIRS_EXAMPLE)
    if spec.kind in ("number", "integer") and not spec.optional:
        lo = spec.lo if spec.lo is not None else 0.0
        hi = spec.hi if spec.hi is not None else lo + 1.0
        value = 0.0 if lo <= 0.0 <= hi and not _strict_zero(spec) else min(max(1.0, lo), hi)
        return int(value) if spec.kind == "integer" else value
    if spec.kind in ("choice", "tristate"):
        return spec.choices[0]
    if spec.kind == "bool":
        return False
    return None


def _strict_zero(spec: FieldSpec) -> bool:
    """Fields like durations must be > 0: start them at a positive value."""
    return spec.lo == 0.0 and (spec.lo_strict or spec.name.endswith(("_s", "side_m")))


def text_of(spec: FieldSpec, value: Any) -> str:
    """How a value is shown in a text input ("0, 5; 5, 5" for waypoints, "1, 2, 3" for a
    vector)."""
    if value is None:
        return ""
    if spec.kind == "json" and isinstance(value, list | tuple):
        if spec.pairs:
            return "; ".join(", ".join(f"{float(x):g}" for x in p) for p in value)
        return ", ".join(f"{float(x):g}" for x in value)
    return json.dumps(value) if spec.kind == "json" else str(value)


def _where(spec: FieldSpec) -> str:
    """How an error names a field: its label and the key in the file."""
    return f"{spec.label} ({spec.name})"


def _number(spec: FieldSpec, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{_where(spec)}: {text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"{_where(spec)}: must be a finite number")
    return value


def parse_pairs(spec: FieldSpec, text: str) -> list[list[float]]:
    """ "0, 5; 5, 5" (or one pair per line) -> [[0, 5], [5, 5]]; ValueError naming the field
    and the point that is not a pair."""
    chunks = [c.strip() for c in text.replace("\n", ";").split(";")]
    points = []
    for i, chunk in enumerate(c for c in chunks if c):
        parts = [p for p in chunk.replace(" ", ",").split(",") if p.strip()]
        if len(parts) != 2:
            raise ValueError(
                f"{_where(spec)}: point {i + 1} ({chunk!r}) is not a north, east pair; "
                f"write pairs like {PAIRS_EXAMPLE}"
            )
        points.append([_number(spec, p) for p in parts])
    if not points:
        raise ValueError(f"{_where(spec)}: give at least one point, e.g. {PAIRS_EXAMPLE}")
    return points


def _parse_vector(spec: FieldSpec, text: str) -> list[float]:
    parts = [p for p in text.replace(";", ",").replace(" ", ",").split(",") if p.strip()]
    return [_number(spec, p) for p in parts]


def check_range(spec: FieldSpec, value: float) -> float:
    """The value if it is inside the field's bounds; ValueError naming the field, the value
    and the allowed range otherwise."""
    low = spec.lo is not None and (value <= spec.lo if spec.lo_strict else value < spec.lo)
    high = spec.hi is not None and (value >= spec.hi if spec.hi_strict else value > spec.hi)
    if low or high:
        unit = f" {spec.unit}" if spec.unit else ""
        raise ValueError(f"{_where(spec)}: {value:g}{unit} is out of range; allowed {spec.allowed}")
    return value


def parse_input(spec: FieldSpec, raw: Any) -> Any:
    """The value of an input for the leg dictionary; ValueError naming the field (its label
    and file key) and the allowed range for text that is not a value, or a number out of
    range. The rest (lengths, the leg as a whole) is checked by the schema later."""
    if raw is None:
        return None
    if spec.kind == "tristate":
        return {"true": True, "false": False}.get(str(raw))
    if spec.kind == "json" or (spec.kind == "text" and spec.optional):
        text = str(raw).strip()
        if text == "":
            if spec.kind == "json" and spec.required:
                example = PAIRS_EXAMPLE if spec.pairs else VECTOR_EXAMPLE
                raise ValueError(f"{_where(spec)}: required; e.g. {example}")
            return None
        if spec.kind == "text":
            return text
        if text.startswith("["):
            try:
                return json.loads(text)
            except json.JSONDecodeError as err:
                raise ValueError(f"{_where(spec)}: not valid JSON ({err.msg})") from None
        return parse_pairs(spec, text) if spec.pairs else _parse_vector(spec, text)
    if spec.kind in ("number", "integer"):
        if isinstance(raw, str):
            text = raw.strip()
            if text == "" and spec.optional:
                return None
            value = _number(spec, text)
        else:
            value = float(raw)
            if not math.isfinite(value):
                raise ValueError(f"{_where(spec)}: must be a finite number")
        check_range(spec, value)
        return int(value) if spec.kind == "integer" else value
    return raw


def build_leg(leg_type: str, values: dict[str, Any]) -> dict[str, Any]:
    """A leg dictionary (None values left out so their defaults apply)."""
    if leg_type not in schema.leg_models():
        raise ValueError(f"type: unknown leg type {leg_type!r}")
    return {"type": leg_type, **{k: v for k, v in values.items() if v is not None}}


def build_mission(name: str, setup: schema.Setup, legs: list[dict[str, Any]]) -> schema.Mission:
    """Validate a built mission; MissionError names the leg and the field."""
    data = {
        "format_version": schema.FORMAT_VERSION,
        "name": name or "built mission",
        "description": "built in the console",
        "setup": setup.model_dump(mode="json"),
        "legs": legs,
    }
    return schema.parse_mission(data, "<mission builder>")


def describe_leg(leg: dict[str, Any]) -> str:
    """One line for the builder's leg list."""
    values = ", ".join(f"{k}={v}" for k, v in leg.items() if k != "type")
    return f"{leg['type']}({values})"


# ---------------------------------------------------------------------- readable errors
_ERROR_LINE = re.compile(r"^(?:line (\d+): )?(?:legs\[(\d+)\] \((\w+)\)\.?)?([\w.\[\]]*): (.*)$")
_LEG_PREFIX = re.compile(r"^legs\[(\d+)\] \((\w+)\)\.(\w+)")


def _leg_field_label(leg_type: str, path: str) -> str:
    """ "points_ne_m[2]" of a waypoints leg -> "Waypoints north, east [m] (points_ne_m[2])"."""
    name = path.split("[")[0].split(".")[0]
    model = schema.leg_models().get(leg_type)
    if model is None or name not in model.model_fields:
        return path
    return f"{label_of(name)} ({path})"


def one_line(err: Exception, limit: int = 2) -> str:
    """An error as one readable line: the leg, the field's label and file key, what is
    wrong and (for a number) the allowed range; further problems counted, not listed."""
    lines = [ln.strip() for ln in str(err).splitlines() if ln.strip()]
    if len(lines) > 1 and lines[0].startswith("invalid mission"):
        lines = lines[1:]
    more = [ln for ln in lines if ln.startswith("... and ")]
    lines = [ln for ln in lines if not ln.startswith("... and ")]
    out = []
    for line in lines:
        m = _ERROR_LINE.match(line)
        if m is None:
            out.append(line)
            continue
        file_line, leg_no, leg_type, path, msg = m.groups()
        where = f"line {file_line}, " if file_line else ""
        msg = _rewrite(msg)
        if leg_no:
            field = _leg_field_label(leg_type, path) if path else ""
            out.append(
                f"{where}leg {leg_no} ({leg_type})" + (f" {field}" if field else "") + f": {msg}"
            )
        elif path in ("", "mission"):
            out.append(f"{where}{msg}")
        else:
            out.append(f"{where}{SETUP_LABELS.get(path, path)}: {msg}")
    extra = len(out) - limit
    text = "; ".join(out[:limit])
    if extra > 0 or more:
        count = extra + sum(int(re.sub(r"\D", "", ln) or 0) for ln in more)
        text += f" (and {count} more)"
    return text


def _rewrite(msg: str) -> str:
    """Schema wording -> the page's: a missing frame names the input that adds one."""
    m = re.match(r"legs\[(\d+)\] \((\w+)\) needs setup\.docking_frame", msg)
    if m:
        return (
            f"leg {m.group(1)} ({m.group(2)}) needs a docking frame: tick "
            f"'{SETUP_LABELS['setup.docking_frame']}' in the set-up (or pick a docking mission "
            f"in 'Set-up from')"
        )
    for path in sorted(SETUP_LABELS, key=len, reverse=True):  # longest first
        if path.startswith("setup."):
            msg = msg.replace(path, f"'{SETUP_LABELS[path]}'")
    return msg


# ---------------------------------------------------------------------- the set-up
@functools.cache
def parameter_sets() -> tuple[str, ...]:
    """Parameter sets the library's missions use (the builder offers these)."""
    return tuple(sorted({schema.load_mission(n).setup.params for n in schema.library_names()}))


SETUP_LABELS = {
    "name": "Mission name",
    "setup.params": "Parameter set",
    "setup.depth_m": "Tree depth [m]",
    "setup.current.speed_mps": "Current speed [m/s]",
    "setup.current.direction_deg": "Current towards [deg]",
    "setup.docking_frame": "Docking frame",
    "setup.docking_frame.center_ne_m": "Frame north, east [m]",
    "setup.docking_frame.heading_deg": "Frame heading [deg]",
    "setup.docking_frame.landing_depth_m": "Landing depth [m]",
}
"""The set-up inputs of the page, by the field each one edits (errors name them so)."""


@dataclass(frozen=True)
class SetupValues:
    """What the page's set-up inputs hold."""

    params: str
    depth_m: float
    current_speed_mps: float
    current_direction_deg: float
    frame: bool
    frame_north_m: float = 0.0
    frame_east_m: float = 0.0
    frame_heading_deg: float = 0.0
    landing_depth_m: float = 0.0

    @staticmethod
    def of(setup: schema.Setup) -> SetupValues:
        f = setup.docking_frame
        return SetupValues(
            params=setup.params,
            depth_m=setup.depth_m,
            current_speed_mps=setup.current.speed_mps,
            current_direction_deg=setup.current.direction_deg,
            frame=f is not None,
            frame_north_m=f.center_ne_m[0] if f else setup.crane_tip_n[0],
            frame_east_m=f.center_ne_m[1] if f else setup.crane_tip_n[1],
            frame_heading_deg=f.heading_deg if f else 0.0,
            landing_depth_m=f.landing_depth_m if f else setup.depth_m + 10.0,
        )


def edited_setup(base: schema.Setup, values: SetupValues) -> schema.Setup:
    """The base set-up (the mission picked in "Set-up from") with the page's values; the rest
    (sensors, control choices, seed, the current's random walk, the frame's survey error) kept.
    MissionError (one line) naming the input when a value is not allowed."""
    data = base.model_dump(mode="json")
    data["params"] = values.params
    data["depth_m"] = values.depth_m
    data["current"] = {
        **data["current"],
        "speed_mps": values.current_speed_mps,
        "direction_deg": values.current_direction_deg,
    }
    if values.frame:
        data["docking_frame"] = {
            **(data.get("docking_frame") or {}),
            "center_ne_m": [values.frame_north_m, values.frame_east_m],
            "heading_deg": values.frame_heading_deg,
            "landing_depth_m": values.landing_depth_m,
        }
    else:
        data["docking_frame"] = None
    try:
        return schema.Setup.model_validate(data)
    except ValidationError as err:
        e = err.errors()[0]
        path = "setup." + ".".join(str(p) for p in e["loc"] if not isinstance(p, int))
        label = SETUP_LABELS.get(path, path)
        msg = e["msg"].removeprefix("Value error, ")
        raise schema.MissionError(f"{label}: {msg}{_got(e.get('input'))}") from None


def _got(value: object) -> str:
    return f" (got {value:g})" if isinstance(value, float | int) else ""


# ---------------------------------------------------------------------- files
def parse_upload(filename: str, content: bytes) -> schema.Mission:
    """A mission from an uploaded file; MissionError with one line for anything malformed
    (too large, not text, not TOML, nested too deeply, invalid)."""
    source = filename or "upload"
    if len(content) > schema.MAX_FILE_BYTES:
        raise schema.MissionError(
            f"{source}: {len(content)} bytes; a mission file has at most "
            f"{schema.MAX_FILE_BYTES} bytes"
        )
    try:
        text = content.decode("utf-8")
    except UnicodeDecodeError:
        raise schema.MissionError(f"{source}: not a text file (UTF-8)") from None
    try:
        return schema.parse_text(text, source)
    except schema.MissionError as err:
        line = one_line(err)
        raise schema.MissionError(line if source in line else f"{source}: {line}") from None


def file_name(mission: schema.Mission) -> str:
    """A download's file name from the mission's name (letters, digits, '-', '_', '.')."""
    stem = re.sub(r"[^A-Za-z0-9._-]+", "-", mission.name).strip("-.") or "mission"
    return f"{stem}.toml"


# ---------------------------------------------------------------------- preview
@dataclass(frozen=True)
class Preview:
    """Where a built mission takes the tree, for the scene: the reference's path in NED
    [m] at the tree's depth, the targets with a short label, and the docking frame."""

    depth_m: float
    path_ne: list[tuple[float, float]]
    targets: list[tuple[float, float, str]]
    frame: tuple[float, float, float, float] | None
    """(north, east, heading [rad], landing depth) of the charted frame."""


def preview(setup: schema.Setup, legs: list[dict[str, Any]]) -> Preview:
    """Follow the legs' targets as the executors set them (missions.legs): moves and steps
    relative to the present target unless told otherwise, squares and waypoints from the
    leg's start, dock to the frame's centre; the rest leaves the target where it is."""
    n, e = float(setup.crane_tip_n[0]), float(setup.crane_tip_n[1])
    path = [(n, e)]
    targets: list[tuple[float, float, str]] = []
    f = setup.docking_frame
    models = schema.leg_models()
    for i, raw in enumerate(legs):
        leg: Any = models[raw["type"]].model_validate(raw)
        tag = f"{i + 1} {leg.type}"
        points: list[tuple[float, float]] = []
        if leg.type in ("move", "step"):
            points = [
                (n + leg.north_m, e + leg.east_m) if leg.relative else (leg.north_m, leg.east_m)
            ]
        elif leg.type == "square":
            side, east = leg.side_m, leg.side_m if leg.clockwise else -leg.side_m
            points = [(n + side, e), (n + side, e + east), (n, e + east), (n, e)]
        elif leg.type == "waypoints":
            points = [(n + pn, e + pe) if leg.relative else (pn, pe) for pn, pe in leg.points_ne_m]
        elif leg.type == "dock" and f is not None:
            points = [(float(f.center_ne_m[0]), float(f.center_ne_m[1]))]
        for k, p in enumerate(points):
            path.append(p)
            targets.append((p[0], p[1], tag if len(points) == 1 else f"{tag} {k + 1}"))
        if points:
            n, e = points[-1]
    frame = (
        None
        if f is None
        else (
            float(f.center_ne_m[0]),
            float(f.center_ne_m[1]),
            math.radians(f.heading_deg),
            f.landing_depth_m,
        )
    )
    return Preview(setup.depth_m, path, targets, frame)
