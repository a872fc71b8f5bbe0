"""A crew on one console, in real headless Chromium: the pilot page, the winch page and the
supervisor's page open in three browser contexts (three people's browsers). The winch
operator pays out and the tension and height on the winch page change; the instructor's
winch slip shows on the winch page and a lost thruster on the pilot page; the supervisor
pauses and resumes, and the operations log names the pilot and the winch operator. The
pages are saved as screenshots (``tests/browser.py``'s folder) to look at."""

from __future__ import annotations

from collections.abc import Iterator

import httpx
import pytest

from app.console import ConsoleSettings
from app.server import RunningServer, serve_in_thread
from tests.browser import CHROMIUM, SCREENSHOTS, TEST_CHROMIUM_ARGS, wait_for

WINCH = "winch-browser-42"
SUPERVISOR = "super-browser-42"
INSTRUCTOR = "teacher-browser-42"


@pytest.fixture(scope="module")
def crew_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningServer]:
    settings = ConsoleSettings(
        port=0,
        view=False,  # the pages' own panels are under test; the 3D view has its own tests
        instructor_token=INSTRUCTOR,
        winch_token=WINCH,
        supervisor_token=SUPERVISOR,
        recordings_dir=tmp_path_factory.mktemp("recordings"),
    )
    with serve_in_thread(settings) as srv:
        yield srv


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM.exists():
        pytest.skip("Debian's chromium is missing")
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=str(CHROMIUM), args=TEST_CHROMIUM_ARGS)
        try:
            yield b
        finally:
            b.close()


def open_station(browser, server: RunningServer, path: str, name: str, token: str, button: str):
    """A new browser context (its own person) with the station's page, signed in."""
    pg = browser.new_context(viewport={"width": 900, "height": 760}).new_page()
    pg.goto(f"{server.base_url}{path}")
    pg.fill("#name", name)
    pg.fill("#token", token)
    pg.click(button)
    wait_for(lambda: pg.locator("#panel").is_visible(), 15.0, f"{path} signed in")
    return pg


def text(pg, selector: str) -> str:
    return str(pg.locator(selector).text_content() or "")


def metres(pg, selector: str) -> float:
    return float(text(pg, selector).split()[0])


def shot(pg, name: str) -> None:
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    pg.screenshot(path=str(SCREENSHOTS / name), full_page=True)


def test_pilot_and_winch_operator_on_one_console(browser, crew_server: RunningServer) -> None:
    server = crew_server
    pilot = open_station(browser, server, "/pilot", "Pia", server.token, "#fly")
    winch = open_station(browser, server, "/winch", "Wanda", WINCH, "#connect")
    wait_for(lambda: text(winch, "#tension") not in ("", "-"), 10.0, "the tension shown")
    height0, tension0 = metres(winch, "#height"), text(winch, "#tension")
    # the pilot takes over by hand (the ROV in the pilot's hands, the tree on the wire)
    pilot.locator("#side").click(position={"x": 5, "y": 5})
    pilot.keyboard.press("p")
    wait_for(lambda: text(pilot, "#mode") == "PILOT (by hand)", 10.0, "pilot mode")
    # the winch operator pays out 1 m at 0.5 m/s
    winch.fill("#rate", "0.5")
    winch.fill("#distance", "1")
    winch.click("#payout-btn")
    tensions = {tension0}

    def lowered() -> bool:
        tensions.add(text(winch, "#tension"))
        return metres(winch, "#height") < height0 - 0.9 and text(winch, "#moving") == "stopped"

    wait_for(lowered, 15.0, "the tree lowered by 1 m on the winch page")
    assert len(tensions) > 1, "the tension shown follows the wire"
    shot(winch, "crew-winch-page.png")
    # the instructor's faults reach whoever answers them
    with httpx.Client(
        base_url=server.base_url, headers={"Authorization": f"Bearer {INSTRUCTOR}"}
    ) as instructor:
        slip = {"kind": "winch_slip", "duration_s": 1, "value": 0.5}
        assert instructor.post("/api/faults", json=slip).status_code == 200
        lost = {"kind": "thruster_lost", "duration_s": 60, "thruster": 2}
        assert instructor.post("/api/faults", json=lost).status_code == 200
        wait_for(lambda: winch.locator("#slip").is_visible(), 10.0, "the slip on the winch page")
        assert "the payout jumped +0.50 m" in text(winch, "#slip")
        wait_for(lambda: "T2 gives 0 %" in text(pilot, "#thrusters"), 10.0, "lost thruster")
        shot(winch, "crew-winch-slip.png")
        shot(pilot, "crew-pilot-thruster-lost.png")
        instructor.delete("/api/faults")
    # the supervisor watches, pauses and resumes; the log names both stations
    boss = open_station(browser, server, "/supervisor", "Sam", SUPERVISOR, "#connect")
    wait_for(lambda: text(boss, "#winch") == "Wanda", 10.0, "the crew on the supervisor page")
    assert text(boss, "#pilot") == "Pia"
    boss.click("#pause")
    wait_for(lambda: text(boss, "#run") == "PAUSED", 10.0, "paused")
    ops = text(boss, "#ops")
    assert "winch (Wanda)" in ops and "pilot (Pia)" in ops and "supervisor (Sam)" in ops
    assert "fault" not in ops  # the instructor's own commands stay with the instructor
    shot(boss, "crew-supervisor-page.png")
    boss.click("#resume")
    wait_for(lambda: text(boss, "#run").startswith("running"), 10.0, "resumed")
    log = httpx.get(f"{server.base_url}/api/operations").json()
    who = {op["who"] for op in log}
    assert {"winch (Wanda)", "pilot (Pia)", "supervisor (Sam)"} <= who
