"""Issue 44's ``vessel = "advise"`` in the console: the dock leg's advice to move the vessel
is in the snapshot and the API's state while the leg waits for it, the operator applies it
(``ApplyVesselAdvice``, a ``MoveVessel`` to the advised crane tip), the vessel goes there and
the tree lands; applying when there is nothing to apply is refused, saying why.

The mission is ``tests/test_vessel_assist.py``'s weak-current case (0.1 m/s, the frame 4.6 m
from the crane tip, which the ROV alone cannot hold the tree over) with shorter waits."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import httpx
import pytest

from app.api.pilot import snapshot_status
from app.console import (
    ConsoleError,
    LoopStats,
    Session,
    VesselAdvice,
    prepare_run,
)
from app.console import commands as cmd
from app.console.crew import supervisor_status
from app.recording import load_session
from app.server import RunningServer
from missions import assist, landing_study, schema
from tests.browser import wait_for

WEAK_ADVISE = landing_study.Case("full", 1, 0.1, 229.3, -82.9, 4.6, 14.8, "advise")
"""``tests/test_vessel_assist.py``'s ``WEAK``, the dock leg advising the operator."""
STATS = LoopStats(0.01, 0.0, 0.0, 0, 0, 0.0)


def advise_mission(name: str = "advise-the-vessel", then_hold: bool = False) -> schema.Mission:
    """The weak-current case with a 15 s hold before the dock leg (the observer has
    converged by then: the advice is the same 4.9 m, the landing as good) and 5 s of settling
    after it: 262 s in all once the vessel is moved. ``then_hold``: a short hold leg after
    the landing."""
    data = landing_study.case_mission(WEAK_ADVISE).model_dump(mode="json")
    data["name"] = name
    data["legs"][0]["duration_s"] = 15.0
    data["legs"][1]["settle_s"] = 5.0
    if then_hold:
        data["legs"].append({"type": "hold", "name": "after", "duration_s": 5.0})
    return schema.parse_mission(data)


def advice_of(session: Session) -> VesselAdvice | None:
    return session.snapshot(1, False, 1.0, STATS).mission.vessel_advice


def stations_line(session: Session) -> object:
    """The advice as the supervisor's station shows it, which the pilot page shows too."""
    snap = session.snapshot(1, False, 1.0, STATS)
    line = supervisor_status(snap, {"pilot": None, "winch": None})["vessel_advice"]
    assert snapshot_status(snap, {})["vessel_advice"] == line, "the pilot's line is the same"
    return line


def _advance_until(session: Session, done: Callable[[], bool], limit_s: float) -> None:
    for _ in range(int(limit_s / 1.0)):
        if done():
            return
        session.advance(100)
    raise AssertionError(f"not done within {limit_s} s of the run")


def test_advice_is_shown_applied_and_followed_until_the_leg_moves_on(tmp_path: Path) -> None:
    session = Session(prepare_run(advise_mission(then_hold=True)), tmp_path)
    loop = SimpleNamespace(session=session)  # what the commands change (``LoopControls``)
    try:
        name = session.start_recording("advice")
        with pytest.raises(ConsoleError, match="the running leg has given none"):
            cmd.ApplyVesselAdvice().apply(loop)  # type: ignore[arg-type]

        def advice() -> VesselAdvice:
            given = advice_of(session)
            assert given is not None
            return given

        _advance_until(session, lambda: advice_of(session) is not None, 60.0)
        given = advice()
        assert given.text.startswith("move the vessel 4.9 m towards 016 deg (crane tip to ")
        assert given.distance_m == pytest.approx(4.9, abs=0.05)
        assert given.bearing_deg == pytest.approx(16.0, abs=1.0)
        assert given.t_s == pytest.approx(15.0, abs=1.0)
        assert not given.applied and given.to_go_m == pytest.approx(given.distance_m, abs=0.01)
        session.advance(1000)  # the leg waits for the operator: the advice stays
        assert advice() == given
        assert stations_line(session) == f"Advice given at 15 s: {given.text}"

        session.actor = "viewer 1 (Vera)"
        answer = cmd.ApplyVesselAdvice().apply(loop)  # type: ignore[arg-type]
        session.actor = None
        north, east = given.crane_tip_ne_m
        assert answer == {
            "north_m": north,
            "east_m": east,
            "speed_mps": assist.VESSEL_SPEED_MPS,
            "advice": given.text,
            "advice_t_s": given.t_s,
        }
        assert list(session.sim.crane_target_n[0:2]) == [north, east]
        assert advice().applied
        with pytest.raises(
            ConsoleError, match="at 15 s is applied already: the vessel is commanded"
        ):
            cmd.ApplyVesselAdvice().apply(loop)  # type: ignore[arg-type]
        session.advance(500)  # 5 s at 0.2 m/s
        assert advice().applied and advice().to_go_m == pytest.approx(given.distance_m - 1.0, 0.05)
        assert stations_line(session) == (
            f"Advice applied (given at 15 s): the vessel is on its way, {advice().to_go_m:.1f} m"
            " to go"
        )

        driver = session.driver
        assert driver is not None
        _advance_until(session, lambda: driver.leg_index == 2, 400.0)
        assert session.mission_status.state == "running", "leg 3 runs"
        assert advice_of(session) is None, "the advice went with its leg"
        assert stations_line(session) is None
        assert driver.ctx.landings[0].success
        _advance_until(session, lambda: session.mission_status.state != "running", 10.0)
        assert session.mission_status.state == "completed"
        with pytest.raises(ConsoleError, match="no vessel advice to apply: no mission is running"):
            cmd.ApplyVesselAdvice().apply(loop)  # type: ignore[arg-type]
        session.stop_recording()
    finally:
        session.close()
    events = load_session(tmp_path / name).events
    (advised,) = [e for e in events if e["kind"] == "vessel"]
    assert advised["text"] == given.text
    (moved,) = [e for e in events if e["kind"] == "command" and e["text"] == "vessel"]
    assert moved["data"] == {
        "north_m": north,
        "east_m": east,
        "speed_mps": assist.VESSEL_SPEED_MPS,
        "who": "viewer 1 (Vera)",
    }


