"""Who flew a scored run (``flown_by``: autopilot, hand or mixed, from the share of the log's
time in manual mode), older databases opened without it, ``rov-console scores --compare``
and the API's scores, comparison and debrief, and the page's scores text."""

from __future__ import annotations

import dataclasses
import json
import os
import sqlite3
import time
from contextlib import closing
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from app import scores
from app.cli import app as cli_app
from app.console import ConsoleSettings
from app.console.session import SCORES_DB
from app.server import create_app
from control.columns import LAYOUT, LogRows
from control.simulation import Simulation
from missions.scoring import LandingResult, MissionResult
from sim import params
from web.tabs.scores import report_url, scores_markdown

MODEL = params.load("model-scale")
TOKEN = "scores-test-token-000001"


def cli(*args: str):
    """The command line in this process (this checkout's code, whatever is installed)."""
    return CliRunner().invoke(cli_app, list(args), env={"COLUMNS": "160"})


@pytest.fixture(scope="module")
def log_rows() -> LogRows:
    return Simulation(MODEL, tree_depth_m=100.0).run_for(1.0)  # 100 rows, mode 0 (tree)


def flown(rows: LogRows, manual_rows: int, miss_m: float, name: str = "dock") -> MissionResult:
    """A result whose log has its first ``manual_rows`` rows in manual mode (mode = 2)."""
    data = rows.data.copy()
    data[:manual_rows, LAYOUT.starts["mode"]] = scores.MODE_MANUAL
    landing = LandingResult(True, miss_m, 1.0, 0.02, "frame", 40.0)
    return MissionResult(
        name, [], 0.01, 0.02, 0.5, 0.4, 0.0, None, [0.0] * 6, False, [], {}, [landing],
        log=LogRows(data, rows.n_thrusters),
    )  # fmt: skip


def test_flown_by_is_the_share_of_time_in_manual_mode(log_rows: LogRows, tmp_path: Path):
    db = tmp_path / "s.sqlite"
    cases = ((0, 0.0, "autopilot"), (5, 0.05, "autopilot"), (50, 0.5, "mixed"))
    for manual, share, how in (*cases, (95, 0.95, "hand"), (100, 1.0, "hand")):
        result = flown(log_rows, manual, 0.1)
        assert scores.manual_share(result) == pytest.approx(share)
        scores.record(db, "Anna", result, "console")
        stored = scores.history(db, "Anna")[0]
        assert (stored.manual_share, stored.flown_by) == (pytest.approx(share), how)
    no_log = flown(log_rows, 100, 0.1)
    no_log.log = None
    assert scores.manual_share(no_log) == 0.0, "no log: the autopilot's (no manual mode then)"


def test_a_log_without_a_mode_column_counts_as_autopilot(log_rows: LogRows) -> None:
    result = flown(log_rows, 0, 0.1)

    class NoMode:
        def __len__(self) -> int:
            return 3

        def __getitem__(self, name: str):
            raise KeyError(name)

    result.log = NoMode()  # type: ignore[assignment]
    assert scores.manual_share(result) == 0.0


def test_a_database_from_before_flown_by_is_opened_and_its_runs_are_the_autopilots(
    tmp_path: Path, log_rows: LogRows
) -> None:
    db = tmp_path / "old.sqlite"
    added = (
        ",\n    manual_share REAL NOT NULL DEFAULT 0,"
        "\n    flown_by TEXT NOT NULL DEFAULT 'autopilot'"
    )
    old_schema = scores.SCHEMA.replace(added, "")
    assert "flown_by" not in old_schema
    with closing(sqlite3.connect(db)) as con, con:
        con.execute(old_schema)
        con.execute(
            "INSERT INTO runs (utc, trainee, mission, source, passed, rms_north_m, rms_east_m, "
            "rms_heading_deg, saturated_s) VALUES ('2026-01-01T00:00:00Z', 'Old', 'dock', "
            "'run', 1, 0.1, 0.1, 1.0, 0.0)"
        )
    [old] = scores.history(db)
    assert (old.trainee, old.flown_by, old.manual_share) == ("Old", "autopilot", 0.0)
    scores.record(db, "New", flown(log_rows, 100, 0.2), "console")
    assert [s.flown_by for s in scores.history(db)] == ["hand", "autopilot"]


