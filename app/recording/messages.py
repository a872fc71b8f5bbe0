"""Message builders: pure functions of one log row (read by block name) to JSON-ready dicts.

Frames
    Foxglove's 3D view is z-up, so the root frame ``world`` is [north, west, up]. Its child
    ``ned`` is [north, east, down], rotated by pi about the north axis (quaternion x = 1). The
    bodies ``tree`` and ``rov`` (x fore, y starboard, z down) and ``reference`` (the tree's
    reference pose at the tree's depth) are children of ``ned``.

Numbers
    Message and stamp times are the session's real start plus the simulation time, in
    nanoseconds (the recorder's ``time_origin_ns``), so Foxglove shows the date the session
    ran; every message also carries the simulation time itself as ``t_s``.
    Non-finite numbers are written as ``null`` (JSON has no NaN) and read back as NaN.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from app.recording.channels import WIRE_FIELDS, PlotChannel
from app.recording.schemas import PRIMITIVE_KEYS
from control.columns import LAYOUT
from sim.docking import DockingFrame, DockingLayout
from sim.drawing import attachment_point_n, rov_drawing_box_m
from sim.gnc import quaternion_wxyz_from_rpy_radians
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]
Vector = Sequence[float] | FloatArray
"""Three numbers [m] (a list or an array)."""

# Drawing-only choices (they change no number in the logs).
PLATE_THICKNESS_M = 0.1
ARROW_LENGTH_M = 2.0
"""Length of the commanded-force arrow at the ROV's whole thrust capacity."""
COLORS = {
    "tree": (0.95, 0.75, 0.1, 0.9),
    "rov": (1.0, 0.45, 0.0, 0.9),
    "wire": (0.8, 0.8, 0.8, 1.0),
    "reference": (0.1, 0.9, 0.3, 0.25),
    "frame": (0.3, 0.4, 0.6, 0.9),
    "post": (0.95, 0.95, 0.95, 1.0),
    "funnel": (0.6, 0.6, 0.65, 0.8),
    "force": (0.9, 0.1, 0.1, 0.9),
}
EVENT_LEVELS = {"alarm": 3, "warning": 3, "error": 4, "diverged": 4, "abort": 4}
"""foxglove.Log level of an event kind (INFO = 2 for the others)."""

WORLD_TO_NED = {"x": 1.0, "y": 0.0, "z": 0.0, "w": 0.0}
"""pi about the north axis: ``ned`` = [north, east, down] in ``world`` = [north, west, up]."""
IDENTITY = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}


def foxglove_quaternion(q_wxyz: FloatArray) -> dict[str, float]:
    """A quaternion [w, x, y, z] as Foxglove's {x, y, z, w}."""
    return {
        "x": float(q_wxyz[1]),
        "y": float(q_wxyz[2]),
        "z": float(q_wxyz[3]),
        "w": float(q_wxyz[0]),
    }


def _orientation(phi: float, theta: float, psi: float) -> dict[str, float]:
    """Foxglove orientation of R_nb = Rzyx(phi, theta, psi)."""
    return foxglove_quaternion(quaternion_wxyz_from_rpy_radians(phi, theta, psi))


def _vec(v: Vector) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def _pose(position: Vector, orientation: dict[str, float] = IDENTITY) -> dict:
    return {"position": _vec(position), "orientation": orientation}


def _color(name: str) -> dict[str, float]:
    r, g, b, a = COLORS[name]
    return {"r": r, "g": g, "b": b, "a": a}


