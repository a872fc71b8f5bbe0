"""Issue 47 items 8, 9, 11, 15 and 17: bad input the console accepted or answered wrongly,
over HTTP (FastAPI's TestClient; the same requests are in tests/corpus/bad_requests.txt
against a live server)."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from app.console import ConsoleSettings
from app.console.faults import MAX_LIVE_FAULTS
from app.console.loop import PacedLoop
from app.server import create_app

TOKEN = "inputs-test-token-0123456789"
INSTRUCTOR = "inputs-instructor-0123"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
JSON = {"content-type": "application/json"}


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    settings = ConsoleSettings(
        view=False,
        token=TOKEN,
        instructor_token=INSTRUCTOR,
        recordings_dir=tmp_path_factory.mktemp("recordings"),
    )
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        yield c


def mission(name: str = "ok", leg_name: str = "", description: str = "") -> dict:
    return {
        "format_version": 1,
        "name": name,
        "description": description,
        "setup": {"params": "full-scale", "depth_m": 100.0},
        "legs": [{"type": "hold", "name": leg_name, "duration_s": 1.0}],
    }


def raw_json(value: object) -> bytes:
    """JSON with lone surrogates written as \\ud800 escapes (as a hostile client sends)."""
    return json.dumps(value).encode()


# ------------------------------------------------------------------ 8, 9: lone surrogates
@pytest.mark.parametrize(
    ("fields", "named"),
    [
        ({"name": "bad\ud800"}, "name: name must be 1 to 80 characters"),
        ({"leg_name": "leg\ud800"}, "legs[1] (hold).name"),
        ({"description": "text\ud800"}, "description"),
    ],
)
def test_a_lone_surrogate_is_refused_naming_the_field_and_nothing_is_stored(
    client: TestClient, fields: dict, named: str
) -> None:
    body = raw_json({"mission": mission(**{"name": "surrogate", **fields})})
    r = client.post("/api/missions/uploads", content=body, headers={**AUTH, **JSON})
    assert r.status_code == 422 and named in r.json()["detail"], r.text
    listed = client.get("/api/missions")
    assert listed.status_code == 200
    assert listed.json()["uploaded"] == []
    assert client.get("/api/state").status_code == 200


def test_health_says_when_the_state_cannot_be_served(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Item 9: with a leg name the state could not be written in, /api/state answered 500
    and every telemetry socket closed while /api/health said 'ok'."""
    assert client.get("/api/health").json()["status"] == "ok"
    snap = client.app.state.console.loop.snapshot  # type: ignore[attr-defined]
    broken = dataclasses.replace(
        snap, seq=-7, mission=dataclasses.replace(snap.mission, leg_name="leg\ud800")
    )
    monkeypatch.setattr(PacedLoop, "snapshot", property(lambda self: broken))
    r = client.get("/api/health")
    assert r.status_code == 503
    assert r.json()["status"] == "broken"
    assert r.json()["state_error"].startswith("the state cannot be served: ")


# ------------------------------------------------------------------ 11: faults cap
def test_scheduled_faults_are_capped_with_the_limit_in_the_answer(client: TestClient) -> None:
    teach = {"Authorization": f"Bearer {INSTRUCTOR}"}
    t0 = client.get("/api/health").json()["t_s"]
    fault = {"kind": "compass_bias", "duration_s": 10.0, "value": 5.0}
    try:
        for k in range(MAX_LIVE_FAULTS):
            r = client.post(
                "/api/faults", json={**fault, "start_s": t0 + 1000.0 + k}, headers=teach
            )
            assert r.status_code == 200, r.text
        r = client.post("/api/faults", json={**fault, "start_s": t0 + 5000.0}, headers=teach)
        assert r.status_code == 409
        assert f"the most at once is {MAX_LIVE_FAULTS}" in r.json()["detail"]
        assert len(client.get("/api/faults", headers=teach).json()["scheduled"]) == MAX_LIVE_FAULTS
    finally:
        client.delete("/api/faults", headers=teach)


