"""The bodies drawn in the 3D view, built with trimesh from the parameter set's dimensions.

Pure functions from dimensions to ``trimesh.Trimesh`` parts (a dict, name to part, each
coloured by its vertices), in the body's own axes (x forward, y starboard, z down, as NED):

- the tree (appendix A's drawings): a frame of corner columns and rings, the valve block with
  its bore pipe and actuators, a funnel (a cone narrowing from the mouth up to the bore, then
  the bore) over each post position, its mouth on the tree's bottom; the running tool on top,
  from the top of the tree up to the wire's attachment point;
- the docking frame: a beam frame under its landing surface and the guideposts with their
  pointed tops;
- a work-class ROV: buoyancy block over an open frame on skids, a camera and lights at the
  bow, and a duct per thruster where the thrust configuration matrix puts it.

The tree's parts fill its box exactly (``tree_dimensions_m``), the ROV's its drawing box; the
tests check both, the funnels' places and the thruster count.
"""

from __future__ import annotations

import math

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
Parts = dict[str, trimesh.Trimesh]
Rgb = tuple[int, int, int]

TREE_FRAME_COLOR: Rgb = (235, 190, 40)
VALVE_COLOR: Rgb = (150, 155, 160)
FUNNEL_COLOR: Rgb = (235, 190, 40)
TOOL_COLOR: Rgb = (70, 80, 90)
DOCK_COLOR: Rgb = (110, 115, 125)
POST_COLOR: Rgb = (225, 225, 230)
ROV_FLOAT_COLOR: Rgb = (230, 110, 30)
ROV_FRAME_COLOR: Rgb = (60, 60, 65)
THRUSTER_COLOR: Rgb = (25, 25, 25)
LAMP_COLOR: Rgb = (250, 250, 220)
SILT_COLOR: Rgb = (150, 135, 100)
SAND_COLOR: Rgb = (194, 178, 128)
SECTIONS = 24
"""Facets around a round part."""


def linear_rgb(srgb: ArrayLike) -> NDArray[np.uint8]:
    """sRGB colours (0-255, any shape (..., 3)) as linear light (0-255): what a GLB's vertex
    colours and viser's fog colour hold (the browser encodes them to sRGB on the screen; given
    sRGB, sand (194, 178, 128) showed as (230, 226, 214))."""
    c = np.asarray(srgb, float) / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return np.round(255.0 * linear).astype(np.uint8)


def _colored(mesh: trimesh.Trimesh, color: Rgb) -> trimesh.Trimesh:
    """The mesh with its faces apart (flat shading: a box's faces are not smoothed into one
    another) and every vertex in ``color`` (sRGB)."""
    mesh.unmerge_vertices()
    rgba = np.array([*linear_rgb(color), 255], np.uint8)
    mesh.visual = trimesh.visual.ColorVisuals(
        mesh, vertex_colors=np.tile(rgba, (len(mesh.vertices), 1))
    )
    return mesh


def box_part(lo: ArrayLike, hi: ArrayLike, color: Rgb) -> trimesh.Trimesh:
    """A box between two corners."""
    return _colored(trimesh.creation.box(bounds=np.array([lo, hi], float)), color)


def lathe_part(
    profile_rz: list[tuple[float, float]], center: FloatArray, color: Rgb, axis: FloatArray
) -> trimesh.Trimesh:
    """A round part turned from a closed (radius, along-axis) profile, its axis along ``axis``
    through ``center`` (the profile's along-axis 0 at ``center``)."""
    rz = list(profile_rz)
    if rz[0][0] > 0.0 and rz[0] != rz[-1]:
        rz.append(rz[0])  # a ring's profile: closed
    mesh = trimesh.creation.revolve(np.array(rz, float), sections=SECTIONS)
    if mesh.volume < 0.0:
        mesh.invert()  # a profile turned clockwise: faces outwards again
    mesh.apply_transform(_axis_transform(np.asarray(center, float), np.asarray(axis, float)))
    return _colored(mesh, color)


