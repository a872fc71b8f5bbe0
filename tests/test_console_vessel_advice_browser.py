"""Issue 44's ``vessel = "advise"`` in a real headless Chromium: a dock leg's advice to move
the vessel shows in the Mission tab (a locked page saying the token applies it), and the
vessel form shows the advised crane tip; "Apply advice", clicked twice, moves the vessel once
and the page shows it on its way; the advice goes when the mission ends. The supervisor's
station and the pilot page (other tabs) show the advice as it goes. The page with the
advice is saved as ``console-vessel-advice.png``, the supervisor's and the pilot's pages with
the advice applied as ``crew-supervisor-advice.png`` and ``pilot-advice.png`` (the pilot
page's own panel; its embedded view is the console's), in ``tests/browser.py``'s folder. (A second
browser and a reload: each is a panel made from the state as it is then, as every page is;
they were tried by hand.)"""

from __future__ import annotations

import time

import httpx
import pytest

from app.server import RunningServer
from tests.browser import (
    FRAME_EVERY_MS,
    choose,
    click,
    field,
    save,
    tab,
    unlock,
    wait_for,
)
from tests.test_console_vessel_advice import advise_mission

MISSION = "advise-in-the-page"


@pytest.fixture(scope="module")
def uploaded(api: httpx.Client) -> str:
    """The advising mission, uploaded before the page opens (its Mission list is made then)."""
    mission = advise_mission(MISSION).model_dump(mode="json")
    api.post("/api/missions/uploads", json={"mission": mission}).raise_for_status()
    return MISSION


def advice_text(pg) -> str:
    """The Mission tab's advice line, as the page shows it."""
    lines = pg.locator("xpath=//p[starts-with(normalize-space(.), 'Advice')]").filter(visible=True)
    texts = lines.all_inner_texts()  # no wait: the line may go between two looks
    return " ".join(texts[0].split()) if texts else ""


def station_advice(pg) -> str:
    """The vessel advice on the supervisor's or the pilot's page ('' while its row is
    hidden)."""
    row = pg.locator("#advice-row")
    return " ".join(str(pg.locator("#advice").text_content()).split()) if row.is_visible() else ""


def open_station(page, server: RunningServer, path: str, name: str, connect: str):
    """A station's page (``/supervisor``, ``/pilot``) in a new tab, signed in as ``name`` with
    the console token."""
    station = page.context.new_page()
    station.goto(f"{server.base_url}{path}")
    station.fill("#name", name)
    station.fill("#token", server.token)
    station.click(connect)
    return station


def _stations_show(stations: dict, start: str, what: str) -> None:
    """Wait until each station's advice starts with ``start`` ('': its row hidden)."""
    for whose, station in stations.items():
        wait_for(
            lambda station=station: (
                station_advice(station).startswith(start)
                if start
                else station_advice(station) == ""
            ),
            15.0,
            f"{what} on the {whose} page",
        )


def apply_button(pg):
    """The shown tab's "Apply advice" (the Mission tab and the Control tab have one each)."""
    return pg.locator("xpath=//button[normalize-space(.)='Apply advice']").filter(visible=True)


def test_the_advice_shown_and_applied_once(
    uploaded: str, page, server: RunningServer, api: httpx.Client
) -> None:
    unlock(page, server.token)
    tab(page, "Mission")
    choose(page, "Mission", uploaded)
    click(page, "Start mission")
    api.put("/api/run/speed", json={"speed": 50.0}).raise_for_status()
    _advice_in_the_page(page, server, api)
    boss = open_station(page, server, "/supervisor", "Sam", "#connect")
    pilot = open_station(page, server, "/pilot", "Pia", "#fly")
    stations = {"supervisor's": boss, "pilot's": pilot}
    _stations_show(stations, "Advice given at 15 s: move the vessel 4.9 m", "the advice")
    page.bring_to_front()

    apply = apply_button(page)
    apply.click(click_count=2)  # a double click: one move, the second refused
    applied = "Advice applied (given at 15 s): the vessel is on its way"
    wait_for(lambda: advice_text(page).startswith(applied), 10.0, "the advice applied")
    assert apply.count() == 0
    applies = [o for o in api.get("/api/operations").json() if o["action"] == "apply vessel advice"]
    assert [o["outcome"] for o in applies][:1] == ["done"]
    assert all("applied already" in o["outcome"] for o in applies[1:]), applies
    moving = api.get("/api/state").json()["mission"]["vessel_advice"]
    assert moving["applied"] and 0.0 < moving["to_go_m"] < moving["distance_m"]
    _stations_show(stations, applied, "the advice applied")
    save(boss.screenshot(), "crew-supervisor-advice.png")
    save(pilot.locator("#side").screenshot(), "pilot-advice.png")  # its panel

    # it lands then (tests/test_console_vessel_advice.py); here the mission is aborted, and
    # the advice goes with it
    api.post("/api/missions/abort").raise_for_status()
    wait_for(lambda: advice_text(page) == "", 10.0, "the advice gone with the mission")
    assert apply_button(page).count() == 0
    _stations_show(stations, "", "no advice row")
    boss.close()
    pilot.close()


def _advice_in_the_page(page, server: RunningServer, api: httpx.Client) -> None:
    """The advice in the Mission tab with its button (disabled, and the line saying why,
    while the page is locked), and its crane tip in the Control tab's vessel form."""
    wait_for(
        lambda: api.get("/api/state").json()["mission"]["vessel_advice"] is not None,
        30.0,
        "the advice",
    )
    api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()  # time to read it
    advice = api.get("/api/state").json()["mission"]["vessel_advice"]
    wait_for(
        lambda: advice_text(page).startswith("Advice given at 15 s: move the vessel 4.9 m"),
        20.0,
        "the advice in the Mission tab",
    )
    apply = apply_button(page)
    assert apply.count() == 1 and apply.is_enabled()
    apply.scroll_into_view_if_needed()
    # for the picture, the scene drawn with the mission's current (its label is drawn in the
    # canvas: read the scene's own) and a frame after
    scene = server.app.state.view.scene
    wait_for(lambda: scene._current_label.text.startswith("current "), 10.0, "the current")
    time.sleep(1.5 * FRAME_EVERY_MS / 1000.0)
    save(page.screenshot(), "console-vessel-advice.png")
    click(page, "Lock controls")
    wait_for(
        lambda: advice_text(page).endswith(
            "(locked: enter the console token under Access to apply it)"
        ),
        10.0,
        "the advice saying the page is locked",
    )
    assert not apply.is_enabled()
    unlock(page, server.token)
    tab(page, "Control")
    north, east = (round(v, 2) for v in advice["crane_tip_ne_m"])
    wait_for(
        lambda: float(field(page, "North m").input_value()) == north,
        10.0,
        "the advised north in the vessel form",
    )
    assert float(field(page, "East m").input_value()) == east
    assert apply_button(page).count() == 1, "the vessel form's own"
    tab(page, "Mission")
