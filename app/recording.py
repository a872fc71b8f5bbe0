"""Session logs: one MCAP file per session, readable in Foxglove and by any MCAP reader.

Writing (``SessionRecorder``)
    Rows of the closed-loop log (``control.loop`` columns, one per plant step) are decimated by
    their *simulation* time, never by wall time, so the same seeded run gives the same messages.
    A row is kept when it is the first one at or after a multiple of 1/rate. Every kept row of
    the numeric rate goes, in full and exactly, to ``/session/log``; the same rows feed the named
    plot channels and ``/tf``; the rows of the (slower) scene rate feed ``/scene``. Message log
    times are simulation times in nanoseconds (Foxglove shows them as 1970-01-01 + t).

    All messages are JSON with a JSON schema that Foxglove can parse (one plain type per
    field, numeric enums, every object with its properties). Foxglove's well-known schemas
    (``foxglove.FrameTransforms``, ``foxglove.SceneUpdate``, ``foxglove.Log``) are written out
    here from Foxglove's documented field names; the plot channels use this project's schemas
    (``rov_console.*``) with one named number per field, angles in degrees and propeller speeds
    in rpm (the interface). Non-finite numbers are written as ``null`` (JSON has no NaN) and
    read back as NaN.

Frames
    Foxglove's 3D view is z-up, so the root frame ``world`` is [north, west, up]. Its child
    ``ned`` is [north, east, down], rotated by pi about the north axis (quaternion x = 1). The
    bodies ``tree`` and ``rov`` (x fore, y starboard, z down) and ``reference`` (the tree's
    reference pose at the tree's depth) are children of ``ned``.

Crash safety
    Messages are grouped in zstd-compressed chunks. A chunk is closed and handed to the
    operating system (``Writer.flush``) whenever ``flush_interval_s`` of wall time (``clock``)
    has passed since the last flush: inside ``write_log`` / ``event`` between rows, and from a
    background thread when the caller is idle (paused simulation). A killed process (SIGKILL)
    therefore loses at most the chunk in progress: about ``flush_interval_s`` of wall time. The
    file is not fsync'ed; the operating system keeps what was handed to it when a process dies,
    not when the machine loses power.

Reading (``load_session``, ``check_session``, ``export_csv``)
    The file is scanned record by record; the reader stops at the first record that is cut off
    or damaged and returns everything before it, with ``complete=False`` and where it stopped.
    Reading never changes the file.

CSV export writes ``session_log.csv`` (every column of ``/session/log``, named, exact), one
file per plot channel (``tree_state.csv`` for ``/tree/state`` ...) and ``events.csv``.
"""

from __future__ import annotations

import csv
import io
import json
import math
import struct
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from importlib import metadata as importlib_metadata
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import zstandard
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Header, Message, Metadata, Schema, Statistics
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer
from numpy.typing import NDArray

from control import loop
from sim import sensors
from sim.docking import DockingFrame, DockingLayout
from sim.gnc import Rzyx
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]

FORMAT_VERSION = 1
"""Version of this file layout (channels, schemas, metadata keys)."""
MCAP_MAGIC = bytes([137, 77, 67, 65, 80, 48, 13, 10])
SETUP_RECORD = "setup"
RESERVED_SETUP_KEYS = ("params", "columns", "recorder")
"""Keys of the setup record that the recorder writes itself."""
SESSION_TOPIC = "/session/log"
EVENTS_TOPIC = "/events"
GRID_EPS = 1e-9
"""Slack when putting a row time on the decimation grid (times are sums of 0.01 s steps)."""

# Drawing-only choices (they change no number in the logs).
ROV_BOX_ASPECT = (1.6, 1.0, 0.9)
"""Length : width : height of the box drawn for the ROV (work-class ROVs are about this shape)."""
ROV_SOLIDITY = 0.5
"""Fraction of the ROV's box that is solid: the box volume is 2 m / rho_water (an open frame;
gives 1.4 x 0.9 x 0.8 m for Minerva, whose real size is 1.44 x 0.82 x 0.8 m)."""
RHO_WATER = 1025.0
PLATE_THICKNESS_M = 0.1
ARROW_LENGTH_M = 2.0
"""Length of the commanded-force arrow at the ROV's whole thrust capacity."""

COLORS = {
    "tree": (0.95, 0.75, 0.1, 0.9), "rov": (1.0, 0.45, 0.0, 0.9),
    "wire": (0.8, 0.8, 0.8, 1.0), "reference": (0.1, 0.9, 0.3, 0.25),
    "frame": (0.3, 0.4, 0.6, 0.9), "post": (0.95, 0.95, 0.95, 1.0),
    "funnel": (0.6, 0.6, 0.65, 0.8), "force": (0.9, 0.1, 0.1, 0.9),
}


class RecordingError(RuntimeError):
    """The recorder was used wrongly (closed, bad input)."""


# --------------------------------------------------------------------------------------------
# Column names of the closed-loop log
# --------------------------------------------------------------------------------------------

_AXES3 = ("surge_n", "sway_n", "yaw_nm")
_AXES6 = ("surge_n", "sway_n", "heave_n", "roll_nm", "pitch_nm", "yaw_nm")
_POSE6 = ("north_m", "east_m", "down_m", "roll_rad", "pitch_rad", "yaw_rad")
_Y_NAMES = ("pos_north_m", "pos_east_m", "pos_down_m", "depth_m", "heading_rad", "dvl_u_mps",
            "dvl_v_mps", "dvl_w_mps", "gyro_p_rad_s", "gyro_q_rad_s", "gyro_r_rad_s")


def _column_blocks() -> list[tuple[int, list[str]]]:
    """(first column, names) of each block of ``control.loop``'s log layout."""
    thr = range(1, loop.M_MAX + 1)
    return [
        (loop.L_T, ["t_s"]),
        (loop.L_TREE, [f"tree_{n}" for n in _POSE6]),
        (loop.L_ROV, [f"rov_{n}" for n in _POSE6]),
        (loop.L_ETA_HAT, ["est_tree_north_m", "est_tree_east_m", "est_tree_yaw_rad"]),
        (loop.L_NU_HAT, ["est_tree_u_mps", "est_tree_v_mps", "est_tree_r_rad_s"]),
        (loop.L_BIAS, [f"bias_{n}" for n in _AXES3]),
        (loop.L_ETA_D, ["ref_north_m", "ref_east_m", "ref_yaw_rad"]),
        (loop.L_DETA_D, ["ref_north_rate_mps", "ref_east_rate_mps", "ref_yaw_rate_rad_s"]),
        (loop.L_TAU_TREE, [f"tau_tree_{n}" for n in _AXES3]),
        (loop.L_TAU_ROV, [f"tau_rov_cmd_{n}" for n in _AXES6]),
        (loop.L_TAU_ACH, [f"tau_rov_ach_{n}" for n in _AXES6]),
        (loop.L_F, [f"thruster{i}_force_n" for i in thr]),
        (loop.L_N, [f"thruster{i}_speed_rps" for i in thr]),
        (loop.L_UTIL, [f"thruster{i}_utilisation" for i in thr]),
        (loop.L_TERMS, [f"term_{p}_{a}" for p in ("p", "i", "d", "ff") for a in _AXES3]),
        (loop.L_Y, [f"y_{n}" for n in _Y_NAMES]),
        (loop.L_MODE, ["mode"]),
        (loop.L_NIS, ["nis_north", "nis_east", "nis_heading"]),
        (loop.L_ACCEPT, [f"accepted_{s}" for s in sensors.SENSOR_NAMES]),
        (loop.L_SITE, ["crane_tip_north_m", "crane_tip_east_m", "wire_rest_length_m",
                       "wire_tension_n"]),
    ]


