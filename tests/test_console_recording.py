"""A console recording carries what a headless ``run --log`` does (issue 47, item 19): a
mission started after the recording began has its set-up written when it starts (a ``run.N``
metadata record) and its own events (legs, landings) at their times, so the debrief of the
console's file says what the headless run's says."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from app.console.session import Session, prepare_run, station_keeping_mission
from app.headless import drive, open_recorder
from app.recording import load_session
from app.report import Debrief, debrief, write_report
from missions import schema
from missions.driver import MissionDriver
from missions.setup import build_simulation

MISSION = "full-docking-current-0.3"
BEFORE_STEPS = 2000
"""Station keeping recorded before the mission starts (20 s)."""


@pytest.fixture(scope="module")
def headless(tmp_path_factory: pytest.TempPathFactory) -> Debrief:
    """``rov-console run MISSION --log`` (its loop and recorder, in this process)."""
    path = tmp_path_factory.mktemp("headless") / "run.mcap"
    spec = schema.load_mission(MISSION)
    sim = build_simulation(spec)
    recorder = open_recorder(str(path), spec, sim, None)
    try:
        drive(MissionDriver(spec, sim), recorder)
    finally:
        recorder.close()
    return debrief(path)


@pytest.fixture(scope="module")
def console(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Session]:
    """Record, hold station, start the mission, run it to its end at full speed, stop."""
    out = tmp_path_factory.mktemp("console")
    session = Session(prepare_run(station_keeping_mission("full-scale", 400.0), False), out)
    name = session.start_recording("debrief")
    session.advance(BEFORE_STEPS)
    session.replace_run(prepare_run(schema.load_mission(MISSION), True))
    while session.mission_status.state == "running":
        session.advance(500)
    assert session.mission_status.state == "completed"
    session.advance(300)  # the console holds station after the mission
    session.stop_recording()
    for _ in range(200):  # the mission is scored on the session's worker thread
        if session._mission_result().result is not None:
            break
        time.sleep(0.05)
    session.close()
    return out / name, session


def test_the_recording_holds_each_runs_set_up(console: tuple[Path, Session]) -> None:
    path, _ = console
    data = load_session(path)
    assert [r["mission_name"] for r in data.runs] == ["station keeping", MISSION]
    assert [r["legs_run"] for r in data.runs] == [False, True]
    assert data.runs[0]["docking_frame"] is None, "station keeping has no frame"
    start = data.runs[1]["start_t_s"]
    assert start == pytest.approx(BEFORE_STEPS * 0.01, abs=0.02)
    assert data.run_at(start + 1.0) is data.runs[1] and data.run_at(1.0) is data.runs[0]
    assert data.runs[1]["current"]["speed_mps"] == pytest.approx(0.3)
    kinds = {e["kind"] for e in data.events}
    assert {"leg", "landing", "dock"} <= kinds


def test_debrief_of_a_console_recording_matches_the_headless_runs(
    console: tuple[Path, Session], headless: Debrief
) -> None:
    """Title, landings, frame, legs and figures as the headless run's; the rows are the
    mission's (from where it started in the recording), and the leg marks fall on the
    recorded leg starts. The console's run steps in ticks of 500 (a run does not depend on
    how its time is cut), but its rows before the mission are not the headless run's: the
    figures agree to the recording's 20 Hz decimation (measured: 4 decimals)."""
    path, _ = console
    d = debrief(path)
    assert d.name == headless.name == MISSION
    assert len(d.landings) == len(headless.landings) == 1
    assert d.landings[0] == headless.landings[0]
    assert d.docking is not None and headless.docking is not None
    np.testing.assert_allclose(d.docking[0].center_n, headless.docking[0].center_n)
    assert d.docking[0].heading_rad == pytest.approx(headless.docking[0].heading_rad)

    t = d.result.log.t_s if d.result.log is not None else np.zeros(0)
    data = load_session(path)
    start = data.runs[1]["start_t_s"] - data.run_offset_s(1)
    assert t[0] == pytest.approx(start, abs=0.06), "rows from the mission's start"
    # one clock (issue 47 item 22): the run's own time, as the console showed it and as the
    # headless run records it, not the recording's (20 s of station keeping came first)
    assert t[0] == pytest.approx(headless.result.log.t_s[0], abs=0.06)
    assert data.runs[1]["start_t_s"] > t[0] + 19.0
    theirs_at = {e["kind"]: e["t_s"] for e in headless.events if e["kind"] in ("landing", "dock")}
    ours_at = {e["kind"]: e["t_s"] for e in d.events if e["kind"] in ("landing", "dock")}
    for kind, when in theirs_at.items():
        assert ours_at[kind] == pytest.approx(when, abs=0.06), kind
    ours, theirs = d.result.legs, headless.result.legs
    assert [(leg.index, leg.type, leg.name) for leg in ours] == [
        (leg.index, leg.type, leg.name) for leg in theirs
    ]
    for a, b in zip(ours, theirs, strict=True):
        assert a.start_s == pytest.approx(b.start_s, abs=0.06)
        assert a.duration_s == pytest.approx(b.duration_s, abs=0.06)
        assert a.rms_north_m == pytest.approx(b.rms_north_m, rel=0.02)
        assert a.rms_heading_deg == pytest.approx(b.rms_heading_deg, rel=0.02)
    leg_events = [e["t_s"] for e in d.events if e["kind"] == "leg"]
    marks = [t[0] + leg.start_s for leg in ours]
    np.testing.assert_allclose(marks, leg_events, atol=0.06)
    assert d.result.rms_north_m == pytest.approx(headless.result.rms_north_m, rel=0.02)
    assert len(d.runs) == 2 and "station keeping" in d.runs[0] and MISSION in d.runs[1]