def _axis_transform(center: FloatArray, axis: FloatArray) -> FloatArray:
    """4x4 taking +z to ``axis`` (unit) and the origin to ``center``."""
    a = axis / np.linalg.norm(axis)
    rot = trimesh.geometry.align_vectors(np.array([0.0, 0.0, 1.0]), a)
    rot[:3, 3] = center
    return rot


def tube_part(
    radius: float, start: ArrayLike, end: ArrayLike, color: Rgb, inner: float = 0.0
) -> trimesh.Trimesh:
    """A round bar (or, ``inner`` > 0, a tube) from ``start`` to ``end``."""
    a, b = np.asarray(start, float), np.asarray(end, float)
    length = float(np.linalg.norm(b - a))
    profile = [(inner, 0.0), (radius, 0.0), (radius, length), (inner, length)]
    return lathe_part(profile, a, color, b - a)


def combined(parts: Parts) -> trimesh.Trimesh:
    """One mesh of all the parts (one node in the scene)."""
    mesh = trimesh.util.concatenate(list(parts.values()))
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def _frame_members(lo: FloatArray, hi: FloatArray, bar: float, color: Rgb) -> list:
    """Four corner columns and a ring of beams round the top and the bottom of the box
    ``lo``..``hi`` (z down), each ``bar`` square."""
    members = []
    for x in (lo[0], hi[0] - bar):
        for y in (lo[1], hi[1] - bar):
            members.append(box_part([x, y, lo[2]], [x + bar, y + bar, hi[2]], color))
    for z in (lo[2], hi[2] - bar):
        members.append(box_part([lo[0], lo[1], z], [hi[0], lo[1] + bar, z + bar], color))
        members.append(box_part([lo[0], hi[1] - bar, z], [hi[0], hi[1], z + bar], color))
        members.append(box_part([lo[0], lo[1], z], [lo[0] + bar, hi[1], z + bar], color))
        members.append(box_part([hi[0] - bar, lo[1], z], [hi[0], hi[1], z + bar], color))
    return members


def funnel_part(
    mouth_radius_m: float,
    bore_radius_m: float,
    cone_height_m: float,
    length_m: float,
    mouth_center: FloatArray,
    color: Rgb = FUNNEL_COLOR,
) -> trimesh.Trimesh:
    """A guide funnel: its mouth (``mouth_radius_m``) at ``mouth_center``, opening downwards;
    the cone narrows to the bore over ``cone_height_m`` and the bore goes on up to
    ``length_m`` above the mouth. Walls a tenth of the bore's radius thick."""
    wall = 0.1 * bore_radius_m
    # (radius, height over the mouth); the lathe's axis points up (-z)
    rz = [
        (mouth_radius_m, 0.0),
        (bore_radius_m, cone_height_m),
        (bore_radius_m, length_m),
        (bore_radius_m + wall, length_m),
        (bore_radius_m + wall, cone_height_m),
        (mouth_radius_m + wall, 0.0),
    ]
    return lathe_part(rz, mouth_center, color, np.array([0.0, 0.0, -1.0]))


