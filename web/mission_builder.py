"""The mission builder's model: which leg types exist and what each one asks for, read from the
pydantic leg models of ``missions.schema`` (a new leg type appears in the panel by itself).

Pure: no viser here; ``web.panels`` turns the field specs into inputs.
"""

from __future__ import annotations

import json
import math
import typing
from dataclasses import dataclass
from typing import Any, Literal

import annotated_types
from pydantic import BaseModel

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

    @property
    def label(self) -> str:
        return self.name + ("" if self.required else " (opt.)" if self.optional else "")


def _bounds(metadata: list) -> tuple[float | None, float | None]:
    lo = hi = None
    for m in metadata:
        if isinstance(m, annotated_types.Ge | annotated_types.Gt):
            lo = float(m.ge if isinstance(m, annotated_types.Ge) else m.gt)  # type: ignore[arg-type]
        if isinstance(m, annotated_types.Le | annotated_types.Lt):
            hi = float(m.le if isinstance(m, annotated_types.Le) else m.lt)  # type: ignore[arg-type]
    return lo, hi


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
        lo, hi = _bounds(info.metadata)
        required = info.is_required()
        default = None if required else info.get_default(call_default_factory=True)
        specs.append(
            FieldSpec(
                name, kind, default, required, optional, lo, hi, choices, info.description or ""
            )
        )
    return specs


def initial_value(spec: FieldSpec) -> Any:
    """What the input shows before the operator types: the default, or a value in range."""
    if spec.default is not None:
        return spec.default
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
    return spec.lo == 0.0 and spec.name.endswith(("_s", "side_m"))


def text_of(spec: FieldSpec, value: Any) -> str:
    """How a value is shown in a text or JSON input."""
    if value is None:
        return ""
    return json.dumps(value) if spec.kind == "json" else str(value)


def parse_input(spec: FieldSpec, raw: Any) -> Any:
    """The value of an input for the leg dictionary (validation is pydantic's, later);
    ValueError naming the field for text that is not JSON."""
    if raw is None:
        return None
    if spec.kind == "tristate":
        return {"true": True, "false": False}.get(str(raw))
    if spec.kind == "json" or (spec.kind == "text" and spec.optional):
        text = str(raw).strip()
        if text == "":
            return None
        if spec.kind == "text":
            return text
        try:
            return json.loads(text)
        except json.JSONDecodeError as err:
            raise ValueError(f"{spec.name}: not valid JSON ({err.msg})") from None
    if spec.kind in ("number", "integer") and spec.optional:
        text = str(raw).strip()
        if text == "":
            return None
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"{spec.name}: {text!r} is not a number") from None
        if not math.isfinite(value):
            raise ValueError(f"{spec.name}: must be finite")
        return value
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
