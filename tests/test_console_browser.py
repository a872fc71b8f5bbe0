"""The console in a real headless Chromium (Debian's /usr/bin/chromium, driven by Playwright):
the page loads, the camera presets show the scene (screenshots go to docs/screenshots/), a
gain set in the panel reaches the controller, a mission built and started in the panel moves
the tree, and a session recorded in the panel is replayed in the same view.

One server and one browser for the module (start-up costs seconds); each test leaves the
console running live.
"""

from __future__ import annotations

import io
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import numpy as np
import pytest
from PIL import Image

from app.console import ConsoleSettings
from app.server import RunningServer, serve_in_thread

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
SCREENSHOTS = Path(__file__).resolve().parents[1] / "docs" / "screenshots"

pytestmark = pytest.mark.skipif(not CHROMIUM.exists(), reason="Debian's chromium is missing")
playwright_api = pytest.importorskip("playwright.sync_api")


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningServer]:
    settings = ConsoleSettings(
        port=0, viser_port=0, recordings_dir=tmp_path_factory.mktemp("recordings")
    )
    with serve_in_thread(settings) as srv:
        yield srv


@pytest.fixture(scope="module")
def page(server: RunningServer, tmp_path_factory: pytest.TempPathFactory):
    with playwright_api.sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            str(tmp_path_factory.mktemp("chromium-profile")),
            executable_path=str(CHROMIUM),
            args=CHROMIUM_ARGS,
            headless=True,
            viewport={"width": 1400, "height": 900},
        )
        try:
            pg = context.new_page()
            pg.goto(server.view_url)
            pg.get_by_text("Unlock controls").wait_for(timeout=60_000)
            time.sleep(1.0)
            _dismiss_notifications(pg)
            yield pg
        finally:
            context.close()


@pytest.fixture(scope="module")
def api(server: RunningServer) -> Iterator[httpx.Client]:
    with httpx.Client(base_url=server.base_url, headers=server.auth, timeout=30.0) as client:
        yield client


# ---------------------------------------------------------------------- helpers
def _dismiss_notifications(pg) -> None:
    """Close viser's 'software WebGL' notice so it does not cover the scene."""
    time.sleep(1.0)
    for button in pg.locator(".mantine-Notification-root button").all():
        try:
            button.click(timeout=1000)
        except Exception:
            pass


def field(pg, label: str):
    """The text/number input of a viser control, found by its label."""
    inputs = "*[self::input[not(@type='hidden')] or self::select or self::textarea]"
    return pg.locator(
        f"xpath=//label[normalize-space(.)='{label}']/ancestor::div[.//{inputs}][1]//{inputs}"
    ).first


def choose(pg, label: str, option: str) -> None:
    """Pick an option of a viser dropdown (a combobox with a list of options)."""
    field(pg, label).click()
    pg.locator(f"xpath=//*[@role='option'][normalize-space(.)='{option}']").filter(
        visible=True
    ).first.click()


def button(pg, name: str):
    """A button by its text (XPath: role queries are slow on viser's large page)."""
    return pg.locator(f"xpath=//button[normalize-space(.)='{name}']").first


def click(pg, name: str) -> None:
    button(pg, name).click()


def tab(pg, name: str) -> None:
    pg.locator(f"xpath=//*[@role='tab'][normalize-space(.)='{name}']").first.click()


def unlock(pg, token: str) -> None:
    field(pg, "Token").fill(token)
    click(pg, "Unlock controls")
    pg.get_by_text("controls unlocked").wait_for(timeout=10_000)


def wait_for(predicate: Callable[[], bool], timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


def image(pg) -> np.ndarray:
    """The page as an RGB array."""
    return np.asarray(Image.open(io.BytesIO(pg.screenshot())).convert("RGB"), dtype=float)


def scene_part(img: np.ndarray) -> np.ndarray:
    """The 3D view without the control panel on the right."""
    return img[:, : int(0.6 * img.shape[1])]


def save(img_bytes: bytes, name: str) -> Path:
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    path = SCREENSHOTS / name
    path.write_bytes(img_bytes)
    return path


# ---------------------------------------------------------------------- tests
def test_page_loads_with_live_state_and_locked_controls(page, server: RunningServer) -> None:
    page.get_by_text("ROV console").first.wait_for()
    page.get_by_text("live").first.wait_for()
    assert page.locator("canvas").count() >= 1
    assert button(page, "Pause").is_disabled()
    t0 = server.console.loop.snapshot.t_s
    time.sleep(0.5)
    assert server.console.loop.snapshot.t_s > t0, "the loop must run while a browser watches"
    assert server.app.state.view.clients >= 1
    assert server.app.state.view.errors == []


def test_camera_presets_show_different_views_and_are_saved(page) -> None:
    shots = {}
    for button, name in (
        ("Overview", "console-overview.png"),
        ("Top-down", "console-top-down.png"),
        ("ROV camera", "console-rov-camera.png"),
    ):
        click(page, button)
        time.sleep(2.0)
        _dismiss_notifications(page)
        data = page.screenshot()
        save(data, name)
        shots[button] = scene_part(
            np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=float)
        )
    for name, img in shots.items():
        assert img.std() > 10.0, f"{name}: the scene looks blank"
    names = list(shots)
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            diff = np.abs(shots[names[i]] - shots[names[j]]).mean()
            assert diff > 5.0, f"{names[i]} and {names[j]} show the same picture"
    click(page, "Overview")


