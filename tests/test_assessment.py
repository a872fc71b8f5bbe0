"""The assessment (issue 46): criteria files validated field by field, a score that falls as
a figure grows past its limit, the logbook entry of a recorded landing as CSV and PDF, a
trainee's trend, and the instructor's criteria route behind the instructor token.

One recording of a short full-scale docking (the library's full-docking-current-0.3 with a
shorter hold, the frame under the crane tip and a weaker current: 310 s simulated) is made
for the module, and one logbook entry of it read as CSV and PDF."""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from fastapi.testclient import TestClient
from hypothesis import given
from hypothesis import strategies as st

from app import assessment as asmt
from app import scores
from app.console import ConsoleSettings
from app.logbook import CSV_COLUMNS
from app.server import create_app
from tests.cli import cli

TRAINEE = "Anna Berg"
TOKEN = "assessment-test-console-1"
INSTRUCTOR = "assessor-token-8"


MISSION = "short-docking"
STRICT = "[criteria.time_to_land]\nlimit = 100\nzero_at = 400\n"
"""Criteria that ask for a landing within 100 s of the dock leg's start."""


def short_docking(folder: Path) -> Path:
    from missions.campaign import resolve_mission

    data = resolve_mission("full-docking-current-0.3").model_dump(mode="json", exclude_none=True)
    data["name"] = MISSION
    data["setup"]["depth_m"] = 395.0
    data["setup"]["current"]["speed_mps"] = 0.1
    data["setup"]["docking_frame"].update(center_ne_m=[1.5, 1.5], heading_deg=0.0)
    data["legs"][0]["duration_s"] = 30.0
    path = folder / "short-docking.toml"
    path.write_text(tomli_w.dumps(data))
    return path


@pytest.fixture(scope="module")
def landed(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """One automatic landing, recorded and stored under a trainee."""
    folder = tmp_path_factory.mktemp("landing")
    log, db = folder / "dock.mcap", folder / "scores.sqlite"
    done = cli(
        "run",
        str(short_docking(folder)),
        "--json",
        "--no-progress",
        "--log",
        str(log),
        "--trainee",
        TRAINEE,
        "--scores-db",
        str(db),
    )
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    return {"log": log, "db": db, "summary": summary, "folder": folder}


@pytest.fixture(scope="module")
def entry(landed: dict) -> dict:
    """The recording's logbook entry, PDF and CSV, with criteria that ask for a quicker
    landing than the autopilot's."""
    folder = landed["folder"]
    (folder / "strict.toml").write_text(STRICT)
    pdf, table = folder / "entry.pdf", folder / "entry.csv"
    done = cli(
        "logbook",
        str(landed["log"]),
        "-o",
        str(pdf),
        "--csv",
        str(table),
        "--criteria",
        str(folder / "strict.toml"),
    )
    assert done.returncode == 0, done.stderr
    return {"pdf": pdf, "csv": table, "stdout": done.stdout}


# --- criteria files ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "words"),
    [
        (
            "[criteria.landing_miss]\nweight = 500",
            "criteria.landing_miss.weight: 500 is outside 0 to 100",
        ),
        ("[criteria.time_saturated]\nlimit = -1", "criteria.time_saturated.limit: -1 is below 0 s"),
        (
            "[criteria.time_saturated]\nlimit = 99999",
            "criteria.time_saturated.limit: 99999 s is outside 0 to 3600 s",
        ),
        (
            "[criteria.time_to_land]\nlimit = 600\nzero_at = 300",
            "criteria.time_to_land.zero_at: 300 s must be above the limit (600 s)",
        ),
        (
            "[criteria.landing_mis]\nweight = 1",
            "criteria.landing_mis: no such criterion (one of landing_miss",
        ),
        ("[criteria.slack_events]\nlimt = 1", "criteria.slack_events.limt: not a field"),
        ("format_version = 2", "format_version: 2 is not 1"),
        ("[criteria.landing_miss\n", "not TOML"),
    ],
)
def test_a_bad_criteria_file_names_the_field_and_its_range(text: str, words: str) -> None:
    with pytest.raises(asmt.CriteriaError) as err:
        asmt.parse_criteria_text(text, "mine.toml")
    assert "mine.toml" in str(err.value) and words in str(err.value)