def test_a_newer_advice_replaces_the_one_before(tmp_path: Path) -> None:
    """The dock leg's outer loop advises again when the current has changed (here its event,
    as ``missions.legs._send_vessel`` writes it): the console shows the newer one."""
    session = Session(prepare_run(advise_mission()), tmp_path)
    try:
        driver = session.driver
        assert driver is not None
        _advance_until(session, lambda: advice_of(session) is not None, 60.0)
        data = {"distance_m": 1.5, "bearing_deg": 180.0, "crane_tip_ne_m": [4.0, 2.0]}
        text = "in 0.500 m/s towards 0 deg now: move the vessel 1.5 m towards 180 deg"
        driver.ctx.event("vessel", text, **data, utilisation=0.01, mode="advise")
        driver.ctx.event("vessel", "moving the vessel", **data, utilisation=0.01, mode="auto")
        session.advance(1)
        newer = advice_of(session)
        assert newer is not None
        assert (newer.text, newer.crane_tip_ne_m, newer.bearing_deg) == (text, (4.0, 2.0), 180.0)
    finally:
        session.close()


def test_the_pages_words_for_the_advice() -> None:
    from web.tabs.advice import advice_markdown

    given = VesselAdvice("move the vessel 4.9 m towards 016 deg", (5.675, 2.348), 15.0, 4.9, 16.0)
    assert advice_markdown(None, True) == ""
    assert advice_markdown(given, True) == (
        "**Advice** given at 15 s: move the vessel 4\\.9 m towards 016 deg"
    )
    assert advice_markdown(given, False).endswith(
        "(locked: enter the console token under Access to apply it)"
    )
    moving = replace(given, applied=True, to_go_m=3.04)
    assert advice_markdown(moving, False) == (
        "**Advice applied** \\(given at 15 s\\): the vessel is on its way, 3\\.0 m to go"
    )
    assert advice_markdown(replace(moving, to_go_m=0.01), True).endswith("the vessel is there")


# ---------------------------------------------------------------------- the HTTP API
APPLY = "/api/environment/vessel/apply-advice"


def test_the_api_shows_the_advice_and_applies_it_once(
    server: RunningServer, api: httpx.Client
) -> None:
    """On a console server (``tests/browser.py``'s; ``api`` sends its token)."""
    mission = advise_mission("advise-over-http").model_dump(mode="json")
    up = api.post("/api/missions/uploads", json={"mission": mission})
    assert up.status_code == 201, up.text
    assert httpx.post(f"{server.base_url}{APPLY}").status_code == 401
    r = api.post(APPLY)
    assert r.status_code == 409 and "no mission is running" in r.json()["detail"]
    assert api.post("/api/missions/start", json={"name": "advise-over-http"}).is_success
    assert api.put("/api/run/speed", json={"speed": 50.0}).is_success

    def state() -> dict:
        return api.get("/api/state").json()

    wait_for(lambda: state()["mission"]["vessel_advice"] is not None, 30.0, "the advice")
    advice = state()["mission"]["vessel_advice"]
    assert advice["text"].startswith("move the vessel 4.9 m towards 016 deg")
    assert advice["applied"] is False
    assert api.get("/api/missions/current").json()["vessel_advice"]["text"] == advice["text"]
    r = api.post(APPLY)
    assert r.status_code == 200, r.text
    assert r.json()["result"]["north_m"] == advice["crane_tip_ne_m"][0]
    again = api.post(APPLY)
    assert again.status_code == 409 and "applied already" in again.json()["detail"]
    assert state()["mission"]["vessel_advice"]["applied"] is True
    ops = [(o["action"], o["outcome"][:7]) for o in api.get("/api/operations").json()]
    assert ops[-2:] == [("apply vessel advice", "done"), ("apply vessel advice", "refused")]
    wait_for(
        lambda: state()["mission"]["vessel_advice"]["to_go_m"] < advice["distance_m"] - 1.0,
        10.0,
        "the vessel on its way",
    )
    assert api.post("/api/missions/abort").is_success  # (it lands: the test above)
    final = state()["mission"]
    assert final["state"] == "aborted" and final["vessel_advice"] is None
    api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()