def test_gain_change_in_the_panel_is_applied(
    page, server: RunningServer, api: httpx.Client
) -> None:
    unlock(page, server.token)
    tab(page, "Control")
    before = api.get("/api/gains").json()
    target = before["kp"][0] * 1.5
    box = field(page, "kp surge")
    box.fill(f"{target:g}")
    box.press("Enter")
    wait_for(
        lambda: abs(api.get("/api/gains").json()["kp"][0] - target) < 1e-6,
        10.0,
        "the panel's gain in GET /api/gains",
    )
    after = api.get("/api/gains").json()
    assert after["kp"][1:] == before["kp"][1:] and after["kd"] == before["kd"]
    click(page, "Preset gains")
    wait_for(lambda: api.get("/api/gains").json() == before, 10.0, "preset gains back")


def test_mission_built_in_the_panel_moves_the_tree(
    page, server: RunningServer, api: httpx.Client
) -> None:
    unlock(page, server.token)
    click(page, "Top-down")
    tab(page, "Mission")
    choose(page, "Set-up from", "full-square-400")
    choose(page, "Leg type", "move")
    field(page, "North [m]").fill("3")
    field(page, "Settle [s]").fill("2")
    click(page, "Add leg")
    page.get_by_text("added move leg").wait_for(timeout=5000)
    click(page, "Validate")
    page.get_by_text("valid: 1 legs").wait_for(timeout=5000)
    click(page, "Start built mission")
    wait_for(
        lambda: api.get("/api/state").json()["mission"]["name"] == "built mission",
        20.0,
        "the built mission to start",
    )
    start = api.get("/api/state").json()["tree_eta_n"]["north_m"]
    tab(page, "Plots")
    time.sleep(1.5)
    _dismiss_notifications(page)
    before = scene_part(image(page))
    api.put("/api/run/speed", json={"speed": 20.0}).raise_for_status()
    wait_for(
        lambda: api.get("/api/state").json()["tree_eta_n"]["north_m"] > start + 2.5,
        40.0,
        "the tree to move 2.5 m north",
    )
    time.sleep(1.5)
    after_bytes = page.screenshot()
    after = scene_part(np.asarray(Image.open(io.BytesIO(after_bytes)).convert("RGB"), dtype=float))
    save(after_bytes, "console-mission.png")
    moved = np.abs(after - before).mean(axis=2) > 30.0
    assert moved.mean() > 0.002, "the tree moved but the picture did not change"
    wait_for(
        lambda: api.get("/api/state").json()["mission"]["state"] == "completed",
        40.0,
        "the mission to complete",
    )
    api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()
    click(page, "Overview")


def test_recording_from_the_panel_is_written_and_replayed(
    page, server: RunningServer, api: httpx.Client
) -> None:
    unlock(page, server.token)
    api.put("/api/run/speed", json={"speed": 10.0}).raise_for_status()
    tab(page, "Record")
    field(page, "Label").fill("browser-test")
    click(page, "Start recording")
    wait_for(
        lambda: api.get("/api/state").json()["recording"] is not None,
        10.0,
        "the recording to start",
    )
    time.sleep(2.0)
    click(page, "Stop recording")
    wait_for(
        lambda: api.get("/api/state").json()["recording"] is None, 10.0, "the recording to stop"
    )
    listed = api.get("/api/recordings").json()["recordings"]
    names = [r["name"] for r in listed if "browser-test" in r["name"]]
    assert names and listed[0]["size_bytes"] > 1000
    click(page, "Refresh list")
    choose(page, "Recording", names[0])
    click(page, "Open replay")
    wait_for(lambda: api.get("/api/state").json()["source"] == "replay", 20.0, "replay mode")
    replay = api.get("/api/replay").json()["replay"]
    assert replay["end_s"] - replay["start_s"] > 5.0
    click(page, "Play replay")
    t0 = api.get("/api/state").json()["t_s"]
    wait_for(lambda: api.get("/api/state").json()["t_s"] > t0 + 1.0, 15.0, "the replay to play")
    page.get_by_text("REPLAY").first.wait_for(timeout=5000)
    save(page.screenshot(), "console-replay.png")
    click(page, "Pause replay")
    wait_for(
        lambda: not api.get("/api/replay").json()["replay"]["playing"], 10.0, "the replay to pause"
    )
    field(page, "Replay time s").fill(f"{replay['start_s'] + 1.0:.1f}")
    field(page, "Replay time s").press("Enter")
    wait_for(
        lambda: abs(api.get("/api/state").json()["t_s"] - replay["start_s"] - 1.0) < 0.5,
        10.0,
        "the replay to seek back",
    )
    click(page, "Close replay")
    wait_for(lambda: api.get("/api/state").json()["source"] == "live", 10.0, "live again")
    api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()


def test_several_browsers_watch_the_same_session(page, server: RunningServer) -> None:
    other = page.context.new_page()
    try:
        other.goto(server.view_url)
        other.get_by_text("Unlock controls").wait_for(timeout=60_000)
        wait_for(lambda: server.app.state.view.clients >= 2, 10.0, "two clients")
        other.get_by_text("live").first.wait_for(timeout=10_000)
        assert button(other, "Pause").is_disabled(), "unlocking one browser must not unlock another"
    finally:
        other.close()
    wait_for(lambda: server.app.state.view.clients == 1, 10.0, "the second client to leave")