def _stamp(t_ns: int) -> dict[str, int]:
    return {"sec": t_ns // 1_000_000_000, "nsec": t_ns % 1_000_000_000}


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _t_s(row: FloatArray) -> float:
    return float(LAYOUT.take(row, "t_s"))


# ------------------------------------------------------------------------------ JSON


def _without_nan(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by None (JSON has no NaN)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _without_nan(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_without_nan(v) for v in obj]
    return obj


def json_bytes(obj: Any) -> bytes:
    """Compact JSON; non-finite numbers become null."""
    try:
        return json.dumps(obj, separators=(",", ":"), allow_nan=False).encode()
    except ValueError:
        return json.dumps(_without_nan(obj), separators=(",", ":"), allow_nan=False).encode()


# ------------------------------------------------------------------------------ geometry


@dataclass(frozen=True)
class SceneGeometry:
    """Sizes of what the scene draws, from the parameter set."""

    tree_box_m: FloatArray
    attachment_height_m: float
    rov_box_m: FloatArray
    layout: DockingLayout
    thrust_capacity_newton: float


def scene_geometry(ps: ParameterSet) -> SceneGeometry:
    thr = ps.rov.thrusters
    return SceneGeometry(
        np.asarray(ps.tree.dimensions_m, float),
        ps.tree.attachment_height_m,
        rov_drawing_box_m(ps),
        ps.spec.docking.to_numeric(),
        float(np.sum(thr.f_max_pos)),
    )


# ------------------------------------------------------------------------------ numbers


def plot_message(channel: PlotChannel, row: FloatArray) -> dict:
    """The named numbers of one plot channel for a log row."""
    out: dict[str, float | None] = {"t_s": _t_s(row)}
    for f, v in zip(channel.fields, channel.values(row), strict=True):
        out[f.name] = _finite_or_none(v)
    return out


def wire_message(row: FloatArray, crane_tip_n: FloatArray, wire_length_m: float) -> dict:
    """``/wire``: crane tip, wire length and the tree's horizontal offset from the tip."""
    tree = LAYOUT.take(row, "tree_eta_n")
    offset = math.hypot(tree[0] - crane_tip_n[0], tree[1] - crane_tip_n[1])
    values = (crane_tip_n[0], crane_tip_n[1], wire_length_m, offset)
    return {"t_s": _t_s(row)} | {
        k: _finite_or_none(float(v)) for k, v in zip(WIRE_FIELDS, values, strict=True)
    }


def session_row_message(row: FloatArray, columns: NDArray[np.intp] | None = None) -> dict:
    """``/session/log``: the row's entries at ``columns`` (None: the whole row), exactly
    (non-finite values as null)."""
    part = row if columns is None else row[columns]
    values = part.tolist()
    if not np.all(np.isfinite(part)):
        values = [v if math.isfinite(v) else None for v in values]
    return {"t_s": _t_s(row), "row": values}


def event_message(t_s: float, kind: str, text: str, data: dict | None) -> dict:
    """``/events``: an event at simulation time ``t_s``."""
    return {"t_s": float(t_s), "kind": str(kind), "text": str(text), "data": data or {}}


def log_message(t_ns: int, kind: str, text: str) -> dict:
    """foxglove.Log of an event, for Foxglove's Log panel."""
    return {
        "timestamp": _stamp(t_ns),
        "level": EVENT_LEVELS.get(kind, 2),
        "message": f"{kind}: {text}",
        "name": "rov-console",
        "file": "",
        "line": 0,
    }


# ------------------------------------------------------------------------------ frames


def _transform(
    t_ns: int, parent: str, child: str, translation: Vector, rotation: dict[str, float]
) -> dict:
    return {
        "timestamp": _stamp(t_ns),
        "parent_frame_id": parent,
        "child_frame_id": child,
        "translation": _vec(translation),
        "rotation": rotation,
    }


def tf_message(t_ns: int, row: FloatArray) -> dict:
    """foxglove.FrameTransforms: world -> ned, ned -> tree, rov, reference."""
    tree = LAYOUT.take(row, "tree_eta_n")
    rov = LAYOUT.take(row, "rov_eta_n")
    ref = LAYOUT.take(row, "eta_ref_n")
    return {
        "transforms": [
            _transform(t_ns, "world", "ned", [0, 0, 0], WORLD_TO_NED),
            _transform(t_ns, "ned", "tree", tree[0:3], _orientation(*tree[3:6])),
            _transform(t_ns, "ned", "rov", rov[0:3], _orientation(*rov[3:6])),
            _transform(
                t_ns, "ned", "reference", [ref[0], ref[1], tree[2]], _orientation(0.0, 0.0, ref[2])
            ),
        ]
    }


# ------------------------------------------------------------------------------ scene


def _entity(t_ns: int, frame_id: str, entity_id: str, locked: bool, **primitives: list) -> dict:
    """A foxglove.SceneEntity (every primitive list present, empty when unused)."""
    ent = {
        "timestamp": _stamp(t_ns),
        "frame_id": frame_id,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": locked,
        "metadata": [],
    }
    for key in PRIMITIVE_KEYS:
        ent[key] = primitives.get(key, [])
    return ent


def _cube(
    position: Vector, size: Vector, color: str, orientation: dict[str, float] = IDENTITY
) -> dict:
    return {"pose": _pose(position, orientation), "size": _vec(size), "color": _color(color)}


def _force_arrows(row: FloatArray, geo: SceneGeometry) -> list[dict]:
    """The ROV's commanded horizontal force, as long as ARROW_LENGTH_M at full capacity."""
    fx, fy = LAYOUT.take(row, "tau_rov_cmd_b")[0:2]
    length = ARROW_LENGTH_M * min(math.hypot(fx, fy) / geo.thrust_capacity_newton, 1.0)
    if not (math.isfinite(length) and length > 1e-3):
        return []
    head = min(0.3, length / 3)
    return [
        {
            "pose": _pose([0, 0, 0], _orientation(0.0, 0.0, math.atan2(fy, fx))),
            "shaft_length": length - head,
            "shaft_diameter": 0.05,
            "head_length": head,
            "head_diameter": 0.15,
            "color": _color("force"),
        }
    ]


def _body_entities(t_ns: int, row: FloatArray, geo: SceneGeometry) -> list[dict]:
    """Tree (with funnels), ROV (with its commanded horizontal force) and reference ghost."""
    lay = geo.layout
    h = geo.tree_box_m[2]
    funnels = [
        {
            "pose": _pose([x, y, h / 2 - lay.post_height_m / 2]),
            "size": _vec([2 * lay.funnel_mouth_radius_m] * 2 + [lay.post_height_m]),
            "bottom_scale": lay.post_radius_m / lay.funnel_mouth_radius_m,
            "top_scale": 1.0,
            "color": _color("funnel"),
        }
        for x, y in lay.post_xy_m
    ]
    tree = _entity(
        t_ns,
        "tree",
        "tree",
        True,
        cubes=[_cube([0, 0, 0], geo.tree_box_m, "tree")],
        cylinders=funnels,
    )
    rov = _entity(
        t_ns,
        "rov",
        "rov",
        True,
        cubes=[_cube([0, 0, 0], geo.rov_box_m, "rov")],
        arrows=_force_arrows(row, geo),
    )
    ref = _entity(
        t_ns, "reference", "reference", True, cubes=[_cube([0, 0, 0], geo.tree_box_m, "reference")]
    )
    return [tree, rov, ref]


def _docking_entity(t_ns: int, frame: DockingFrame, layout: DockingLayout) -> dict:
    """Frame top plate and guideposts, in NED."""
    plate_centre = [
        frame.center_n[0],
        frame.center_n[1],
        frame.landing_depth_m + PLATE_THICKNESS_M / 2,
    ]
    plate = _cube(
        plate_centre,
        [*layout.frame_size_m, PLATE_THICKNESS_M],
        "frame",
        _orientation(0.0, 0.0, frame.heading_rad),
    )
    posts = [
        {
            "pose": _pose([n, e, frame.landing_depth_m - layout.post_height_m / 2]),
            "size": _vec([2 * layout.post_radius_m] * 2 + [layout.post_height_m]),
            "bottom_scale": 1.0,
            "top_scale": 1.0,
            "color": _color("post"),
        }
        for n, e in frame.post_positions_n(layout)
    ]
    return _entity(t_ns, "ned", "docking_frame", False, cubes=[plate], cylinders=posts)


def scene_message(
    t_ns: int,
    row: FloatArray,
    geo: SceneGeometry,
    crane_tip_n: FloatArray | None,
    docking: DockingFrame | None,
) -> dict:
    """foxglove.SceneUpdate for one row: bodies, wire (crane tip to attachment), docking."""
    entities = _body_entities(t_ns, row, geo)
    if crane_tip_n is not None:
        attach = attachment_point_n(LAYOUT.take(row, "tree_eta_n"), geo.attachment_height_m)
        wire = {
            "type": 0,
            "pose": _pose([0, 0, 0]),
            "thickness": 3.0,
            "scale_invariant": True,
            "points": [_vec(crane_tip_n), _vec(attach)],
            "color": _color("wire"),
            "colors": [],
            "indices": [],
        }
        entities.append(_entity(t_ns, "ned", "wire", False, lines=[wire]))
    if docking is not None:
        entities.append(_docking_entity(t_ns, docking, geo.layout))
    return {"deletions": [], "entities": entities}
