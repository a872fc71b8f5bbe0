"""Underwater light and what stirs it, in pure functions, with the ROV's and the tree's
meshes and lamps put into the scene: the water's colour and fog from its visibility, contact
with the seabed or the frame, the silt cloud it raises (thinning out over a minute), and a
scanning sonar's picture from the scene's geometry.

Fog follows the visibility ``V`` the session sets: for the ROV's camera it begins at a tenth
of ``V`` and hides everything at ``V``; the other presets, far from the site, see it as from
their look-at point (their stand-off is added to both). Near a silt cloud the visibility
drops to ``SILT_VISIBILITY_SIZES`` tree sizes over the cloud's density.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from app.console import VISIBILITY_MAX_M, VISIBILITY_MIN_M, SceneInfo
from web import meshes

FloatArray = NDArray[np.float64]

CLEAR_WATER_RGB = np.array([16.0, 58.0, 84.0])
"""The water's colour at the clearest visibility (deep blue-green)."""
TURBID_WATER_RGB = np.array([58.0, 70.0, 54.0])
"""The water's colour at the least visibility (green-brown, silt in it)."""
FOG_NEAR_SHARE = 0.1
"""Share of the visibility the water is clear to (fog begins there)."""
SILT_TIME_CONSTANT_S = 15.0
"""A silt cloud's density falls as exp(-age / this): 2 % left after a minute."""
SILT_GONE = 0.02
"""Density under which a cloud is no longer drawn."""
SILT_VISIBILITY_SIZES = 0.25
"""Visibility inside a fresh cloud, in tree sizes (the view is clouded)."""
SILT_RADIUS_SIZES = 0.8
"""A fresh cloud's radius, in tree sizes; it grows to twice that as it spreads."""
SILT_SPREAD_S = 30.0
"""Time for a cloud's radius to grow by its first radius [s]."""
SILT_OPACITY = 0.7
"""Opacity of a fresh cloud."""
CONTACT_TOL_SIZES = 0.01
"""How near (in tree sizes) a body's bottom must come to a surface to touch it."""
FRAME_DEPTH_SIZES = 0.15
"""Depth of the docking frame's base under its landing surface, in tree heights."""
LAMP_INTENSITY_PER_M2 = 6.0
"""Lamp intensity over the tree's size squared: the same light on the tree at every scale."""


def tree_size_m(info: SceneInfo) -> float:
    return max(info.tree_dimensions_m)


def frame_depth_m(info: SceneInfo) -> float:
    """How deep the docking frame's base is under its landing surface [m] (the seabed is its
    bottom)."""
    return FRAME_DEPTH_SIZES * info.tree_dimensions_m[2]


def seabed_depth_m(info: SceneInfo) -> float:
    return info.frame.landing_depth_m + frame_depth_m(info)


# ----------------------------------------------------------------------------- meshes
def tree_parts(info: SceneInfo) -> meshes.Parts:
    """The tree and its running tool (``web.meshes``) from the scene's dimensions."""
    lay = info.layout
    parts = meshes.tree_parts(
        np.array(info.tree_dimensions_m),
        lay.post_xy_m,
        lay.funnel_mouth_radius_m,
        lay.funnel_bore_radius_m,
        lay.funnel_cone_height_m,
    )
    parts.update(meshes.running_tool_parts(info.tree_dimensions_m[2], info.attachment_height_m))
    return parts


def rov_configuration(info: SceneInfo) -> FloatArray:
    """(6, m) the thrust configuration matrix T (a thruster ahead, one aft and two vertical,
    when the scene does not carry it: a replay of an older recording)."""
    if info.thruster_configuration:
        return np.array(info.thruster_configuration, float).T
    return np.array(
        [[1, 0, 0, 0, 0, 0.3], [1, 0, 0, 0, 0, -0.3], [0, 0, 1, 0, 0, 0], [0, 0, 1, 0, 0, 0]],
        float,
    ).T


