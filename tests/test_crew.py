"""The crew's stations (FastAPI's TestClient, no browser): the winch's typed commands and
their range checks, each station's token and what it may not do, the winch operator's
commands in the operations log, a winch slip shown to the winch station and a lost thruster
to the pilot, the supervisor's pause and nothing else, and the snap alarm."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
from fastapi.testclient import TestClient

from app.api.crew import parse_supervisor, parse_winch
from app.console import ConsoleSettings
from app.console.alarms import AlarmLimits, AlarmMonitor
from app.console.commands import HeaveCompensation, WinchHaulIn, WinchPayOut
from app.console.crew import SlipWatch
from app.console.operations import trainee_of
from app.server import create_app, crew_line
from control.columns import N_LOG, LogRows
from control.simulation import Simulation
from sim import environment as envmod
from sim import params
from sim import vessel as vm

TOKEN = "crew-console-token-0123456789"
WINCH = "winch-secret-42"
SUPERVISOR = "super-secret-42"
INSTRUCTOR = "teacher-secret-42"


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: WinchPayOut(0.0), "speed_mps must be in (0, 2] m/s, got 0"),
        (lambda: WinchHaulIn(2.5), "speed_mps must be in (0, 2] m/s, got 2.5"),
        (lambda: WinchPayOut(math.nan), "speed_mps must be finite, got nan"),
        (lambda: WinchPayOut(True), "speed_mps must be a number, got bool"),
        (lambda: WinchPayOut(0.2, -1.0), "distance_m must be in (0, 1000] m, got -1"),
        (lambda: WinchHaulIn(0.2, 5000.0), "distance_m must be in (0, 1000] m, got 5000"),
        (lambda: HeaveCompensation("yes"), "heave compensation 'on' must be true or false"),  # type: ignore[arg-type]
    ],
)
def test_winch_commands_name_the_field_and_its_range(make, message: str) -> None:
    with pytest.raises(ValueError) as err:
        make()
    assert str(err.value) == message


def test_station_messages_are_parsed_or_refused_by_name() -> None:
    assert parse_winch('{"type": "pay_out", "speed_mps": 0.3}') == WinchPayOut(0.3)
    assert parse_winch('{"type": "haul_in", "speed_mps": 0.1, "distance_m": 2}') == WinchHaulIn(
        0.1, 2
    )
    for text, message in [
        ('{"type": "pay_out"}', "speed_mps must be a number, got NoneType"),
        ('{"type": "pay_out", "speed_mps": 1, "rate": 2}', "not rate"),
        ('{"type": "fly"}', "message type must be pay_out, haul_in, stop or compensation"),
        ("[1]", "message must be a JSON object"),
    ]:
        with pytest.raises(ValueError, match=message):
            parse_winch(text)
    with pytest.raises(ValueError, match="the supervisor may pause and resume only"):
        parse_supervisor('{"type": "pay_out", "speed_mps": 0.3}')


def test_crew_tokens_are_checked_and_differ() -> None:
    with pytest.raises(ValueError, match="winch_token must have at least 8"):
        ConsoleSettings(winch_token="short")
    with pytest.raises(ValueError, match="instructor_token and supervisor_token must differ"):
        ConsoleSettings(instructor_token=INSTRUCTOR, supervisor_token=INSTRUCTOR)
    assert trainee_of("winch (Wanda)") == "Wanda" and trainee_of("supervisor (Sam)") == "Sam"
    both = ConsoleSettings(winch_token=WINCH, supervisor_token=SUPERVISOR)
    line = crew_line(both)
    assert (
        "winch and supervisor tokens set" in line and WINCH not in line and SUPERVISOR not in line
    )
    assert "console token" in crew_line(ConsoleSettings())


def test_slip_watch_tells_a_payout_jump_from_the_winch_running() -> None:
    w = SlipWatch()
    assert w.update(10.0, 100.0, 0.5) is None
    assert w.update(10.2, 100.1, 0.5) is None  # the winch's own travel
    text = w.update(10.4, 101.1, 0.5)
    assert text is not None and "jumped +1.00 m at 10.4 s" in text
    assert w.update(20.0, 101.1, 0.5) == text  # shown a while
    assert w.update(45.0, 101.1, 0.5) is None
    assert w.update(46.0, 102.1, 0.5) is not None
    assert w.update(0.0, 50.0, 0.5, run=2) is None  # a new run hangs the tree anew
    assert w.update(0.2, 50.0, 0.5, run=2) is None


def test_heave_compensation_fades_in_and_takes_most_of_the_heave_out() -> None:
    """Tree alone at 100 m under a vessel in a Hs 4 m, Tp 10 s head sea: the tree heaves with
    the crane tip; with the compensation on (80 %), a fifth of it is left. Switched on, it
    fades in over two peak periods: switched at once, the tip's heave stepped and the tree
    snapped on the wire (tension 0 to 3.3 W0 in the next 5 s; now 0.95 to 1.07 W0)."""
    waves = envmod.WaveParams(4.0, 10.0, 0.0, load="drag")
    motion = vm.VesselMotion(heading_rad=math.pi)
    sim = Simulation(
        params.load("full-scale"),
        tree_depth_m=100.0,
        has_rov=False,
        control=False,
        waves=waves,
        vessel=motion,
    )
    weight = float(sim.ps.tree.submerged_weight_newton)
    assert sim.heave_compensation is False
    sim.run_for(20.0)  # the vessel's ramp-in
    free = sim.run_for(30.0)
    sim.set_heave_compensation(True)
    fading = sim.run_for(20.0)["wire_tension"] / weight
    held = sim.run_for(30.0)
    assert sim.heave_compensation is True
    assert 0.85 < fading.min() and fading.max() < 1.15, "no slack, no snap while it fades in"
    # the tree heaves with the crane tip (the stiff wire), the tip by a fifth of its heave:
    # compared with the tip's own motion in the same seconds (the sea differs between them)
    north, east = float(sim.crane_tip_n[0]), float(sim.crane_tip_n[1])
    for rows, left in ((free, 1.0), (held, 0.2)):
        tip = vm.crane_tip_motion_n(sim.wave_field, rows.t_s, motion, north, east)[:, 2]
        heave = float(np.std(rows["tree_eta_n"][:, 2]))
        assert heave == pytest.approx(left * float(np.std(tip)), rel=0.1), (left, heave)
    calm = Simulation(params.load("full-scale"), tree_depth_m=100.0, has_rov=False, control=False)
    assert calm.heave_compensation is None
    with pytest.raises(ValueError, match="does not heave in this run"):
        calm.set_heave_compensation(True)


def test_compensation_ramp_goes_from_where_it_stands() -> None:
    ramp = vm.CompensationRamp(10.0, 0.0, 1.0, 20.0, 0.8)
    np.testing.assert_allclose(ramp.share([0.0, 10.0, 20.0, 30.0, 99.0]), [0, 0, 0.5, 1, 1])
    np.testing.assert_allclose(ramp.z_factor([10.0, 30.0]), [1.0, 0.2])


def test_snap_alarm_after_a_slack_wire_under_a_hanging_tree() -> None:
    limits = AlarmLimits(position_error_m=0.25, sample_period_s=(1.0,) * 5)
    m = AlarmMonitor(limits, 4, 300e3, uses_sensors=False)
    t = np.arange(1, 501) * 0.01
    rows = LogRows(np.zeros((len(t), N_LOG)), n_thrusters=4)
    rows["t_s"][:] = t
    rows["wire_tension"][:] = 300e3
    rows["wire_tension"][100:150] = 1e3  # slack for 0.5 s
    rows["wire_tension"][150:160] = 750e3  # and the jerk
    m.update(rows, 300e3)
    snap = next(a for a in m.state if a.name == "wire_snap")
    assert snap.active and "2.50 x the static tension" in snap.message
    later = LogRows(np.zeros((1500, N_LOG)), n_thrusters=4)
    later["t_s"][:] = 5.0 + np.arange(1, 1501) * 0.01
    later["wire_tension"][:] = 300e3
    m.update(later, 300e3)
    assert not next(a for a in m.state if a.name == "wire_snap").active


# ---------------------------------------------------------------------- the server
@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    settings = ConsoleSettings(
        view=False,
        token=TOKEN,
        instructor_token=INSTRUCTOR,
        winch_token=WINCH,
        supervisor_token=SUPERVISOR,
        recordings_dir=tmp_path_factory.mktemp("recordings"),
    )
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        yield c


def until(ws, predicate, what: str, limit: int = 100) -> dict:
    m: dict = {}
    for _ in range(limit):
        m = ws.receive_json()
        if predicate(m):
            return m
    raise AssertionError(f"no message with {what} in {limit}; the last: {m}")


def sign_in(client: TestClient, station: str, token: str | None, name: str = "Wanda") -> dict:
    with client.websocket_connect(f"ws://127.0.0.1/api/{station}") as ws:
        ws.send_json({"type": "hello", "token": token, "name": name})
        return ws.receive_json()


def test_the_pages_are_served_self_contained(client: TestClient) -> None:
    for path, socket in (("/winch", "/api/winch"), ("/supervisor", "/api/supervisor")):
        page = client.get(path)
        assert page.status_code == 200 and socket in page.text
        assert "<script src" not in page.text and "https://" not in page.text
        assert "default-src 'self'" in page.headers["content-security-policy"]


@pytest.mark.parametrize(
    ("station", "token", "message"),
    [
        ("winch", None, "wrong token: the winch page needs the winch token or the console token"),
        ("winch", "not-a-token-at-all", "wrong token: the winch page needs the winch token"),
        ("winch", SUPERVISOR, "that token opens another station"),
        ("winch", INSTRUCTOR, "that token opens another station"),
        ("supervisor", WINCH, "that token opens another station"),
        ("supervisor", "", "wrong token: the supervisor page needs the supervisor token"),
    ],
)
def test_each_station_needs_its_own_token(
    client: TestClient, station: str, token: str | None, message: str
) -> None:
    m = sign_in(client, station, token)
    assert m["type"] == "error" and message in m["message"]


def test_crew_tokens_open_their_stations_and_nothing_else(client: TestClient) -> None:
    assert sign_in(client, "winch", WINCH)["type"] == "welcome"
    assert sign_in(client, "winch", TOKEN)["type"] == "welcome"  # the console token too
    assert sign_in(client, "supervisor", SUPERVISOR)["role"] == "supervisor"
    # the winch token cannot fly the ROV, nor change the run over HTTP
    m = sign_in(client, "pilot", WINCH)
    assert m == {
        "type": "error",
        "message": "wrong token: flying needs the console token (printed at start-up)",
    }
    for token, code in ((None, 401), (WINCH, 403), (SUPERVISOR, 403)):
        headers = {} if token is None else {"Authorization": f"Bearer {token}"}
        r = client.post("/api/run/pause", headers=headers)
        assert r.status_code == code, r.text
    r = client.post("/api/run/pause", headers={"Authorization": f"Bearer {WINCH}"})
    assert "winch station's token" in r.json()["detail"] and WINCH not in r.text
    r = client.post("/api/faults", headers={"Authorization": f"Bearer {WINCH}"}, json={})
    assert r.status_code == 401  # the instructor's routes: not the winch token either
    # crew tokens are no guesses: the console token's lockout has counted none of them
    console = client.app.state.console  # type: ignore[attr-defined]
    assert console.guesses.retry_after_s("http:testclient") == 0.0


def test_winch_operator_pays_out_and_the_log_names_them(client: TestClient) -> None:
    with client.websocket_connect("ws://127.0.0.1/api/winch") as ws:
        ws.send_json({"type": "hello", "token": WINCH, "name": "Wanda"})
        assert ws.receive_json()["type"] == "welcome"
        first = until(ws, lambda m: m["type"] == "status", "a status")["status"]
        assert first["tension_kn"] > 0 and first["heave_compensation"] is None
        assert {a["name"] for a in first["alarms"]} == {"wire_slack", "wire_snap"}
        with client.websocket_connect("ws://127.0.0.1/api/winch") as other:
            other.send_json({"type": "hello", "token": WINCH, "name": "Bob"})
            assert other.receive_json()["message"] == (
                "Wanda is on the winch: one winch operator at a time"
            )
        ws.send_json({"type": "pay_out", "speed_mps": 5})
        error = until(ws, lambda m: m["type"] == "error", "an error")
        assert error["message"] == "speed_mps must be in (0, 2] m/s, got 5"
        ws.send_json({"type": "compensation", "on": True})
        error = until(ws, lambda m: m["type"] == "error", "an error")
        assert "does not heave in this run" in error["message"]
        ws.send_json({"type": "pay_out", "speed_mps": 1.0, "distance_m": 0.5})
        done = until(ws, lambda m: m["type"] == "done", "the answer")["result"]
        assert done["target_m"] == pytest.approx(first["payout_m"] + 0.5, abs=1e-6)
        later = until(
            ws,
            lambda m: (
                m["type"] == "status"
                and m["status"]["payout_m"] > first["payout_m"] + 0.49
                and not m["status"]["moving"]
            ),
            "the payout done",
            limit=200,
        )["status"]
        assert later["height_above_posts_m"] < first["height_above_posts_m"] - 0.2
        ws.send_json({"type": "stop"})
        assert until(ws, lambda m: m["type"] == "done", "the stop")["result"]["moving"] is False
    ops = client.get("/api/operations").json()
    mine = [op for op in ops if op["who"] == "winch (Wanda)"]
    assert [op["action"] for op in mine if op["outcome"] == "done"] == [
        "winch pay out: speed_mps 1, distance_m 0.5",
        "winch stop",
    ]
    refused = [op for op in mine if op["outcome"].startswith("refused: heave compensation")]
    assert [op["action"] for op in refused] == ["heave compensation on"]


def test_the_winch_over_http(client: TestClient) -> None:
    auth = {"Authorization": f"Bearer {WINCH}"}
    before = client.get("/api/winch").json()
    assert before["slip"] is None and before["moving"] is False
    r = client.post("/api/winch/haul-in", headers=auth, json={"speed_mps": 2, "distance_m": 0.2})
    assert r.status_code == 200, r.text
    assert r.json()["result"]["target_m"] == pytest.approx(before["payout_m"] - 0.2, abs=1e-6)
    assert client.post("/api/winch/stop", headers=auth).status_code == 200
    ops = client.get("/api/operations").json()
    assert ops[-1]["who"] == "winch (API testclient)" and ops[-1]["action"] == "winch stop"


def test_a_winch_slip_reaches_the_winch_station(client: TestClient) -> None:
    auth = {"Authorization": f"Bearer {INSTRUCTOR}"}
    with client.websocket_connect("ws://127.0.0.1/api/winch") as ws:
        ws.send_json({"type": "hello", "token": WINCH, "name": "Wanda"})
        until(ws, lambda m: m["type"] == "status", "a status")
        r = client.post(
            "/api/faults", headers=auth, json={"kind": "winch_slip", "duration_s": 1, "value": 1.0}
        )
        assert r.status_code == 200, r.text
        slip = until(ws, lambda m: m["type"] == "status" and m["status"]["slip"], "the slip")
        assert "winch slip: the payout jumped +1.00 m" in slip["status"]["slip"]


def test_a_lost_thruster_reaches_the_pilot(client: TestClient) -> None:
    auth = {"Authorization": f"Bearer {INSTRUCTOR}"}
    with client.websocket_connect("ws://127.0.0.1/api/pilot") as ws:
        ws.send_json({"type": "hello", "token": TOKEN, "name": "Pia"})
        assert ws.receive_json()["type"] == "welcome"
        r = client.post(
            "/api/faults",
            headers=auth,
            json={"kind": "thruster_lost", "duration_s": 30, "thruster": 2},
        )
        assert r.status_code == 200, r.text
        for _ in range(40):
            ws.send_json({"type": "demand", "surge": 0, "sway": 0, "heave": 0, "yaw": 0})
            m = ws.receive_json()
            if m.get("status", {}).get("thrusters_out"):
                break
        assert m["status"]["thrusters_out"] == [{"number": 2, "share": 0.0}]
    client.delete("/api/faults", headers=auth)


def test_the_supervisor_pauses_and_resumes_and_nothing_else(client: TestClient) -> None:
    with client.websocket_connect("ws://127.0.0.1/api/supervisor") as ws:
        ws.send_json({"type": "hello", "token": SUPERVISOR, "name": "Sam"})
        assert ws.receive_json()["type"] == "welcome"
        status = until(ws, lambda m: m["type"] == "status", "a status")["status"]
        assert {"pilot", "winch"} == set(status["crew"]) and status["alarms"]
        ws.send_json({"type": "pay_out", "speed_mps": 0.3})
        assert (
            "pause and resume only" in until(ws, lambda m: m["type"] == "error", "error")["message"]
        )
        ws.send_json({"type": "pause"})
        assert until(ws, lambda m: m["type"] == "done", "the pause")["result"] == {"paused": True}
        assert client.get("/api/state").json()["loop"]["paused"] is True
        ws.send_json({"type": "resume"})
        until(ws, lambda m: m["type"] == "done", "the resume")
        seen = until(
            ws,
            lambda m: (
                m["type"] == "status"
                and any(op["who"] == "supervisor (Sam)" for op in m["status"]["operations"])
            ),
            "the supervisor in the log",
        )
        actions = [op["action"] for op in seen["status"]["operations"]]
        assert "pause" in actions and "winch stop" in actions
        assert not any("fault" in a for a in actions)  # the instructor's stay hidden


HOLD_MISSION = """
format_version = 1
name = "crew-hold"
[setup]
params = "full-scale"
depth_m = 100.0
[[legs]]
type = "hold"
duration_s = 600.0
"""


def test_a_running_mission_keeps_the_winch_but_not_the_stop(client: TestClient) -> None:
    """Last in the module: it replaces the run. A mission's legs drive the winch, so the
    winch operator's pay-out is refused (409 naming the mission); the stop is not."""
    console = {"Authorization": f"Bearer {TOKEN}"}
    winch = {"Authorization": f"Bearer {WINCH}"}
    assert client.post(
        "/api/missions/uploads", json={"toml": HOLD_MISSION}, headers=console
    ).is_success
    assert client.post(
        "/api/missions/start", json={"name": "crew-hold"}, headers=console
    ).is_success
    for _ in range(200):
        if client.get("/api/missions/current").json()["state"] == "running":
            break
    r = client.post("/api/winch/pay-out", headers=winch, json={"speed_mps": 0.1})
    assert r.status_code == 409
    assert r.json()["detail"] == "winch: mission 'crew-hold' is running; abort it first"
    assert client.post("/api/winch/stop", headers=winch).status_code == 200
    assert client.post("/api/missions/abort", headers=console).status_code == 200