def column_names() -> list[str]:
    """Names of the N_LOG columns of a ``control.loop`` row (units in the suffix).

    Raises RecordingError when the blocks here no longer tile ``control.loop``'s layout (a
    column was added there without a name here)."""
    names: list[str] = []
    for start, block in _column_blocks():
        if start != len(names):
            raise RecordingError(f"log column {start} ({block[0]}) does not follow column "
                                 f"{len(names) - 1}: update app.recording._column_blocks")
        names.extend(block)
    if len(names) != loop.N_LOG:
        raise RecordingError(f"{len(names)} column names for {loop.N_LOG} log columns: "
                             "update app.recording._column_blocks")
    return names


COLUMNS = column_names()

# --------------------------------------------------------------------------------------------
# Plot channels: named numbers taken from a row
# --------------------------------------------------------------------------------------------

DEG = math.degrees(1.0)
RPM = 60.0


@dataclass(frozen=True)
class PlotField:
    """One number of a plot channel: ``row[column] * scale`` (scale converts units)."""

    name: str
    column: int
    scale: float = 1.0
    minus: int | None = None
    """Column subtracted before scaling (for errors: row[column] - row[minus])."""


@dataclass(frozen=True)
class PlotChannel:
    """A channel of named numbers for Foxglove's Plot panel."""

    topic: str
    schema_name: str
    description: str
    fields: tuple[PlotField, ...]


def _pose_fields(start: int) -> tuple[PlotField, ...]:
    names = ("north_m", "east_m", "down_m", "roll_deg", "pitch_deg", "yaw_deg")
    return tuple(PlotField(n, start + i, DEG if i >= 3 else 1.0) for i, n in enumerate(names))


def _triple(prefix: str, start: int, names: Sequence[str] = _AXES3) -> tuple[PlotField, ...]:
    return tuple(PlotField(f"{prefix}{n}", start + i) for i, n in enumerate(names))


def plot_channels(n_thrusters: int) -> tuple[PlotChannel, ...]:
    """The plot channels for an ROV with ``n_thrusters`` thrusters."""
    y = loop.L_Y
    est = (PlotField("north_m", loop.L_ETA_HAT), PlotField("east_m", loop.L_ETA_HAT + 1),
           PlotField("yaw_deg", loop.L_ETA_HAT + 2, DEG), PlotField("u_mps", loop.L_NU_HAT),
           PlotField("v_mps", loop.L_NU_HAT + 1), PlotField("r_deg_s", loop.L_NU_HAT + 2, DEG),
           *_triple("bias_", loop.L_BIAS),
           *_triple("nis_", loop.L_NIS, ("north", "east", "heading")))
    ref = (PlotField("north_m", loop.L_ETA_D), PlotField("east_m", loop.L_ETA_D + 1),
           PlotField("yaw_deg", loop.L_ETA_D + 2, DEG),
           PlotField("north_rate_mps", loop.L_DETA_D), PlotField("east_rate_mps",
                                                                  loop.L_DETA_D + 1),
           PlotField("yaw_rate_deg_s", loop.L_DETA_D + 2, DEG),
           PlotField("error_north_m", loop.L_TREE, 1.0, loop.L_ETA_D),
           PlotField("error_east_m", loop.L_TREE + 1, 1.0, loop.L_ETA_D + 1),
           PlotField("error_yaw_deg", loop.L_TREE + 5, DEG, loop.L_ETA_D + 2))
    meas = tuple(PlotField(n.replace("_rad", "_deg"), y + i, DEG if "rad" in n else 1.0)
                 for i, n in enumerate(_Y_NAMES))
    meas += tuple(PlotField(f"accepted_{s}", loop.L_ACCEPT + k)
                  for k, s in enumerate(sensors.SENSOR_NAMES))
    forces = (*_triple("tree_", loop.L_TAU_TREE), *_triple("rov_cmd_", loop.L_TAU_ROV, _AXES6),
              *_triple("rov_ach_", loop.L_TAU_ACH, _AXES6), PlotField("mode", loop.L_MODE))
    thr: list[PlotField] = []
    for i in range(n_thrusters):
        thr += [PlotField(f"thruster{i + 1}_force_n", loop.L_F + i),
                PlotField(f"thruster{i + 1}_speed_rpm", loop.L_N + i, RPM),
                PlotField(f"thruster{i + 1}_utilisation", loop.L_UTIL + i)]
    terms = tuple(PlotField(f"{p}_{a}", loop.L_TERMS + 3 * j + i)
                  for j, p in enumerate(("p", "i", "d", "ff")) for i, a in enumerate(_AXES3))
    return (
        PlotChannel("/tree/state", "rov_console.TreeState", "true tree pose (NED)",
                    _pose_fields(loop.L_TREE)),
        PlotChannel("/rov/state", "rov_console.RovState", "true ROV pose (NED)",
                    _pose_fields(loop.L_ROV)),
        PlotChannel("/tree/estimate", "rov_console.TreeEstimate",
                    "what the controller believes of the tree: pose, body rates, bias, NIS", est),
        PlotChannel("/reference", "rov_console.Reference",
                    "reference pose and rate; error = true tree minus reference", ref),
        PlotChannel("/measurements", "rov_console.Measurements",
                    "held sensor values (sim.sensors) and accepted-sample flags", meas),
        PlotChannel("/control/forces", "rov_console.ControlForces",
                    "commanded force on the tree (tree axes), commanded and achieved ROV "
                    "wrench (ROV axes), supervisor mode (0 tree, 1 free)", forces),
        PlotChannel("/thrusters", "rov_console.Thrusters",
                    "per-thruster force, propeller speed and utilisation", tuple(thr)),
        PlotChannel("/control/terms", "rov_console.ControlTerms",
                    "P, I, D and feedforward parts of the tree force (tree axes)", terms),
    )


