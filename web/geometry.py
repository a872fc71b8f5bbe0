"""Pure geometry for the 3D view, in NED (x north, y east, z down) like the core.

The scene is drawn in NED directly: the view sets its up direction to -z. Rotations and the
wire's attachment point come from the core (one implementation, re-exported by
``app.console``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from app.console import Rzyx, attachment_point_n, quaternion_wxyz_from_rpy_radians

__all__ = [
    "CameraPose",
    "attachment_point_n",
    "funnel_points_b",
    "loaded_wire_points_n",
    "overview_camera",
    "polyline_segments",
    "quaternion_wxyz_from_rpy_radians",
    "rov_camera",
    "top_down_camera",
]

FloatArray = NDArray[np.float64]


def loaded_wire_points_n(
    top_n: FloatArray,
    bottom_n: FloatArray,
    length_m: float,
    weight_newton_per_m: float,
    load_newton: float,
    drag_newton_per_m: FloatArray,
    n_points: int = 40,
) -> FloatArray:
    """(n_points, 3) points of the loaded line from the load (first) to the crane tip (last).

    Small-angle shape of a heavy wire with the load W0 hanging at its end and a uniform
    horizontal drag q per metre (MODEL_NOTES, eq. 2.29): at arc length s above the load the
    tension has vertical part V(s) = W0 + w s and horizontal part H(s) = H0 + q s, and the
    slope is dx/ds = -H(s) / V(s). With I1(s) = ln((W0 + w s)/W0)/w and
    I2(s) = s/w - W0/w^2 ln((W0 + w s)/W0), x(s) = x_load - H0 I1(s) - q I2(s), and H0 (the
    horizontal force at the load, a 2-vector) is what puts the top at the crane tip. Depth goes
    linearly with s between the two ends. Reduces to a straight line without drag."""
    top = np.asarray(top_n, float)
    bottom = np.asarray(bottom_n, float)
    q = np.asarray(drag_newton_per_m, float)[:2]
    length = max(float(length_m), 1e-6)
    w = max(float(weight_newton_per_m), 1e-9)
    w0 = max(float(load_newton), 1e-9)
    s = np.linspace(0.0, length, n_points)
    i1 = np.log1p(w * s / w0) / w
    i2 = s / w - w0 / w**2 * np.log1p(w * s / w0)
    h0 = ((bottom[:2] - top[:2]) - q * i2[-1]) / i1[-1]
    out = np.empty((n_points, 3))
    out[:, 0:2] = bottom[None, :2] - np.outer(i1, h0) - np.outer(i2, q)
    out[:, 2] = bottom[2] + (top[2] - bottom[2]) * s / length
    return out


def polyline_segments(points: FloatArray) -> FloatArray:
    """(n-1, 2, 3) segments joining consecutive points (viser's line-segment layout)."""
    p = np.asarray(points, float)
    return np.stack([p[:-1], p[1:]], axis=1)


@dataclass(frozen=True)
class CameraPose:
    """Where a camera is, what it looks at and which way is up (NED)."""

    position_n: FloatArray
    look_at_n: FloatArray
    up_n: FloatArray


UP_N = np.array([0.0, 0.0, -1.0])


def overview_camera(tree_eta_n: FloatArray, tree_size_m: float) -> CameraPose:
    """Up and to the south-west of the tree, looking at it and the frame below."""
    eta = np.asarray(tree_eta_n, float)
    d = 4.0 * tree_size_m
    target = eta[0:3] + np.array([0.0, 0.0, 0.5 * tree_size_m])
    return CameraPose(target + np.array([-d, -0.8 * d, -0.9 * d]), target, UP_N)


def top_down_camera(
    frame_center_n: FloatArray, landing_depth_m: float, tree_eta_n: FloatArray, tree_size_m: float
) -> CameraPose:
    """Straight down over the docking frame: the funnels over the posts (alignment view).
    'Up' on the screen is north."""
    eta = np.asarray(tree_eta_n, float)
    center = np.array([frame_center_n[0], frame_center_n[1], landing_depth_m])
    height = max(landing_depth_m - eta[2], 0.0) + 3.0 * tree_size_m
    return CameraPose(center - np.array([0.0, 0.0, height]), center, np.array([1.0, 0.0, 0.0]))


def rov_camera(
    rov_eta_n: FloatArray, rov_size_m: FloatArray, tree_eta_n: FloatArray, tree_height_m: float
) -> CameraPose:
    """The pilot's camera: on a mast over the ROV's stern, tilted down past the tree to where
    its funnels meet the posts (the view the pilot aligns the landing with)."""
    eta = np.asarray(rov_eta_n, float)
    rot = Rzyx(*eta[3:6])
    size = np.asarray(rov_size_m, float)
    lens_b = np.array([-0.5 * size[0], 0.0, -(0.5 * size[2] + 0.8 * tree_height_m)])
    tree = np.asarray(tree_eta_n, float)
    look_n = tree[0:3] + np.array([0.0, 0.0, 0.6 * tree_height_m])
    return CameraPose(eta[0:3] + rot @ lens_b, look_n, rot @ np.array([0.0, 0.0, -1.0]))


def funnel_points_b(post_xy_m: FloatArray, tree_height_m: float) -> FloatArray:
    """(k, 3) funnel centres in the tree's axes: under the post positions, at its bottom."""
    xy = np.asarray(post_xy_m, float)
    return np.column_stack([xy, np.full(len(xy), 0.5 * tree_height_m)])
