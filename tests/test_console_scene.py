"""Seeing the work, in a real headless Chromium: a still or changed current draws without
scene-tree warnings in the browser, the overview keeps the tree on screen while a mission
carries it several tree lengths, the pilot's readout matches the state the API reports, and
the ROV's camera is not filled by the ROV. Screenshots of every camera preset go to
docs/screenshots/.

Uses the server, browser and helpers of ``tests/browser.py`` (its fixtures are module-scoped:
this module gets its own server and browser).
"""

from __future__ import annotations

import io
import math
import re
import time

import httpx
import numpy as np
from PIL import Image

from app.server import RunningServer
from tests import browser as tb
from tests.browser import click, open_console, save, scene_part, unlock, wait_for

MOVE_NORTH_M = 18.0
"""How far the uploaded mission carries the tree: five lengths of the full-scale tree."""
MOVE_MISSION = f"""
format_version = 1
name = "scene-move-north"
description = "vessel and tree {MOVE_NORTH_M:g} m north"
[setup]
params = "full-scale"
depth_m = 400.0
crane_tip_n = [1.0, 1.0]
[[legs]]
type = "vessel"
north_m = {MOVE_NORTH_M}
east_m = 0.0
speed_mps = 0.5
settle_s = 0.0
[[legs]]
type = "move"
north_m = {MOVE_NORTH_M}
east_m = 0.0
settle_s = 5.0
"""


