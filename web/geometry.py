"""Pure geometry for the 3D view, in NED (x north, y east, z down) like the core.

The scene is drawn in NED directly: the view sets its up direction to -z. Rotations and the
wire's attachment point come from the core (one implementation, re-exported by
``app.console``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from app.console import Rzyx, attachment_point_n, quaternion_wxyz_from_rpy_radians

__all__ = [
    "CameraPose",
    "CurrentArrow",
    "PilotReadout",
    "Rzyx",
    "attachment_point_n",
    "current_arrow",
    "current_arrow_ends_n",
    "follow_rov_camera",
    "framing_camera",
    "funnel_points_b",
    "loaded_wire_points_n",
    "overview_camera",
    "pilot_readout",
    "polyline_segments",
    "quaternion_wxyz_from_rpy_radians",
    "readout_markdown",
    "rov_camera",
    "scale_bar_length_m",
    "top_down_camera",
    "wrap_pi",
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


OVERVIEW_DIRECTION_N = np.array([-1.0, -0.8, -0.9]) / np.linalg.norm([-1.0, -0.8, -0.9])
"""From the overview's target to its camera: up and to the south-west."""
OVERVIEW_FOV_RAD = np.radians(50.0)
"""Vertical field of view of the overview and top-down presets."""
TOP_DOWN_FILL = 0.35
"""Share of the vertical field of view from the middle of the top-down view to the edge of
what it must show (the tree, the ROV, the frame)."""
ROV_CAMERA_FOV_RAD = np.radians(60.0)
"""Vertical field of view of the ROV's camera."""
ROV_CAMERA_PITCH_RAD = (math.radians(10.0), math.radians(35.0))
"""Tilt range of the ROV's camera below the horizontal."""
ROV_CAMERA_YAW_RAD = math.radians(20.0)
"""Largest turn of the ROV's camera off the ROV's heading. With the lens ahead of the ROV's
bow, every ray of a 60 deg (vertical) frustum up to 2.1:1 wide, tilted at most 35 deg and
turned at most 20 deg, still points forward (the worst corner keeps cos 35 cos 20 -
tan 30 sin 35 cos 20 - 2.1 tan 30 sin 20 = 0.04 of its length forward), so no part of the
ROV (all behind the lens) can be in the picture."""


def overview_camera(
    tree_eta_n: FloatArray, tree_size_m: float, frame_point_n: FloatArray | None = None
) -> CameraPose:
    """Up and to the south-west, looking at the middle between the tree and the docking frame
    (``frame_point_n``: its centre on the landing surface) from far enough that a sphere holding
    both, two tree sizes around each (room for the north arrow and the current), fits the
    vertical field of view. Without a frame point, at the tree. The pose moves continuously
    with the tree, so following it each frame is smooth."""
    eta = np.asarray(tree_eta_n, float)
    tree = eta[0:3]
    if frame_point_n is None:
        target = tree + np.array([0.0, 0.0, 0.5 * tree_size_m])
        radius = 1.5 * tree_size_m
    else:
        frame = np.asarray(frame_point_n, float)
        target = 0.5 * (tree + frame)
        radius = 0.5 * float(np.linalg.norm(frame - tree)) + 2.0 * tree_size_m
    distance = max(radius / math.sin(0.5 * OVERVIEW_FOV_RAD), 4.0 * tree_size_m)
    return CameraPose(target + distance * OVERVIEW_DIRECTION_N, target, UP_N)


