"""The pilot page in a real headless Chromium with real key events: hold W and the ROV goes
forward in its own frame; let go and it holds station; P hands over to the autopilot and back;
a wrong token is refused with a message. (The console's own server and API client fixtures
come from ``tests/browser.py``.)"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import httpx
import numpy as np
import pytest

from app.server import RunningServer
from tests.browser import CHROMIUM, TEST_CHROMIUM_ARGS, wait_for

NAME = "Test Pilot"


@pytest.fixture(scope="module")
def pilot(server: RunningServer) -> Iterator:
    if not CHROMIUM.exists():
        pytest.skip("Debian's chromium is missing")
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(
            executable_path=str(CHROMIUM), args=TEST_CHROMIUM_ARGS, headless=True
        )
        try:
            pg = browser.new_page(viewport={"width": 1200, "height": 800})
            pg.goto(f"{server.base_url}/pilot")
            yield pg
        finally:
            browser.close()


def sign_in(pg, token: str) -> None:
    pg.fill("#name", NAME)
    pg.fill("#token", token)
    pg.click("#fly")


def text(pg, selector: str) -> str:
    return str(pg.locator(selector).text_content() or "")


def rov(api: httpx.Client) -> tuple[np.ndarray, float, str, float]:
    """The ROV's (north, east, down), heading [rad], the mode and the simulation time [s],
    from /api/state."""
    s = api.get("/api/state").json()
    e = s["rov_eta_n"]
    position = np.array([e["north_m"], e["east_m"], e["down_m"]])
    return position, math.radians(e["heading_deg"]), s["mode"], s["t_s"]


def test_wrong_token_is_refused_with_a_message(pilot) -> None:
    sign_in(pilot, "certainly-not-the-console-token")
    wait_for(lambda: "wrong token" in text(pilot, "#message"), 10.0, "the refusal")
    assert text(pilot, "#message") == (
        "wrong token: flying needs the console token (printed at start-up)"
    )
    assert pilot.locator("#panel").is_hidden()


def test_hold_w_flies_forward_and_letting_go_holds_station(
    pilot, server: RunningServer, api: httpx.Client
) -> None:
    sign_in(pilot, server.token)
    wait_for(lambda: text(pilot, "#message") == f"flying as {NAME}", 15.0, "signed in")
    assert api.put("/api/control/grip", json={"grip": False}).status_code == 200
    pilot.keyboard.press("p")
    wait_for(lambda: text(pilot, "#mode") == "PILOT (by hand)", 10.0, "pilot mode on the page")
    assert rov(api)[2] == "manual"
    time.sleep(1.0)
    start, psi, _, t0 = rov(api)
    forward = np.array([math.cos(psi), math.sin(psi)])
    side = np.array([-math.sin(psi), math.cos(psi)])
    track = []
    pilot.keyboard.down("w")
    deadline = time.monotonic() + 30.0
    while time.monotonic() < deadline:  # 2 s of simulated time (the loop may lag under load)
        p, _, _, t = rov(api)
        track.append((t - t0, float((p - start)[0:2] @ forward)))
        if t - t0 > 2.0:
            break
        time.sleep(0.05)
    assert text(pilot, "#v-surge") == "0.50"  # the key is half stick
    pilot.keyboard.up("w")
    # where W was let go is where the simulation took the stick back to zero, and the hold's
    # set point is the pose of that step: read it from the simulation, not from a sample of
    # /api/state taken after the release (under load a CI run sampled the ROV 1.1 m before that
    # point, still at full speed; another sampled it 0.6 m past it, coasting, and each took the
    # difference for a drift of the station keeping)
    sim = server.console.loop.session.sim
    wait_for(lambda: float(sim.pilot_demand[0]) == 0.0, 10.0, "the simulation's stick at zero")
    t, along = np.array(track).T
    t, first = np.unique(t, return_index=True)  # one sample per published state
    along = along[first]
    moving = t > t[np.argmax(along > 1e-3)]  # from the first visible move on
    early = np.polyfit(t[moving][:4], along[moving][:4], 1)[0]
    late = np.polyfit(t[t > 1.5], along[t > 1.5], 1)[0]
    assert along[-1] > 0.5  # metres forward in 2 s (half stick, free ROV)
    assert late > early + 0.2 and late > 0.3  # the surge speed grows [m/s]
    wait_for(lambda: text(pilot, "#v-surge") == "0.00", 5.0, "the stick back at zero")
    t_release = rov(api)[3]  # a step after the stick reached zero: the set point is frozen
    hold_n = sim.free_setpoint_n[0:2]
    # where it was let go: at or past the last sample before the release (the stick reached
    # the simulation after it); 0.05 m for the heading the samples were projected on, taken at
    # the start (a 1 deg turn over the 1-2 m run moves the projection by under 0.02 m)
    assert float((hold_n - start[0:2]) @ forward) > along[-1] - 0.05
    assert abs(float((hold_n - start[0:2]) @ side)) < 0.2 * along[-1]  # not sideways
    wait_for(lambda: rov(api)[3] > t_release + 10.0, 60.0, "10 s of simulated time")
    held = rov(api)[0]
    assert np.array_equal(sim.free_setpoint_n[0:2], hold_n)  # the set point did not move
    # the station keeping brings it back to that point (0.09 m after 10 s simulated)
    assert np.linalg.norm(held[0:2] - hold_n) < 0.5


def test_p_hands_over_to_the_autopilot_and_back_and_h_toggles_auto_heading(
    pilot, server: RunningServer, api: httpx.Client
) -> None:
    if text(pilot, "#mode") != "PILOT (by hand)":
        sign_in(pilot, server.token)
        pilot.keyboard.press("p")
    wait_for(lambda: text(pilot, "#mode") == "PILOT (by hand)", 10.0, "pilot mode")
    pilot.keyboard.press("p")
    wait_for(lambda: text(pilot, "#mode") == "AUTOPILOT (free)", 10.0, "autopilot")
    assert rov(api)[2] == "free"
    pilot.keyboard.press("p")
    wait_for(lambda: text(pilot, "#mode") == "PILOT (by hand)", 10.0, "pilot again")
    assert rov(api)[2] == "manual"
    pilot.keyboard.press("h")
    wait_for(lambda: text(pilot, "#hold-heading") == "off", 10.0, "auto-heading off")
    assert server.console.loop.session.sim.pilot_holds == (False, True)
    pilot.keyboard.press("h")
    wait_for(lambda: text(pilot, "#hold-heading") == "on", 10.0, "auto-heading on")
    who = {o.who for o in server.console.loop.snapshot.operations}
    assert f"pilot ({NAME})" in who


FAKE_GAMEPAD = """
Object.defineProperty(navigator, "getGamepads", {value: () => [null, {
  id: "test pad", connected: true, axes: window.__axes || [0, 0, 0, 0], buttons: [],
}]});
"""


def test_gamepad_axes_with_a_dead_band_reach_the_demand(pilot) -> None:
    """A gamepad (the Gamepad API, faked in the page: headless Chromium has none): the left
    stick's Y is surge (up is forward), X is sway; inside 0.15 the stick is zero, beyond it
    the rest of the travel maps onto 0..1."""
    context = pilot.context.browser.new_context()
    try:
        context.add_init_script(FAKE_GAMEPAD)
        pg = context.new_page()
        pg.goto(pilot.url)
        pg.evaluate("window.__axes = [0.1, -0.6, 0.0, 1.0]")
        assert text(pg, "#v-surge") == "0.00"  # nothing is sent (nor drawn) before sign-in
        pg.evaluate("drawBars(demand())")  # what the page sends every 50 ms once signed in
        assert text(pg, "#pad") == "Gamepad: test pad"
        assert text(pg, "#v-surge") == f"{(0.6 - 0.15) / 0.85:.2f}"  # 0.53
        assert text(pg, "#v-sway") == "0.00"  # 0.1 is inside the dead band
        assert text(pg, "#v-heave") == "1.00"
    finally:
        context.close()


def test_the_embedded_view_has_the_console_panel_minimised(pilot, server: RunningServer) -> None:
    """Defect (issue 47 item 27): the pilot page embedded the whole console, whose panel
    covered a third of the view. The view's socket is opened on ``PILOT_VIEW_PATH`` and the
    console minimises that browser's panel (a click on its bar opens it again)."""
    from app.console import PILOT_VIEW_PATH
    from tests.browser import save

    view = server.app.state.view

    def pilot_panel() -> bool:
        pilot.evaluate("1")  # let Playwright take in the page's events
        with view._lock:
            ids = list(view._panels)
        return any(view._socket_path(i) == PILOT_VIEW_PATH for i in ids)

    wait_for(pilot_panel, 60.0, "the pilot page's view to connect on its own path")
    frame = next(f for f in pilot.frames if "websocket=" in f.url)
    frame.get_by_text("ROV console").first.wait_for(timeout=60_000)
    time.sleep(2.0)  # the minimise comes with the panel's first messages
    assert not frame.get_by_text("Unlock controls").first.is_visible()
    save(pilot.screenshot(), "pilot-page.png")