def _hue_sat(img: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hue [deg], saturation and value [0, 255] of an RGB image."""
    hi, lo = img.max(axis=2), img.min(axis=2)
    span = np.maximum(hi - lo, 1e-9)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    hue = np.where(
        hi == r,
        60.0 * ((g - b) / span % 6.0),
        np.where(hi == g, 60.0 * ((b - r) / span + 2.0), 0.0),
    )
    return hue, (hi - lo) / np.maximum(hi, 1e-9), hi


def _share(img: np.ndarray, hue_deg: tuple[float, float]) -> float:
    """Share of strongly coloured pixels (saturation over 0.4) in a band of hue. The scene's
    lights and environment map shade the faces of one box very differently in brightness,
    much less in hue: the tree (235, 190, 40; hue 46 deg) shows 44 to 70 deg, the ROV
    (230, 110, 30; 24 deg) 17 to 33 deg; the sand is below 0.35 saturation, the frame grey."""
    hue, sat, val = _hue_sat(img)
    return float(((hue >= hue_deg[0]) & (hue <= hue_deg[1]) & (sat > 0.4) & (val > 40)).mean())


MOVED = "camera moved by hand"
TREE_HUE = (40.0, 80.0)
ROV_HUE = (5.0, 36.0)


def _tree_off_centre(img: np.ndarray, full_width: int) -> float:
    """Distance of the tree's pixels' centroid from the middle of the whole canvas (the
    camera's axis; the panel covers the right of it), in canvas heights."""
    hue, sat, val = _hue_sat(img)
    ys, xs = np.nonzero((hue >= TREE_HUE[0]) & (hue <= TREE_HUE[1]) & (sat > 0.4) & (val > 40))
    return float(np.hypot(xs.mean() - full_width / 2, ys.mean() - img.shape[0] / 2)) / img.shape[0]


def _shot(pg, name: str) -> np.ndarray:
    tb._dismiss_notifications(pg)
    data = pg.screenshot()
    save(data, name)
    return scene_part(np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=float))


def _readout(pg) -> dict[str, float]:
    text = pg.get_by_text("above posts").first.inner_text()
    m = re.search(
        r"above posts (-?[\d.]+) m \| to frame ([\d.]+) m \| heading error ([+-][\d.]+) deg"
        r" \| wire ([\d.]+) kN",
        text,
    )
    assert m, f"readout not understood: {text!r}"
    return dict(
        zip(("height", "distance", "heading", "tension"), map(float, m.groups()), strict=True)
    )


def test_no_scene_warnings_with_a_still_or_changed_current(
    page, server: RunningServer, api: httpx.Client
) -> None:
    """A fresh browser, listening from its first message, at current 0, then the current set
    through the API and back to 0: the browser never hears of a node it does not have, and
    the current is labelled."""
    messages: list[str] = []
    other = page.context.new_page()
    other.on("console", lambda msg: messages.append(msg.text))
    try:
        api.put(
            "/api/environment/current", json={"speed_mps": 0.0, "direction_deg": 0.0}
        ).raise_for_status()
        open_console(other, server.view_url)
        time.sleep(2.0)
        for speed, direction in ((0.1, 225.0), (0.0, 0.0), (0.3, 90.0), (0.0, 0.0), (0.1, 225.0)):
            api.put(
                "/api/environment/current", json={"speed_mps": speed, "direction_deg": direction}
            ).raise_for_status()
            time.sleep(0.7)
        # labels are drawn in the canvas (not the page's text): read the scene's own
        scene = server.app.state.view.scene
        wait_for(
            lambda: scene._current_label.text == "current 0.10 m/s towards 225 deg",
            10.0,
            "the current's label",
        )
    finally:
        other.close()
    bad = [m for m in messages if "non-existent" in m]
    assert not bad, f"the browser logged: {bad[:3]}"


def test_camera_presets_and_the_rov_camera_clear_of_the_rov(page) -> None:
    shots = {}
    for name in ("Overview", "Top-down", "ROV camera", "Follow ROV"):
        click(page, name)
        time.sleep(2.5)
        shots[name] = _shot(page, f"console-scene-{name.lower().replace(' ', '-')}.png")
        assert shots[name].std() > 10.0, f"{name}: the scene looks blank"
    rov_share = {name: _share(img, ROV_HUE) for name, img in shots.items()}
    assert rov_share["ROV camera"] < 0.02, f"the ROV fills its own camera: {rov_share}"
    assert rov_share["Follow ROV"] > 0.01, f"the ROV is not in its follow camera: {rov_share}"
    click(page, "Overview")


def test_overview_follows_the_tree_and_the_readout_matches_the_state(
    page, server: RunningServer, api: httpx.Client
) -> None:
    unlock(page, server.token)
    click(page, "Overview")
    time.sleep(2.0)
    start_img = _shot(page, "console-scene-overview-start.png")
    start_px = _share(start_img, TREE_HUE)
    assert start_px > 0.002, f"the tree is not on screen at the start ({start_px:.4f})"
    assert _tree_off_centre(start_img, 1400) < 0.15
    api.post("/api/missions/uploads", json={"toml": MOVE_MISSION}).raise_for_status()
    api.post("/api/missions/start", json={"name": "scene-move-north"}).raise_for_status()
    north0 = api.get("/api/state").json()["tree_eta_n"]["north_m"]
    api.put("/api/run/speed", json={"speed": 50.0}).raise_for_status()
    wait_for(
        lambda: api.get("/api/state").json()["tree_eta_n"]["north_m"] > north0 + MOVE_NORTH_M - 1,
        180.0,
        f"the tree to travel {MOVE_NORTH_M - 1:g} m north",
    )
    api.post("/api/run/pause").raise_for_status()
    api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()
    # the page has just drawn a 50x run in software WebGL; under a full run's load its main
    # thread took more than 10 s to show the pause once (2026-11-27), so it gets 30 s
    page.get_by_text("paused").first.wait_for(timeout=30_000)
    time.sleep(2.0)
    end_img = _shot(page, "console-scene-overview-end.png")
    end_px = _share(end_img, TREE_HUE)
    # the view widens to keep the frame in it too: the tree's share shrinks with the square
    # of the distance (about (17 / 30)^2 here), never to nothing, and the tree stays near the
    # middle (a camera left where it was has it 0.42 canvas heights off, at the top left)
    assert end_px > 0.1 * start_px, f"the tree left the overview ({start_px:.4f} -> {end_px:.4f})"
    off = _tree_off_centre(end_img, 1400)
    assert off < 0.3, f"the tree drifted {off:.2f} canvas heights off the overview's middle"

    state = api.get("/api/state").json()
    info = server.console.loop.snapshot.scene
    eta = state["tree_eta_n"]
    post_tops = info.frame.landing_depth_m - info.layout.post_height_m
    height = post_tops - (eta["down_m"] + 0.5 * info.tree_dimensions_m[2])
    distance = math.hypot(
        eta["north_m"] - info.frame.center_n[0], eta["east_m"] - info.frame.center_n[1]
    )
    heading = (eta["heading_deg"] - math.degrees(info.frame.heading_rad) + 180.0) % 360.0 - 180.0
    wait_for(lambda: _readout(page)["distance"] > 1.0, 10.0, "the readout of the paused state")
    shown = _readout(page)
    assert abs(shown["height"] - height) <= 0.006
    assert abs(shown["distance"] - distance) <= 0.006 and distance > MOVE_NORTH_M - 2
    assert abs(shown["heading"] - heading) <= 0.06
    assert abs(shown["tension"] - state["wire_tension_newton"] / 1000.0) <= 0.06
    assert page.get_by_text(MOVED).count() == 0, "the page's own camera moves taken for the user's"

    # the user drags the view: the overview stops following (and says so) until pressed again
    box = page.locator("canvas").first.bounding_box()
    x, y = box["x"] + 0.3 * box["width"], box["y"] + 0.6 * box["height"]
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + 160, y + 40, steps=8)
    page.mouse.up()
    # the drag turns the camera at the page's next frame, the page reports the camera and the
    # server answers with the notice; after the 50x run above, under a full run's load, that
    # took more than 10 s once (2026-11-27), as the pause did
    page.get_by_text(MOVED).first.wait_for(timeout=30_000)
    click(page, "Overview")
    wait_for(lambda: page.get_by_text(MOVED).count() == 0, 10.0, "following again")
    api.post("/api/run/resume").raise_for_status()