def top_down_camera(
    frame_center_n: FloatArray, landing_depth_m: float, tree_eta_n: FloatArray, tree_size_m: float
) -> CameraPose:
    """Straight down over the middle between the tree and the docking frame: the funnels over
    the posts (alignment view). 'Up' on the screen is north. High enough over the tree that a
    circle holding both, a tree size around each (the ROV beside the tree, the frame's
    posts), fits ``TOP_DOWN_FILL`` of the vertical field of view from the middle: the panel
    covers the right part of the screen, and three tree sizes over the frame (as it was) cut
    the tree off."""
    eta = np.asarray(tree_eta_n, float)
    frame_ne = np.asarray(frame_center_n, float)[:2]
    middle = 0.5 * (eta[0:2] + frame_ne)
    radius = 0.5 * float(np.linalg.norm(eta[0:2] - frame_ne)) + tree_size_m
    height = radius / math.tan(TOP_DOWN_FILL * OVERVIEW_FOV_RAD)
    center = np.array([middle[0], middle[1], landing_depth_m])
    above = np.array([middle[0], middle[1], min(eta[2], landing_depth_m) - height])
    return CameraPose(above, center, np.array([1.0, 0.0, 0.0]))


def framing_camera(points_n: FloatArray, tree_size_m: float) -> CameraPose:
    """From up and to the south-west (as the overview), looking at the middle of
    ``points_n`` ((k, 3)) from far enough that a sphere holding them all, a tree size around
    each, fits the vertical field of view: the mission builder's preview, wherever it is."""
    pts = np.asarray(points_n, float).reshape(-1, 3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    target = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo)) + tree_size_m
    distance = max(radius / math.sin(0.5 * OVERVIEW_FOV_RAD), 4.0 * tree_size_m)
    return CameraPose(target + distance * OVERVIEW_DIRECTION_N, target, UP_N)


def rov_camera(
    rov_eta_n: FloatArray,
    rov_size_m: FloatArray,
    tree_eta_n: FloatArray,
    tree_height_m: float,
    post_tops_n: FloatArray,
) -> CameraPose:
    """The pilot's camera: on a skid just ahead of the ROV's bow, below the tree's bottom (its
    funnels' skirts end 0.12 tree heights below it), turned and tilted towards the post top
    farthest ahead (``post_tops_n``: (k, 3)), so a funnel coming down over its post is in the
    picture. Turn and tilt stay within ``ROV_CAMERA_YAW_RAD`` and ``ROV_CAMERA_PITCH_RAD``
    so the ROV stays out of it; with no post ahead, it looks straight ahead at the least tilt.
    The skid hangs at most one tree height below the ROV's bottom."""
    eta = np.asarray(rov_eta_n, float)
    size = np.asarray(rov_size_m, float)
    tree = np.asarray(tree_eta_n, float)
    psi = float(eta[5])
    forward = np.array([math.cos(psi), math.sin(psi), 0.0])
    starboard = np.array([-math.sin(psi), math.cos(psi), 0.0])
    below_tree = tree[2] + 0.7 * tree_height_m - eta[2]
    drop = min(max(below_tree, 0.5 * size[2] + 0.05), 0.5 * size[2] + tree_height_m)
    lens = eta[0:3] + (0.5 * size[0] + 0.05) * forward + np.array([0.0, 0.0, drop])
    tops = np.asarray(post_tops_n, float).reshape(-1, 3)
    ahead_each = (tops - lens) @ forward
    far = int(np.argmax(ahead_each))
    yaw, pitch = 0.0, ROV_CAMERA_PITCH_RAD[0]
    if ahead_each[far] > 0.0:
        to_top = tops[far] - lens
        yaw = math.atan2(float(to_top @ starboard), float(ahead_each[far]))
        yaw = min(max(yaw, -ROV_CAMERA_YAW_RAD), ROV_CAMERA_YAW_RAD)
        pitch = math.atan2(float(to_top[2]), float(np.hypot(to_top[0], to_top[1])))
        pitch = min(max(pitch, ROV_CAMERA_PITCH_RAD[0]), ROV_CAMERA_PITCH_RAD[1])
    heading = forward * math.cos(yaw) + starboard * math.sin(yaw)
    look = heading * math.cos(pitch) + np.array([0.0, 0.0, math.sin(pitch)])
    return CameraPose(lens, lens + tree_height_m * look, UP_N)


