"""A replay shows what happened (issue 47, item 20): in a recording started before the
mission, the replay showed the start-up scene all through (a frame under the tree at 404.3 m,
"no current", "mission: station keeping (replay)") and an alarm that never fired live (a
dropout made up by re-running the alarm monitor over the rows with guessed sample periods).

After the mission starts, the replay now shows that mission's frame, name and current (its
``run.2`` set-up), and only the alarms the recorded ``alarm`` events say the console showed.
Both replays are checked: a browser's (``ViewerReplay``) and the API's (``Replay``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.console.replay import Replay, recorded_alarms
from app.console.session import Session, prepare_run, station_keeping_mission
from app.console.snapshot import LoopStats, Snapshot
from app.console.viewer_replay import ViewerReplay, recording_scene
from app.recording import SessionData, load_session
from missions import schema

MISSION = "full-docking-current-0.3"
BEFORE_STEPS = 2000
"""Station keeping recorded before the mission starts (20 s)."""
MISSION_STEPS = 30_000
"""The mission's first 300 s: its hold leg and the dock leg's approach."""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionData, Snapshot]:
    """Record, hold station for 20 s, start the mission, run 300 s of it at full speed, stop;
    the recording read back, and a live snapshot to lend a viewer's replay its clock."""
    out = tmp_path_factory.mktemp("replay-runs")
    session = Session(prepare_run(station_keeping_mission("full-scale", 400.0), False), out)
    try:
        name = session.start_recording("replay")
        session.advance(BEFORE_STEPS)
        session.replace_run(prepare_run(schema.load_mission(MISSION), True))
        for _ in range(MISSION_STEPS // 500):
            session.advance(500)
        session.stop_recording()
        live = session.snapshot(1, False, 1.0, LoopStats(0.01, 0.0, 0.0, 0, 0, 0.0))
    finally:
        session.close()
    return load_session(out / name), live


def _mission_start_s(data: SessionData) -> float:
    assert [r["mission_name"] for r in data.runs] == ["station keeping", MISSION]
    return float(data.runs[1]["start_t_s"])


def test_a_replay_after_the_mission_started_shows_the_missions_scene(
    recorded: tuple[SessionData, Snapshot],
) -> None:
    data, live = recorded
    spec = schema.load_mission(MISSION)
    frame_spec = spec.setup.docking_frame
    assert frame_spec is not None
    viewer = ViewerReplay("replay.mcap", data, live, 1)
    start = _mission_start_s(data)

    before = viewer.snapshot(live)  # opened at the recording's start: station keeping
    assert before.mission.name == "station keeping" and not before.scene.frame_in_mission
    assert before.current_speed_mps == 0.0

    viewer.seek(start + 200.0)
    snap = viewer.snapshot(live)
    frame = snap.scene.frame
    assert snap.scene.frame_in_mission
    np.testing.assert_allclose(frame.center_n, [4.0, 2.5])
    np.testing.assert_allclose(frame.center_n, frame_spec.center_ne_m)
    assert math.degrees(frame.heading_rad) == pytest.approx(30.0)
    assert frame.landing_depth_m == pytest.approx(400.0)
    assert snap.scene.version != before.scene.version, "the view redraws the site"
    assert snap.mission.name == MISSION
    assert snap.current_speed_mps == pytest.approx(0.3)
    assert math.degrees(snap.current_direction_rad) == pytest.approx(225.0)

    viewer.seek(start - 1.0)  # back before the mission: the start-up scene again
    assert viewer.snapshot(live).scene == before.scene


def test_a_replay_shows_only_the_alarms_that_were_recorded(
    recorded: tuple[SessionData, Snapshot],
) -> None:
    """At every second of the recording, each alarm the replay shows on has an 'on' event
    recorded at or before that time in the same run (the made-up dropout had none)."""
    data, live = recorded
    start = _mission_start_s(data)
    came_on = [
        (float(e["t_s"]), e["data"]["name"])
        for e in data.events
        if e["kind"] == "alarm" and e["data"].get("active")
    ]
    api = Replay("replay.mcap", data, recording_scene(data, live.scene, 1), 0.01)
    shown: list[tuple[float, str]] = []
    for t in np.arange(float(data.t_s[0]), float(data.t_s[-1]), 1.0):
        api.seek(float(t))
        run_start = start if t >= start else -math.inf
        for alarm in api.alarms:
            if alarm.active:
                shown.append((float(t), alarm.name))
                assert any(
                    run_start <= t_on <= t + 1e-9 and n == alarm.name for t_on, n in came_on
                ), f"{alarm.name} shown at {t:.0f} s: {alarm.message}"
    assert api.mission == MISSION and api.scene.frame_in_mission


def test_recorded_alarms_follow_their_events() -> None:
    """On at its 'on' event with the recorded message, off at its 'off' event, and none from
    a run before (a new run starts with no alarm on)."""

    def event(t_s: float, active: bool) -> dict:
        text = "dropout on: no position sample for 3.0 s" if active else "dropout off"
        return {
            "t_s": t_s,
            "kind": "alarm",
            "text": text,
            "data": {"name": "dropout", "active": active},
        }

    events = [event(10.0, True), event(20.0, False), event(30.0, True)]
    dropout = {a.name: a for a in recorded_alarms(events, -math.inf, 15.0)}["dropout"]
    assert dropout.active and dropout.message == "no position sample for 3.0 s"
    assert not any(a.active for a in recorded_alarms(events, -math.inf, 25.0))
    assert not any(a.active for a in recorded_alarms(events, -math.inf, 5.0))
    assert any(a.active for a in recorded_alarms(events, 25.0, 35.0))
    assert not any(a.active for a in recorded_alarms(events[:1], 12.0, 15.0))


def test_a_replay_shows_the_runs_own_clock(recorded: tuple[SessionData, Snapshot]) -> None:
    """Issue 47 item 22: the console showed a run's own time (an instructor's "compass freeze
    from 110.59 s") while a replay of the same run said 534.7 s, the time on the recording's
    axis, where a run started while recording goes on after the one before. A replay's
    snapshot (its status line) is on the run's clock; the scrub bar stays on the recording's."""
    data, live = recorded
    viewer = ViewerReplay("replay.mcap", data, live, 1)
    start = _mission_start_s(data)
    offset = data.run_offset_s(1)
    assert offset > 19.0, "the mission's run began after 20 s of station keeping"
    viewer.seek(start + 200.0)
    snap = viewer.snapshot(live)
    assert snap.replay is not None
    assert snap.replay.t_s == pytest.approx(start + 200.0, abs=0.06), "the scrub bar's axis"
    assert snap.t_s == pytest.approx(start + 200.0 - offset, abs=0.06), "the run's own clock"
    assert data.run_time_s(1.0) == 1.0, "the first run's clock is the recording's"
    from web.status import status_markdown

    text = status_markdown(snap, live)
    assert f"t = {snap.t_s:8.1f} s ({snap.replay.t_s:.1f} s into the recording)" in text
