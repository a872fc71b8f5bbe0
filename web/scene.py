"""The shared 3D scene: seabed, docking frame with guideposts, the tree with its funnels, the
ROV, the loaded wire from the crane tip, the current arrow with its label, the reference ghost,
the track, a north arrow and a scale bar beside the frame, and depth labels on the tree and
the frame.

Drawn in NED (``set_up_direction("-z")``); every pose update of one frame goes out in one
``server.atomic()`` block so the browser never shows a half-updated scene.
"""

from __future__ import annotations

import math
import time

import numpy as np
import viser

from app.console import SceneInfo, Snapshot
from web import geometry as geo
from web import meshes
from web.underwater import add_rov, frame_depth_m, tree_parts
from web.water import SiltView

GHOST_COLOR = (60, 200, 230)
GUIDE_COLOR = (220, 40, 40)
FUNNEL_COLOR = (90, 90, 100)
WIRE_COLOR = (30, 30, 30)
TRACK_COLOR = (40, 90, 220)
CURRENT_COLOR = (20, 160, 90)
NORTH_COLOR = (30, 60, 160)
SCALE_COLOR = (20, 20, 20)
POSE_EPS = 1e-4
"""Changes below this (m, rad) are not sent: a still scene costs the browsers nothing."""
TRACK_EVERY_S = 1.0
"""Wall time between track redraws."""


