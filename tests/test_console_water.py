"""The water in a real headless Chromium: the scene's meshes are drawn, the water's visibility
is a setting of the session (the API refuses one out of range), and turbid water hides the
far part of the picture that clear water shows. Screenshots of the overview and the ROV
camera, clear and turbid, go to the screenshots folder (``docs/screenshots`` with
``ROV_SCREENSHOTS_DIR``).

Uses the server, browser and helpers of ``tests/browser.py``.
"""

from __future__ import annotations

import io
import time

import httpx
import numpy as np
from PIL import Image

from app.server import RunningServer
from tests import browser as tb
from tests.browser import click, save, scene_part, unlock
from web.underwater import water_rgb

CLEAR_M, TURBID_M = 30.0, 4.0


def _shot(pg, name: str) -> np.ndarray:
    tb._dismiss_notifications(pg)
    data = pg.screenshot()
    save(data, name)
    return scene_part(np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=float))


def _set_visibility(api: httpx.Client, visibility_m: float) -> None:
    api.put("/api/environment/visibility", json={"visibility_m": visibility_m}).raise_for_status()


def test_meshes_drawn_and_fog_follows_the_visibility(
    page, server: RunningServer, api: httpx.Client
) -> None:
    refused = api.put("/api/environment/visibility", json={"visibility_m": 45.0})
    assert refused.status_code == 422 and "less than or equal to 30" in refused.text
    scene = server.app.state.view.scene
    names = scene.names()
    assert {"/tree/body", "/rov/body", "/site/frame", "/silt", "/rov/lamp_0"} <= names
    unlock(page, server.token)
    shots = {}
    for visibility, word in ((CLEAR_M, "clear"), (TURBID_M, "turbid")):
        if word == "turbid":  # the sonar's picture in the panel, for the view that is gone
            page.get_by_text("Water", exact=True).first.click()
        _set_visibility(api, visibility)
        assert api.get("/api/environment/visibility").json()["visibility_m"] == visibility
        for preset in ("Overview", "ROV camera"):
            click(page, preset)
            time.sleep(1.5)
            key = f"{preset.lower().replace(' ', '-')}-{word}"
            shots[key] = _shot(page, f"console-water-{key}.png")
            if word == "turbid":  # the camera's move and the fog reach the page in their time
                clear_share = _water_share(
                    shots[f"{preset.lower().replace(' ', '-')}-clear"], CLEAR_M
                )
                deadline = time.monotonic() + 10.0
                while (
                    _water_share(shots[key], TURBID_M) <= clear_share + 0.1
                    and time.monotonic() < deadline
                ):
                    time.sleep(1.0)
                    shots[key] = _shot(page, f"console-water-{key}.png")
    _set_visibility(api, 20.0)
    click(page, "Overview")
    for preset in ("overview", "rov-camera"):
        clear, turbid = shots[f"{preset}-clear"], shots[f"{preset}-turbid"]
        assert clear.std() > 10.0, f"{preset}: the clear scene looks blank"
        # turbid water hides the far scene in the water's colour (the background's): more of
        # the picture is water (the overview sees the site as from its look-at point, so
        # only what lies beyond that point goes)
        hidden = (_water_share(clear, CLEAR_M), _water_share(turbid, TURBID_M))
        assert hidden[1] > hidden[0] + 0.1, f"{preset}: water share clear, turbid {hidden}"


def _water_share(img: np.ndarray, visibility_m: float) -> float:
    """Share of the picture within 6 levels of the water's colour."""
    rgb = np.array(water_rgb(visibility_m), float)
    return float((np.abs(img - rgb).max(axis=2) <= 6.0).mean())


def test_landing_raises_a_silt_cloud_that_clouds_the_rov_camera(
    page, server: RunningServer, api: httpx.Client
) -> None:
    """The winch lowers the tree onto the frame: the landing raises a cloud round the frame,
    drawn in the scene and seen from the ROV's camera (the sea trial's clouded view)."""
    scene = server.app.state.view.scene
    snap = server.console.loop.snapshot
    info = snap.scene
    above = info.frame.post_top_depth_m(info.layout) - (
        snap.tree_eta_n[2] + 0.5 * info.tree_dimensions_m[2]
    )
    drop = above + info.layout.post_height_m + 0.3
    api.put("/api/run/speed", json={"speed": 5.0}).raise_for_status()
    api.post("/api/winch/pay-out", json={"speed_mps": 0.5, "distance_m": drop}).raise_for_status()
    tb.wait_for(lambda: scene.silt.state.cloud is not None, 60.0, "the landing's silt cloud")
    api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()
    api.post("/api/run/pause").raise_for_status()
    for preset in ("ROV camera", "Overview"):
        click(page, preset)
        time.sleep(1.5)
        _shot(page, f"console-water-silt-{preset.lower().replace(' ', '-')}.png")
    api.post("/api/run/resume").raise_for_status()
