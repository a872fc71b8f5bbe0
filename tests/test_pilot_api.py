"""The pilot page's server side (FastAPI's TestClient, no browser): sign-in, the pilot's
commands with their checks, the watchdog that zeroes the stick, one pilot at a time."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from app.api.pilot import newest_stick_wins
from app.console import ConsoleSettings
from app.console.operations import trainee_of
from app.console.pilot import DEMAND_TIMEOUT_S, PilotDemand, PilotHolds, PilotTakeOver
from app.server import create_app

TOKEN = "pilot-test-token-0123456789"
URL = "ws://127.0.0.1/api/pilot"


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    settings = ConsoleSettings(
        view=False, token=TOKEN, recordings_dir=tmp_path_factory.mktemp("recordings")
    )
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        yield c


def sim_of(client: TestClient):
    return client.app.state.console.loop.session.sim  # type: ignore[attr-defined]


def until(ws, predicate, what: str, limit: int = 100) -> dict:
    """Read messages until one satisfies ``predicate``."""
    m: dict = {}
    for _ in range(limit):
        m = ws.receive_json()
        if predicate(m):
            return m
    # the last message says what the page was told instead (mode, demand, an error)
    raise AssertionError(f"no message with {what} in {limit}; the last: {m}")


def test_the_page_is_served_self_contained(client: TestClient) -> None:
    page = client.get("/pilot")
    assert page.status_code == 200
    assert "<script src" not in page.text and "https://" not in page.text  # nothing fetched
    assert "/api/pilot" in page.text and "getGamepads" in page.text
    assert "3D view is off" in page.text and 'Number("0")' in page.text  # view=False here


def test_wrong_token_is_refused_with_a_message(client: TestClient) -> None:
    with client.websocket_connect(URL) as ws:
        ws.send_json({"type": "hello", "token": "not-the-token-at-all", "name": "Eve"})
        m = ws.receive_json()
    assert m == {
        "type": "error",
        "message": "wrong token: flying needs the console token (printed at start-up)",
    }
    assert client.app.state.pilot_name is None  # type: ignore[attr-defined]


def test_bad_name_is_refused_by_field(client: TestClient) -> None:
    with client.websocket_connect(URL) as ws:
        ws.send_json({"type": "hello", "token": TOKEN, "name": "   "})
        assert "pilot name must be 1 to 40 printable characters" in ws.receive_json()["message"]


def test_fly_by_socket_and_the_stick_is_zeroed_when_the_page_falls_silent(
    client: TestClient,
) -> None:
    with client.websocket_connect(URL) as ws:
        ws.send_json({"type": "hello", "token": TOKEN, "name": "Anna"})
        assert ws.receive_json()["type"] == "welcome"
        # a second page is refused while Anna flies
        with client.websocket_connect(URL) as other:
            other.send_json({"type": "hello", "token": TOKEN, "name": "Bob"})
            assert other.receive_json()["message"] == "Anna is flying: one pilot at a time"
        ws.send_json({"type": "mode", "pilot": True})
        until(ws, lambda m: m.get("status", {}).get("mode") == "manual", "manual mode")
        ws.send_json({"type": "demand", "surge": 0.3, "sway": 0.0, "heave": 0.0, "yaw": -0.2})
        m = until(ws, lambda m: m.get("status", {}).get("demand", {}).get("surge") == 0.3, "ack")
        assert m["status"]["demand"]["yaw"] == pytest.approx(-0.2)
        # out of range: refused by name, the stick stays as it was
        ws.send_json({"type": "demand", "surge": 2.0, "sway": 0.0, "heave": 0.0, "yaw": 0.0})
        m = until(ws, lambda m: m["type"] == "error", "an error")
        assert m["message"] == "pilot surge must be in [-1, 1], got 2"
        ws.send_json({"type": "holds", "heading": "yes", "depth": True})
        assert until(ws, lambda m: m["type"] == "error", "an error")["message"] == (
            "heading hold must be true or false"
        )
        assert sim_of(client).pilot_demand[0] == pytest.approx(0.3)
        # silence: the status messages keep coming, the stick goes to zero
        start = time.monotonic()
        until(ws, lambda m: m.get("status", {}).get("demand", {}).get("surge") == 0.0, "zero")
        waited = time.monotonic() - start
        assert DEMAND_TIMEOUT_S * 0.9 < waited < DEMAND_TIMEOUT_S + 2.0
        assert list(sim_of(client).pilot_demand) == [0.0, 0.0, 0.0, 0.0]
        ws.send_json({"type": "demand", "surge": 0.0, "sway": 0.0, "heave": 0.0, "yaw": 1.0})
        until(ws, lambda m: m.get("status", {}).get("demand", {}).get("yaw") == 1.0, "yaw")
        time.sleep(1.0)  # the tree turns under the ROV
        ws.send_json({"type": "mode", "pilot": False})
        until(ws, lambda m: m.get("status", {}).get("mode") == "tree", "back on the autopilot")
        # the autopilot holds the tree where the pilot left it, not at the old target
        sim = sim_of(client)
        assert abs(sim.target[2] - sim.eta_estimate[2]) < 0.05
        assert abs(sim.target[2]) > 0.01
    ops = client.app.state.console.loop.snapshot.operations  # type: ignore[attr-defined]
    mine = [(o.who, o.action) for o in ops if trainee_of(o.who) == "Anna"]
    assert ("pilot (Anna)", "pilot take over: pilot on") in mine
    assert ("pilot (Anna)", "pilot disconnected: reason no input for 0.5 s") in mine
    assert not any(a.startswith("pilot demand") for _, a in mine)  # the stick is not logged
    time.sleep(0.3)
    assert client.app.state.pilot_name is None  # type: ignore[attr-defined]


def test_the_newest_stick_wins_holds_and_take_overs_are_kept() -> None:
    stick = [PilotDemand(v, 0.0, 0.0, 0.0) for v in (0.1, 0.2, 0.3)]
    holds, take = PilotHolds(True, False), PilotTakeOver(True)
    assert newest_stick_wins([stick[0], holds, stick[1], take, stick[2]]) == [
        holds,
        take,
        stick[2],
    ]
    assert newest_stick_wins([holds, take]) == [holds, take]
    assert newest_stick_wins([]) == []


def test_a_zero_stick_after_a_burst_is_applied_next_and_no_stale_stick_after_it(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Issue 47 item 10: sticks at 400 Hz for 5 s, then let go. Each stick waited for its own
    tick, so the zero came 20 s later with full thrust meanwhile. Now the sticks that
    arrived since the last tick give way to the newest: the zero is applied straight after
    the burst has been read and no stick of the burst is applied after it."""
    loop = client.app.state.console.loop  # type: ignore[attr-defined]
    submitted: list[object] = []
    submit = loop.submit

    def spy(command, who=None):
        submitted.append(command)
        return submit(command, who)

    monkeypatch.setattr(loop, "submit", spy)
    burst = 2000
    with client.websocket_connect(URL) as ws:
        ws.send_json({"type": "hello", "token": TOKEN, "name": "Anna"})
        assert ws.receive_json()["type"] == "welcome"
        ws.send_json({"type": "mode", "pilot": True})
        until(ws, lambda m: m.get("status", {}).get("mode") == "manual", "manual mode")
        full = {"type": "demand", "surge": 1.0, "sway": 0.0, "heave": 0.0, "yaw": 0.0}
        for _ in range(burst):
            ws.send_json(full)
        ws.send_json({**full, "surge": 0.0})
        until(
            ws,
            lambda m: m.get("status", {}).get("demand", {}).get("surge") == 0.0,
            "the zero stick",
            limit=5 * burst,
        )
        sticks = [c for c in submitted if isinstance(c, PilotDemand)]
        assert sticks[-1].surge == 0.0
        assert len(sticks) < burst / 10, f"{len(sticks)} of {burst + 1} sticks were queued"
        assert sim_of(client).pilot_demand[0] == 0.0
        ws.send_json({"type": "mode", "pilot": False})
        until(ws, lambda m: m.get("status", {}).get("mode") == "tree", "back on the autopilot")


def test_take_over_is_refused_while_a_mission_runs_its_legs(client: TestClient) -> None:
    auth = {"Authorization": f"Bearer {TOKEN}"}
    r = client.post("/api/missions/start", json={"name": "full-square-100"}, headers=auth)
    assert r.status_code == 200, r.text
    try:
        with client.websocket_connect(URL) as ws:
            ws.send_json({"type": "hello", "token": TOKEN, "name": "Anna"})
            ws.receive_json()
            ws.send_json({"type": "mode", "pilot": True})
            m = until(ws, lambda m: m["type"] == "error", "an error")
        assert m["message"] == ("pilot: mission 'full-square-100' is running; abort it first")
        assert sim_of(client).mode != "manual"
    finally:
        client.post("/api/missions/abort", headers=auth)