SEAWAY_MISSION = """
format_version = 1
name = "crew-seaway"
[setup]
params = "full-scale"
depth_m = 100.0
[setup.waves]
significant_height_m = 2.0
peak_period_s = 8.0
direction_deg = 0.0
[setup.vessel]
[[legs]]
type = "hold"
duration_s = 600.0
"""


def test_the_winch_station_switches_the_heave_compensation_in_a_sea(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    folder = tmp_path_factory.mktemp("seaway")
    mission = folder / "crew-seaway.toml"
    mission.write_text(SEAWAY_MISSION)
    settings = ConsoleSettings(
        view=False, token=TOKEN, winch_token=WINCH, mission=str(mission), recordings_dir=folder
    )
    with (
        TestClient(create_app(settings), base_url="http://127.0.0.1") as c,
        c.websocket_connect("ws://127.0.0.1/api/winch") as ws,
    ):
        ws.send_json({"type": "hello", "token": WINCH, "name": "Wanda"})
        assert ws.receive_json()["type"] == "welcome"
        first = until(ws, lambda m: m["type"] == "status", "a status")["status"]
        assert first["heave_compensation"] is False and first["mission"] == "crew-seaway"
        ws.send_json({"type": "compensation", "on": True})
        done = until(ws, lambda m: m["type"] in ("done", "error"), "the answer")
        assert done["type"] == "done" and done["result"]["heave_compensation"] is True
        status = until(ws, lambda m: m["type"] == "status", "a status")["status"]
        assert status["heave_compensation"] is True
        ws.send_json({"type": "pay_out", "speed_mps": 0.1})
        error = until(ws, lambda m: m["type"] == "error", "the refusal")
        assert error["message"] == "winch: mission 'crew-seaway' is running; abort it first"
    sim = c.app.state.console.loop.session.sim  # type: ignore[attr-defined]
    assert sim.heave_compensation is True
