"""The water seen in the 3D view: the silt cloud in a scene (``SiltView``, one per
``SceneView``), and each browser's fog, water colour, visibility setting and sonar picture
(``WaterPanel``, one per panel). The formulas are in ``web.underwater``."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import viser

from app.console import (
    VISIBILITY_MAX_M,
    VISIBILITY_MIN_M,
    Console,
    ConsoleError,
    SceneInfo,
    Snapshot,
    md_text,
)
from web import underwater as uw
from web.meshes import SILT_COLOR

SONAR_EVERY_S = 1.0
"""Wall time between sonar pictures."""
FOG_EPS = 0.01
"""Relative change of the fog's distances below which it is not sent again."""


class SiltView:
    """The silt cloud of one scene: raised when the tree or the ROV touches the seabed or the
    frame, drawn as translucent blobs that spread and fade."""

    def __init__(self) -> None:
        self.state = uw.SiltState()
        self._node: Any = None
        self._shown: tuple[float, ...] = ()

    def build(self, scene: Any, info: SceneInfo) -> None:
        """Add the cloud's node (hidden) to a scene being built (``scene``: its ``add_*``)."""
        mesh = uw.silt_mesh(info)
        self._node = scene.add_mesh_simple(
            "/silt",
            vertices=np.asarray(mesh.vertices, np.float32),
            faces=np.asarray(mesh.faces, np.uint32),
            color=SILT_COLOR,
            opacity=uw.SILT_OPACITY,
            flat_shading=False,
            cast_shadow=False,
            receive_shadow=False,
            visible=False,
        )
        self.state = uw.SiltState()
        self._shown = ()

    def update(self, snap: Snapshot) -> None:
        """Follow the snapshot: contact, the cloud's rise, spread and fading."""
        info = snap.scene
        contacts = uw.contact_points_n(info, np.array(snap.tree_eta_n), np.array(snap.rov_eta_n))
        self.state = uw.next_silt(self.state, info, snap.t_s, contacts)
        cloud = self.state.cloud
        if self._node is None:
            return
        if cloud is None:
            if self._shown != ():
                self._node.visible = False
                self._shown = ()
            return
        opacity = round(uw.SILT_OPACITY * cloud.density(snap.t_s), 2)
        radius = round(cloud.radius_at_m(snap.t_s), 2)
        shown = (opacity, radius, *cloud.origin_n)
        if shown == self._shown:
            return
        self._shown = shown
        self._node.position = cloud.origin_n
        self._node.scale = radius
        self._node.opacity = opacity
        self._node.visible = True


class WaterPanel:
    """One browser's water: the "Water" folder (visibility setting, sonar picture), the fog
    and the water's colour for its camera, thickened by a silt cloud near what it looks at."""

    def __init__(self, client: viser.ClientHandle, console: Console, operator: Any) -> None:
        self.client = client
        self.console = console
        self.operator = operator
        self._fog: tuple[float, float, tuple[int, int, int]] | None = None
        self._sonar_wall = 0.0
        self._rng = np.random.default_rng(client.client_id)
        gui = client.gui
        with gui.add_folder("Water", expand_by_default=False):
            self.visibility = operator.guard(
                gui.add_slider(
                    "Visibility (m)",
                    min=VISIBILITY_MIN_M,
                    max=VISIBILITY_MAX_M,
                    step=0.5,
                    initial_value=console.water.visibility_m,
                    hint="how far the water lets one see: turbid 2 m, clear 30 m",
                )
            )
            self.visibility.on_update(self._on_visibility)
            self.water_md = gui.add_markdown("")
            self.sonar = gui.add_image(
                np.zeros((uw.SONAR_PX, uw.SONAR_PX, 3), np.uint8), label="Sonar", format="png"
            )
            self.sonar_md = gui.add_markdown("")

    def _on_visibility(self, event: Any) -> None:
        if event.client is None:
            return
        try:
            self.console.water.set_visibility_m(float(self.visibility.value))
        except ConsoleError as err:
            self.water_md.content = f"**refused**: {md_text(str(err))}"

    def update(self, snap: Snapshot, rov_camera: bool, silt: uw.SiltState) -> None:
        """Fog and colour for this browser's camera (the publisher thread, each frame), and
        the sonar's picture once a second."""
        visibility = self.console.water.visibility_m
        if abs(float(self.visibility.value) - visibility) > 1e-9:
            self.visibility.value = visibility  # set by the API or another browser
        self._update_fog(snap, visibility, rov_camera, silt)
        now = time.monotonic()
        if now - self._sonar_wall >= SONAR_EVERY_S:
            self._sonar_wall = now
            info = snap.scene
            self.sonar.image = uw.sonar_image(
                info, np.array(snap.rov_eta_n), np.array(snap.tree_eta_n), self._rng
            )
            self.sonar_md.content = (
                f"range {uw.sonar_range_m(info):g} m, rings every "
                f"{uw.sonar_range_m(info) / 4:g} m; ROV heading up"
            )

    def _update_fog(
        self, snap: Snapshot, visibility: float, rov_camera: bool, silt: uw.SiltState
    ) -> None:
        cam = self.client.camera
        try:
            eye, look = np.asarray(cam.position, float), np.asarray(cam.look_at, float)
        except AssertionError:
            return  # the browser has not reported its camera yet
        standoff = 0.0 if rov_camera else float(np.linalg.norm(look - eye))
        where = eye if rov_camera else look
        seen = uw.silt_visibility_m(
            visibility, silt.cloud, snap.t_s, where, uw.tree_size_m(snap.scene)
        )
        near, far = uw.fog_range_m(seen, standoff)
        rgb = uw.water_rgb(seen)
        if self._fog is not None:
            _, old_far, old_rgb = self._fog
            if old_rgb == rgb and abs(far - old_far) <= FOG_EPS * old_far:
                return
        self._fog = (near, far, rgb)
        scene = self.client.scene
        scene.configure_fog(near, far, color=uw.fog_rgb(rgb))
        scene.set_background_image(np.full((8, 8, 3), rgb, np.uint8), format="png")
        self.water_md.content = f"visibility {visibility:.1f} m" + (
            f", **{seen:.1f} m in the silt**" if seen < visibility - 0.05 else ""
        )
