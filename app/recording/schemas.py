"""JSON schemas of every channel: Foxglove's well-known types and this project's own.

All messages are JSON with a JSON schema that Foxglove can parse (one plain type per field,
numeric enums, every object with its properties). Foxglove's well-known schemas
(``foxglove.FrameTransforms``, ``foxglove.SceneUpdate``, ``foxglove.Log``) are written out here
from Foxglove's documented field names; the plot channels use this project's schemas
(``rov_console.*``) with one named number per field.
"""

from __future__ import annotations

from collections.abc import Sequence

from app.recording.channels import WIRE_FIELDS, PlotChannel


def _num(description: str = "") -> dict:
    return {"type": "number", "description": description} if description else {"type": "number"}


def _object(title: str, description: str, properties: dict) -> dict:
    return {
        "title": title,
        "description": description,
        "type": "object",
        "properties": properties,
        "required": list(properties),
    }


def _array(items: dict, description: str) -> dict:
    return {"type": "array", "items": items, "description": description}


def _enum(title: str, values: Sequence[str]) -> dict:
    return {"title": title, "oneOf": [{"title": v, "const": i} for i, v in enumerate(values)]}


def _stamp(title: str, sec_min: int | None) -> dict:
    sec: dict = {"type": "integer"} if sec_min is None else {"type": "integer", "minimum": 0}
    return {
        "type": "object",
        "title": title,
        "properties": {
            "sec": sec,
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
        },
    }


TIME = _stamp("time", 0)
DURATION = _stamp("duration", None)
VECTOR3 = _object("foxglove.Vector3", "vector in 3D", {k: _num() for k in "xyz"})
POINT3 = _object("foxglove.Point3", "point in 3D", {k: _num() for k in "xyz"})
QUATERNION = _object("foxglove.Quaternion", "orientation", {k: _num() for k in "xyzw"})
POSE = _object(
    "foxglove.Pose", "position and orientation", {"position": VECTOR3, "orientation": QUATERNION}
)
COLOR = _object("foxglove.Color", "RGBA, 0..1", {k: _num() for k in "rgba"})
KEY_VALUE = _object(
    "foxglove.KeyValuePair",
    "key and value",
    {"key": {"type": "string"}, "value": {"type": "string"}},
)


def _primitive_schemas() -> dict[str, dict]:
    """Schemas of the SceneEntity primitives, keyed by the entity's field name."""
    boolean = {"type": "boolean"}
    indices = _array({"type": "integer", "minimum": 0}, "indices into points")
    colors = _array(COLOR, "per-point colors")
    return {
        "arrows": _object(
            "foxglove.ArrowPrimitive",
            "arrow along +x",
            {
                "pose": POSE,
                "shaft_length": _num(),
                "shaft_diameter": _num(),
                "head_length": _num(),
                "head_diameter": _num(),
                "color": COLOR,
            },
        ),
        "cubes": _object(
            "foxglove.CubePrimitive", "box", {"pose": POSE, "size": VECTOR3, "color": COLOR}
        ),
        "spheres": _object(
            "foxglove.SpherePrimitive", "ellipsoid", {"pose": POSE, "size": VECTOR3, "color": COLOR}
        ),
        "cylinders": _object(
            "foxglove.CylinderPrimitive",
            "cylinder or cone along z",
            {
                "pose": POSE,
                "size": VECTOR3,
                "bottom_scale": _num("0-1, at min z"),
                "top_scale": _num("0-1, at max z"),
                "color": COLOR,
            },
        ),
        "lines": _object(
            "foxglove.LinePrimitive",
            "connected points",
            {
                "type": _enum("foxglove.LineType", ("LINE_STRIP", "LINE_LOOP", "LINE_LIST")),
                "pose": POSE,
                "thickness": _num(),
                "scale_invariant": boolean,
                "points": _array(POINT3, "points"),
                "color": COLOR,
                "colors": colors,
                "indices": indices,
            },
        ),
        "triangles": _object(
            "foxglove.TriangleListPrimitive",
            "triangles",
            {
                "pose": POSE,
                "points": _array(POINT3, "vertices"),
                "color": COLOR,
                "colors": colors,
                "indices": indices,
            },
        ),
        "texts": _object(
            "foxglove.TextPrimitive",
            "text label",
            {
                "pose": POSE,
                "billboard": boolean,
                "font_size": _num(),
                "scale_invariant": boolean,
                "color": COLOR,
                "text": {"type": "string"},
            },
        ),
        "models": _object(
            "foxglove.ModelPrimitive",
            "3D model",
            {
                "pose": POSE,
                "scale": VECTOR3,
                "color": COLOR,
                "override_color": boolean,
                "url": {"type": "string"},
                "media_type": {"type": "string"},
                "data": {"type": "string", "contentEncoding": "base64"},
            },
        ),
    }