def tree_parts(
    dimensions_m: FloatArray,
    post_xy_m: FloatArray,
    funnel_mouth_radius_m: float,
    funnel_bore_radius_m: float,
    funnel_cone_height_m: float,
) -> Parts:
    """The tree in its own axes (origin at its centre of gravity, the box's middle): frame,
    valve block, bore pipe, actuators and a funnel over each post position (``post_xy_m``,
    (k, 2)), its mouth on the tree's bottom. Spans exactly ``dimensions_m`` [L, W, H]."""
    length, width, height = (float(v) for v in dimensions_m)
    half = np.array([length, width, height]) / 2.0
    bar = 0.06 * min(length, width)
    parts: Parts = {}
    for k, member in enumerate(_frame_members(-half, half, bar, TREE_FRAME_COLOR)):
        parts[f"frame_{k}"] = member
    block = np.array([0.42 * length, 0.42 * width, 0.45 * height])
    block_top = 0.5 * height - bar - block[2]
    parts["valve_block"] = box_part(
        [-block[0] / 2, -block[1] / 2, block_top],
        [block[0] / 2, block[1] / 2, 0.5 * height - bar],
        VALVE_COLOR,
    )
    pipe_r = 0.08 * min(length, width)
    parts["bore_pipe"] = tube_part(
        pipe_r, [0.0, 0.0, block_top], [0.0, 0.0, -0.5 * height], VALVE_COLOR
    )
    for k, side in enumerate((-1.0, 1.0)):
        # valve actuators: round bonnets on the block's port and starboard faces
        y0 = side * block[1] / 2
        z = block_top + 0.5 * block[2]
        parts[f"actuator_{k}"] = tube_part(
            0.3 * block[2], [0.0, y0, z], [0.0, y0 + side * 0.15 * width, z], VALVE_COLOR
        )
    funnel_len = min(0.45 * height, funnel_cone_height_m + 0.3 * height)
    for k, (x, y) in enumerate(np.asarray(post_xy_m, float)):
        parts[f"funnel_{k}"] = funnel_part(
            funnel_mouth_radius_m,
            funnel_bore_radius_m,
            funnel_cone_height_m,
            funnel_len,
            np.array([x, y, 0.5 * height]),
        )
    return parts


def running_tool_parts(tree_height_m: float, attachment_height_m: float) -> Parts:
    """The running tool on the tree's top, in the tree's axes: a body from the top
    (``-tree_height_m / 2``) up to a padeye whose top is the wire's attachment point
    (``attachment_height_m`` above the centre of gravity). At least a twentieth of the tree's
    height tall, when the attachment point is (nearly) on the top."""
    top = -0.5 * tree_height_m
    tip = min(-attachment_height_m, top - 0.05 * tree_height_m)
    tall = top - tip
    radius = 0.1 * tree_height_m
    body_end = top - 0.7 * tall
    return {
        "tool_body": tube_part(radius, [0.0, 0.0, top], [0.0, 0.0, body_end], TOOL_COLOR),
        "tool_flange": tube_part(
            1.3 * radius, [0.0, 0.0, top], [0.0, 0.0, top - 0.12 * tall], TOOL_COLOR
        ),
        "padeye": box_part(
            [-0.15 * radius, -0.5 * radius, tip],
            [0.15 * radius, 0.5 * radius, body_end],
            TOOL_COLOR,
        ),
    }


def docking_frame_parts(
    frame_size_m: FloatArray,
    post_xy_m: FloatArray,
    post_radius_m: float,
    post_height_m: float,
    base_depth_m: float,
) -> Parts:
    """The docking frame in its own axes (origin at its centre on the landing surface, z
    down): a beam frame ``base_depth_m`` deep under the landing surface with cross beams, and
    a guidepost at each ``post_xy_m`` standing ``post_height_m`` over the surface, its top a
    cone of twice its radius. Spans ``frame_size_m`` and from the post tops to the base."""
    lx, ly = (float(v) for v in frame_size_m)
    lo = np.array([-lx / 2, -ly / 2, 0.0])
    hi = np.array([lx / 2, ly / 2, base_depth_m])
    bar = min(0.08 * min(lx, ly), 0.5 * base_depth_m)
    parts: Parts = {}
    for k, member in enumerate(_frame_members(lo, hi, bar, DOCK_COLOR)):
        parts[f"beam_{k}"] = member
    parts["cross_x"] = box_part([lo[0], -bar / 2, 0.0], [hi[0], bar / 2, bar], DOCK_COLOR)
    parts["cross_y"] = box_part([-bar / 2, lo[1], 0.0], [bar / 2, hi[1], bar], DOCK_COLOR)
    tip = min(2.0 * post_radius_m, 0.5 * post_height_m)
    for k, (x, y) in enumerate(np.asarray(post_xy_m, float)):
        base = np.array([x, y, base_depth_m])
        rz = [(0.0, 0.0), (post_radius_m, 0.0)]
        rz += [(post_radius_m, base_depth_m + post_height_m - tip)]
        rz += [(0.0, base_depth_m + post_height_m)]
        parts[f"post_{k}"] = lathe_part(rz, base, POST_COLOR, np.array([0.0, 0.0, -1.0]))
    return parts