def test_scores_compare_shows_the_best_hand_and_autopilot_runs_side_by_side(
    tmp_path: Path, log_rows: LogRows
) -> None:
    db = tmp_path / "s.sqlite"
    auto_worse = scores.record(db, "Anna", flown(log_rows, 0, 0.30), "run")
    auto_best = scores.record(db, "Anna", flown(log_rows, 0, 0.05), "run")
    hand_best = scores.record(db, "Anna", flown(log_rows, 100, 0.12), "console")
    scores.record(db, "Anna", flown(log_rows, 100, 0.40), "console")
    scores.record(db, "Anna", flown(log_rows, 100, 0.01, name="other"), "console")
    best = scores.compare(scores.history(db, mission="dock"))
    assert {how: s.id for how, s in best.items()} == {"autopilot": auto_best, "hand": hand_best}
    assert auto_worse not in {s.id for s in best.values()}

    done = cli("scores", "--compare", "dock", "--db", str(db), "--json")
    assert done.exit_code == 0, done.output
    side = json.loads(done.output)
    assert {how: s["miss_m"] for how, s in side.items()} == {"autopilot": 0.05, "hand": 0.12}
    table = cli("scores", "--compare", "dock", "--db", str(db)).output
    assert "best autopilot" in table and "best hand" in table and "0.050" in table
    assert "0.120" in table and "0.300" not in table
    lonely = cli("scores", "--compare", "other", "--db", str(db)).output
    assert "no autopilot run of other yet" in lonely
    listing = cli("scores", "--db", str(db)).output
    assert "flown by" in listing and "hand" in listing


def test_the_api_serves_scores_the_comparison_and_a_recordings_debrief(
    tmp_path: Path, log_rows: LogRows
) -> None:
    scores.record(tmp_path / SCORES_DB, "Anna", flown(log_rows, 0, 0.05), "run")
    scores.record(tmp_path / SCORES_DB, "Anna", flown(log_rows, 100, 0.1), "console", "x.mcap")
    settings = ConsoleSettings(view=False, token=TOKEN, speed=10.0, recordings_dir=tmp_path)
    auth = {"Authorization": f"Bearer {TOKEN}"}
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        mine = c.get("/api/scores", params={"trainee": "Anna"}).json()
        assert [s["flown_by"] for s in mine] == ["hand", "autopilot"]
        side = c.get("/api/scores/compare", params={"mission": "dock"}).json()
        assert set(side) == {"autopilot", "hand"} and side["hand"]["log_file"] == "x.mcap"
        name = c.post("/api/recordings/start", json={"label": "deb"}, headers=auth).json()["name"]
        report = f"/api/recordings/{name}/report"
        assert c.get(report, headers=auth).status_code == 409, "not while written"
        t0 = c.get("/api/state").json()["t_s"]
        while c.get("/api/state").json()["t_s"] < t0 + 5.0:
            time.sleep(0.1)
        assert c.post("/api/recordings/stop", headers=auth).is_success
        page = c.get(report, headers=auth)
        assert page.status_code == 200, page.text
        assert page.headers["content-type"].startswith("text/html")
        assert "<h1>Debrief:" in page.text and "data:image/png;base64" in page.text
        assert c.get("/api/recordings/nothing-here.mcap/report", headers=auth).status_code == 404