def test_camera_echoes_are_kept_by_time_not_by_count():
    """Defect: under load (load average 11) the browser's report of a follow-mode camera came
    back more than 100 poses (2.5 s at 20 frames a second) late and was taken for the user's
    hand, so the overview stopped following."""
    from web.geometry import CameraEchoes

    echoes = CameraEchoes(keep_s=10.0)
    frames = [
        (0.05 * k, np.array([k * 0.01, 0.0, 390.0]), np.array([0.0, 0.0, 400.0]))
        for k in range(200)
    ]
    for t, pos, look in frames:
        echoes.sent(pos, look, t)
    _, pos_late, look_late = frames[199 - 120]  # sent 6 s before the last pose
    assert echoes.is_echo(pos_late, look_late), "a 6 s late echo is the browser's, not a hand"
    assert not echoes.is_echo(np.array([5.0, 0.0, 390.0]), np.array([0.0, 0.0, 400.0]))
    for k in range(20):  # a still scene: the same two poses each frame are kept once
        echoes.sent(np.array([1.0, 1.0, 390.0]), np.array([0.0, 0.0, 400.0]), 20.0 + 0.05 * k)
        echoes.sent(np.array([1.0, 1.0, 390.0]), np.array([0.1, 0.0, 400.0]), 20.0 + 0.05 * k)
    assert not echoes.is_echo(pos_late, look_late), "poses older than 10 s are dropped"
    assert echoes.is_echo(np.array([1.0, 1.0, 390.0]), np.array([0.1, 0.0, 400.0]))
    assert len(echoes._sent) == 2


def test_a_lagging_browsers_in_between_camera_is_its_own():
    """Defect (CI, load 6-8: "the page's own camera moves taken for the user's"): setting the
    camera's position carries its look-at point along, so between two follow poses the
    browser reports the new position with the previous pose's offset to its look-at point.
    The server noted that in-between point from the camera the browser had last reported,
    which under load is several poses old, so the browser's true in-between was not among
    the poses noted and the overview stopped following. The offset is matched now; a camera
    at a position never sent is still a hand."""
    from web.geometry import CameraEchoes

    echoes = CameraEchoes(keep_s=10.0)
    poses = [
        # a fast follow at 50x: 1 m a pose, the look-at point swinging by metres (the match
        # is to 1 mm per metre from the origin, 0.4 m here)
        (np.array([1.0 * k, 0.0, 390.0]), np.array([1.0 * k + 2.0, 5.0 * np.sin(k / 3), 400.0]))
        for k in range(60)
    ]
    for k, (pos, look) in enumerate(poses):
        stale_pos, stale_look = poses[max(k - 5, 0)]  # the server's last report: 5 poses old
        echoes.sent(pos, stale_look + (pos - stale_pos), 0.05 * k)
        echoes.sent(pos, look, 0.05 * k)
    for k in (10, 30, 59):
        pos, (prev_pos, prev_look) = poses[k][0], poses[k - 1]
        between = prev_look + (pos - prev_pos)  # what the browser shows between two poses
        assert echoes.is_echo(pos, between), k
    hand = poses[30][0] + np.array([0.0, 3.0, -1.0])
    assert not echoes.is_echo(hand, poses[30][1])
    assert not echoes.is_echo(hand, hand + (poses[30][1] - poses[30][0]))