def thruster_poses_b(configuration: FloatArray, rov_size_m: FloatArray) -> FloatArray:
    """(m, 6) thruster places and axes in the ROV's axes [x, y, z, dx, dy, dz] from the columns
    of the thrust configuration matrix T ((6, m): force direction d and moment m = r x d).

    The place is the point of the thrust's line nearest the ROV's centre, r = d x m / |d|^2
    (m's part along d, which no place gives, is left out). Thrusters with the same column
    (the model gives both vertical thrusters of Minerva the same one) are spread evenly
    fore and aft of that point: equal forces there give the same moment the allocation
    uses. Places are kept inside the box ``rov_size_m`` shrunk by a duct's size."""
    t = np.asarray(configuration, float)
    size = np.asarray(rov_size_m, float)
    duct = thruster_duct_radius_m(size)
    out = np.empty((t.shape[1], 6))
    for i in range(t.shape[1]):
        d = t[0:3, i] / np.linalg.norm(t[0:3, i])
        r = np.cross(t[0:3, i], t[3:6, i]) / float(t[0:3, i] @ t[0:3, i])
        out[i] = [*r, *d]
    for i in range(t.shape[1]):
        same = [j for j in range(t.shape[1]) if np.allclose(t[:, j], t[:, i])]
        if len(same) > 1:
            spread = np.linspace(-1.0, 1.0, len(same)) * 0.25 * size[0]
            out[i, 0] += spread[same.index(i)]
    limit = 0.5 * size - 1.2 * duct
    out[:, 0:3] = np.clip(out[:, 0:3], -limit, limit)
    return out


def thruster_duct_radius_m(rov_size_m: FloatArray) -> float:
    """Outer radius of a thruster's duct: a seventh of the ROV's smaller cross dimension."""
    size = np.asarray(rov_size_m, float)
    return float(min(size[1], size[2])) / 7.0


def rov_parts(rov_size_m: FloatArray, configuration: FloatArray) -> Parts:
    """A work-class ROV in its axes (origin at the box's middle): buoyancy block over the
    upper third, an open frame down to the skids, a camera and two lamps at the bow, and a
    duct per column of the thrust configuration (``thruster_poses_b``), named
    ``thruster_<i>``. Spans exactly ``rov_size_m`` [L, W, H]."""
    size = np.asarray(rov_size_m, float)
    half = size / 2.0
    bar = 0.06 * min(size[1], size[2])
    parts: Parts = {
        "buoyancy": box_part(
            [-half[0], -half[1], -half[2]],
            [half[0], half[1], -half[2] + 0.3 * size[2]],
            ROV_FLOAT_COLOR,
        )
    }
    frame_lo = np.array([-half[0], -half[1], -half[2] + 0.3 * size[2]])
    for k, member in enumerate(_frame_members(frame_lo, half, bar, ROV_FRAME_COLOR)):
        parts[f"frame_{k}"] = member
    for k, side in enumerate((-1.0, 1.0)):
        y = side * (half[1] - 2.0 * bar)
        parts[f"skid_{k}"] = box_part(
            [-half[0], y - bar, half[2] - bar], [half[0], y + bar, half[2]], ROV_FRAME_COLOR
        )
    cam = 0.08 * size[2]
    parts["camera"] = tube_part(
        cam, [half[0] - 3 * cam, 0.0, 0.15 * size[2]], [half[0], 0.0, 0.15 * size[2]], LAMP_COLOR
    )
    for k, pos in enumerate(rov_lamps_b(size)):
        parts[f"lamp_{k}"] = tube_part(cam, pos - [2 * cam, 0.0, 0.0], pos, LAMP_COLOR)
    radius = thruster_duct_radius_m(size)
    for i, pose in enumerate(thruster_poses_b(configuration, size)):
        axis = pose[3:6]
        parts[f"thruster_{i}"] = tube_part(
            radius,
            pose[0:3] - 0.5 * radius * axis,
            pose[0:3] + 0.5 * radius * axis,
            THRUSTER_COLOR,
            inner=0.8 * radius,
        )
    return parts


