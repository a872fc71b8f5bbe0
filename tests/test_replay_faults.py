"""A replay shows the thrusters the instructor killed or weakened (left open since issue 47's
wave: "a killed thruster is not shown as killed in a replay (faults are events, not state)").
The recording holds each injection as an ``instructor`` event with the fault's kind, value,
thruster and its start and duration on the run's clock, and each clearing as another; the
replay lists the faults active or still to come at its moment, in the run going on then."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from app.console import ClearFaults, InjectFault
from app.console.replay import recorded_faults
from app.console.session import Session, prepare_run, station_keeping_mission
from app.console.snapshot import LoopStats
from app.console.viewer_replay import ViewerReplay
from app.recording import SessionData, load_session
from web.status import thruster_states

STATS = LoopStats(0.01, 0.0, 0.0, 0, 0, 0.0)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> SessionData:
    """Station keeping at model scale, recorded: T2 lost from 10 s for 30 s, T3 weakened to
    40 % from 20 s for 100 s, both cleared at 35 s; at 40 s a new run, in which T1 is lost
    from its own 5 s for 20 s."""
    out = tmp_path_factory.mktemp("replay-faults")
    session = Session(prepare_run(station_keeping_mission("model-scale", 100.0), False), out)
    loop = SimpleNamespace(session=session)  # what the commands change (``LoopControls``)
    try:
        name = session.start_recording("faults")
        session.advance(1000)
        InjectFault("thruster_lost", 30.0, thruster=2).apply(loop)  # type: ignore[arg-type]
        InjectFault("thruster_weakened", 100.0, 0.4, 20.0, 3).apply(loop)  # type: ignore[arg-type]
        session.advance(2500)
        ClearFaults().apply(loop)  # type: ignore[arg-type]
        session.advance(500)
        session.replace_run(prepare_run(station_keeping_mission("model-scale", 100.0), False))
        session.advance(500)
        InjectFault("thruster_lost", 20.0, thruster=1).apply(loop)  # type: ignore[arg-type]
        session.advance(1000)
        session.stop_recording()
    finally:
        session.close()
    return load_session(out / name)


def _states_at(viewer: ViewerReplay, live, t_s: float) -> dict[int, str]:
    viewer.seek(t_s)
    return thruster_states(viewer.snapshot(live))


def test_the_replay_shows_the_thrusters_as_the_console_did(recorded: SessionData, tmp_path) -> None:
    data = recorded
    session = Session(prepare_run(station_keeping_mission("model-scale", 100.0), False), tmp_path)
    try:
        live = session.snapshot(1, False, 1.0, STATS)
    finally:
        session.close()
    viewer = ViewerReplay("faults.mcap", data, live, 1)
    second = float(data.runs[1]["start_t_s"])
    # 4 000 steps of 10 ms before it; within a row of the recorder's (at most 0.1 s apart)
    assert second == pytest.approx(40.0, abs=0.1)
    assert _states_at(viewer, live, 5.0) == {}
    assert _states_at(viewer, live, 15.0) == {2: "killed"}
    assert _states_at(viewer, live, 25.0) == {2: "killed", 3: "weakened to 40 %"}
    assert _states_at(viewer, live, 37.0) == {}, "cleared at 35 s"
    assert _states_at(viewer, live, second + 2.0) == {}, "a new run has none"
    assert _states_at(viewer, live, second + 10.0) == {1: "killed"}, "on its own clock"
    assert _states_at(viewer, live, second + 14.0) == {1: "killed"}


def test_the_listed_faults_are_the_ones_active_or_to_come_then(recorded: SessionData) -> None:
    """The instructor's list at 15 s: T2 lost (active), T3 weakened (scheduled from 20 s), in
    the console's words."""
    texts = [(f.state, f.text) for f in recorded_faults(recorded, 15.0)]
    assert texts == [
        ("active", "thruster lost 2 from 10 s for 30 s"),
        ("scheduled", "thruster weakened 3 0.4 factor from 20 s for 100 s"),
    ]


def test_an_event_that_makes_no_fault_is_passed_over() -> None:
    """Another tool's instructor event, or a damaged one, lists nothing and breaks nothing."""
    good = {"kind": "thruster_lost", "start_s": 1.0, "duration_s": 5.0, "thruster": 2}
    events = [
        {"t_s": 1.0, "kind": "instructor", "text": "?", "data": {"kind": "gremlins"}},
        {"t_s": 1.0, "kind": "instructor", "text": "?", "data": {**good, "thruster": "two"}},
        {"t_s": 1.0, "kind": "instructor", "text": "?", "data": "not a dict"},
        {"t_s": 1.0, "kind": "instructor", "text": "?", "data": {**good, "duration_s": -1}},
        {"t_s": 1.0, "kind": "instructor", "text": "fault injected", "data": good},
    ]
    empty = np.zeros(0)
    data = SessionData({}, [], empty, np.zeros((0, 0)), events, True, {}, math.nan)
    assert [f.text for f in recorded_faults(data, 2.0)] == ["thruster lost 2 from 1 s for 5 s"]
