"""The instructor: its own token, faults injected now or later over HTTP, listed and cleared;
the injections are events in the recording and shown to the instructor, while the operations
log a trainee reads (the API without the instructor token, the page's operations text) leaves
them out."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from app.console import ConsoleSettings
from app.console.operations import Operation, trainee_view
from app.recording import load_session
from app.server import create_app, instructor_line

TOKEN = "instructor-test-console-1"
INSTRUCTOR = "teach-me-8"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
TEACH = {"Authorization": f"Bearer {INSTRUCTOR}"}


def wait_for(predicate: Callable[[], bool], timeout_s: float = 20.0, what: str = "") -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


@pytest.fixture(scope="module")
def rec_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("recordings")


@pytest.fixture(scope="module")
def client(rec_dir: Path) -> Iterator[TestClient]:
    settings = ConsoleSettings(
        view=False, token=TOKEN, instructor_token=INSTRUCTOR, speed=5.0, recordings_dir=rec_dir
    )
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        yield c


def t_now(client: TestClient) -> float:
    return float(client.get("/api/state").json()["t_s"])


def test_the_instructor_token_is_checked_when_the_console_is_set_up() -> None:
    with pytest.raises(ValueError, match="instructor_token must have at least 8"):
        ConsoleSettings(instructor_token="short")
    with pytest.raises(ValueError, match="must differ from the console token"):
        ConsoleSettings(token=TOKEN, instructor_token=TOKEN)
    assert "off" in instructor_line(ConsoleSettings())
    assert "on" in instructor_line(ConsoleSettings(instructor_token=INSTRUCTOR))
    assert INSTRUCTOR not in instructor_line(ConsoleSettings(instructor_token=INSTRUCTOR))


def test_without_an_instructor_token_the_features_are_off_and_say_how_to_turn_them_on(
    tmp_path: Path,
) -> None:
    settings = ConsoleSettings(view=False, token=TOKEN, recordings_dir=tmp_path)
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        body = {"kind": "compass_bias", "duration_s": 10.0, "value": 5.0}
        for headers in ({}, AUTH, TEACH):
            r = c.post("/api/faults", json=body, headers=headers)
            assert r.status_code == 403 and "--instructor-token" in r.json()["detail"]
        kinds = c.get("/api/faults/kinds").json()
        bias = next(k for k in kinds if k["kind"] == "compass_bias")
        assert (bias["unit"], bias["min"], bias["max"]) == ("deg", -180.0, 180.0)


def test_inject_now_and_later_list_clear_and_the_trainee_does_not_see_it(
    client: TestClient, rec_dir: Path
) -> None:
    assert client.post("/api/recordings/start", json={"label": "drill"}, headers=AUTH).is_success
    assert client.put("/api/run/speed", json={"speed": 5.0}, headers=AUTH).is_success
    now = client.post(
        "/api/faults",
        json={"kind": "compass_bias", "duration_s": 600.0, "value": 20.0},
        headers=TEACH,
    )
    assert now.status_code == 200, now.text
    later_s = t_now(client) + 900.0
    later = client.post(
        "/api/faults",
        json={"kind": "thruster_lost", "duration_s": 5.0, "thruster": 2, "start_s": later_s},
        headers=TEACH,
    )
    assert later.status_code == 200, later.text
    wait_for(
        lambda: any(
            "compass bias" in e["text"]
            for e in client.get("/api/faults", headers=TEACH).json()["events"]
        ),
        what="the fault's start",
    )
    listed = client.get("/api/faults", headers=TEACH).json()
    assert [(f["kind"], f["value"], f["unit"]) for f in listed["active"]] == [
        ("compass_bias", 20.0, "deg")
    ]
    assert [(f["kind"], f["thruster"]) for f in listed["scheduled"]] == [("thruster_lost", 2)]
    assert listed["scheduled"][0]["start_s"] == pytest.approx(later_s)

    trainee = client.get("/api/operations").json()
    instructor = client.get("/api/operations", headers=TEACH).json()
    not_the_instructor = client.get("/api/operations", headers=AUTH).json()
    assert any(op["action"].startswith("set speed") for op in trainee), "the trainee's own"
    assert not any("fault" in op["action"] for op in trainee + not_the_instructor)
    assert [op["action"].split(":")[0] for op in instructor if "fault" in op["action"]] == [
        "inject fault",
        "inject fault",
    ]
    state_text = client.get("/api/state").text
    assert "compass" not in state_text and "inject" not in state_text

    cleared = client.delete("/api/faults", headers=TEACH)
    assert cleared.json()["result"] == {"cleared": 2}
    assert client.get("/api/faults", headers=TEACH).json()["active"] == []
    assert client.delete("/api/faults", headers=TEACH).status_code == 409
    time.sleep(0.3)
    name = client.post("/api/recordings/stop", headers=AUTH).json()["name"]
    events = load_session(rec_dir / name).events
    texts = [(e["kind"], e["text"]) for e in events]
    assert any(
        k == "instructor" and t.startswith("fault injected: compass bias 20 deg from")
        for k, t in texts
    )
    assert any(k == "fault" and t.startswith("fault: compass bias 20 deg") for k, t in texts)
    assert any(k == "fault" and t == "fault cleared: compass_bias" for k, t in texts)
    assert any(k == "instructor" and t == "faults cleared (2)" for k, t in texts)


def test_the_pages_operations_text_leaves_the_instructors_commands_out() -> None:
    from web.status import operations_markdown  # the trainee's view of the log in the page

    ops = (
        Operation("2026-01-01T00:00:01Z", 1.0, "viewer 1 (Anna)", "pause", "done"),
        Operation(
            "2026-01-01T00:00:02Z", 2.0, "viewer 2 (Ian)", "inject fault: kind x", "done", True
        ),
    )
    assert trainee_view(ops) == ops[:1]

    class Snap:
        operations = ops

    text = operations_markdown(Snap())  # type: ignore[arg-type]
    assert "pause" in text and "inject fault" not in text and "Ian" not in text
