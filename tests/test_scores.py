"""Scores in the embedded SQLite database: the console stores a mission someone flew under
their name, ``run --trainee`` stores a headless run, ``rov-console scores`` lists them and
picks the best; the stored figures are the mission's own."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest

from app import scores
from app.console import PacedLoop, Session, prepare_run, station_keeping_mission
from missions import schema
from missions.scoring import LandingResult, MissionResult
from tests.cli import cli
from tests.test_console_loop import MOVE


def _result(name: str, miss_m: float | None, rms: float, failed: bool = False) -> MissionResult:
    landings = (
        []
        if miss_m is None
        else [
            LandingResult(not failed, miss_m, 1.5, 0.03, "frame" if not failed else "posts", 42.0)
        ]
    )
    return MissionResult(
        name, [], rms, rms, 1.0, 0.5, 0.0, None, [0.0] * 6, False, [], {}, landings
    )


def test_record_history_and_best_round_trip(tmp_path: Path) -> None:
    db = tmp_path / "s.sqlite"
    a = scores.record(db, "  Anna   Berg ", _result("dock", 0.10, 0.05), "console", "a.mcap")
    b = scores.record(db, "Anna Berg", _result("dock", 0.04, 0.07), "console")
    c = scores.record(db, "Anna Berg", _result("dock", 0.30, 0.01, failed=True), "run")
    scores.record(db, "Bo", _result("square", None, 0.02), "run")
    mine = scores.history(db, "Anna Berg")
    assert [s.id for s in mine] == [c, b, a], "newest first, the name folded as stored"
    assert mine[-1].log_file == "a.mcap" and mine[-1].time_to_dock_s == 42.0
    assert mine[0].passed is False and mine[0].landed is False
    best = scores.best(mine)
    assert [s.id for s in best] == [b], "passed first, then the smallest miss"
    square = scores.history(db, mission="square")[0]
    assert square.landed is None and square.miss_m is None, "no landing: no landing figures"
    with pytest.raises(ValueError, match="trainee: give a name"):
        scores.record(db, "   ", _result("dock", 0.1, 0.1), "run")


def test_a_mission_flown_in_the_console_is_stored_under_the_pilots_name(tmp_path: Path) -> None:
    eng = Session(prepare_run(station_keeping_mission("full-scale", 100.0), False), tmp_path)
    eng.actor = "viewer 4 (Anna)"  # what the loop sets while it applies Anna's StartRun
    eng.replace_run(prepare_run(schema.parse_mission(MOVE), True))
    eng.actor = None
    while eng.mission_status.state == "running":
        eng.advance(500)
    snap = eng.snapshot(1, False, 1.0, PacedLoop(eng).snapshot.stats)
    deadline = time.monotonic() + 10.0
    while snap.mission.result is None and time.monotonic() < deadline:
        time.sleep(0.05)
        snap = eng.snapshot(2, False, 1.0, snap.stats)
    assert snap.mission.result is not None and "score_id" in snap.mission.result
    (row,) = scores.history(tmp_path / "scores.sqlite", "Anna")
    assert row.mission == "loop-test" and row.source == "console"
    assert row.rms_north_m == pytest.approx(snap.mission.result["rms_north_m"], rel=1e-12)


def test_run_with_trainee_stores_and_scores_lists(tmp_path: Path) -> None:
    db = tmp_path / "db.sqlite"
    done = cli(
        "run",
        "model-step-priority",
        "--seed",
        "0",
        "--json",
        "--no-progress",
        "--trainee",
        "Cai",
        "--scores-db",
        str(db),
    )
    assert done.returncode in (0, 1), done.stderr
    summary = json.loads(done.stdout)
    listed = cli("scores", "--db", str(db), "--json")
    (row,) = json.loads(listed.stdout)
    assert row["trainee"] == "Cai" and row["id"] == summary["score_id"]
    assert row["rms_heading_deg"] == pytest.approx(summary["rms_heading_deg"], rel=1e-12)
    table = cli("scores", "--db", str(db), "--trainee", "Cai")
    assert "model-step-priority" in table.stdout and "Cai" in table.stdout
    assert "no scores" in cli("scores", "--db", str(db), "--trainee", "Nobody").stdout


def test_scores_of_a_file_that_is_not_a_database_is_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.sqlite"
    bad.write_text("not a database at all, just text " * 40)
    done = cli("scores", "--db", str(bad))
    assert done.returncode == 2 and "not a scores database" in done.stderr
    assert "Traceback" not in done.stderr


def test_saturation_and_settling_read_every_column_of_their_blocks() -> None:
    """``utilisation_figures`` counts a row as saturated when any thruster is at
    ``SATURATED``, and ``settling_time`` finds the reference's last change in any of its
    three columns: a log whose only saturated thruster is the last one (rows 10-14 and 30)
    and whose only late reference change is the heading's (row 60, the tree following at row
    70) gives 6 rows x 0.1 s saturated and 10 rows x 0.1 s to settle. Exact: both figures
    are a count of rows times dt."""
    from control.columns import LAYOUT, LogRows
    from missions.scoring import SATURATED, settling_time, utilisation_figures

    data = np.zeros((100, LAYOUT.width))
    util = LAYOUT.slice("thruster_utilisation")
    last = util.start + 3  # the fourth of four thrusters
    data[10:15, last] = SATURATED
    data[30, last] = 1.0
    data[:, util.start] = SATURATED - 0.01  # the first thruster busy, never saturated
    ref = LAYOUT.slice("eta_ref_n")
    data[:5, ref.start] = -1.0  # an early change of the north reference (rows 0-4 -> 5)
    data[60:, ref.start + 2] = 0.5  # the heading's reference changes at row 60
    tree = LAYOUT.slice("tree_eta_n")
    data[:70, tree.start + 5] = 0.0  # the tree's heading 0.5 rad off until row 70
    data[70:, tree.start + 5] = 0.5
    rows = LogRows(data, n_thrusters=4)
    umax, sat = utilisation_figures(rows, 0.1)
    assert umax == 1.0
    assert sat == 6 * 0.1  # 6 rows, as the figure is made: a count times dt
    # the heading error (28.6 deg) is outside 2 deg up to row 69: settled from row 70 on,
    # counted from row 60, the reference's last change
    assert settling_time(rows, 0.1, 0.1, 2.0) == 10 * 0.1