def test_a_debrief_needs_a_token_is_written_once_and_one_at_a_time(
    tmp_path: Path, log_rows: LogRows
) -> None:
    """Defect (issue 47, 6): the debrief needed no token and cost 11-17 s each time; six at
    once took 43-52 s and 730 MB. Now: the console or instructor token (or the view's
    ticket), each recording's page kept while its file is unchanged, one written at a time."""
    settings = ConsoleSettings(
        view=False,
        token=TOKEN,
        instructor_token="debrief-instructor",
        speed=10.0,
        recordings_dir=tmp_path,
    )
    auth = {"Authorization": f"Bearer {TOKEN}"}
    app = create_app(settings)
    with TestClient(app, base_url="http://127.0.0.1") as c:
        name = c.post("/api/recordings/start", json={"label": "deb"}, headers=auth).json()["name"]
        t0 = c.get("/api/state").json()["t_s"]
        while c.get("/api/state").json()["t_s"] < t0 + 3.0:
            time.sleep(0.1)
        assert c.post("/api/recordings/stop", headers=auth).is_success
        report = f"/api/recordings/{name}/report"
        anonymous = c.get(report)
        assert anonymous.status_code == 401 and "console token" in anonymous.json()["detail"]
        assert c.get(report, headers={"Authorization": "Bearer wrong-wrong"}).status_code == 401
        cache = app.state.reports
        cache._writing.acquire()  # another report is being written
        try:
            busy = c.get(report, headers=auth)
        finally:
            cache._writing.release()
        assert busy.status_code == 503 and "try again" in busy.json()["detail"]
        assert int(busy.headers["Retry-After"]) > 0
        first = c.get(report, headers=auth)
        assert first.status_code == 200 and cache.written == 1
        instructor = {"Authorization": "Bearer debrief-instructor"}
        assert c.get(report, headers=instructor).text == first.text
        ticket = app.state.console.debrief_ticket()
        assert c.get(report, params={"ticket": ticket}).status_code == 200
        assert c.get(report, params={"ticket": "not-the-ticket"}).status_code == 401
        assert cache.written == 1, "served from the cache while the file is unchanged"
        path = tmp_path / name
        stat = path.stat()
        os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000_000))
        assert c.get(report, headers=auth).status_code == 200 and cache.written == 2


def test_the_pages_scores_text_lists_runs_best_and_debrief_links(
    tmp_path: Path, log_rows: LogRows
) -> None:
    db = tmp_path / "s.sqlite"
    scores.record(db, "Anna", flown(log_rows, 100, 0.1), "console", "a.mcap")
    scores.record(db, "Anna", flown(log_rows, 0, 0.05), "run")
    text = scores_markdown(scores.history(db, "Anna"), "http://127.0.0.1:8000", "Anna")
    # in a tab of its own (issue 47 item 27: the debrief replaced the console's tab, and
    # coming back needed the token again)
    url = report_url("http://127.0.0.1:8000", "a.mcap")
    assert f'<a href="{url}" target="_blank" rel="noopener">report</a>' in text
    assert "latest runs of Anna" in text and "best run of each mission" in text
    best_part = text.split("best run of each mission")[1]
    assert "0.050" in best_part and "autopilot" in best_part and "0.100" not in best_part
    assert "no scores for **Bo** yet" in scores_markdown([], "http://x", "Bo")


def test_the_faults_a_mission_met_are_stored_with_its_score(tmp_path: Path) -> None:
    """Defect: the faults column stayed empty for every run (nobody passed it); now it holds
    the faults the mission's events record."""
    from missions import runner, schema

    text = (
        'format_version = 1\nname = "hold"\n[setup]\nparams = "model-scale"\n'
        'depth_m = 100.0\nfeedback = "ekf"\n[[legs]]\ntype = "hold"\nduration_s = 10.0\n'
        '[[faults]]\nkind = "dvl_lost"\nstart_s = 2.0\nduration_s = 3.0\n'
    )
    mission = schema.parse_text(text, "<test>")
    result = runner.run_mission(mission)
    db = tmp_path / "s.sqlite"
    scores.record(db, "Anna", result, "run")
    assert scores.history(db)[0].faults == "dvl lost from 2 s for 3 s"


def test_the_pages_scores_say_why_a_landed_run_failed(tmp_path: Path, log_rows: LogRows) -> None:
    """Issue 47 item 21, the page's side: a run that landed but failed a criterion, with an
    instructor's fault, reads as a failure with its reasons, not "pass, landed"."""
    db = tmp_path / "s.sqlite"
    scores.record(db, "Anna", flown(log_rows, 100, 0.1), "console", "a.mcap")
    (row,) = scores.history(db, "Anna")
    bad = dataclasses.replace(
        row, criteria_failed="time saturated 122.0 s > 30 s", faults="compass freeze"
    )
    text = scores_markdown([bad], "http://127.0.0.1:8000", "Anna")
    # as page text: Markdown's dot and '>' escaped
    assert "FAIL, faulted, landed: time saturated 122\\.0 s &gt; 30 s" in text
    assert "| pass" not in text
