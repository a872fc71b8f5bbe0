"""Docking frame with guideposts, and the tree's funnels (thesis chapter 5, appendix C).

The frame stands on the seabed; its guideposts stick up from its landing surface. The tree
carries a funnel over each post position. A landing succeeds when, at the moment the funnels
reach the post tops, every funnel's centre is within the capture tolerance of its post
(funnel mouth radius minus post radius) and the tree comes down slower than the limit; the
posts then guide it down onto the landing surface. Otherwise the funnel skirts land on the
post tops and the tree stands on the posts: a failed landing, reported with the miss.

Geometry only (frames, points, the check); the contact forces live in ``sim.plant``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class DockingLayout:
    """Post and funnel layout, from the parameter set (it belongs with the tree)."""

    post_xy_m: FloatArray
    """(k, 2) post positions in the frame's axes = funnel positions in the tree's axes when the
    tree is aligned [m]."""
    post_height_m: float
    """Post top above the frame's landing surface [m]."""
    post_radius_m: float
    """[m]"""
    funnel_mouth_radius_m: float
    """Capture radius of a funnel's mouth [m]."""
    funnel_bore_radius_m: float
    """Radius of the funnel's bore above its cone [m]."""
    funnel_cone_height_m: float
    """Height of the cone from the mouth up to the bore [m]."""
    max_landing_speed_mps: float
    """Largest vertical speed at contact for a good landing [m/s]."""
    frame_size_m: FloatArray
    """(2,) length and width of the frame's top, for drawing [m]."""

    @property
    def tolerance_m(self) -> float:
        """How far off a funnel may be and still catch its post [m]."""
        return self.funnel_mouth_radius_m - self.post_radius_m

    @property
    def clearance_m(self) -> float:
        """How far a landed post can move in its funnel's bore [m]."""
        return self.funnel_bore_radius_m - self.post_radius_m

    @property
    def heading_clearance_rad(self) -> float:
        """How far a landed tree can turn before a post meets its bore: the clearance over
        the distance of the nearest post from the tree's centre [rad] (small angle)."""
        arm = float(np.min(np.hypot(self.post_xy_m[:, 0], self.post_xy_m[:, 1])))
        return self.clearance_m / arm if arm > 0.0 else math.inf


@dataclass(frozen=True)
class DockingFrame:
    """Where the frame stands (from the mission's set-up)."""

    center_n: FloatArray
    """(2,) north, east of the frame's centre [m]."""
    heading_rad: float
    """Heading of the frame's x axis [rad]; the tree must land with the same heading."""
    landing_depth_m: float
    """Depth of the landing surface: where the tree's bottom rests when landed [m]."""

    def post_positions_n(self, layout: DockingLayout) -> FloatArray:
        """(k, 2) posts in NED north/east."""
        c, s = math.cos(self.heading_rad), math.sin(self.heading_rad)
        rot = np.array([[c, -s], [s, c]])
        return self.center_n + layout.post_xy_m @ rot.T

    def post_top_depth_m(self, layout: DockingLayout) -> float:
        return self.landing_depth_m - layout.post_height_m


def funnel_positions_n(tree_eta_n: FloatArray, layout: DockingLayout) -> FloatArray:
    """(k, 2) funnel centres in NED north/east for a tree pose (roll and pitch ignored: they are
    fractions of a degree on the wire)."""
    c, s = math.cos(tree_eta_n[5]), math.sin(tree_eta_n[5])
    rot = np.array([[c, -s], [s, c]])
    return tree_eta_n[0:2] + layout.post_xy_m @ rot.T


@dataclass(frozen=True)
class LandingCheck:
    """Alignment of the funnels over the posts at one instant."""

    miss_m: float
    """Largest horizontal distance between a funnel and its post [m]."""
    heading_error_deg: float
    """Tree heading minus frame heading, wrapped [deg]."""
    captured: bool
    """Every funnel within the capture tolerance."""


def check_alignment(
    tree_eta_n: FloatArray, frame: DockingFrame, layout: DockingLayout
) -> LandingCheck:
    """How well the funnels sit over the posts right now."""
    miss = np.linalg.norm(
        funnel_positions_n(tree_eta_n, layout) - frame.post_positions_n(layout), axis=1
    )
    err = (tree_eta_n[5] - frame.heading_rad + math.pi) % (2 * math.pi) - math.pi
    worst = float(miss.max())
    return LandingCheck(worst, math.degrees(err), worst <= layout.tolerance_m)