def add_rov(scene: Any, info: SceneInfo) -> None:
    """The ROV's mesh under ``/rov`` and its two bow lamps, spot lights tilted 30 deg down,
    reaching as far as the clearest water lets light go back to the camera."""
    size = np.array(info.rov_dimensions_m)
    scene.add_mesh_trimesh(
        "/rov/body",
        meshes.combined(meshes.rov_parts(size, rov_configuration(info))),
        cast_shadow=False,
        receive_shadow=False,
    )
    tilt = math.radians(30.0)
    for k, lamp in enumerate(meshes.rov_lamps_b(size)):
        scene.add_light_spot(
            f"/rov/lamp_{k}",
            color=(255, 246, 225),
            intensity=LAMP_INTENSITY_PER_M2 * tree_size_m(info) ** 2,
            distance=VISIBILITY_MAX_M,
            angle=math.radians(35.0),
            penumbra=0.5,
            decay=2.0,
            direction=(math.cos(tilt), 0.0, math.sin(tilt)),
            position=tuple(lamp),
        )


# ----------------------------------------------------------------------------- water
def water_rgb(visibility_m: float) -> tuple[int, int, int]:
    """The water's colour: clear blue at the greatest visibility to green-brown at the least
    (on a log scale of visibility)."""
    lo, hi = math.log(VISIBILITY_MIN_M), math.log(VISIBILITY_MAX_M)
    share = (math.log(min(max(visibility_m, VISIBILITY_MIN_M), VISIBILITY_MAX_M)) - lo) / (hi - lo)
    rgb = TURBID_WATER_RGB + share * (CLEAR_WATER_RGB - TURBID_WATER_RGB)
    return (int(round(rgb[0])), int(round(rgb[1])), int(round(rgb[2])))


def fog_rgb(rgb: tuple[int, int, int]) -> tuple[int, int, int]:
    """The colour to give viser's fog so that fully fogged things show ``rgb`` on the screen,
    as the background does (the browser takes the fog's colour as linear light: fogged things
    came out at (131, 143, 127) for a fog of (58, 70, 54))."""
    out = meshes.linear_rgb(rgb)
    return (int(out[0]), int(out[1]), int(out[2]))


def fog_range_m(visibility_m: float, standoff_m: float = 0.0) -> tuple[float, float]:
    """(near, far) of the linear fog [m]: clear to ``FOG_NEAR_SHARE`` of the visibility, all
    hidden at the visibility, both pushed out by the camera's stand-off from what it looks at
    (0 for the ROV's camera)."""
    return standoff_m + FOG_NEAR_SHARE * visibility_m, standoff_m + visibility_m


# ----------------------------------------------------------------------------- contact
def _over_frame(info: SceneInfo, point_ne: FloatArray) -> bool:
    """Whether a point (north, east) is over the docking frame's top."""
    frame = info.frame
    c, s = math.cos(frame.heading_rad), math.sin(frame.heading_rad)
    d = np.asarray(point_ne, float) - frame.center_n
    local = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])
    return bool(np.all(np.abs(local) <= 0.5 * info.layout.frame_size_m))


def surface_depth_m(info: SceneInfo, point_ne: FloatArray, on_posts: bool = False) -> float:
    """Depth of what a body's bottom would rest on at ``point_ne`` [m]: with ``on_posts`` (a
    funnel's mouth), a post top when a post is under the funnel's rim (off by more than the
    capture tolerance, less than the mouth's and the post's radii: the skirt lands on it; a
    funnel within the tolerance takes its post in); else the frame's landing surface, else
    the seabed."""
    lay = info.layout
    posts = info.frame.post_positions_n(lay)
    if on_posts and len(posts):
        off = float(np.min(np.linalg.norm(posts - point_ne, axis=1)))
        if lay.tolerance_m < off <= lay.funnel_mouth_radius_m + lay.post_radius_m:
            return info.frame.post_top_depth_m(lay)
    if _over_frame(info, point_ne):
        return info.frame.landing_depth_m
    return seabed_depth_m(info)