def test_the_command_line_refuses_a_bad_file_and_prints_a_good_one(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[criteria.contact_speed]\nweight = -2\n")
    done = cli("criteria", "--check", str(bad))
    assert done.returncode == 2
    assert "criteria.contact_speed.weight: -2 is outside 0 to 100" in done.stderr
    good = tmp_path / "good.toml"
    good.write_text("[criteria.time_to_land]\nlimit = 300\nweight = 4\n")
    printed = cli("criteria", "--check", str(good)).stdout
    again = asmt.parse_criteria_text(printed)
    (c,) = [c for c in again if c.name == "time_to_land"]
    assert (c.limit, c.zero_at, c.weight) == (300.0, 2400.0, 4.0)


def test_the_defaults_written_as_a_file_read_back_the_same() -> None:
    defaults = asmt.default_criteria()
    assert asmt.parse_criteria_text(defaults.to_toml()) == defaults


# --- scores --------------------------------------------------------------------------------


@given(
    limit=st.floats(0.0, 10.0),
    span=st.floats(0.01, 10.0),
    a=st.floats(0.0, 30.0),
    b=st.floats(0.0, 30.0),
)
def test_a_score_never_rises_with_the_value(limit: float, span: float, a: float, b: float) -> None:
    lo, hi = sorted((a, b))
    s_lo = asmt.criterion_score(lo, limit, limit + span)
    s_hi = asmt.criterion_score(hi, limit, limit + span)
    assert 0.0 <= s_hi <= s_lo <= 100.0
    if lo <= limit:
        assert s_lo == 100.0
    if hi >= limit + span:
        assert s_hi == 0.0


def test_the_landing_score_falls_as_the_miss_grows_past_the_capture_tolerance() -> None:
    """Full scale: capture tolerance 0.35 - 0.10 = 0.25 m (the parameter set's funnel mouth
    less its post), 0 at twice that."""
    from sim import params

    layout = params.load("full-scale").spec.docking.to_numeric()
    crit = asmt.default_criteria()
    by_miss = []
    for miss in (0.05, 0.25, 0.30, 0.40, 0.49, 0.60):
        a = asmt.assess({"landing_miss": miss, "contact_speed": 0.03}, crit, layout)
        (c,) = [c for c in a.criteria if c.name == "landing_miss"]
        assert c.limit == pytest.approx(0.25)
        by_miss.append((c.score, a.total))
    scores_ = [s for s, _ in by_miss]
    assert scores_[:2] == [100.0, 100.0], "within the tolerance: full marks"
    assert scores_[2] > scores_[3] > scores_[4] > 0.0, "falls past the limit"
    assert scores_[5] == 0.0, "a funnel on the post top: nothing"
    assert scores_[2] == pytest.approx(80.0), "linear: 0.05 m past a 0.25 m span"
    totals = [t for _, t in by_miss]
    assert totals == sorted(totals, reverse=True) and totals[0] > totals[-1]
    assert math.isclose(totals[-1], 100.0 * 2 / 5), "miss weighs 3 of the 5 judged"


def test_a_landing_never_reached_scores_nothing_and_other_missions_are_not_judged() -> None:
    crit = asmt.default_criteria()
    a = asmt.assess({"landing_miss": math.inf, "time_saturated": 0.0}, crit, None)
    assert a.criteria[0].score is None, "no frame: the capture tolerance is not known"
    limits = asmt.FrameLimits(0.25, 0.1)
    a = asmt.assess({"landing_miss": math.inf, "time_saturated": 0.0}, crit, limits)
    assert a.criteria[0].score == 0.0 and a.criteria[0].value_text() == "not landed"
    assert a.total == pytest.approx(100.0 * 1 / 4)
    none = asmt.assess({"time_saturated": 45.0}, crit, limits)
    assert [c.name for c in none.criteria if c.score is not None] == ["time_saturated"]
    assert none.total == pytest.approx(100.0 * 75 / 90)


def test_slack_episodes_are_counted_below_a_tenth_of_the_static_tension() -> None:
    w0 = 1000.0
    tension = [1000, 900, 99, 50, 120, 1000, 80, 1100, 101]
    assert asmt.slack_episodes(tension, w0) == 2


def test_the_longest_alarm_is_timed_from_on_to_off_or_the_end() -> None:
    def ev(t: float, name: str, active: bool) -> dict:
        return {"t_s": t, "kind": "alarm", "data": {"name": name, "active": active}}

    events = [ev(10, "saturation", True), ev(14, "saturation", False), ev(20, "dropout", True)]
    assert asmt.longest_alarm_s(events, 100.0) == 80.0
    assert asmt.longest_alarm_s(events[:2], 100.0) == 4.0
    assert asmt.longest_alarm_s([], 100.0) is None, "no alarm states recorded: not judged"


# --- the logbook ---------------------------------------------------------------------------


def _rows(text: str) -> list[dict]:
    return list(csv.DictReader(io.StringIO(text)))


def test_the_logbook_csv_has_each_criterion_with_its_limit_weight_value_and_score(
    landed: dict, entry: dict
) -> None:
    text = entry["csv"].read_text()
    assert text.splitlines()[0].split(",") == list(CSV_COLUMNS)
    rows = _rows(text)
    assert [r["criterion"] for r in rows] == [d.name for d in asmt.DEFINITIONS] + ["total"]
    assert {r["trainee"] for r in rows} == {TRAINEE}, "from the scores database beside it"
    assert {r["mission"] for r in rows} == {MISSION}
    assert {r["recording"] for r in rows} == {"dock.mcap"}
    by = {r["criterion"]: r for r in rows}
    (landing,) = landed["summary"]["landings"]
    miss = by["landing_miss"]
    assert float(miss["value"]) == pytest.approx(landing["miss_m"], rel=1e-5)
    assert (float(miss["limit"]), float(miss["weight"]), float(miss["score"])) == (0.25, 3.0, 100.0)
    speed = by["contact_speed"]
    assert float(speed["value"]) == pytest.approx(abs(landing["contact_speed_mps"]), rel=1e-5)
    assert float(speed["limit"]) == 0.1
    assert float(by["time_saturated"]["value"]) == 0.0
    assert float(by["slack_events"]["value"]) == 0.0
    to_land = by["time_to_land"]
    contact_s = landing["t_contact_s"] - 30.0  # the dock leg starts after a 30 s hold
    assert float(to_land["value"]) == pytest.approx(contact_s, abs=0.05), "20 rows a second"
    assert (float(to_land["limit"]), float(to_land["zero_at"])) == (100.0, 400.0), "the file's"
    assert float(to_land["score"]) == pytest.approx(100 * (400 - contact_s) / 300, abs=0.1)
    assert all(
        float(r["score"]) == 100.0
        for r in rows
        if r["criterion"] != "time_to_land" and r["score"] and r["criterion"] != "total"
    )
    weights = {r["criterion"]: float(r["weight"]) for r in rows[:-1] if r["score"]}
    total = sum(w * float(by[n]["score"]) for n, w in weights.items()) / sum(weights.values())
    assert float(by["total"]["score"]) == pytest.approx(total, abs=0.05)
    for r in rows:
        assert r["instructor"] == r["signature"] == r["signed_date"] == r["remarks"] == ""


def test_the_logbook_pdf_is_a_pdf_with_the_criteria_and_sign_off(entry: dict) -> None:
    from pypdf import PdfReader

    data = entry["pdf"].read_bytes()
    assert data.startswith(b"%PDF-")
    reader = PdfReader(io.BytesIO(data))
    assert len(reader.pages) == 1
    text = reader.pages[0].extract_text()
    for words in (
        "ROV pilot logbook",
        TRAINEE,
        MISSION,
        "landing miss",
        "contact speed",
        "time off the funnels' tolerance",
        "time saturated",
        "slack-wire events",
        "longest alarm before cleared",
        "time to land",
        "Weighted total",
        "Instructor's name",
        "Signature",
        "Remarks",
    ):
        assert words in text, words
    assert f"{TRAINEE}, {MISSION}: total" in entry["stdout"]


def test_the_logbook_needs_an_output(landed: dict) -> None:
    done = cli("logbook", str(landed["log"]))
    assert done.returncode == 2 and "give -o FILE.pdf, --csv FILE.csv or both" in done.stderr


# --- the trend -----------------------------------------------------------------------------


def test_the_trend_rescores_the_stored_runs_with_the_criteria_in_force(landed: dict) -> None:
    db = landed["db"]
    points = scores.trend(db, TRAINEE, asmt.default_criteria())
    assert len(points) == 1 and points[0].total == 100.0
    assert points[0].scores["slack_events"] == 100.0, "measured with the run's own tree"
    strict = asmt.parse_criteria_text(STRICT)
    (again,) = scores.trend(db, TRAINEE, strict)
    assert again.scores["time_to_land"] is not None and again.scores["time_to_land"] < 100.0
    assert again.total is not None and again.total < 100.0
    shown = cli("trend", TRAINEE, "--db", str(db))
    assert shown.returncode == 0 and MISSION in shown.stdout


# --- the instructor's route ----------------------------------------------------------------


@pytest.fixture(scope="module")
def client(landed: dict) -> Iterator[TestClient]:
    settings = ConsoleSettings(
        view=False,
        token=TOKEN,
        instructor_token=INSTRUCTOR,
        paused=True,
        recordings_dir=landed["folder"],
    )
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        yield c


def test_only_the_instructor_changes_the_criteria(client: TestClient, landed: dict) -> None:
    body = {"criteria": {"time_to_land": {"limit": 120.0, "weight": 2.0}}}
    assert client.put("/api/assessment/criteria", json=body).status_code == 401
    console = {"Authorization": f"Bearer {TOKEN}"}
    refused = client.put("/api/assessment/criteria", json=body, headers=console)
    assert refused.status_code == 403 and "instructor token" in refused.json()["detail"]
    assert client.get("/api/assessment/criteria").json()["source"] == "default"
    assert not (landed["folder"] / asmt.CRITERIA_FILE).exists()
    teach = {"Authorization": f"Bearer {INSTRUCTOR}"}
    bad = client.put(
        "/api/assessment/criteria",
        json={"criteria": {"time_to_land": {"weight": 1000.0}}},
        headers=teach,
    )
    assert bad.status_code == 422 and "time_to_land.weight: 1000.0 is outside 0 to 100" in str(
        bad.json()
    )
    done = client.put("/api/assessment/criteria", json=body, headers=teach)
    assert done.status_code == 200, done.text
    got = client.get("/api/assessment/criteria").json()
    assert got["source"] == "instructor"
    (c,) = [c for c in got["criteria"] if c["name"] == "time_to_land"]
    assert (c["limit"], c["weight"]) == (120.0, 2.0)
    trend = client.get("/api/scores/trend", params={"trainee": TRAINEE}).json()
    assert len(trend) == 1 and trend[0]["scores"]["time_to_land"] < 100.0
    assert client.delete("/api/assessment/criteria").status_code == 401
    assert client.delete("/api/assessment/criteria", headers=teach).json()["source"] == "default"


def test_the_logbook_over_http_needs_a_token(client: TestClient) -> None:
    url = "/api/recordings/dock.mcap/logbook"
    assert client.get(url).status_code == 401
    teach = {"Authorization": f"Bearer {INSTRUCTOR}"}
    rows = _rows(client.get(url, params={"format": "csv"}, headers=teach).text)
    assert rows[-1]["criterion"] == "total" and rows[0]["trainee"] == TRAINEE


def test_a_tree_put_down_by_hand_is_judged_where_it_reached_the_posts() -> None:
    """No dock leg (the pilot cannot take over during a mission's legs): the landing is read
    from the rows, where the tree's bottom first reaches the post tops."""
    from control.columns import LAYOUT, N_LOG, LogRows
    from missions.scoring import MissionResult
    from sim.docking import DockingFrame
    from sim.params import load

    ps = load("full-scale")
    layout = ps.spec.docking.to_numeric()
    frame = DockingFrame(np.array([10.0, 5.0]), 0.0, 400.0)
    half_h = float(ps.tree.dimensions_m[2]) / 2.0
    t = np.arange(0.0, 100.0, 0.05)
    data = np.zeros((len(t), N_LOG))
    data[:, LAYOUT.starts["t_s"]] = t
    tree = LAYOUT.starts["tree_eta_n"]
    data[:, tree] = 10.0 + 0.12  # 0.12 m north of the posts
    data[:, tree + 1] = 5.0
    post_top = frame.post_top_depth_m(layout)
    data[:, tree + 2] = post_top - half_h - 2.0 + 0.04 * t  # 0.04 m/s down, 2 m to go
    rows = LogRows(data, 4)
    result = MissionResult("by hand", [], 0, 0, 0, 0, 0.0, None, [0.0] * 6, False, [], {})
    result.log = rows
    facts = asmt.RunFacts(result, [], frame, layout, half_h, None)
    values = asmt.measure(facts)
    assert values["landing_miss"] == pytest.approx(0.12, abs=1e-9)
    assert values["contact_speed"] == pytest.approx(0.04, rel=1e-6)
    assert values["time_to_land"] == pytest.approx(50.0, abs=0.05)
    assert values["time_off_tolerance"] is None, "no dock leg: no reference to land by"