PRIMITIVE_KEYS = tuple(_primitive_schemas())
"""The primitive lists of a foxglove.SceneEntity."""


def scene_update_schema() -> dict:
    """foxglove.SceneUpdate as JSON schema."""
    entity_props = {
        "timestamp": TIME,
        "frame_id": {"type": "string"},
        "id": {"type": "string"},
        "lifetime": DURATION,
        "frame_locked": {"type": "boolean"},
        "metadata": _array(KEY_VALUE, "user metadata"),
    }
    entity_props |= {k: _array(v, k) for k, v in _primitive_schemas().items()}
    entity = _object("foxglove.SceneEntity", "a visual element in a 3D scene", entity_props)
    deletion = _object(
        "foxglove.SceneEntityDeletion",
        "entities to remove",
        {
            "timestamp": TIME,
            "type": _enum("foxglove.SceneEntityDeletionType", ("MATCHING_ID", "ALL")),
            "id": {"type": "string"},
        },
    )
    return _object(
        "foxglove.SceneUpdate",
        "an update to the entities of a 3D scene",
        {
            "deletions": _array(deletion, "entities to delete"),
            "entities": _array(entity, "entities to add or replace"),
        },
    )


def frame_transforms_schema() -> dict:
    """foxglove.FrameTransforms as JSON schema."""
    transform = _object(
        "foxglove.FrameTransform",
        "parent frame to child frame",
        {
            "timestamp": TIME,
            "parent_frame_id": {"type": "string"},
            "child_frame_id": {"type": "string"},
            "translation": VECTOR3,
            "rotation": QUATERNION,
        },
    )
    return _object(
        "foxglove.FrameTransforms",
        "frame transforms",
        {"transforms": _array(transform, "transforms")},
    )


def log_schema() -> dict:
    """foxglove.Log as JSON schema."""
    return _object(
        "foxglove.Log",
        "a log message",
        {
            "timestamp": TIME,
            "level": _enum(
                "foxglove.LogLevel", ("UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL")
            ),
            "message": {"type": "string"},
            "name": {"type": "string"},
            "file": {"type": "string"},
            "line": {"type": "integer", "minimum": 0},
        },
    )


def _named_numbers(title: str, description: str, names: Sequence[str]) -> dict:
    props = {"t_s": _num("simulation time [s]")} | {n: _num() for n in names}
    return _object(title, description, props)


def plot_schema(channel: PlotChannel) -> dict:
    """A plot channel's schema: t_s and one number per field."""
    return _named_numbers(
        channel.schema_name, channel.description, [f.name for f in channel.fields]
    )


def wire_schema() -> dict:
    return _named_numbers(
        "rov_console.Wire",
        "crane tip, wire length and the tree's horizontal offset from the tip",
        WIRE_FIELDS,
    )


def session_log_schema() -> dict:
    return _object(
        "rov_console.SessionLogRow",
        "one row of the closed-loop log: the columns no plot channel carries exactly (the "
        "channel's 'carried' metadata names the topic and field of each other column)",
        {
            "t_s": _num("simulation time [s]"),
            "row": _array(
                _num(), "values in the order of the channel's 'columns' metadata (null: not finite)"
            ),
        },
    )


def event_schema() -> dict:
    return _object(
        "rov_console.Event",
        "leg change, alarm, gain change, landing ...",
        {
            "t_s": _num("simulation time [s]"),
            "kind": {"type": "string"},
            "text": {"type": "string"},
            "data": {"type": "object", "properties": {}, "description": "free-form details"},
        },
    )
