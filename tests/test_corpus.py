"""The corpus of bad requests (tests/corpus/bad_requests.txt) against a live console: each
gets its status and a message with the expected words, and afterwards the loop still steps."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest

from app.console import ConsoleSettings
from app.server import serve_in_thread

CORPUS = Path(__file__).parent / "corpus" / "bad_requests.txt"
TOKEN = "corpus-test-token-0001"
INSTRUCTOR = "corpus-instructor-01"
WINCH = "corpus-winch-01"
SUPERVISOR = "corpus-supervisor-01"


@dataclass(frozen=True)
class Case:
    line: int
    method: str
    path: str
    auth: str
    body: str
    status: int
    words: tuple[str, ...]

    @property
    def label(self) -> str:
        return f"line {self.line}: {self.method} {self.path} -> {self.status}"


def read_corpus(path: Path = CORPUS) -> list[Case]:
    cases = []
    for number, raw in enumerate(path.read_text().splitlines(), start=1):
        if not raw.strip() or raw.startswith("#"):
            continue
        request, auth, body, status, words = (p.strip() for p in raw.split(" | "))
        method, route = request.split()
        cases.append(
            Case(
                number,
                method,
                route,
                auth,
                body,
                int(status),
                tuple(w.strip() for w in words.split(",")),
            )
        )
    return cases


def _mission_toml(extra: str) -> str:
    return (
        'format_version = 1\nname = "generated"\n[setup]\nparams = "full-scale"\n'
        "depth_m = 100.0\n" + extra
    )


def body_bytes(spec: str) -> bytes | None:
    """The body a case sends (see the corpus's header)."""
    if spec == "-":
        return None
    kind, _, arg = spec.partition(":")
    if kind == "@bytes":
        return json.dumps({"toml": "x" * int(arg)}).encode()
    if kind == "@nested_json":
        depth = int(arg)
        return ('{"mission": ' + "[" * depth + "]" * depth + "}").encode()
    if kind == "@nested_toml":
        depth = int(arg)
        toml = _mission_toml("x = " + "[" * depth + "]" * depth + "\n")
        return json.dumps({"toml": toml}).encode()
    if kind == "@legs":
        n, seconds = (float(v) for v in arg.split(","))
        legs = [{"type": "hold", "duration_s": seconds, "timeout_s": seconds}] * int(n)
        mission = {
            "format_version": 1,
            "name": "many legs",
            "setup": {"params": "full-scale", "depth_m": 100.0},
            "legs": legs,
        }
        return json.dumps({"mission": mission}).encode()
    if kind == "@raw":
        return arg.encode()
    return spec.encode()


def request_body(spec: str) -> tuple[bytes | Iterator[bytes] | None, dict[str, str]]:
    """(content, headers) of a case: JSON, but @text:TEXT goes as text/plain and
    @chunked:N as N bytes of JSON string in 8 kB chunks with no declared length."""
    kind, _, arg = spec.partition(":")
    if kind == "@text":
        return arg.encode(), {"content-type": "text/plain"}
    json_type = {"content-type": "application/json"}
    if kind == "@chunked":
        whole = json.dumps({"toml": "x" * int(arg)}).encode()
        return (whole[i : i + 8192] for i in range(0, len(whole), 8192)), json_type
    content = body_bytes(spec)
    return content, json_type if content is not None else {}


CASES = read_corpus()


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory):
    settings = ConsoleSettings(
        port=0,
        view=False,
        token=TOKEN,
        instructor_token=INSTRUCTOR,
        winch_token=WINCH,
        supervisor_token=SUPERVISOR,
        recordings_dir=tmp_path_factory.mktemp("rec"),
        speed=2.0,
    )
    with serve_in_thread(settings) as running:
        yield running


def test_the_corpus_is_readable_and_covers_the_issue():
    assert len(CASES) >= 40
    assert {c.status for c in CASES} >= {400, 401, 404, 409, 413, 422}


def test_every_bad_request_gets_its_status_and_words_and_the_loop_goes_on(served):
    headers = {
        "token": {"Authorization": f"Bearer {TOKEN}"},
        "wrong": {"Authorization": "Bearer not-the-token-at-all"},
        "instructor": {"Authorization": f"Bearer {INSTRUCTOR}"},
        "winch": {"Authorization": f"Bearer {WINCH}"},
        "supervisor": {"Authorization": f"Bearer {SUPERVISOR}"},
        "none": {},
    }
    problems = []
    with httpx.Client(base_url=served.base_url, timeout=60.0) as client:
        t0 = client.get("/api/health").json()["t_s"]
        for case in CASES:
            content, extra = request_body(case.body)
            r = client.request(
                case.method, case.path, content=content, headers={**headers[case.auth], **extra}
            )
            text = r.text
            missing = [w for w in case.words if w not in text]
            if r.status_code != case.status or missing:
                problems.append(
                    f"{case.label}: got {r.status_code}, missing {missing}: {text[:200]}"
                )
            if len(text) > 20_000:
                problems.append(f"{case.label}: answer of {len(text)} bytes echoes the input")
        time.sleep(0.5)
        health = client.get("/api/health")
        faults = client.get("/api/faults", headers=headers["instructor"]).json()
    assert not problems, "\n".join(problems)
    assert faults["active"] == [] and faults["scheduled"] == [], "no bad request left a fault"
    assert health.status_code == 200 and health.json()["status"] == "ok"
    assert health.json()["t_s"] > t0, "the loop is still stepping"


def test_a_host_header_not_naming_the_server_is_refused(served):
    with httpx.Client(base_url=served.base_url, timeout=10.0) as client:
        r = client.get("/api/state", headers={"Host": "evil.example:8000"})
        assert r.status_code == 400 and "Invalid host header" in r.text
        assert client.get("/api/state", headers={"Host": "localhost"}).status_code == 200
