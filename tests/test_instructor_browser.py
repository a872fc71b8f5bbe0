"""The instructor's panel in a real headless Chromium: the instructor unlocks it with the
instructor token, injects a compass bias now and sees it listed; a trainee's page, watching
the same session, does not see the injection in its operations log (only its own commands).
Fixtures from ``tests/browser.py``, with a server that has an instructor token."""

from __future__ import annotations

import time
from collections.abc import Iterator

import httpx
import pytest

from app.console import ConsoleSettings
from app.server import RunningServer, serve_in_thread
from tests.browser import button, choose, click, field, open_console, save, tab, wait_for

INSTRUCTOR = "browser-instructor-1"


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningServer]:
    settings = ConsoleSettings(
        port=0,
        viser_port=0,
        instructor_token=INSTRUCTOR,
        recordings_dir=tmp_path_factory.mktemp("recordings"),
    )
    with serve_in_thread(settings) as srv:
        yield srv


def test_instructor_injects_a_compass_bias_and_a_trainee_does_not_see_it(
    page, server: RunningServer, api
) -> None:
    tab(page, "Instructor")
    assert button(page, "Inject fault").is_disabled(), "locked until the instructor token"
    field(page, "Instructor token").fill(server.token)
    time.sleep(0.2)  # viser sends an input's value at most every 50 ms
    click(page, "Unlock instructor")
    page.get_by_text("that is the console token").wait_for(timeout=10_000)
    field(page, "Instructor token").fill(INSTRUCTOR)
    time.sleep(0.2)
    click(page, "Unlock instructor")
    page.get_by_text("instructor unlocked").wait_for(timeout=10_000)
    assert button(page, "Pause").is_disabled(), "the instructor token does not open the run"

    choose(page, "Fault kind", "compass_bias")
    page.get_by_text("value in [-180, 180] deg").wait_for(timeout=10_000)
    field(page, "Fault value").fill("15")
    field(page, "Fault duration s").fill("300")
    time.sleep(0.3)
    click(page, "Inject fault")
    page.get_by_text("active: compass bias 15 deg", exact=False).first.wait_for(timeout=15_000)
    faults = server.console.loop.snapshot.faults
    assert [(f.kind, f.value, f.state) for f in faults] == [("compass_bias", 15.0, "active")]
    save(page.screenshot(), "console-instructor.png")

    assert api.put("/api/run/speed", json={"speed": 2.0}).is_success  # the trainee acts
    trainee = page.context.new_page()
    try:
        open_console(trainee, server.view_url)
        trainee.get_by_text("Operations log").first.click()
        trainee.get_by_text("set speed: speed 2").first.wait_for(timeout=15_000)
        html = trainee.content()
        assert "inject fault" not in html and "compass bias" not in html
        tab(trainee, "Instructor")
        assert button(trainee, "Inject fault").is_disabled()
    finally:
        trainee.close()
    wait_for(lambda: server.app.state.view.clients == 1, 10.0, "the trainee's page to leave")
    click(page, "Clear faults")
    page.get_by_text("cleared 1 fault(s)").wait_for(timeout=10_000)
    assert server.console.loop.snapshot.faults == ()


def test_the_scores_tab_shows_the_pilots_runs_with_a_debrief_link(page, server: RunningServer):
    from app import scores
    from app.console import SCORES_DB
    from missions.scoring import LandingResult, MissionResult

    landing = LandingResult(True, 0.07, 1.0, 0.02, "frame", 40.0)
    result = MissionResult(
        "dock-drill", [], 0.01, 0.02, 0.5, 0.4, 0.0, None, [0.0] * 6, False, [], {}, [landing]
    )
    scores.record(
        server.settings.recordings_dir / SCORES_DB, "Anna", result, "console", "drill.mcap"
    )
    field(page, "Your name").fill("Anna")
    time.sleep(0.3)
    tab(page, "Scores")
    click(page, "Show my scores")
    page.get_by_text("latest runs of Anna").wait_for(timeout=10_000)
    link = page.locator("a", has_text="report").first
    href = link.get_attribute("href") or ""
    # this browser is unlocked (the instructor's tab): the link carries the debrief ticket,
    # which the report asks for as it would a token (no such recording here: 404, not 401)
    plain = f"{server.base_url}/api/recordings/drill.mcap/report"
    assert href.startswith(f"{plain}?ticket=")
    assert httpx.get(href, timeout=10.0).status_code == 404
    assert httpx.get(plain, timeout=10.0).status_code == 401
    assert page.get_by_text("dock-drill").count() >= 2, "in the latest runs and the best"


def thruster_state(pg, number: int) -> str:
    """What the page's *Thrusters* panel says of thruster ``number`` ('on' or 'killed')."""
    row = pg.locator(f"[data-thruster='{number}']").first
    return str(row.get_attribute("data-state"))


def test_a_replay_shows_the_thruster_the_instructor_killed(
    page, server: RunningServer, api
) -> None:
    """Left open since issue 47's wave: a replay showed every thruster on, faults being
    events of the recording and not its state. T2 lost while recording: the replay of that
    recording reads it killed, the live run (its faults cleared) all on."""
    instructor = {"Authorization": f"Bearer {INSTRUCTOR}"}
    name = api.post("/api/recordings/start", json={"label": "t2-lost"}).json()["name"]
    lost = {"kind": "thruster_lost", "duration_s": 600.0, "thruster": 2}
    api.post("/api/faults", json=lost, headers=instructor).raise_for_status()
    wait_for(lambda: thruster_state(page, 2) == "killed", 15.0, "T2 killed, live")
    t0 = api.get("/api/state").json()["t_s"]
    wait_for(lambda: api.get("/api/state").json()["t_s"] > t0 + 2.0, 30.0, "2 s of the run")
    api.post("/api/recordings/stop").raise_for_status()
    api.delete("/api/faults", headers=instructor).raise_for_status()
    wait_for(lambda: thruster_state(page, 2) == "on", 15.0, "T2 on again, live")

    tab(page, "Record")
    click(page, "Refresh list")
    choose(page, "Recording", name)
    click(page, "Open replay")
    page.get_by_text(f"REPLAY {name}").first.wait_for(timeout=30_000)
    assert thruster_state(page, 2) == "on", "at the recording's start, before the fault"
    click(page, "Play replay")
    wait_for(lambda: thruster_state(page, 2) == "killed", 15.0, "T2 killed in the replay")
    assert thruster_state(page, 1) == "on"
    page.locator("[data-thruster='2']").first.scroll_into_view_if_needed()
    save(page.screenshot(), "console-replay-thruster-lost.png")
    click(page, "Close replay")
    wait_for(lambda: thruster_state(page, 2) == "on", 15.0, "T2 on, live again")
