"""The console's HTTP API and telemetry stream (FastAPI's TestClient; the loop task runs for
real): every endpoint, its bad inputs (4xx naming the field), the token, and that nothing a
client sends stops the loop."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from app.console import ConsoleSettings
from app.server import create_app

TOKEN = "test-token-1234567"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
MCAP_MAGIC = b"\x89MCAP0\r\n"


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    settings = ConsoleSettings(
        view=False, token=TOKEN, speed=5.0, recordings_dir=tmp_path_factory.mktemp("recordings")
    )
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        yield c


def state(client: TestClient) -> dict:
    r = client.get("/api/state")
    assert r.status_code == 200
    return r.json()


def wait_for(predicate: Callable[[], bool], timeout_s: float = 15.0, what: str = "") -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def detail(response) -> str:
    assert 400 <= response.status_code < 500, response.text
    return str(response.json()["detail"])


# ------------------------------------------------------------------ settings and app
def test_binding_to_a_public_address_must_be_asked_for() -> None:
    with pytest.raises(ValueError, match="allow_remote"):
        ConsoleSettings(host="0.0.0.0")
    assert ConsoleSettings(host="0.0.0.0", allow_remote=True).host == "0.0.0.0"
    assert ConsoleSettings(host="::1").host == "::1"
    with pytest.raises(ValueError, match="token"):
        ConsoleSettings(token="short")


def test_two_apps_share_nothing(tmp_path: Path) -> None:
    a = create_app(ConsoleSettings(view=False, recordings_dir=tmp_path))
    b = create_app(ConsoleSettings(view=False, recordings_dir=tmp_path))
    assert a.state.console is not b.state.console
    assert a.state.console.token != b.state.console.token, "tokens are generated per app"


def test_openapi_lists_one_router_per_resource(client: TestClient) -> None:
    spec = client.get("/openapi.json").json()
    tags = {
        tag for path in spec["paths"].values() for op in path.values() for tag in op.get("tags", [])
    }
    assert {
        "health",
        "state",
        "run",
        "missions",
        "gains",
        "control",
        "environment",
        "recordings",
        "replay",
    } <= tags
    assert "/api/state" in spec["paths"] and "/api/gains" in spec["paths"]


# ------------------------------------------------------------------ watching
def test_health_and_state_need_no_token(client: TestClient) -> None:
    h = client.get("/api/health").json()
    assert h["status"] == "ok" and h["loop_running"] is True
    s = state(client)
    assert s["source"] == "live" and s["mode"] == "tree"
    assert set(s["tree_eta_n"]) == {
        "north_m",
        "east_m",
        "down_m",
        "roll_deg",
        "pitch_deg",
        "heading_deg",
    }
    assert s["tree_eta_n"]["down_m"] == pytest.approx(400.0, abs=1.0)
    assert s["mission"]["state"] in ("idle", "completed", "aborted")
    assert len(s["thrusters"]) == 4 and {a["name"] for a in s["alarms"]} >= {
        "saturation",
        "position_error",
        "wire_slack",
        "innovation",
        "dropout",
    }
    t0 = s["t_s"]
    wait_for(lambda: state(client)["t_s"] > t0, what="time to advance")


def test_changing_the_run_needs_the_right_token(client: TestClient) -> None:
    body = {"speed": 2.0}
    assert client.put("/api/run/speed", json=body).status_code == 401
    r = client.put("/api/run/speed", json=body, headers={"Authorization": "Bearer wrong-token"})
    assert r.status_code == 401 and "token" in detail(r)
    assert client.put("/api/run/speed", json=body, headers=AUTH).status_code == 200
    client.put("/api/run/speed", json={"speed": 5.0}, headers=AUTH)


# ------------------------------------------------------------------ run
def test_pause_step_resume_and_speed(client: TestClient) -> None:
    assert client.post("/api/run/pause", headers=AUTH).json()["result"] == {"paused": True}
    t0 = state(client)["t_s"]
    time.sleep(0.2)
    assert state(client)["t_s"] == t0, "a paused run must not advance"
    r = client.post("/api/run/step", json={"steps": 25}, headers=AUTH)
    assert r.status_code == 200 and r.json()["result"]["t_s"] == pytest.approx(t0 + 0.25)
    assert client.get("/api/run").json()["paused"] is True
    client.post("/api/run/resume", headers=AUTH)
    wait_for(lambda: state(client)["t_s"] > t0 + 0.5, what="resume")
    r = client.post("/api/run/step", json={"steps": 1}, headers=AUTH)
    assert r.status_code == 409 and "pause" in detail(r)


@pytest.mark.parametrize(
    "body, field",
    [
        ({"speed": 0.1}, "speed"),
        ({"speed": 51}, "speed"),
        ({"speed": "fast"}, "speed"),
        ({}, "speed"),
        ({"speed": 1, "extra": 1}, "extra"),
    ],
)
def test_bad_speed_is_refused_naming_the_field(client: TestClient, body: dict, field: str) -> None:
    r = client.put("/api/run/speed", json=body, headers=AUTH)
    assert r.status_code == 422 and field in detail(r)


def test_step_bounds(client: TestClient) -> None:
    for steps in (0, 10_001, -1):
        r = client.post("/api/run/step", json={"steps": steps}, headers=AUTH)
        assert r.status_code == 422 and "steps" in detail(r)


def test_reset_builds_a_new_setup_and_refuses_unknown_params(client: TestClient) -> None:
    r = client.post("/api/run/reset", json={"params": "../../etc/passwd"}, headers=AUTH)
    assert r.status_code == 422 and "params" in detail(r)
    r = client.post(
        "/api/run/reset", json={"params": "model-scale", "depth_m": 100.0}, headers=AUTH
    )
    assert r.status_code == 200
    wait_for(lambda: len(state(client)["thrusters"]) == 5, what="model-scale ROV (5 thrusters)")
    assert state(client)["tree_eta_n"]["down_m"] == pytest.approx(100.0, abs=1.0)
    assert state(client)["t_s"] < 30.0, "a reset starts the clock again"
    client.post("/api/run/reset", json={"params": "full-scale"}, headers=AUTH)
    wait_for(lambda: len(state(client)["thrusters"]) == 4, what="full scale again")


# ------------------------------------------------------------------ gains
def test_gains_read_set_and_read_back(client: TestClient) -> None:
    before = client.get("/api/gains").json()
    assert before["kp"] == [2000.0, 2000.0, 2000.0]
    new = {
        "kp": [2500.0, 2400.0, 2300.0],
        "ki": [150.0, 150.0, 70.0],
        "kd": [9000.0, 9000.0, 40000.0],
    }
    r = client.put("/api/gains", json=new, headers=AUTH)
    assert r.status_code == 200 and r.json()["kp"] == new["kp"]
    wait_for(lambda: client.get("/api/gains").json()["kd"] == new["kd"], what="gains")
    client.put("/api/gains", json={k: before[k] for k in ("kp", "ki", "kd")}, headers=AUTH)


@pytest.mark.parametrize(
    "change, field",
    [
        ({"kp": [1.0, 2.0, -3.0]}, "kp"),
        ({"ki": [0.0, 0.0, 2.0e6]}, "ki"),
        ({"kd": [1.0, 2.0]}, "kd"),
        ({"kp": [1.0, "x", 3.0]}, "kp"),
        ({"kp": None}, "kp"),
    ],
)
def test_bad_gains_are_refused_naming_the_field(
    client: TestClient, change: dict, field: str
) -> None:
    body = {"kp": [1.0, 1.0, 1.0], "ki": [0.0, 0.0, 0.0], "kd": [1.0, 1.0, 1.0]} | change
    before = client.get("/api/gains").json()
    r = client.put("/api/gains", json=body, headers=AUTH)
    assert r.status_code == 422 and field in detail(r)
    assert client.get("/api/gains").json() == before, "a refused change changes nothing"


# ------------------------------------------------------------------ control
def test_mode_allocation_grip_and_target(client: TestClient) -> None:
    assert (
        client.put("/api/control/allocation", json={"allocation": "pinv"}, headers=AUTH).status_code
        == 200
    )
    wait_for(lambda: client.get("/api/control").json()["allocation"] == "pinv", what="pinv")
    client.put("/api/control/allocation", json={"allocation": "priority"}, headers=AUTH)
    assert client.put("/api/control/mode", json={"mode": "free"}, headers=AUTH).status_code == 200
    wait_for(lambda: state(client)["mode"] == "free", what="free mode")
    client.put("/api/control/mode", json={"mode": "tree"}, headers=AUTH)
    wait_for(lambda: state(client)["mode"] == "tree", what="tree mode")
    s = state(client)
    target = {
        "north_m": s["tree_eta_n"]["north_m"] + 0.5,
        "east_m": s["tree_eta_n"]["east_m"],
        "heading_deg": 0.0,
    }
    assert client.put("/api/control/target", json=target, headers=AUTH).status_code == 200
    wait_for(
        lambda: (
            client.get("/api/control").json()["reference"]["north_m"]
            > s["reference"]["north_m"] + 0.05
        ),
        what="the reference to move north",
    )


@pytest.mark.parametrize(
    "path, body, field",
    [
        ("/api/control/mode", {"mode": "autopilot"}, "mode"),
        ("/api/control/allocation", {"allocation": "magic"}, "allocation"),
        ("/api/control/grip", {"grip": "maybe"}, "grip"),
        ("/api/control/target", {"north_m": 1e9, "east_m": 0, "heading_deg": 0}, "north_m"),
        ("/api/control/target", {"north_m": 0, "east_m": 0}, "heading_deg"),
    ],
)
def test_bad_control_requests_name_the_field(
    client: TestClient, path: str, body: dict, field: str
) -> None:
    r = client.put(path, json=body, headers=AUTH)
    assert r.status_code == 422 and field in detail(r)


# ------------------------------------------------------------------ environment
def test_current_and_vessel(client: TestClient) -> None:
    r = client.put(
        "/api/environment/current", json={"speed_mps": 0.2, "direction_deg": 90.0}, headers=AUTH
    )
    assert r.status_code == 200
    wait_for(
        lambda: abs(client.get("/api/environment").json()["current"]["speed_mps"] - 0.2) < 1e-9,
        what="the current",
    )
    env = client.get("/api/environment").json()
    assert env["current"]["direction_deg"] == pytest.approx(90.0)
    assert env["wire_tension_newton"] > 1e5
    tip = env["crane_tip_n"]
    r = client.put(
        "/api/environment/vessel",
        json={"north_m": tip[0] + 1.0, "east_m": tip[1], "speed_mps": 1.0},
        headers=AUTH,
    )
    assert r.status_code == 200
    wait_for(
        lambda: client.get("/api/environment").json()["crane_tip_n"][0] > tip[0] + 0.05,
        what="the vessel to move",
    )
    client.put(
        "/api/environment/current", json={"speed_mps": 0.0, "direction_deg": 0.0}, headers=AUTH
    )


@pytest.mark.parametrize(
    "path, body, field",
    [
        ("/api/environment/current", {"speed_mps": 5.0, "direction_deg": 0}, "speed_mps"),
        ("/api/environment/current", {"speed_mps": 0.1, "direction_deg": "nan"}, "direction_deg"),
        ("/api/environment/vessel", {"north_m": 0, "east_m": 5000}, "east_m"),
        ("/api/environment/vessel", {"north_m": 0, "east_m": 0, "speed_mps": 0}, "speed_mps"),
    ],
)
def test_bad_environment_requests_name_the_field(
    client: TestClient, path: str, body: dict, field: str
) -> None:
    r = client.put(path, json=body, headers=AUTH)
    assert r.status_code == 422 and field in detail(r)


# ------------------------------------------------------------------ missions
SMALL_MISSION = """
format_version = 1
name = "api-test-move"