def follow_rov_camera(
    rov_eta_n: FloatArray, rov_size_m: FloatArray, tree_size_m: float
) -> CameraPose:
    """Behind and above the ROV along its heading (roll and pitch ignored, so the picture does
    not rock), looking at a point one ROV length ahead of it."""
    eta = np.asarray(rov_eta_n, float)
    size = np.asarray(rov_size_m, float)
    psi = float(eta[5])
    forward = np.array([math.cos(psi), math.sin(psi), 0.0])
    back = 2.0 * size[0] + tree_size_m
    up = 1.5 * size[2] + 0.6 * tree_size_m
    look = eta[0:3] + size[0] * forward
    return CameraPose(eta[0:3] - back * forward - np.array([0.0, 0.0, up]), look, UP_N)


def wrap_pi(angle_rad: float) -> float:
    """The angle in [-pi, pi)."""
    return (float(angle_rad) + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class PilotReadout:
    """What a pilot reads while landing the tree."""

    height_above_posts_m: float
    """Tree's bottom above the post tops (negative: below them) [m]."""
    distance_to_frame_m: float
    """Horizontal distance from the tree's centre to the frame's centre [m]."""
    heading_error_rad: float
    """Tree heading minus frame heading, wrapped to [-pi, pi) [rad]."""
    wire_tension_newton: float | None


def pilot_readout(
    tree_eta_n: FloatArray,
    tree_height_m: float,
    frame_center_n: FloatArray,
    frame_heading_rad: float,
    post_top_depth_m: float,
    wire_tension_newton: float | None,
) -> PilotReadout:
    """The readout from the tree's pose and the frame (the tree's bottom is half its height
    below its centre, depth positive down)."""
    eta = np.asarray(tree_eta_n, float)
    center = np.asarray(frame_center_n, float)
    return PilotReadout(
        height_above_posts_m=float(post_top_depth_m - (eta[2] + 0.5 * tree_height_m)),
        distance_to_frame_m=float(math.hypot(eta[0] - center[0], eta[1] - center[1])),
        heading_error_rad=wrap_pi(float(eta[5]) - float(frame_heading_rad)),
        wire_tension_newton=wire_tension_newton,
    )


def readout_markdown(r: PilotReadout) -> str:
    """The readout as one markdown line (tension in kN)."""
    tension = "-" if r.wire_tension_newton is None else f"{r.wire_tension_newton / 1000.0:.1f} kN"
    return (
        f"above posts {r.height_above_posts_m:.2f} m | to frame {r.distance_to_frame_m:.2f} m"
        f" | heading error {math.degrees(r.heading_error_rad):+.1f} deg | wire {tension}"
    )


@dataclass(frozen=True)
class CurrentArrow:
    """How the current is drawn."""

    length_m: float
    """Arrow length [m]; 0 with no current."""
    label: str


CURRENT_ARROW_MIN_SIZES = 1.0
"""Shortest current arrow, in tree sizes (readable at the overview's distance)."""
CURRENT_ARROW_SIZES_PER_MPS = 4.0
"""Arrow growth, in tree sizes per m/s."""


def current_arrow(speed_mps: float, direction_rad: float, tree_size_m: float) -> CurrentArrow:
    """Arrow length and label for the current: at least ``CURRENT_ARROW_MIN_SIZES`` tree sizes
    long, growing with speed; "no current" when still (speeds under 0.5 mm/s show as 0.00)."""
    if round(speed_mps, 2) <= 0.0:
        return CurrentArrow(0.0, "no current")
    deg = math.degrees(direction_rad) % 360.0
    length = tree_size_m * (CURRENT_ARROW_MIN_SIZES + CURRENT_ARROW_SIZES_PER_MPS * speed_mps)
    return CurrentArrow(length, f"current {speed_mps:.2f} m/s towards {deg:.0f} deg")


def current_arrow_ends_n(
    center_n: FloatArray, reach_m: float, direction_rad: float, length_m: float
) -> tuple[FloatArray, FloatArray]:
    """Tail and head of the current arrow: centred ``reach_m`` to the side of ``center_n``
    (square to the current, on the side towards the overview camera), pointing along the
    current. With no current (length 0), both at that point."""
    along = np.array([math.cos(direction_rad), math.sin(direction_rad), 0.0])
    side = np.array([-along[1], along[0], 0.0])
    if side @ OVERVIEW_DIRECTION_N < 0.0:
        side = -side
    middle = np.asarray(center_n, float) + reach_m * side
    return middle - 0.5 * length_m * along, middle + 0.5 * length_m * along


def scale_bar_length_m(tree_size_m: float) -> float:
    """A round length (1, 2 or 5 times a power of ten) no longer than the tree's size, for the
    scale bar."""
    exponent = math.floor(math.log10(tree_size_m))
    for mult in (5.0, 2.0, 1.0):
        length = mult * 10.0**exponent
        if length <= tree_size_m:
            return length
    return 10.0**exponent


def funnel_points_b(post_xy_m: FloatArray, tree_height_m: float) -> FloatArray:
    """(k, 3) funnel centres in the tree's axes: under the post positions, at its bottom."""
    xy = np.asarray(post_xy_m, float)
    return np.column_stack([xy, np.full(len(xy), 0.5 * tree_height_m)])


CAMERA_ECHO_S = 10.0
"""How long a camera pose sent to a browser may still come back as that browser's report of
its camera. A loaded browser reports seconds late (measured over 2.5 s at load 11 on the
2-core test machine, where the follow-mode camera had been taken for a hand move)."""


class CameraEchoes:
    """The camera poses sent to one browser lately, to tell its echoes of them from a camera
    the user moved. Poses are kept by the time they were sent, not by count, so a browser
    that lags behind a fast-moving follow camera still finds its report among them."""

    def __init__(self, keep_s: float = CAMERA_ECHO_S) -> None:
        self.keep_s = keep_s
        self._sent: list[tuple[float, np.ndarray, np.ndarray]] = []

    def __bool__(self) -> bool:
        return bool(self._sent)

    def sent(self, position_n: np.ndarray, look_at_n: np.ndarray, now_s: float) -> None:
        """Note a pose sent at ``now_s`` [s, monotonic clock]; drops those older than
        ``keep_s``. A pose equal to one of the last two sent is kept once (a still scene
        sends the same two poses each frame)."""
        position_n, look_at_n = np.array(position_n, float), np.array(look_at_n, float)
        for i in range(len(self._sent) - 1, max(len(self._sent) - 3, -1), -1):
            _, p, q = self._sent[i]
            if np.array_equal(p, position_n) and np.array_equal(q, look_at_n):
                del self._sent[i]  # sent again: kept once, as of now
                break
        self._sent.append((now_s, position_n, look_at_n))
        cutoff = now_s - self.keep_s
        first = next((i for i, entry in enumerate(self._sent) if entry[0] >= cutoff), 0)
        del self._sent[:first]

    def is_echo(self, position_n: np.ndarray, look_at_n: np.ndarray) -> bool:
        """Whether a reported camera is one of the poses sent (to 1 mm per metre of
        distance from the origin, the browser's float32 round trip).

        The position must be one sent. The look-at point may be one sent, or the browser's
        in-between pose: setting the position carries its look-at point along, so between
        two poses it reports the new position with the old pose's offset from position to
        look-at. That offset is matched against the offsets sent. The in-between point the
        server notes (worked out from the camera it last heard of, as viser's own position
        setter does) is not enough alone: under load that report is stale, the point differs
        from the browser's, and the follow camera was taken for a hand on it (CI, load 6-8).
        A user cannot move the look-at point without moving the camera, so the position
        alone tells a hand move."""
        if not self._sent:
            return False
        pos, look = np.asarray(position_n, float), np.asarray(look_at_n, float)
        scale = 1e-3 * (1.0 + float(np.linalg.norm(self._sent[-1][1])))
        ours_pos = any(np.linalg.norm(pos - p) < scale for _, p, _ in self._sent)
        if not ours_pos:
            return False
        offset = look - pos
        return any(
            np.linalg.norm(look - q) < scale or np.linalg.norm(offset - (q - p)) < scale
            for _, p, q in self._sent
        )