class SceneView:
    """Owns the scene nodes of one viser server (the shared scene every browser sees), or of
    one browser (``client``: nodes of the same names in that browser's own scope, which viser
    draws instead of the shared ones for that browser alone); ``update`` from the publisher
    thread."""

    def __init__(self, server: viser.ViserServer, client: viser.ClientHandle | None = None) -> None:
        self.server = server
        self._atomic = server.atomic if client is None else client.atomic
        self.scene = server.scene if client is None else client.scene
        if client is None:  # a browser's own scope keeps the shared settings
            self.scene.set_up_direction("-z")
            # software-rendered browsers (no GPU) stay responsive without shadows
            self.scene.configure_default_lights(enabled=True, cast_shadow=False)
        self._last_pose: np.ndarray | None = None
        self._version = -1
        self._track_wall = 0.0
        self._current_key: tuple[float, float] | None = None
        self.info: SceneInfo | None = None
        self._handles: list = []
        self._hidden: list = []
        self.silt = SiltView()

    def names(self) -> set[str]:
        """Names of the nodes drawn (after the first ``update``)."""
        return {h.name for h in self._handles}

    def hide(self, names: set[str]) -> None:
        """Hide these names in this view's scope (a browser's own scene hides the shared
        nodes it has no node of its own for: a post or funnel the other set-up lacks)."""
        for name in sorted(names - self.names() - {h.name for h in self._hidden}):
            self._hidden.append(self.scene.add_frame(name, show_axes=False, visible=False))

    def clear(self) -> None:
        """Remove every node this view drew (a browser's own scope: the shared scene shows
        again)."""
        # children before their parents (a parent takes its children along)
        for handle in [*reversed(self._hidden), *reversed(self._handles)]:
            handle.remove()
        self._handles, self._hidden = [], []
        self._version = -1
        self._last_pose = None

    # ----------------------------------------------------------------- static parts
    def _build(self, info: SceneInfo) -> None:
        """(Re)draw what only changes with a new set-up."""
        for handle in [*reversed(self._hidden), *reversed(self._handles)]:  # children first
            handle.remove()
        self._handles, self._hidden = [], []
        sc = _Recorder(self.scene, self._handles)
        self.info = info
        lay, frame = info.layout, info.frame
        length, width, height = info.tree_dimensions_m
        size = max(length, width, height)
        thick = frame_depth_m(info)
        c, s = math.cos(frame.heading_rad), math.sin(frame.heading_rad)
        center = np.array([frame.center_n[0], frame.center_n[1], frame.landing_depth_m])
        frame_q = geo.quaternion_wxyz_from_rpy_radians(0.0, 0.0, frame.heading_rad)
        extent = 16.0 * size
        sc.add_mesh_trimesh(
            "/site/seabed",
            meshes.seabed_mesh(extent, size / 4, seed=info.version),
            position=center + np.array([0.0, 0.0, thick + 0.01]),
            cast_shadow=False,
            receive_shadow=False,
        )
        sc.add_mesh_trimesh(
            "/site/frame",
            meshes.combined(
                meshes.docking_frame_parts(
                    lay.frame_size_m, lay.post_xy_m, lay.post_radius_m, lay.post_height_m, thick
                )
            ),
            position=center,
            wxyz=frame_q,
            cast_shadow=False,
            receive_shadow=False,
        )
        tree = sc.add_frame("/tree", show_axes=False)
        sc.add_mesh_trimesh(
            "/tree/body",
            meshes.combined(tree_parts(info)),
            cast_shadow=False,
            receive_shadow=False,
        )
        for k, p in enumerate(geo.funnel_points_b(lay.post_xy_m, height)):
            # the funnels' places marked on the tree's top, to line up with the guides
            sc.add_cylinder(
                f"/tree/funnel_mark_{k}",
                radius=float(lay.funnel_mouth_radius_m),
                height=0.01 * height,
                color=FUNNEL_COLOR,
                position=(p[0], p[1], -0.5 * height - 0.006 * height),
            )
        sc.add_icosphere(
            "/tree/attachment",
            radius=0.04 * size,
            color=WIRE_COLOR,
            position=(0.0, 0.0, -info.attachment_height_m),
        )
        guide_len = 2.0 * height  # from the post tops to half a tree height over the tree
        guide_top = frame.landing_depth_m - lay.post_height_m - guide_len
        for k, (px, py) in enumerate(lay.post_xy_m):
            pn = center[:2] + np.array([c * px - s * py, s * px + c * py])
            # alignment guides: each post's axis carried up past the tree (seen from above,
            # a guide inside its funnel mark means that funnel will catch its post)
            sc.add_cylinder(
                f"/site/guide_{k}",
                radius=0.5 * float(lay.post_radius_m),
                height=guide_len,
                color=GUIDE_COLOR,
                opacity=0.55,
                position=(pn[0], pn[1], guide_top + guide_len / 2),
            )
        rov = sc.add_frame("/rov", show_axes=False)
        add_rov(sc, info)
        ghost = sc.add_frame("/reference", show_axes=False)
        sc.add_line_segments(  # an outline: it stands on the tree when station keeping
            "/reference/body",
            meshes.box_edges((length, width, height)),
            GHOST_COLOR,
            thickness=2.0,
            thickness_units="screen",
        )
        self._tree, self._rov, self._ghost = tree, rov, ghost
        self._wire = sc.add_line_segments(
            "/wire", np.zeros((1, 2, 3)), WIRE_COLOR, thickness=2.0, thickness_units="screen"
        )
        self._track = sc.add_line_segments(
            "/track", np.zeros((1, 2, 3)), TRACK_COLOR, thickness=2.0, thickness_units="screen"
        )
        # the current: one arrow and one label for the set-up's lifetime, never removed and
        # re-added (the browser would be sent updates for a node it is between having)
        self._current = sc.add_arrows(
            "/current",
            np.zeros((1, 2, 3)) + center,
            CURRENT_COLOR,
            shaft_radius=0.03 * size,
            head_radius=0.09 * size,
            head_length=0.25 * size,
        )
        self._current_label = sc.add_label(
            "/current_label", "no current", position=center, anchor="bottom-center"
        )
        self._current_key = None
        self._build_marks(sc, info, center, size)
        self._tree_label = sc.add_label(
            "/tree/depth_label", "", position=(0.0, 0.0, -0.5 * height - 0.2 * size)
        )
        self._tree_label_text = ""
        self.silt.build(sc, info)
        self._version = info.version

    def _build_marks(self, sc: _Recorder, info: SceneInfo, center: np.ndarray, size: float) -> None:
        """North arrow and scale bar on the landing surface off the frame's south-west corner,
        and the frame's depth label."""
        lay, frame = info.layout, info.frame
        corner = center + np.array(
            [-0.5 * lay.frame_size_m[0] - 0.5 * size, -0.5 * lay.frame_size_m[1] - 0.5 * size, 0.0]
        )
        north_tip = corner + np.array([size, 0.0, 0.0])
        sc.add_arrows(
            "/site/north_arrow",
            np.array([[corner, north_tip]]),
            NORTH_COLOR,
            shaft_radius=0.03 * size,
            head_radius=0.1 * size,
            head_length=0.25 * size,
        )
        sc.add_label("/site/north_label", "N", position=north_tip, anchor="bottom-center")
        bar = geo.scale_bar_length_m(size)
        ends = [corner, corner + np.array([0.0, bar, 0.0])]
        tick = np.array([0.15 * size, 0.0, 0.0])
        sc.add_line_segments(
            "/site/scale_bar",
            np.array([ends, [ends[0] - tick, ends[0] + tick], [ends[1] - tick, ends[1] + tick]]),
            SCALE_COLOR,
            thickness=3.0,
            thickness_units="screen",
        )
        sc.add_label(
            "/site/scale_label",
            f"{bar:g} m",
            position=0.5 * (ends[0] + ends[1]) - 0.2 * tick,
            anchor="bottom-center",
        )
        sc.add_label(
            "/site/frame_label",
            f"frame {frame.landing_depth_m:.1f} m depth "
            f"(post tops {frame.post_top_depth_m(lay):.1f} m)",
            position=center + np.array([0.5 * lay.frame_size_m[0], 0.0, 0.0]),
            anchor="top-center",
        )

    def _draw_current(self, snap: Snapshot, size: float) -> None:
        """Arrow along the current on the landing surface's level, beside the frame on the
        side facing the overview camera (so neither hides the other), with its label at the
        tail ("no current" and no arrow when the water is still). Length from
        ``geometry.current_arrow``."""
        key = (round(snap.current_speed_mps, 4), round(snap.current_direction_rad, 4))
        if key == self._current_key:
            return
        self._current_key = key
        arrow = geo.current_arrow(snap.current_speed_mps, snap.current_direction_rad, size)
        info = snap.scene
        center = np.array([*info.frame.center_n, info.frame.landing_depth_m - 0.05 * size])
        reach = 0.5 * float(np.hypot(*info.layout.frame_size_m)) + 0.5 * size
        start, end = geo.current_arrow_ends_n(
            center, reach, snap.current_direction_rad, arrow.length_m
        )
        with self._atomic():
            if arrow.length_m > 0.0:
                self._current.points = np.array([[start, end]])
            self._current.visible = arrow.length_m > 0.0
            self._current_label.position = start
            self._current_label.text = arrow.label

    # ----------------------------------------------------------------- per frame
    def redraw(self) -> None:
        """Send the moving parts and the current's arrow again at the next ``update``, however
        little they moved: an update cut short by an error sent only some of them."""
        self._last_pose = None
        self._current_key = None

    def update(self, snap: Snapshot) -> None:
        if snap.scene.version != self._version:
            self._build(snap.scene)
            self._last_pose = None
        info = snap.scene
        tree_eta = np.array(snap.tree_eta_n)
        self._draw_current(snap, max(info.tree_dimensions_m))
        self._update_track(snap, tree_eta[2])
        self.silt.update(snap)
        ref = snap.eta_ref
        ghost_shown = snap.mode != "manual"
        pose = np.concatenate(
            [
                [float(ghost_shown)],
                tree_eta,
                snap.rov_eta_n,
                ref,
                snap.crane_tip_n,
                [snap.wire_length_m, snap.wire_drag_newton_per_m],
            ]
        )
        if self._last_pose is not None and np.all(np.abs(pose - self._last_pose) < POSE_EPS):
            return
        self._last_pose = pose
        wire = geo.loaded_wire_points_n(
            np.array(snap.crane_tip_n),
            geo.attachment_point_n(tree_eta, info.attachment_height_m),
            snap.wire_length_m,
            info.wire_weight_newton_per_m,
            info.tree_weight_newton,
            snap.wire_drag_newton_per_m
            * np.array(
                [math.cos(snap.current_direction_rad), math.sin(snap.current_direction_rad)]
            ),
        )
        with self._atomic():
            self._tree.position = tree_eta[0:3]
            self._tree.wxyz = geo.quaternion_wxyz_from_rpy_radians(*tree_eta[3:6])
            self._rov.position = np.array(snap.rov_eta_n[0:3])
            self._rov.wxyz = geo.quaternion_wxyz_from_rpy_radians(*snap.rov_eta_n[3:6])
            # by hand the autopilot's reference is not where the ROV is going (it stays at the
            # last target): the ghost is shown only while a controller follows it
            if self._ghost.visible != ghost_shown:
                self._ghost.visible = ghost_shown
            self._ghost.position = (ref[0], ref[1], tree_eta[2])
            self._ghost.wxyz = geo.quaternion_wxyz_from_rpy_radians(0.0, 0.0, ref[2])
            self._wire.points = geo.polyline_segments(wire)
            label = f"tree {tree_eta[2]:.1f} m depth"
            if label != self._tree_label_text:
                self._tree_label_text = label
                self._tree_label.text = label

    def _update_track(self, snap: Snapshot, depth_m: float) -> None:
        now = time.monotonic()
        if now - self._track_wall < TRACK_EVERY_S or len(snap.trend) < 2:
            return
        self._track_wall = now
        pts = np.column_stack(
            [
                snap.trend[-1200:, 1],
                snap.trend[-1200:, 2],
                np.full(min(len(snap.trend), 1200), depth_m),
            ]
        )
        self._track.points = geo.polyline_segments(pts)


class _Recorder:
    """Passes ``add_*`` calls to the scene and remembers the handles (to remove them all when
    the set-up changes)."""

    def __init__(self, scene: viser.SceneApi, handles: list) -> None:
        self._scene = scene
        self._handles = handles

    def __getattr__(self, name: str):
        method = getattr(self._scene, name)

        def add(*args, **kwargs):
            handle = method(*args, **kwargs)
            self._handles.append(handle)
            return handle

        return add