[setup]
params = "full-scale"
depth_m = 100.0

[[legs]]
type = "move"
north_m = 1.0
east_m = 0.0
settle_s = 5.0

[[legs]]
type = "hold"
duration_s = 600.0
"""


def test_mission_library_and_leg_types(client: TestClient) -> None:
    listing = client.get("/api/missions").json()
    names = [m["name"] for m in listing["library"]]
    assert "full-square-400" in names
    assert {"hold", "rotate", "move", "square"} <= set(listing["leg_types"])
    one = client.get("/api/missions/full-square-400").json()
    assert one["mission"]["setup"]["depth_m"] == 400.0 and "[[legs]]" in one["toml"]
    schemas = client.get("/api/missions/leg-types").json()
    assert schemas["rotate"]["properties"]["angle_deg"]["maximum"] == 1080.0
    assert client.get("/api/missions/no-such-mission").status_code == 404
    assert client.get("/api/missions/..%2F..%2Fetc%2Fpasswd").status_code == 404


def test_validate_names_the_field_and_its_range(client: TestClient) -> None:
    ok = client.post("/api/missions/validate", json={"toml": SMALL_MISSION}).json()
    assert ok == {"valid": True, "errors": [], "name": "api-test-move", "legs": 2}
    bad = SMALL_MISSION.replace("north_m = 1.0", "north_m = 5000.0")
    result = client.post("/api/missions/validate", json={"toml": bad}).json()
    assert result["valid"] is False
    assert any("north_m" in e and "1000" in e for e in result["errors"]), result["errors"]
    broken = client.post("/api/missions/validate", json={"toml": "name = "}).json()
    assert broken["valid"] is False and "toml" in broken["errors"][0]
    neither = client.post("/api/missions/validate", json={}).json()
    assert neither["valid"] is False and "exactly one" in neither["errors"][0]


def test_upload_start_follow_and_abort_a_mission(client: TestClient) -> None:
    bad = client.post(
        "/api/missions/uploads",
        json={"toml": SMALL_MISSION.replace('type = "hold"', 'type = "teleport"')},
        headers=AUTH,
    )
    assert bad.status_code == 422 and "legs[2]" in detail(bad)
    clash = client.post(
        "/api/missions/uploads",
        json={"toml": SMALL_MISSION.replace("api-test-move", "full-square-400")},
        headers=AUTH,
    )
    assert clash.status_code == 409 and "name" in detail(clash)
    up = client.post("/api/missions/uploads", json={"toml": SMALL_MISSION}, headers=AUTH)
    assert up.status_code == 201 and up.json() == {"name": "api-test-move"}
    assert "api-test-move" in [m["name"] for m in client.get("/api/missions").json()["uploaded"]]
    assert (
        client.post("/api/missions/start", json={"name": "nope"}, headers=AUTH).status_code == 404
    )
    r = client.post("/api/missions/start", json={"name": "api-test-move"}, headers=AUTH)
    assert r.status_code == 200
    wait_for(lambda: state(client)["mission"]["name"] == "api-test-move", what="start")
    client.put("/api/run/speed", json={"speed": 50.0}, headers=AUTH)
    wait_for(lambda: state(client)["mission"]["leg_index"] == 2, 30.0, "the hold leg")
    current = client.get("/api/missions/current").json()
    assert current["state"] == "running" and current["leg_type"] == "hold"
    assert state(client)["tree_eta_n"]["north_m"] > 1.7, "the move leg moved the tree north"
    assert client.post("/api/missions/abort", headers=AUTH).status_code == 200
    wait_for(
        lambda: client.get("/api/missions/current").json()["result"] is not None,
        what="the aborted mission's figures",
    )
    assert client.get("/api/missions/current").json()["state"] == "aborted"
    r = client.post("/api/missions/abort", headers=AUTH)
    assert r.status_code == 409 and "no mission" in detail(r)
    client.put("/api/run/speed", json={"speed": 5.0}, headers=AUTH)


# ------------------------------------------------------------------ recordings and replay
def test_record_list_download_and_replay(client: TestClient) -> None:
    assert client.post("/api/recordings/stop", headers=AUTH).status_code == 409
    r = client.post("/api/recordings/start", json={"label": "api"}, headers=AUTH)
    assert r.status_code == 200
    name = r.json()["name"]
    assert name.endswith(".mcap") and "api" in name
    assert client.post("/api/recordings/start", json={}, headers=AUTH).status_code == 409
    assert client.get(f"/api/recordings/{name}").status_code == 409, "not while writing"
    t0 = state(client)["t_s"]
    wait_for(lambda: state(client)["t_s"] > t0 + 3.0, what="3 s of recording")
    assert client.post("/api/recordings/stop", headers=AUTH).json() == {"name": name}
    listing = client.get("/api/recordings").json()
    assert name in [x["name"] for x in listing["recordings"]] and listing["recording"] is None
    download = client.get(f"/api/recordings/{name}")
    assert download.status_code == 200 and download.content.startswith(MCAP_MAGIC)

    assert (
        client.post("/api/replay/open", json={"name": "missing.mcap"}, headers=AUTH).status_code
        == 404
    )
    r = client.post("/api/replay/open", json={"name": name}, headers=AUTH)
    assert r.status_code == 200
    replay = r.json()["replay"]
    assert replay["end_s"] > replay["start_s"] + 2.5 and replay["complete"] is True
    # the API's replay plays beside the live run: /api/state stays live, and the live run
    # goes on stepping while the replay plays (it used to wait, paused, under the replay)
    live = state(client)
    assert live["source"] == "live" and live["replay"]["name"] == name
    client.post("/api/replay/play", headers=AUTH)
    wait_for(
        lambda: client.get("/api/replay").json()["replay"]["t_s"] > replay["start_s"] + 1.0,
        what="replay playing",
    )
    assert state(client)["t_s"] > live["t_s"] + 0.5, "the live run stepped meanwhile"
    client.post("/api/replay/pause", headers=AUTH)
    seek = client.put("/api/replay/seek", json={"t_s": replay["start_s"] + 0.5}, headers=AUTH)
    assert seek.json()["replay"]["t_s"] == pytest.approx(replay["start_s"] + 0.5, abs=0.06)
    assert client.put("/api/replay/seek", json={"t_s": -1}, headers=AUTH).status_code == 422
    assert client.post("/api/replay/close", headers=AUTH).json() == {"replay": None}
    assert state(client)["source"] == "live" and state(client)["replay"] is None
    assert client.post("/api/replay/play", headers=AUTH).status_code == 409


@pytest.mark.parametrize("name", ["..%2Fsecret.mcap", "x.txt", ".hidden.mcap"])
def test_recording_names_cannot_leave_the_directory(client: TestClient, name: str) -> None:
    assert client.get(f"/api/recordings/{name}").status_code in (404, 422)
    r = client.post("/api/replay/open", json={"name": name.replace("%2F", "/")}, headers=AUTH)
    assert r.status_code in (404, 422)


def test_recording_label_is_checked(client: TestClient) -> None:
    r = client.post("/api/recordings/start", json={"label": "../../x"}, headers=AUTH)
    assert r.status_code == 422 and "label" in detail(r)


# ------------------------------------------------------------------ telemetry
def test_telemetry_stream_sends_fresh_states(client: TestClient) -> None:
    with client.websocket_connect("ws://127.0.0.1/api/telemetry?rate_hz=50") as ws:
        messages = [ws.receive_json() for _ in range(5)]
    seqs = [m["seq"] for m in messages]
    assert seqs == sorted(seqs) and len(set(seqs)) == 5
    assert {"t_s", "tree_eta_n", "mode", "mission", "alarms"} <= set(messages[0])


def test_a_client_that_does_not_read_does_not_hold_up_the_loop(client: TestClient) -> None:
    with client.websocket_connect("ws://127.0.0.1/api/telemetry?rate_hz=100"):
        ticks = client.get("/api/run").json()["ticks"]
        time.sleep(1.5)
        assert client.get("/api/run").json()["ticks"] > ticks + 50


def test_bad_telemetry_rate_is_refused(client: TestClient) -> None:
    from starlette.websockets import WebSocketDisconnect

    with (
        pytest.raises(WebSocketDisconnect),
        client.websocket_connect("ws://127.0.0.1/api/telemetry?rate_hz=1000") as ws,
    ):
        ws.receive_json()


def test_nothing_sent_stops_the_loop(client: TestClient) -> None:
    junk = [
        ("put", "/api/gains", {"kp": "x"}),
        ("put", "/api/run/speed", {"speed": 1e308}),
        ("post", "/api/missions/start", {"name": ""}),
        ("put", "/api/replay/seek", {}),
        ("post", "/api/recordings/start", {"label": "a" * 500}),
        ("put", "/api/control/target", {"north_m": "inf", "east_m": 0, "heading_deg": 0}),
    ]
    for method, path, body in junk:
        r = getattr(client, method)(path, json=body, headers=AUTH)
        assert 400 <= r.status_code < 500, (path, r.status_code, r.text)
    t0 = state(client)["t_s"]
    wait_for(lambda: state(client)["t_s"] > t0 + 0.5, what="the loop to keep running")
    assert client.get("/api/health").json()["loop_running"] is True


def test_a_loop_that_does_not_answer_gives_503_in_words(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Defect: TimeoutError is an OSError in Python 3.11, so a command the loop did not apply
    in time was answered 507 "cannot write: " (seen once under load in the schemathesis run)."""
    from app.api import deps

    monkeypatch.setattr(deps, "COMMAND_TIMEOUT_S", 0.3)
    settings = ConsoleSettings(view=False, token=TOKEN, recordings_dir=tmp_path)
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        c.app.state.console.loop.stop()  # type: ignore[attr-defined]
        wait_for(lambda: not c.app.state.console.loop.running, 5.0, "the loop to stop")  # type: ignore[attr-defined]
        r = c.put("/api/control/allocation", json={"allocation": "pinv"}, headers=AUTH)
    assert r.status_code == 503
    assert "did not answer within 0.3 s" in r.json()["detail"]
