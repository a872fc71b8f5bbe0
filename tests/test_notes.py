"""Notes on the timeline: made live by whoever has unlocked the controls or by the
instructor (into the recording, as events), added in review beside a finished recording
(its bytes untouched), listed and exported by ``rov-console log notes``, shown in the
debrief; bad notes get an error naming what is wrong."""

from __future__ import annotations

import csv
import hashlib
import json
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from app.console import ConsoleSettings
from app.recording.notes import read_notes, side_file
from app.report import debrief, render_html
from app.server import create_app
from tests.cli import cli

TOKEN = "notes-token-0123456789"
INSTRUCTOR = "teach-notes-8"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
TEACH = {"Authorization": f"Bearer {INSTRUCTOR}"}


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[TestClient, Path, dict]]:
    """A console that recorded a short stretch with two live notes: (client, the recording,
    the answers to the two notes)."""
    rec_dir = tmp_path_factory.mktemp("notes")
    settings = ConsoleSettings(
        view=False, token=TOKEN, instructor_token=INSTRUCTOR, speed=10.0, recordings_dir=rec_dir
    )
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as client:
        name = client.post("/api/recordings/start", json={"label": "notes"}, headers=AUTH).json()[
            "name"
        ]
        time.sleep(1.0)
        first = client.post(
            "/api/notes", json={"text": "silt cloud, lost the view", "author": "Anna"}, headers=AUTH
        )
        time.sleep(1.0)
        second = client.post("/api/notes", json={"text": "winch slip"}, headers=TEACH)
        time.sleep(0.5)
        assert client.post("/api/recordings/stop", headers=AUTH).status_code == 200
        assert first.status_code == 200 and second.status_code == 200, (first.text, second.text)
        yield client, rec_dir / name, {"first": first.json(), "second": second.json()}


def test_live_notes_are_in_the_recording_with_author_and_time(session) -> None:
    _, path, answers = session
    notes = read_notes(path)
    assert [(n.text, n.source) for n in notes] == [
        ("silt cloud, lost the view", "live"),
        ("winch slip", "live"),
    ]
    assert notes[0].author == "Anna"
    assert notes[1].author == answers["second"]["author"] != ""
    assert notes[0].t_s == pytest.approx(answers["first"]["t_s"], abs=0.6)
    assert notes[0].t_s < notes[1].t_s


@pytest.mark.parametrize(
    "body, words",
    [
        ({"text": "   "}, "text must not be empty"),
        ({"text": "x" * 501}, "text must be at most 500 characters, got 501"),
        ({"text": "bell \u0007 here"}, "text must not hold control characters, got U+0007"),
        ({"text": "right\u202eto left"}, "U+202E"),
        ({"text": "ok", "author": "\n"}, "author must not be empty"),
    ],
)
def test_a_bad_note_is_refused_naming_what_is_wrong(session, body: dict, words: str) -> None:
    client, _, _ = session
    r = client.post("/api/notes", json=body, headers=AUTH)
    assert r.status_code == 422 and words in r.json()["detail"], r.text


def test_a_note_needs_the_console_or_the_instructors_token(session) -> None:
    client, _, _ = session
    assert client.post("/api/notes", json={"text": "hello"}).status_code == 401
    r = client.post("/api/notes", json={"text": "hello"}, headers={"Authorization": "Bearer no"})
    assert r.status_code == 401


def test_a_review_note_goes_beside_the_recording_which_stays_as_written(session) -> None:
    client, path, _ = session
    before = hashlib.sha256(path.read_bytes()).hexdigest()
    url = f"/api/recordings/{path.name}/notes"
    r = client.post(url, json={"t_s": 0.5, "text": "look here", "author": "Ben"}, headers=AUTH)
    assert r.status_code == 200 and r.json()["source"] == "review", r.text
    assert hashlib.sha256(path.read_bytes()).hexdigest() == before
    assert side_file(path).is_file()
    listed = client.get(url, headers=AUTH).json()["notes"]
    assert listed[0]["text"] == "look here", "sorted by time: 0.5 s comes first"
    late = client.post(url, json={"t_s": 1e6, "text": "too late"}, headers=AUTH)
    assert late.status_code == 422 and "t_s must be in [0, " in late.json()["detail"]
    assert client.get(url).status_code == 401


def test_log_notes_exports_json_and_csv_and_the_debrief_lists_them(session, tmp_path) -> None:
    _, path, _ = session
    out = tmp_path / "notes.csv"
    done = cli("log", "notes", str(path), "--json", "--csv", str(out))
    assert done.returncode == 0, done.stderr
    listed = json.loads(done.stdout)
    assert {"t_s", "author", "text"} <= set(listed[0])
    assert "silt cloud, lost the view" in [n["text"] for n in listed]
    rows = list(csv.DictReader(out.open()))
    assert [r["text"] for r in rows] == [n["text"] for n in listed]
    page = render_html(debrief(path))
    assert "<h2>Notes</h2>" in page and "silt cloud, lost the view" in page and "Anna" in page


def test_log_notes_adds_in_review_and_refuses_a_bad_one(session) -> None:
    _, path, _ = session
    done = cli("log", "notes", str(path), "--add", "checked", "--at", "1.0", "--author", "Cy")
    assert done.returncode == 0 and "checked" in done.stdout and "[review]" in done.stdout
    bad = cli("log", "notes", str(path), "--add", "", "--at", "1.0")
    assert bad.returncode == 2 and "text must not be empty" in bad.stderr
    no_time = cli("log", "notes", str(path), "--add", "x")
    assert no_time.returncode == 2 and "--add needs --at" in no_time.stderr
