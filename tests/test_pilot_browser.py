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
from tests.browser import CHROMIUM, CHROMIUM_ARGS, wait_for

NAME = "Test Pilot"


@pytest.fixture(scope="module")
def pilot(server: RunningServer) -> Iterator:
    if not CHROMIUM.exists():
        pytest.skip("Debian's chromium is missing")
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(
            executable_path=str(CHROMIUM), args=CHROMIUM_ARGS, headless=True
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


def rov(api: httpx.Client) -> tuple[np.ndarray, float, str]:
    """The ROV's (north, east, down), heading [rad] and the mode, from /api/state."""
    s = api.get("/api/state").json()
    e = s["rov_eta_n"]
    return (
        np.array([e["north_m"], e["east_m"], e["down_m"]]),
        math.radians(e["heading_deg"]),
        s["mode"],
    )


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
    start, psi, _ = rov(api)
    forward = np.array([math.cos(psi), math.sin(psi)])
    side = np.array([-math.sin(psi), math.cos(psi)])
    track = []
    pilot.keyboard.down("w")
    t0 = time.monotonic()
    while time.monotonic() - t0 < 2.0:
        p, _, _ = rov(api)
        track.append((time.monotonic() - t0, float((p - start)[0:2] @ forward)))
        time.sleep(0.1)
    assert text(pilot, "#v-surge") == "0.50"  # the key is half stick
    pilot.keyboard.up("w")
    release, _, _ = rov(api)
    t, along = np.array(track).T
    early = np.polyfit(t[t < 0.8], along[t < 0.8], 1)[0]
    late = np.polyfit(t[t > 1.2], along[t > 1.2], 1)[0]
    assert along[-1] > 0.5  # metres forward in 2 s (half stick, free ROV)
    assert late > early + 0.2 and late > 0.3  # the surge speed grows [m/s]
    assert abs(float((release - start)[0:2] @ side)) < 0.2 * along[-1]  # not sideways
    wait_for(lambda: text(pilot, "#v-surge") == "0.00", 5.0, "the stick back at zero")
    time.sleep(10.0)
    held, _, _ = rov(api)
    # the station keeping brings it back to where W was let go (0.09 m after 10 s simulated)
    assert np.linalg.norm((held - release)[0:2]) < 0.5


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