def contact_points_n(info: SceneInfo, tree_eta_n: FloatArray, rov_eta_n: FloatArray) -> FloatArray:
    """(k, 3) where the tree or the ROV touches the seabed or the frame (roll and pitch
    ignored: fractions of a degree): a body's bottom within ``CONTACT_TOL_SIZES`` of what it
    would rest on, under its centre or (the tree) under a funnel."""
    tol = CONTACT_TOL_SIZES * tree_size_m(info)
    tree, rov = np.asarray(tree_eta_n, float), np.asarray(rov_eta_n, float)
    out = []
    tree_bottom = tree[2] + 0.5 * info.tree_dimensions_m[2]
    c, s = math.cos(tree[5]), math.sin(tree[5])
    funnels = tree[0:2] + info.layout.post_xy_m @ np.array([[c, s], [-s, c]])
    under = [(tree[0:2], False)] + [(f, True) for f in funnels]
    for point, on_posts in under:
        if tree_bottom >= surface_depth_m(info, point, on_posts) - tol:
            out.append([point[0], point[1], tree_bottom])
            break
    rov_bottom = rov[2] + 0.5 * info.rov_dimensions_m[2]
    if rov_bottom >= surface_depth_m(info, rov[0:2]) - tol:
        out.append([rov[0], rov[1], rov_bottom])
    return np.array(out, float).reshape(-1, 3)


@dataclass(frozen=True)
class SiltCloud:
    """A cloud of silt raised at ``origin_n`` at simulation time ``start_t_s``."""

    origin_n: FloatArray
    start_t_s: float
    radius_m: float
    """Its radius when raised [m]."""

    def density(self, t_s: float) -> float:
        """1 when raised, exp(-age / ``SILT_TIME_CONSTANT_S``) after; 0 before it was."""
        age = t_s - self.start_t_s
        return math.exp(-age / SILT_TIME_CONSTANT_S) if age >= 0.0 else 0.0

    def radius_at_m(self, t_s: float) -> float:
        """It spreads: its radius grows by its first radius over ``SILT_SPREAD_S``, up to
        twice that."""
        age = max(t_s - self.start_t_s, 0.0)
        return self.radius_m * (1.0 + min(age / SILT_SPREAD_S, 1.0))


@dataclass(frozen=True)
class SiltState:
    """What has been stirred up: the newest cloud, and whether a body touched at the last
    time seen (a cloud rises when a touch begins)."""

    t_s: float = -math.inf
    touching: bool = False
    cloud: SiltCloud | None = None


def next_silt(state: SiltState, info: SceneInfo, t_s: float, contacts_n: FloatArray) -> SiltState:
    """The silt after a new sample at ``t_s``: a touch beginning raises a cloud at the first
    contact point (a body already resting raises none: its cloud settles). Time going back (a
    replay turned back) forgets the cloud."""
    touching = len(contacts_n) > 0
    cloud = state.cloud if t_s >= state.t_s else None
    if touching and (not state.touching or t_s < state.t_s):
        radius = SILT_RADIUS_SIZES * tree_size_m(info)
        ground = np.array([contacts_n[0][0], contacts_n[0][1], contacts_n[0][2]])
        cloud = SiltCloud(ground, t_s, radius)
    if cloud is not None and cloud.density(t_s) < SILT_GONE:
        cloud = None
    return SiltState(t_s, touching, cloud)


def silt_visibility_m(
    visibility_m: float, cloud: SiltCloud | None, t_s: float, eye_n: FloatArray, size_m: float
) -> float:
    """The visibility at ``eye_n`` [m]: the water's, or less inside a silt cloud
    (``SILT_VISIBILITY_SIZES`` tree sizes over its density), blending back to the water's
    over a cloud radius outside it."""
    if cloud is None:
        return visibility_m
    density = cloud.density(t_s)
    radius = cloud.radius_at_m(t_s)
    dist = float(np.linalg.norm(np.asarray(eye_n, float) - cloud.origin_n))
    near = min(max(2.0 - dist / radius, 0.0), 1.0)  # 1 inside, 0 a radius outside
    if near * density <= 0.0:
        return visibility_m
    return min(visibility_m, SILT_VISIBILITY_SIZES * size_m / (near * density))