def test_the_console_scores_what_the_debrief_scores(console: tuple[Path, Session]) -> None:
    """The mission's own result (stored in the scores) and the debrief of its recording."""
    path, session = console
    summary = session.mission_status.result or {}
    d = debrief(path)
    dock = next(leg for leg in summary["legs"] if leg["type"] == "dock")
    ours = next(leg for leg in d.result.legs if leg.type == "dock")
    assert ours.duration_s == pytest.approx(dock["duration_s"], abs=0.06)
    assert ours.rms_north_m == pytest.approx(dock["rms_north_m"], rel=0.02)


def test_the_report_page_says_which_run_it_is_of(
    console: tuple[Path, Session], tmp_path: Path
) -> None:
    path, _ = console
    out = tmp_path / "report.html"
    write_report(path, out)
    page = out.read_text()
    assert f"<h1>Debrief: {MISSION}</h1>" in page
    assert "several runs" in page and "<li>none</li>" not in page


def test_alarms_on_when_a_recording_starts_are_in_it(tmp_path: Path) -> None:
    """Defect (issue 47): only an alarm's changes were written, so an alarm already on when
    the recording started was missing from it (its replay and debrief) until it went off.
    The recording now starts with an event for each alarm on, which its replay shows."""
    from app.console.replay import Replay, recorded_alarms
    from app.console.snapshot import LoopStats

    session = Session(prepare_run(station_keeping_mission("model-scale", 100.0), False), tmp_path)
    try:
        session.sim.set_target(5.0, 0.0, 0.0)  # far from the reference: a position error
        for _ in range(40):
            session.advance(100)
            if any(a.active for a in session.monitor.state):
                break
        on = {a.name: a.message for a in session.monitor.state if a.active}
        assert on, "an alarm is on before the recording starts"
        name = session.start_recording("alarms")
        session.advance(200)
        session.stop_recording()
        live = session.snapshot(1, False, 1.0, LoopStats(0.01, 0.0, 0.0, 0, 0, 0.0))
    finally:
        session.close()
    data = load_session(tmp_path / name)
    events = [e for e in data.events if e["kind"] == "alarm" and e["data"].get("on_at_start")]
    assert {e["data"]["name"] for e in events} == set(on)
    start = float(data.rows[0, 0])
    assert all(e["t_s"] <= start for e in events), "at the recording's first moment"
    shown = recorded_alarms(data.events, float(data.runs[0]["start_t_s"]), start)
    assert {a.name for a in shown if a.active} == set(on)
    replay = Replay(name, data, live.scene, 0.01)
    assert {a.name for a in replay.alarms if a.active} == set(on), "shown from its start"


def test_a_console_recordings_log_times_are_the_wall_clocks(tmp_path: Path) -> None:
    """Issue 47 item 22: a console recording's log times were its start plus the simulated
    time, so a run at 5x stamped its messages minutes into the future in a reviewer's tool
    (Foxglove, the mcap CLI order and show messages by log time). They are now the wall clock
    when each row was simulated (spread over its tick, one time a row) and each event
    happened; the messages keep their simulation time, and the product's readers read the
    rows, events and time range as before."""
    from mcap.reader import make_reader

    from app.recording import check_session

    session = Session(prepare_run(station_keeping_mission("model-scale", 100.0), False), tmp_path)
    try:
        before_ns = time.time_ns()
        name = session.start_recording("wall")
        for _ in range(20):  # 10 s simulated in a fraction of a second: far faster than 5x
            session.advance(50)
        session.note("command", "pause", {})
        session.stop_recording()
        after_ns = time.time_ns()
    finally:
        session.close()
    path = tmp_path / name
    with path.open("rb") as f:
        stamps = [(ch.topic, m.log_time) for _, ch, m in make_reader(f).iter_messages()]
    times = [t for _, t in stamps]
    assert before_ns <= min(times) and max(times) <= after_ns, "none in the future"
    rows = [t for topic, t in stamps if topic == "/session/log"]
    assert rows == sorted(rows) and len(set(rows)) == len(rows), "a time a row, in order"
    data = load_session(path)
    assert data.t_s[-1] - data.t_s[0] > 9.0, "the rows keep their simulation time"
    assert not np.isnan(data.rows).any(), "every row whole: its channels joined by log time"
    assert data.end_time_s == pytest.approx(data.t_s[-1], abs=0.05)
    report = check_session(path)
    start_s, end_s = report["time_range_s"]
    assert start_s == pytest.approx(data.t_s[0], abs=0.05)
    assert end_s == pytest.approx(data.t_s[-1], abs=0.05)