WIRE_FIELDS = ("crane_tip_north_m", "crane_tip_east_m", "wire_length_m",
               "tree_offset_from_tip_m")

# --------------------------------------------------------------------------------------------
# JSON schemas (Foxglove's well-known types, written from their documented field names)
# --------------------------------------------------------------------------------------------


def _num(description: str = "") -> dict:
    return {"type": "number", "description": description} if description else {"type": "number"}


def _object(title: str, description: str, properties: dict) -> dict:
    return {"title": title, "description": description, "type": "object",
            "properties": properties, "required": list(properties)}


def _array(items: dict, description: str) -> dict:
    return {"type": "array", "items": items, "description": description}


def _enum(title: str, values: Sequence[str]) -> dict:
    return {"title": title, "oneOf": [{"title": v, "const": i} for i, v in enumerate(values)]}


def _stamp(title: str, sec_min: int | None) -> dict:
    sec: dict = {"type": "integer"} if sec_min is None else {"type": "integer", "minimum": 0}
    return {"type": "object", "title": title, "properties": {
        "sec": sec, "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}}


TIME = _stamp("time", 0)
DURATION = _stamp("duration", None)
VECTOR3 = _object("foxglove.Vector3", "vector in 3D", {k: _num() for k in "xyz"})
POINT3 = _object("foxglove.Point3", "point in 3D", {k: _num() for k in "xyz"})
QUATERNION = _object("foxglove.Quaternion", "orientation", {k: _num() for k in "xyzw"})
POSE = _object("foxglove.Pose", "position and orientation",
               {"position": VECTOR3, "orientation": QUATERNION})
COLOR = _object("foxglove.Color", "RGBA, 0..1", {k: _num() for k in "rgba"})
KEY_VALUE = _object("foxglove.KeyValuePair", "key and value",
                    {"key": {"type": "string"}, "value": {"type": "string"}})


def _primitive_schemas() -> dict[str, dict]:
    """Schemas of the SceneEntity primitives, keyed by the entity's field name."""
    boolean = {"type": "boolean"}
    indices = _array({"type": "integer", "minimum": 0}, "indices into points")
    colors = _array(COLOR, "per-point colors")
    return {
        "arrows": _object("foxglove.ArrowPrimitive", "arrow along +x", {
            "pose": POSE, "shaft_length": _num(), "shaft_diameter": _num(),
            "head_length": _num(), "head_diameter": _num(), "color": COLOR}),
        "cubes": _object("foxglove.CubePrimitive", "box", {
            "pose": POSE, "size": VECTOR3, "color": COLOR}),
        "spheres": _object("foxglove.SpherePrimitive", "ellipsoid", {
            "pose": POSE, "size": VECTOR3, "color": COLOR}),
        "cylinders": _object("foxglove.CylinderPrimitive", "cylinder or cone along z", {
            "pose": POSE, "size": VECTOR3, "bottom_scale": _num("0-1, at min z"),
            "top_scale": _num("0-1, at max z"), "color": COLOR}),
        "lines": _object("foxglove.LinePrimitive", "connected points", {
            "type": _enum("foxglove.LineType", ("LINE_STRIP", "LINE_LOOP", "LINE_LIST")),
            "pose": POSE, "thickness": _num(), "scale_invariant": boolean,
            "points": _array(POINT3, "points"), "color": COLOR, "colors": colors,
            "indices": indices}),
        "triangles": _object("foxglove.TriangleListPrimitive", "triangles", {
            "pose": POSE, "points": _array(POINT3, "vertices"), "color": COLOR,
            "colors": colors, "indices": indices}),
        "texts": _object("foxglove.TextPrimitive", "text label", {
            "pose": POSE, "billboard": boolean, "font_size": _num(), "scale_invariant": boolean,
            "color": COLOR, "text": {"type": "string"}}),
        "models": _object("foxglove.ModelPrimitive", "3D model", {
            "pose": POSE, "scale": VECTOR3, "color": COLOR, "override_color": boolean,
            "url": {"type": "string"}, "media_type": {"type": "string"},
            "data": {"type": "string", "contentEncoding": "base64"}}),
    }


def scene_update_schema() -> dict:
    """foxglove.SceneUpdate as JSON schema."""
    entity_props = {
        "timestamp": TIME, "frame_id": {"type": "string"}, "id": {"type": "string"},
        "lifetime": DURATION, "frame_locked": {"type": "boolean"},
        "metadata": _array(KEY_VALUE, "user metadata"),
    }
    entity_props |= {k: _array(v, k) for k, v in _primitive_schemas().items()}
    entity = _object("foxglove.SceneEntity", "a visual element in a 3D scene", entity_props)
    deletion = _object("foxglove.SceneEntityDeletion", "entities to remove", {
        "timestamp": TIME, "type": _enum("foxglove.SceneEntityDeletionType",
                                         ("MATCHING_ID", "ALL")), "id": {"type": "string"}})
    return _object("foxglove.SceneUpdate", "an update to the entities of a 3D scene", {
        "deletions": _array(deletion, "entities to delete"),
        "entities": _array(entity, "entities to add or replace")})


def frame_transforms_schema() -> dict:
    """foxglove.FrameTransforms as JSON schema."""
    transform = _object("foxglove.FrameTransform", "parent frame to child frame", {
        "timestamp": TIME, "parent_frame_id": {"type": "string"},
        "child_frame_id": {"type": "string"}, "translation": VECTOR3, "rotation": QUATERNION})
    return _object("foxglove.FrameTransforms", "frame transforms",
                   {"transforms": _array(transform, "transforms")})


def log_schema() -> dict:
    """foxglove.Log as JSON schema."""
    return _object("foxglove.Log", "a log message", {
        "timestamp": TIME,
        "level": _enum("foxglove.LogLevel", ("UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR",
                                             "FATAL")),
        "message": {"type": "string"}, "name": {"type": "string"},
        "file": {"type": "string"}, "line": {"type": "integer", "minimum": 0}})


def _plot_schema(title: str, description: str, names: Sequence[str]) -> dict:
    props = {"t_s": _num("simulation time [s]")} | {n: _num() for n in names}
    return _object(title, description, props)


def session_log_schema() -> dict:
    return _object("rov_console.SessionLogRow", "one full row of the closed-loop log", {
        "t_s": _num("simulation time [s]"),
        "row": _array(_num(), "values in the order of the channel's 'columns' metadata "
                      "(null: not finite)")})


def event_schema() -> dict:
    return _object("rov_console.Event", "leg change, alarm, gain change, landing ...", {
        "t_s": _num("simulation time [s]"), "kind": {"type": "string"},
        "text": {"type": "string"},
        "data": {"type": "object", "properties": {}, "description": "free-form details"}})


# --------------------------------------------------------------------------------------------
# Geometry helpers for the scene
# --------------------------------------------------------------------------------------------


def quaternion_from_rpy_radians(phi: float, theta: float, psi: float) -> dict[str, float]:
    """Unit quaternion {x, y, z, w} of R_zyx(phi, theta, psi) (Fossen 2011, eq. 2.18)."""
    cr, sr = math.cos(phi / 2), math.sin(phi / 2)
    cp, sp = math.cos(theta / 2), math.sin(theta / 2)
    cy, sy = math.cos(psi / 2), math.sin(psi / 2)
    return {"x": sr * cp * cy - cr * sp * sy, "y": cr * sp * cy + sr * cp * sy,
            "z": cr * cp * sy - sr * sp * cy, "w": cr * cp * cy + sr * sp * sy}


WORLD_TO_NED = {"x": 1.0, "y": 0.0, "z": 0.0, "w": 0.0}
"""pi about the north axis: ``ned`` = [north, east, down] in ``world`` = [north, west, up]."""
IDENTITY = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}


def _vec(v: Sequence[float]) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def _pose(position: Sequence[float], orientation: dict[str, float] = IDENTITY) -> dict:
    return {"position": _vec(position), "orientation": orientation}


def _color(name: str) -> dict[str, float]:
    r, g, b, a = COLORS[name]
    return {"r": r, "g": g, "b": b, "a": a}


def _stamp_of(t_ns: int) -> dict[str, int]:
    return {"sec": t_ns // 1_000_000_000, "nsec": t_ns % 1_000_000_000}


def attachment_point_n(tree_eta_n: FloatArray, attachment_height_m: float) -> FloatArray:
    """Wire attachment in NED: the tree's centre plus R_nb [0, 0, -z_a] (z_a above it)."""
    r_nb = Rzyx(float(tree_eta_n[3]), float(tree_eta_n[4]), float(tree_eta_n[5]))
    return tree_eta_n[0:3] + r_nb @ np.array([0.0, 0.0, -attachment_height_m])


def rov_box_m(ps: ParameterSet) -> FloatArray:
    """Box drawn for the ROV [L, W, H]: volume 1 / ROV_SOLIDITY times the displaced water of
    its mass, shape ROV_BOX_ASPECT (drawing only)."""
    volume = ps.rov.M_rb[0, 0] / RHO_WATER / ROV_SOLIDITY
    aspect = np.array(ROV_BOX_ASPECT)
    return aspect * (volume / float(np.prod(aspect))) ** (1.0 / 3.0)


@dataclass(frozen=True)
class SceneGeometry:
    """Sizes of what the scene draws, from the parameter set."""

    tree_box_m: FloatArray
    attachment_height_m: float
    rov_box_m: FloatArray
    layout: DockingLayout
    thrust_capacity_n: float


def scene_geometry(ps: ParameterSet) -> SceneGeometry:
    thr = ps.rov.thrusters
    return SceneGeometry(np.asarray(ps.tree.dimensions_m, float), ps.tree.attachment_height_m,
                         rov_box_m(ps), ps.spec.docking.to_numeric(),
                         float(np.sum(thr.f_max_pos)))


# --------------------------------------------------------------------------------------------
# Message builders (pure functions of a row)
# --------------------------------------------------------------------------------------------


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


def plot_message(channel: PlotChannel, row: FloatArray) -> dict:
    """The named numbers of one plot channel for a log row."""
    out: dict[str, float | None] = {"t_s": float(row[loop.L_T])}
    for f in channel.fields:
        v = float(row[f.column]) - (float(row[f.minus]) if f.minus is not None else 0.0)
        out[f.name] = _finite_or_none(v * f.scale)
    return out


PRIMITIVE_KEYS = tuple(_primitive_schemas())


def _entity(t_ns: int, frame_id: str, entity_id: str, locked: bool, **primitives: list) -> dict:
    """A foxglove.SceneEntity (every primitive list present, empty when unused)."""
    ent = {"timestamp": _stamp_of(t_ns), "frame_id": frame_id, "id": entity_id,
           "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": locked, "metadata": []}
    for key in PRIMITIVE_KEYS:
        ent[key] = primitives.get(key, [])
    return ent


def _cube(position: Sequence[float], size: Sequence[float], color: str,
          orientation: dict[str, float] = IDENTITY) -> dict:
    return {"pose": _pose(position, orientation), "size": _vec(size), "color": _color(color)}


def _body_entities(t_ns: int, row: FloatArray, geo: SceneGeometry) -> list[dict]:
    """Tree (with funnels), ROV (with its commanded horizontal force) and reference ghost."""
    lay = geo.layout
    h = geo.tree_box_m[2]
    funnels = [{"pose": _pose([x, y, h / 2 - lay.post_height_m / 2]),
                "size": _vec([2 * lay.funnel_mouth_radius_m] * 2 + [lay.post_height_m]),
                "bottom_scale": lay.post_radius_m / lay.funnel_mouth_radius_m,
                "top_scale": 1.0, "color": _color("funnel")} for x, y in lay.post_xy_m]
    tree = _entity(t_ns, "tree", "tree", True,
                   cubes=[_cube([0, 0, 0], geo.tree_box_m, "tree")], cylinders=funnels)
    fx, fy = row[loop.L_TAU_ROV], row[loop.L_TAU_ROV + 1]
    length = ARROW_LENGTH_M * min(math.hypot(fx, fy) / geo.thrust_capacity_n, 1.0)
    arrows = []
    if math.isfinite(length) and length > 1e-3:
        head = min(0.3, length / 3)
        arrows = [{"pose": _pose([0, 0, 0], quaternion_from_rpy_radians(
            0.0, 0.0, math.atan2(fy, fx))), "shaft_length": length - head,
            "shaft_diameter": 0.05, "head_length": head, "head_diameter": 0.15,
            "color": _color("force")}]
    rov = _entity(t_ns, "rov", "rov", True, cubes=[_cube([0, 0, 0], geo.rov_box_m, "rov")],
                  arrows=arrows)
    ref = _entity(t_ns, "reference", "reference", True,
                  cubes=[_cube([0, 0, 0], geo.tree_box_m, "reference")])
    return [tree, rov, ref]


def _docking_entity(t_ns: int, frame: DockingFrame, layout: DockingLayout) -> dict:
    """Frame top plate and guideposts, in NED."""
    q = quaternion_from_rpy_radians(0.0, 0.0, frame.heading_rad)
    plate_centre = [frame.center_n[0], frame.center_n[1],
                    frame.landing_depth_m + PLATE_THICKNESS_M / 2]
    plate = _cube(plate_centre, [*layout.frame_size_m, PLATE_THICKNESS_M], "frame", q)
    posts = [{"pose": _pose([n, e, frame.landing_depth_m - layout.post_height_m / 2]),
              "size": _vec([2 * layout.post_radius_m] * 2 + [layout.post_height_m]),
              "bottom_scale": 1.0, "top_scale": 1.0, "color": _color("post")}
             for n, e in frame.post_positions_n(layout)]
    return _entity(t_ns, "ned", "docking_frame", False, cubes=[plate], cylinders=posts)


def scene_message(t_ns: int, row: FloatArray, geo: SceneGeometry,
                  crane_tip_n: FloatArray | None, docking: DockingFrame | None) -> dict:
    """foxglove.SceneUpdate for one row: bodies, wire (crane tip to attachment), docking."""
    entities = _body_entities(t_ns, row, geo)
    if crane_tip_n is not None:
        tree_eta = row[loop.L_TREE:loop.L_TREE + 6]
        attach = attachment_point_n(tree_eta, geo.attachment_height_m)
        wire = {"type": 0, "pose": _pose([0, 0, 0]), "thickness": 3.0, "scale_invariant": True,
                "points": [_vec(crane_tip_n), _vec(attach)], "color": _color("wire"),
                "colors": [], "indices": []}
        entities.append(_entity(t_ns, "ned", "wire", False, lines=[wire]))
    if docking is not None:
        entities.append(_docking_entity(t_ns, docking, geo.layout))
    return {"deletions": [], "entities": entities}


def _transform(t_ns: int, parent: str, child: str, translation: Sequence[float],
               rotation: dict[str, float]) -> dict:
    return {"timestamp": _stamp_of(t_ns), "parent_frame_id": parent, "child_frame_id": child,
            "translation": _vec(translation), "rotation": rotation}


def tf_message(t_ns: int, row: FloatArray) -> dict:
    """foxglove.FrameTransforms: world -> ned, ned -> tree, rov, reference."""
    tree = row[loop.L_TREE:loop.L_TREE + 6]
    rov = row[loop.L_ROV:loop.L_ROV + 6]
    ref = row[loop.L_ETA_D:loop.L_ETA_D + 3]
    return {"transforms": [
        _transform(t_ns, "world", "ned", [0, 0, 0], WORLD_TO_NED),
        _transform(t_ns, "ned", "tree", tree[0:3], quaternion_from_rpy_radians(*tree[3:6])),
        _transform(t_ns, "ned", "rov", rov[0:3], quaternion_from_rpy_radians(*rov[3:6])),
        _transform(t_ns, "ned", "reference", [ref[0], ref[1], tree[2]],
                   quaternion_from_rpy_radians(0.0, 0.0, ref[2])),
    ]}


def wire_message(row: FloatArray, crane_tip_n: FloatArray, wire_length_m: float) -> dict:
    offset = math.hypot(row[loop.L_TREE] - crane_tip_n[0], row[loop.L_TREE + 1] - crane_tip_n[1])
    values = (crane_tip_n[0], crane_tip_n[1], wire_length_m, offset)
    return {"t_s": float(row[loop.L_T])} | {k: _finite_or_none(float(v))
                                           for k, v in zip(WIRE_FIELDS, values, strict=True)}


def session_row_message(row: FloatArray) -> dict:
    values = row.tolist()
    if not np.all(np.isfinite(row)):
        values = [v if math.isfinite(v) else None for v in values]
    return {"t_s": float(row[loop.L_T]), "row": values}


EVENT_LEVELS = {"alarm": 3, "warning": 3, "error": 4, "diverged": 4, "abort": 4}
"""foxglove.Log level of an event kind (INFO = 2 for the others)."""


# --------------------------------------------------------------------------------------------
# Decimation by simulation time
# --------------------------------------------------------------------------------------------


@dataclass
class Decimator:
    """Keeps the first row at or after each multiple of 1/rate_hz of simulation time."""

    rate_hz: float
    last_slot: float = -math.inf

    def select(self, t_s: FloatArray) -> NDArray[np.bool_]:
        """Mask of the rows to keep (rows in time order); remembers the last slot taken."""
        slots = np.floor(t_s * self.rate_hz + GRID_EPS)
        previous = np.concatenate(([self.last_slot], slots[:-1]))
        keep = slots > np.maximum.accumulate(previous)
        if len(slots):
            self.last_slot = max(self.last_slot, float(slots.max()))
        return keep


def decimated_indices(t_s: FloatArray, rate_hz: float) -> NDArray[np.int64]:
    """Indices of the rows a fresh recorder keeps at ``rate_hz`` (for callers and tests)."""
    return np.flatnonzero(Decimator(rate_hz).select(np.asarray(t_s, float)))


# --------------------------------------------------------------------------------------------
# The recorder
# --------------------------------------------------------------------------------------------


def _crane_tip(value: Sequence[float]) -> FloatArray:
    """[north, east, down] of the crane tip from 2 or 3 numbers [m]."""
    tip = np.asarray(value, dtype=float).ravel()
    if tip.size == 2:
        tip = np.append(tip, 0.0)
    if tip.size != 3 or not np.all(np.isfinite(tip)):
        raise ValueError(f"crane_tip_n must be 2 or 3 finite numbers [m], got {value!r}")
    return tip


def software_version() -> str:
    try:
        return importlib_metadata.version("rov-console")
    except importlib_metadata.PackageNotFoundError:
        return "unknown"


def _without_nan(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by None (JSON has no NaN)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _without_nan(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_without_nan(v) for v in obj]
    return obj


def _json_bytes(obj: Any) -> bytes:
    """Compact JSON; non-finite numbers become null."""
    try:
        return json.dumps(obj, separators=(",", ":"), allow_nan=False).encode()
    except ValueError:
        return json.dumps(_without_nan(obj), separators=(",", ":"), allow_nan=False).encode()


def _setup_record(metadata: dict[str, Any], ps: ParameterSet, n_thrusters: int,
                  rates: dict[str, float]) -> dict[str, str]:
    """The metadata record: every value JSON-encoded (strings too, so reading is exact).

    A caller's value for a key the recorder writes itself must be the recorder's value."""
    recorder = {"format_version": FORMAT_VERSION, "software_version": software_version(),
                "mcap_python": importlib_metadata.version("mcap"),
                "n_thrusters": n_thrusters, "frames": "world = [north, west, up] (z up); "
                "ned = [north, east, down]; tree, rov, reference: children of ned"} | rates
    own = {"params": ps.spec.model_dump(mode="json"), "columns": COLUMNS, "recorder": recorder}
    clash = sorted(k for k in set(metadata) & set(own) if metadata[k] != own[k])
    if clash:
        raise ValueError(f"metadata keys {clash} are written by the recorder itself "
                         "(leave them out)")
    out = {}
    for key, value in {**metadata, **own}.items():
        try:
            out[str(key)] = json.dumps(value, sort_keys=True, allow_nan=False)
        except (TypeError, ValueError) as err:
            raise ValueError(f"metadata[{key!r}] cannot be written as JSON: {err}") from None
    return out


class SessionRecorder:
    """Writes one session to an MCAP file (see the module docstring)."""

    def __init__(self, path: str | Path, *, metadata: dict[str, str | dict], params: ParameterSet,
                 n_thrusters: int, flush_interval_s: float = 0.5,
                 numeric_rate_hz: float = 20.0, scene_rate_hz: float = 5.0,
                 clock: Callable[[], float] = time.monotonic, overwrite: bool = False,
                 docking: DockingFrame | None = None) -> None:
        """Create ``path`` (refuses an existing file unless ``overwrite``), write the header,
        schemas, channels and the ``setup`` metadata record, and start the flush thread.
        ``docking``: the docking frame to draw from the start (``write_log`` can change it)."""
        if not 1 <= n_thrusters <= loop.M_MAX:
            raise ValueError(f"n_thrusters must be in [1, {loop.M_MAX}], got {n_thrusters}")
        for name, v in (("flush_interval_s", flush_interval_s),
                        ("numeric_rate_hz", numeric_rate_hz), ("scene_rate_hz", scene_rate_hz)):
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be a positive number, got {v}")
        rates = {"numeric_rate_hz": numeric_rate_hz, "scene_rate_hz": scene_rate_hz,
                 "flush_interval_s": flush_interval_s}
        setup = _setup_record(metadata, params, n_thrusters, rates)
        self._plots = plot_channels(n_thrusters)
        self._geo = scene_geometry(params)
        self.path = Path(path)
        self._file: BinaryIO = open(self.path, "wb" if overwrite else "xb")
        self._writer = Writer(self._file, compression=CompressionType.ZSTD)
        self._writer.start(profile="", library=f"rov-console {software_version()}")
        self._numeric = Decimator(numeric_rate_hz)
        self._scene = Decimator(scene_rate_hz)
        self._channels = self._register_channels()
        self._sequence = dict.fromkeys(self._channels, 0)
        self._writer.add_metadata(SETUP_RECORD, setup)
        self._crane_tip_n: FloatArray | None = None
        self._wire_length_m = math.nan
        self._docking = docking
        self._last_t_s = -math.inf
        self._clock = clock
        self._flush_interval_s = flush_interval_s
        self._lock = threading.Lock()
        self._dirty = False
        self._closed = False
        self._last_flush = clock()
        self._writer.flush()
        self._stop = threading.Event()
        self._flusher: threading.Thread | None = self._start_flusher()

    def _start_flusher(self) -> threading.Thread | None:
        """The thread that flushes while the caller is idle."""
        thread = threading.Thread(target=self._flush_loop, name="mcap-flush", daemon=True)
        thread.start()
        return thread

    # ------------------------------------------------------------------ set-up
    def _register_channels(self) -> dict[str, int]:
        w = self._writer

        def add(topic: str, schema: dict, meta: dict[str, str] | None = None) -> None:
            sid = w.register_schema(schema["title"], "jsonschema", _json_bytes(schema))
            channels[topic] = w.register_channel(topic, "json", sid, meta or {})

        channels: dict[str, int] = {}
        add(SESSION_TOPIC, session_log_schema(),
            {"kind": "table", "columns": json.dumps(COLUMNS)})
        add("/tf", frame_transforms_schema())
        add("/scene", scene_update_schema())
        for ch in self._plots:
            names = [f.name for f in ch.fields]
            add(ch.topic, _plot_schema(ch.schema_name, ch.description, names),
                {"kind": "numeric"})
        add("/wire", _plot_schema("rov_console.Wire", "crane tip, wire length and the tree's "
                                  "horizontal offset from the tip", WIRE_FIELDS),
            {"kind": "numeric"})
        add(EVENTS_TOPIC, event_schema(), {"kind": "events"})
        add("/log", log_schema())
        return channels

    # ------------------------------------------------------------------ writing
    def _add(self, topic: str, t_ns: int, message: dict) -> None:
        cid = self._channels[topic]
        self._sequence[topic] += 1
        self._writer.add_message(cid, log_time=t_ns, publish_time=t_ns,
                                 data=_json_bytes(message), sequence=self._sequence[topic])
        self._dirty = True

    def _check_open(self) -> None:
        if self._closed:
            raise RecordingError(f"{self.path}: the recorder is closed")

    def write_log(self, data: FloatArray, crane_tip_n: Sequence[float] | None = None,
                  wire_length_m: float | None = None, docking: DockingFrame | None = None) -> None:
        """Record rows of ``control.loop`` columns (n, N_LOG), later than every row recorded so
        far and in time order (else ValueError: a restarted simulation needs a new recorder).

        ``crane_tip_n`` (NED, m), ``wire_length_m`` and ``docking``: None keeps the last value
        given; the wire is drawn and ``/wire`` written once a crane tip is known."""
        rows = np.asarray(data, dtype=float)
        if rows.ndim != 2 or rows.shape[1] != loop.N_LOG:
            raise ValueError(f"log rows must have shape (n, {loop.N_LOG}), got {rows.shape}")
        t = rows[:, loop.L_T]
        with self._lock:
            self._check_open()
            if len(t) and not (t[0] > self._last_t_s and np.all(np.diff(t) > 0.0)):
                raise ValueError(f"log rows must go forward in time after the last recorded "
                                 f"t = {self._last_t_s} s; got t = {t[0]} .. {t[-1]} s")
            if crane_tip_n is not None:
                self._crane_tip_n = _crane_tip(crane_tip_n)
            if wire_length_m is not None:
                self._wire_length_m = float(wire_length_m)
            if docking is not None:
                self._docking = docking
            self._last_t_s = float(t[-1]) if len(t) else self._last_t_s
            numeric = self._numeric.select(t)
            scene = self._scene.select(t)
            for k in np.flatnonzero(numeric | scene):
                self._write_row(rows[k], bool(numeric[k]), bool(scene[k]))
                self._maybe_flush()

    def _write_row(self, row: FloatArray, numeric: bool, scene: bool) -> None:
        t_ns = round(float(row[loop.L_T]) * 1e9)
        if numeric:
            self._add(SESSION_TOPIC, t_ns, session_row_message(row))
            self._add("/tf", t_ns, tf_message(t_ns, row))
            for ch in self._plots:
                self._add(ch.topic, t_ns, plot_message(ch, row))
            if self._crane_tip_n is not None:
                self._add("/wire", t_ns, wire_message(row, self._crane_tip_n,
                                                      self._wire_length_m))
        if scene:
            self._add("/scene", t_ns, scene_message(t_ns, row, self._geo, self._crane_tip_n,
                                                    self._docking))

    def event(self, t_s: float, kind: str, text: str, data: dict | None = None) -> None:
        """Record an event at simulation time ``t_s`` on ``/events`` (and ``/log`` for
        Foxglove's Log panel). ``kind``: e.g. leg, alarm, gains, landing."""
        if not math.isfinite(t_s) or t_s < 0.0:
            raise ValueError(f"event time must be a finite number of seconds >= 0, got {t_s}")
        if not kind:
            raise ValueError("event kind must not be empty")
        message = {"t_s": float(t_s), "kind": str(kind), "text": str(text), "data": data or {}}
        try:
            _json_bytes(message)
        except (TypeError, ValueError) as err:
            raise ValueError(f"event data cannot be written as JSON: {err}") from None
        t_ns = round(t_s * 1e9)
        log = {"timestamp": _stamp_of(t_ns), "level": EVENT_LEVELS.get(kind, 2),
               "message": f"{kind}: {text}", "name": "rov-console", "file": "", "line": 0}
        with self._lock:
            self._check_open()
            self._add(EVENTS_TOPIC, t_ns, message)
            self._add("/log", t_ns, log)
            self._maybe_flush()

    # ------------------------------------------------------------------ flushing and closing
    def _maybe_flush(self) -> None:
        """Flush (lock held) when flush_interval_s of wall time has passed."""
        if self._dirty and self._clock() - self._last_flush >= self._flush_interval_s:
            self._flush_locked()

    def _flush_locked(self) -> None:
        self._writer.flush()
        self._dirty = False
        self._last_flush = self._clock()

    def flush(self) -> None:
        """Close the chunk in progress and hand everything to the operating system now."""
        with self._lock:
            self._check_open()
            self._flush_locked()

    def _flush_loop(self) -> None:
        poll = min(self._flush_interval_s / 4.0, 0.1)
        while not self._stop.wait(poll):
            with self._lock:
                if self._closed:
                    return
                self._maybe_flush()

    def close(self) -> None:
        """Write the summary and footer and close the file. Idempotent."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            try:
                self._writer.finish()
            finally:
                self._file.close()
        self._stop.set()
        if self._flusher is not None and self._flusher is not threading.current_thread():
            self._flusher.join()

    def __enter__(self) -> SessionRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SessionData:
    """A session log as read back (complete or cut off)."""

    metadata: dict
    """The setup record, decoded."""
    columns: list[str]
    t_s: FloatArray
    """(n,) simulation time of each row [s]."""
    rows: FloatArray
    """(n, N_LOG) the rows of ``/session/log``."""
    events: list[dict]
    complete: bool
    """Footer present and every record intact."""
    message_counts: dict[str, int]
    end_time_s: float
    """Latest message time [s] (nan when there is none)."""
    file_bytes: int = 0
    intact_bytes: int = 0
    """Bytes of whole, valid records from the start; the rest is cut off or damaged."""
    problem: str = ""
    """Why the file is not complete ('' when it is)."""


@dataclass
class _Scan:
    """Everything found in the intact part of a file."""

    file_bytes: int
    intact_bytes: int = 8
    complete: bool = False
    problem: str = ""
    header: Header | None = None
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    messages: dict[str, list[Message]] = field(default_factory=dict)
    statistics: Statistics | None = None


_READ_ERRORS = (McapError, ValueError, struct.error, zstandard.ZstdError, EOFError)


def _record_spans(buf: bytes) -> Iterator[tuple[int, int, int]]:
    """(start, end, opcode) of each whole top-level record after the magic."""
    pos = len(MCAP_MAGIC)
    while pos + 9 <= len(buf):
        opcode = buf[pos]
        (length,) = struct.unpack_from("<Q", buf, pos + 1)
        end = pos + 9 + length
        if end > len(buf):
            return
        yield pos, end, opcode
        pos = end


def _parse_record(buf: bytes, start: int, end: int) -> list:
    """The record at buf[start:end], a chunk broken up into its records (CRC checked)."""
    reader = StreamReader(io.BytesIO(buf[start:end]), skip_magic=True, emit_chunks=True,
                          validate_crcs=True)
    record = next(iter(reader.records))
    if isinstance(record, Chunk):
        return breakup_chunk(record, validate_crc=True)
    return [record]


def _take(scan: _Scan, record: object) -> None:
    if isinstance(record, Header):
        scan.header = record
    elif isinstance(record, Schema):
        scan.schemas[record.id] = record
    elif isinstance(record, Channel):
        scan.channels[record.id] = record
    elif isinstance(record, Metadata):
        scan.metadata[record.name] = dict(record.metadata)
    elif isinstance(record, Message):
        channel = scan.channels.get(record.channel_id)
        if channel is None:
            raise ValueError(f"message on unknown channel {record.channel_id}")
        scan.messages.setdefault(channel.topic, []).append(record)
    elif isinstance(record, Statistics):
        scan.statistics = record


def _scan_file(path: Path) -> _Scan:
    """Read every intact record; stop at the first cut-off or damaged one."""
    try:
        buf = path.read_bytes()
    except OSError as err:
        raise ValueError(f"{path}: cannot read: {err.strerror or err}") from None
    if buf[:len(MCAP_MAGIC)] != MCAP_MAGIC:
        what = "empty" if not buf else "does not start with the MCAP magic bytes"
        raise ValueError(f"{path}: not an MCAP file ({what})")
    scan = _Scan(file_bytes=len(buf))
    _scan_records(buf, scan)
    if scan.header is None:
        raise ValueError(f"{path}: MCAP file without a readable header record "
                         f"({len(buf)} bytes): {scan.problem or 'nothing to read'}")
    return scan


def _scan_records(buf: bytes, scan: _Scan) -> None:
    """Fill ``scan`` from the records of ``buf`` up to the footer or the first bad record."""
    known = {int(op) for op in Opcode}
    for start, end, opcode in _record_spans(buf):
        if opcode not in known:  # a newer writer's record: skipped, as the MCAP spec asks
            scan.intact_bytes = end
            continue
        try:
            for record in _parse_record(buf, start, end):
                _take(scan, record)
        except _READ_ERRORS as err:
            scan.problem = f"damaged record (opcode {opcode:#04x}) at byte {start}: {err}"
            return
        scan.intact_bytes = end
        if opcode == Opcode.FOOTER:
            scan.complete = buf[end:] == MCAP_MAGIC
            if scan.complete:
                scan.intact_bytes = len(buf)
            else:
                scan.problem = f"footer at byte {start} is not followed by the closing magic"
            return
    scan.problem = (f"cut off at byte {scan.intact_bytes} of {len(buf)}: no footer "
                    "(the writer did not finish: killed or still writing)")


def _check_statistics(scan: _Scan) -> None:
    """A complete file's statistics must agree with the messages read."""
    if not scan.complete or scan.statistics is None:
        return
    for cid, n in scan.statistics.channel_message_counts.items():
        topic = scan.channels[cid].topic if cid in scan.channels else f"#{cid}"
        if len(scan.messages.get(topic, [])) != n:
            scan.complete = False
            scan.problem = (f"statistics say {n} messages on {topic}, "
                            f"found {len(scan.messages.get(topic, []))}")


def _decode_setup(scan: _Scan) -> dict:
    out = {}
    for key, text in scan.metadata.get(SETUP_RECORD, {}).items():
        try:
            out[key] = json.loads(text)
        except json.JSONDecodeError:
            out[key] = text
    return out


def _rows(messages: list[Message], width: int) -> FloatArray:
    """(n, width) rows of ``/session/log`` messages (null read as NaN)."""
    rows = np.empty((len(messages), width))
    for i, m in enumerate(messages):
        values = json.loads(m.data)["row"]
        if len(values) != width:
            raise ValueError(f"{SESSION_TOPIC} message {i} has {len(values)} values for "
                             f"{width} columns")
        rows[i] = [math.nan if v is None else v for v in values]
    return rows


def _read(path: str | Path) -> tuple[_Scan, SessionData]:
    p = Path(path)
    scan = _scan_file(p)
    _check_statistics(scan)
    setup = _decode_setup(scan)
    columns = list(setup.get("columns") or _session_columns(scan) or COLUMNS)
    rows = _rows(scan.messages.get(SESSION_TOPIC, []), len(columns))
    events = [json.loads(m.data) for m in scan.messages.get(EVENTS_TOPIC, [])]
    ends = [m.log_time for msgs in scan.messages.values() for m in msgs]
    data = SessionData(
        metadata=setup, columns=columns, t_s=rows[:, 0].copy(), rows=rows, events=events,
        complete=scan.complete,
        message_counts={t: len(m) for t, m in sorted(scan.messages.items())},
        end_time_s=max(ends) / 1e9 if ends else math.nan, file_bytes=scan.file_bytes,
        intact_bytes=scan.intact_bytes, problem=scan.problem)
    return scan, data


def _session_columns(scan: _Scan) -> list[str] | None:
    for ch in scan.channels.values():
        if ch.topic == SESSION_TOPIC and "columns" in ch.metadata:
            return json.loads(ch.metadata["columns"])
    return None


def load_session(path: str | Path) -> SessionData:
    """Read a session log, complete or cut off (up to its last intact record).

    Raises ValueError naming the file when it is not an MCAP file at all."""
    return _read(path)[1]


def check_session(path: str | Path) -> dict:
    """What a file holds: status, where it stops, channels with counts, time range, metadata.

    Raises ValueError naming the file when it is not an MCAP file at all."""
    scan, data = _read(path)
    channels = []
    for ch in sorted(scan.channels.values(), key=lambda c: c.id):
        msgs = scan.messages.get(ch.topic, [])
        schema = scan.schemas.get(ch.schema_id)
        channels.append({
            "topic": ch.topic, "schema": schema.name if schema else "",
            "encoding": ch.message_encoding, "messages": len(msgs),
            "first_s": min(m.log_time for m in msgs) / 1e9 if msgs else None,
            "last_s": max(m.log_time for m in msgs) / 1e9 if msgs else None})
    starts = [c["first_s"] for c in channels if c["first_s"] is not None]
    return {
        "file": str(path), "status": "complete" if data.complete else "truncated",
        "complete": data.complete, "problem": data.problem, "file_bytes": data.file_bytes,
        "intact_bytes": data.intact_bytes, "writer": scan.header.library if scan.header else "",
        "time_range_s": [min(starts), data.end_time_s] if starts else None,
        "rows": len(data.rows), "events": len(data.events),
        "metadata_records": sorted(scan.metadata),
        "metadata_keys": sorted(data.metadata), "channels": channels,
    }


# --------------------------------------------------------------------------------------------
# CSV export
# --------------------------------------------------------------------------------------------


def _csv_name(topic: str) -> str:
    return topic.strip("/").replace("/", "_") + ".csv"


def _write_csv(path: Path, header: Sequence[str], rows: Iterator[Sequence[object]]) -> Path:
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    return path


def _csv_value(v: object) -> object:
    """Floats as repr (exact round trip), missing numbers as 'nan'."""
    if v is None:
        return "nan"
    return repr(v) if isinstance(v, float) else v


def export_csv(path: str | Path, out_dir: str | Path, *, overwrite: bool = False) -> list[Path]:
    """Write ``session_log.csv`` (all columns of ``/session/log``), one CSV per plot channel
    (``tree_state.csv`` ...; columns = the message's fields) and ``events.csv``. Numbers are
    written exactly (shortest round-trip repr). Refuses to replace files unless ``overwrite``.
    Returns the files written."""
    scan, data = _read(path)
    out = Path(out_dir)
    topics = [ch.topic for ch in sorted(scan.channels.values(), key=lambda c: c.id)
              if ch.metadata.get("kind") == "numeric"]
    names = ["session_log.csv", *(_csv_name(t) for t in topics), "events.csv"]
    if not overwrite:
        existing = [n for n in names if (out / n).exists()]
        if existing:
            raise FileExistsError(f"{out}: would replace {', '.join(existing)} "
                                  "(choose another folder or allow overwriting)")
    out.mkdir(parents=True, exist_ok=True)
    written = [_write_csv(out / names[0], data.columns,
                          ([_csv_value(float(v)) for v in r] for r in data.rows))]
    for topic, name in zip(topics, names[1:-1], strict=True):
        decoded = [json.loads(m.data) for m in scan.messages.get(topic, [])]
        header = list(decoded[0]) if decoded else []
        written.append(_write_csv(out / name, header,
                                  ([_csv_value(d.get(k)) for k in header] for d in decoded)))
    written.append(_write_csv(out / names[-1], ["t_s", "kind", "text", "data"], (
        [_csv_value(e["t_s"]), e["kind"], e["text"], json.dumps(e.get("data", {}))]
        for e in data.events)))
    return written