def silt_mesh(info: SceneInfo) -> trimesh.Trimesh:
    """A cloud of unit radius scaled by the view (``meshes.silt_cloud_mesh``)."""
    return meshes.silt_cloud_mesh(1.0, seed=info.version)


# ----------------------------------------------------------------------------- sonar
SONAR_PX = 240
"""Side of the sonar's picture [px]."""
SONAR_RANGE_SIZES = 4.0
"""The sonar's range, in tree sizes (rounded up to 5 m)."""
SONAR_TILT_RAD = math.radians(15.0)
"""The sonar head's tilt below the horizontal."""
SONAR_BEAM_RAD = math.radians(30.0)
"""Its vertical beam width."""
SONAR_BEARING_NOISE_RAD = math.radians(0.7)
SONAR_RANGE_NOISE_M = 0.02


def sonar_range_m(info: SceneInfo) -> float:
    return 5.0 * math.ceil(SONAR_RANGE_SIZES * tree_size_m(info) / 5.0)


def sonar_targets_n(info: SceneInfo, tree_eta_n: FloatArray) -> tuple[FloatArray, FloatArray]:
    """((k, 3) points, (k,) echo strengths) of what the sonar sees: the tree's outline at its
    depth, the posts, the frame's outline."""
    tree = np.asarray(tree_eta_n, float)
    length, width, _ = info.tree_dimensions_m
    u = np.linspace(-0.5, 0.5, 9)
    outline = np.concatenate(
        [np.column_stack([u * length, np.full(9, s * 0.5 * width)]) for s in (-1.0, 1.0)]
        + [np.column_stack([np.full(9, s * 0.5 * length), u * width]) for s in (-1.0, 1.0)]
    )
    c, s = math.cos(tree[5]), math.sin(tree[5])
    tree_pts = tree[0:2] + outline @ np.array([[c, s], [-s, c]])
    frame = info.frame
    fl, fw = info.layout.frame_size_m
    fc, fs = math.cos(frame.heading_rad), math.sin(frame.heading_rad)
    frame_outline = np.concatenate(
        [np.column_stack([u * fl, np.full(9, sgn * 0.5 * fw)]) for sgn in (-1.0, 1.0)]
        + [np.column_stack([np.full(9, sgn * 0.5 * fl), u * fw]) for sgn in (-1.0, 1.0)]
    )
    frame_pts = frame.center_n + frame_outline @ np.array([[fc, fs], [-fs, fc]])
    posts = frame.post_positions_n(info.layout)
    points = np.concatenate(
        [
            np.column_stack([tree_pts, np.full(len(tree_pts), tree[2])]),
            np.column_stack([posts, np.full(len(posts), frame.post_top_depth_m(info.layout))]),
            np.column_stack([frame_pts, np.full(len(frame_pts), frame.landing_depth_m)]),
        ]
    )
    strength = np.concatenate(
        [np.full(len(tree_pts), 1.0), np.full(len(posts), 0.9), np.full(len(frame_pts), 0.6)]
    )
    return points, strength


SONAR_BEARINGS = 180
"""Bearing cells of the sonar's scan (2 deg each)."""
SONAR_RANGES = 120
"""Range cells out to its range."""
SONAR_BEAM_WIDTH_RAD = math.radians(3.0)
"""Horizontal beam width (between the half-power points of its Gaussian)."""