# ------------------------------------------------------------------ 15: chunked bodies
def test_a_chunked_body_over_the_limit_gets_413(client: TestClient) -> None:
    def chunks() -> Iterator[bytes]:
        yield b'{"toml": "'
        for _ in range(40):
            yield b"x" * 8192
        yield b'"}'

    r = client.post("/api/missions/validate", content=chunks(), headers=JSON)
    assert r.request.headers.get("transfer-encoding") == "chunked"
    assert r.status_code == 413
    assert r.json()["detail"] == "request body too large: at most 262144 bytes"


# ------------------------------------------------------------------ 17: the smaller items
@pytest.mark.parametrize(
    ("path", "allow"),
    [("/api/recordings/start", "OPTIONS, POST"), ("/api/missions/uploads", "OPTIONS, POST")],
)
def test_get_on_a_post_only_path_is_405_with_allow(client: TestClient, path: str, allow: str):
    r = client.get(path)
    assert r.status_code == 405 and r.headers["allow"] == allow
    assert r.json()["detail"] == f"GET is not allowed on this path; it takes {allow}"


def test_options_lists_every_method_of_the_path(client: TestClient) -> None:
    r = client.options("/api/gains")
    assert r.status_code == 204 and r.headers["allow"] == "GET, OPTIONS, PUT"
    assert client.options("/api/missions/some-name").headers["allow"] == "GET, OPTIONS"


def test_a_body_that_is_not_json_gets_415(client: TestClient) -> None:
    r = client.put(
        "/api/run/speed", content=b'{"speed": 2}', headers={**AUTH, "content-type": "text/plain"}
    )
    assert r.status_code == 415
    assert r.json()["detail"] == (
        "the body must be JSON (Content-Type: application/json), got 'text/plain'"
    )


def test_a_key_given_twice_is_refused(client: TestClient) -> None:
    r = client.put("/api/run/speed", content=b'{"speed": 2, "speed": 3}', headers={**AUTH, **JSON})
    assert r.status_code == 422
    assert r.json()["detail"] == "body: the key 'speed' is given twice"


def test_the_404_of_an_unknown_mission_quotes_a_long_name_cut(client: TestClient) -> None:
    r = client.get("/api/missions/" + "x" * 4000)
    assert r.status_code == 404
    assert r.json()["detail"] == f"no mission named {'x' * 60!r}... (4000 characters)"
    r = client.post("/api/missions/start", json={"name": "y" * 200}, headers=AUTH)
    assert r.status_code == 404 and len(r.text) < 200


def test_errors_name_files_not_the_server_folders_they_are_in(client: TestClient) -> None:
    folder = client.app.state.console.settings.recordings_dir  # type: ignore[attr-defined]
    (folder / "cut.mcap").write_bytes(b"\x89MCAP0\r\n" + b"not a recording" * 10)
    r = client.post("/api/replay/open", json={"name": "cut.mcap"}, headers=AUTH)
    assert r.status_code == 422 and "cut.mcap" in r.json()["detail"]
    assert str(folder) not in r.text


def test_the_openapi_gain_ranges_are_the_ones_enforced(client: TestClient) -> None:
    """The schema said kp <= 1e7 while PUT /api/gains refused 4x the set's gain (8000)."""
    kp = client.get("/openapi.json").json()["components"]["schemas"]["GainsIn"]["properties"]["kp"]
    bands = [axis["maximum"] for axis in kp["prefixItems"]]
    gains = client.get("/api/gains").json()
    body = {"kp": bands, "ki": gains["ki"], "kd": gains["kd"]}
    assert client.put("/api/gains", json=body, headers=AUTH).status_code == 200
    over = {**body, "kp": [bands[0] * 1.001, bands[1], bands[2]]}
    r = client.put("/api/gains", json=over, headers=AUTH)
    assert r.status_code == 422 and f"gain kp surge must be in [0, {bands[0]:g}]" in r.text
    client.put("/api/gains", json={k: gains[k] for k in ("kp", "ki", "kd")}, headers=AUTH)


@pytest.mark.parametrize("name", ["Full-Square-400", "full-square-400\u200b", "full-square-400 "])
def test_an_upload_that_looks_like_a_library_mission_is_refused(client: TestClient, name: str):
    r = client.post("/api/missions/uploads", json={"mission": mission(name)}, headers=AUTH)
    assert r.status_code in (409, 422), r.text
    assert name not in [m["name"] for m in client.get("/api/missions").json()["uploaded"]]
