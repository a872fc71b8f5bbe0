"""One browser's camera: the "View" folder's presets (overview, top-down, the ROV's camera,
following the ROV) and the poses sent to follow the scene."""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
import viser

from app.console import Console, Snapshot
from web import geometry as geo

CAMERAS = ("Overview", "Top-down", "ROV camera", "Follow ROV")
FOLLOWING = ("Overview", "Top-down", "ROV camera", "Follow ROV")
"""Presets that follow the scene each frame (the overview and the top-down view only until
the user moves the camera)."""
LET_GO = ("Overview", "Top-down")
"""Presets that stop following when the user moves the camera by hand."""
PREVIEW = "Preview"
"""The mode of a camera turned to something shown once (``Camera.show_points``)."""
CAMERA_SETTLE_S = 1.5
"""After a preset is pressed (or the first pose is sent), camera reports are not taken for
the user's: the browser may still report the camera it had."""


class Camera:
    """The camera presets of one browser and the poses sent to its camera."""

    def __init__(self, client: viser.ClientHandle, console: Console) -> None:
        self.client = client
        self.console = console
        self.mode = "Overview"
        self.pending = True
        """A pose is due on the next frame (a preset pressed, a preset that follows)."""
        self.lock = threading.Lock()
        """Held while a pose is chosen and sent to this browser's camera: a preset pressed (a
        viser callback thread) and the publisher thread's following of the scene each send
        whole poses, one after the other. Interleaved, one's position went out with the
        other's look-at point and up direction (viser carries the look-at along with each
        position it sets), and a page pressed to "Top-down" while its overview was
        following showed the seabed edge-on (CI on a slower machine,
        tests/test_console_replay.py)."""
        self._framed: geo.CameraPose | None = None
        """The pose ``show_points`` chose."""
        self._sent = geo.CameraEchoes()
        self._settle = 0.0
        gui = client.gui
        with gui.add_folder("View"):
            self.buttons = gui.add_button_group("Camera", CAMERAS)
            self.buttons.on_click(self._on_preset)
            self.camera_md = gui.add_markdown("")
        client.camera.on_update(self._on_moved)

    def follow(self, snap: Snapshot) -> None:
        """Send the preset's pose if one is due (the publisher thread, each frame)."""
        with self.lock:
            if self.pending:
                self._apply(snap)

    def _on_preset(self, event: Any) -> None:
        with self.lock:
            self.mode = str(self.buttons.value)
            self.pending = True
            self._settle = time.monotonic() + CAMERA_SETTLE_S
            self.camera_md.content = ""
            self._apply(self.console.loop.snapshot)

    def show_points(self, points_n: np.ndarray, what: str) -> None:
        """Turn this browser's camera to ``points_n`` ((k, 3), NED), framed whole, and stay
        there until a preset is pressed (the builder's preview at another depth than the live
        run's would be out of sight)."""
        size = max(self.console.loop.snapshot.scene.tree_dimensions_m)
        with self.lock:
            self.mode = PREVIEW
            self._framed = geo.framing_camera(points_n, size)
            self.pending = True
            self._settle = time.monotonic() + CAMERA_SETTLE_S
            self.camera_md.content = f"camera on {what}: press a preset to go back"
            self._apply(self.console.loop.snapshot)

    def _on_moved(self, camera: viser.CameraHandle) -> None:
        """The browser reports its camera: one that matches none of the poses sent lately
        was moved by the user, and the overview stops following until a preset is pressed."""
        if self.mode not in LET_GO or not self.pending or not self._sent:
            return
        if time.monotonic() < self._settle:
            return  # reports of the camera the browser had before
        if not self._sent.is_echo(np.asarray(camera.position), np.asarray(camera.look_at)):
            self.pending = False
            self.camera_md.content = f"camera moved by hand: press {self.mode} to follow again"

    def _pose(self, snap: Snapshot) -> geo.CameraPose:
        """The present preset's pose for the scene in ``snap``."""
        if self.mode == PREVIEW and self._framed is not None:
            return self._framed
        info = snap.scene
        size = max(info.tree_dimensions_m)
        tree = np.array(snap.tree_eta_n)
        frame = info.frame
        if self.mode == "Top-down":
            return geo.top_down_camera(frame.center_n, frame.landing_depth_m, tree, size)
        if self.mode == "ROV camera":
            posts = frame.post_positions_n(info.layout)
            tops = np.column_stack(
                [posts, np.full(len(posts), frame.post_top_depth_m(info.layout))]
            )
            return geo.rov_camera(
                np.array(snap.rov_eta_n),
                np.array(info.rov_dimensions_m),
                tree,
                info.tree_dimensions_m[2],
                tops,
            )
        if self.mode == "Follow ROV":
            return geo.follow_rov_camera(
                np.array(snap.rov_eta_n), np.array(info.rov_dimensions_m), size
            )
        return geo.overview_camera(tree, size, np.array([*frame.center_n, frame.landing_depth_m]))

    def _apply(self, snap: Snapshot) -> None:
        """Send the present preset's pose (call with ``lock`` held)."""
        pose = self._pose(snap)
        cam = self.client.camera
        fov = geo.ROV_CAMERA_FOV_RAD if self.mode == "ROV camera" else geo.OVERVIEW_FOV_RAD
        try:
            # setting the position carries the look-at point along before it is set: the
            # browser may report that in-between pose too
            between = cam.look_at + (pose.position_n - cam.position)
            with self.client.atomic():
                cam.up_direction = pose.up_n
                cam.position = pose.position_n
                cam.look_at = pose.look_at_n
                cam.fov = float(fov)
        except AssertionError:
            return  # the browser has not reported its camera yet: try again next frame
        except RuntimeError:
            # viser wakes its event loop from this thread; rarely the loop is reading the same
            # waiters ("deque mutated during iteration"): the pose goes again next frame
            return
        # the poses sent lately, to tell the browser's echoes of them from a camera the user
        # moved (the in-between pose and the pose itself)
        now = time.monotonic()
        if not self._sent:
            self._settle = now + CAMERA_SETTLE_S
        self._sent.sent(pose.position_n, between, now)
        self._sent.sent(pose.position_n, pose.look_at_n, now)
        self.pending = self.mode in FOLLOWING