@functools.lru_cache(maxsize=4)
def _sonar_pixels(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per pixel of an n x n picture centred on the ROV, heading up: (range over the
    picture's half width, bearing cell, starboard and ahead over the half width)."""
    half = 0.5 * n
    ys, xs = np.mgrid[0:n, 0:n]
    starboard, ahead = (xs - half + 0.5) / half, (half - ys - 0.5) / half
    bearing = np.arctan2(starboard, ahead)
    cell = np.floor((bearing + math.pi) / (2.0 * math.pi) * SONAR_BEARINGS).astype(int)
    return np.hypot(starboard, ahead), cell % SONAR_BEARINGS, starboard, ahead


def sonar_scan(
    info: SceneInfo, rov_eta_n: FloatArray, tree_eta_n: FloatArray, rng: np.random.Generator
) -> np.ndarray:
    """(SONAR_BEARINGS, SONAR_RANGES) echo strengths 0..1 of one scan round the ROV, bearing
    cell 0 astern (-180 deg off the heading) and going clockwise, out to ``sonar_range_m``:
    echoes of the tree, the posts and the frame (range and bearing with noise, within the
    vertical beam; each shadows its bearing behind it), the seabed's speckle from where the
    beam first meets it, and noise."""
    rov = np.asarray(rov_eta_n, float)
    reach = sonar_range_m(info)
    dr = reach / SONAR_RANGES
    r = (np.arange(SONAR_RANGES) + 0.5) * dr
    scan = np.zeros((SONAR_BEARINGS, SONAR_RANGES))
    height = seabed_depth_m(info) - rov[2]
    if height > 0.0:
        first = height / math.tan(SONAR_TILT_RAD + 0.5 * SONAR_BEAM_RAD)
        fade = np.where(r >= first, 0.25 * np.exp(-(r - first) / reach), 0.0)
        scan += fade * rng.rayleigh(0.6, scan.shape)
    points, strength = sonar_targets_n(info, tree_eta_n)
    d = points - rov[0:3]
    rng_h = np.hypot(d[:, 0], d[:, 1])
    depression = np.arctan2(d[:, 2], np.maximum(rng_h, 1e-6))
    lo, hi = SONAR_TILT_RAD - SONAR_BEAM_RAD, SONAR_TILT_RAD + SONAR_BEAM_RAD
    seen = (rng_h <= reach) & (depression >= lo) & (depression <= hi)
    k = int(seen.sum())
    brg = np.arctan2(d[seen, 1], d[seen, 0]) - rov[5] + rng.normal(0.0, SONAR_BEARING_NOISE_RAD, k)
    rho = rng_h[seen] + rng.normal(0.0, SONAR_RANGE_NOISE_M, k)
    cell_rad = 2.0 * math.pi / SONAR_BEARINGS
    sigma = SONAR_BEAM_WIDTH_RAD / 2.355
    for b, rr, a in zip(brg, rho, strength[seen], strict=True):
        centre = ((b + math.pi) % (2.0 * math.pi)) / cell_rad - 0.5
        cells = np.arange(int(centre) - 3, int(centre) + 5)
        beam = np.exp(-0.5 * ((cells - centre) * cell_rad / sigma) ** 2)
        rows = cells % SONAR_BEARINGS
        scan[rows] += a * np.outer(beam, np.exp(-0.5 * ((r - rr) / (1.5 * dr)) ** 2))
        scan[rows] *= 1.0 - 0.7 * np.outer(beam, r > rr + 3.0 * dr)  # its shadow
    scan += rng.rayleigh(0.04, scan.shape)
    return np.clip(scan, 0.0, 1.0)


def sonar_image(
    info: SceneInfo, rov_eta_n: FloatArray, tree_eta_n: FloatArray, rng: np.random.Generator
) -> np.ndarray:
    """(SONAR_PX, SONAR_PX, 3) uint8: a scan (``sonar_scan``) drawn round the ROV, its
    heading up, amber on black, with range rings every quarter of the range and the ROV
    marked in the middle."""
    scan = sonar_scan(info, rov_eta_n, tree_eta_n, rng)
    r, cell, starboard, ahead = _sonar_pixels(SONAR_PX)
    inside = r <= 1.0
    img = scan[cell, np.minimum((r * SONAR_RANGES).astype(int), SONAR_RANGES - 1)] * inside
    rgb = np.stack([255 * img, 200 * img**1.3, 60 * img**2], axis=-1)
    px = 2.0 / SONAR_PX
    rings = np.zeros(r.shape, bool)
    for k in (1, 2, 3, 4):
        rings |= np.abs(r - 0.25 * k) < 0.6 * px
    rgb[rings] = (90, 110, 120)
    rgb[(np.abs(starboard) < 1.5 * px) & (np.abs(ahead) < 3 * px)] = (230, 110, 30)
    return rgb.astype(np.uint8)