def rov_lamps_b(rov_size_m: FloatArray) -> FloatArray:
    """(2, 3) the bow lamps' places in the ROV's axes: port and starboard on the bow, under
    the buoyancy block."""
    size = np.asarray(rov_size_m, float)
    z = -0.5 * size[2] + 0.38 * size[2]
    return np.array([[0.5 * size[0], side * 0.35 * size[1], z] for side in (-1.0, 1.0)])


def silt_cloud_mesh(radius_m: float, seed: int = 0, blobs: int = 24) -> trimesh.Trimesh:
    """A silt cloud: ``blobs`` spheres scattered in a flat dome ``radius_m`` wide (its origin
    on the seabed, the dome above it, up being -z), so it reads as a cloud and not a ball."""
    rng = np.random.default_rng(seed)
    spheres = []
    for _ in range(blobs):
        angle = rng.uniform(0.0, 2.0 * math.pi)
        reach = radius_m * math.sqrt(rng.uniform(0.0, 1.0)) * 0.7
        r = radius_m * rng.uniform(0.2, 0.38)
        center = [reach * math.cos(angle), reach * math.sin(angle), -rng.uniform(0.2, 0.6) * r]
        sphere = trimesh.creation.icosphere(subdivisions=2, radius=r)
        sphere.apply_translation(center)
        spheres.append(sphere)
    mesh = trimesh.util.concatenate(spheres)
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def box_edges(dimensions_m: ArrayLike) -> FloatArray:
    """(12, 2, 3) the edges of a box centred on the origin (a line drawing: the reference
    ghost, which must not hide the tree it stands on)."""
    box = trimesh.creation.box(extents=np.asarray(dimensions_m, float))
    creases = box.face_adjacency_edges[box.face_adjacency_angles > 0.1]  # not the diagonals
    return np.asarray(box.vertices[creases], float)


def seabed_mesh(extent_m: float, cell_m: float, seed: int = 0) -> trimesh.Trimesh:
    """A square of sand ``extent_m`` wide centred on the origin (z down, its mean level 0):
    a grid of ``cell_m`` cells with low ripples (a fiftieth of a cell) and speckled sand
    colours, smooth-shaded."""
    rng = np.random.default_rng(seed)
    n = max(int(round(extent_m / cell_m)), 1)
    u = np.linspace(-0.5 * extent_m, 0.5 * extent_m, n + 1)
    x, y = np.meshgrid(u, u, indexing="ij")
    ripple = np.sin(2.0 * math.pi * (x + 0.3 * y) / (3.0 * cell_m))
    z = 0.02 * cell_m * (ripple + rng.normal(0.0, 0.5, x.shape))
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    faces = np.concatenate(
        [np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
    )
    shade = 1.0 + 0.06 * ripple.ravel() + rng.normal(0.0, 0.05, len(vertices))
    rgb = linear_rgb(np.clip(np.outer(shade, SAND_COLOR), 0, 255))
    colors = np.column_stack([rgb, np.full(len(vertices), 255, np.uint8)])
    return trimesh.Trimesh(vertices, faces, vertex_colors=colors, process=False)
