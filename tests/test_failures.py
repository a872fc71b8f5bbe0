"""What a mission or a step that goes wrong does: the leg fails with the reason, the mission
ends as failed, and whoever drives the simulation (headless runner, console loop) goes on."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path

import pytest

from app.console import PacedLoop, Session, prepare_run
from app.console import commands as cmd
from missions import schema
from missions.driver import MissionDriver
from missions.setup import build_simulation

ROOT = Path(__file__).resolve().parents[1]

# full scale at 100 m hangs the tree on 97.3 m of wire: the winch refuses to haul in 97.5 m.
# The file's check refuses it too (test_the_file_check_refuses_a_winch_plan_beyond_the_wire);
# what is under test here is a leg the simulation refuses while it runs, so these tests parse
# the mission with that check turned off (``unchecked``), as for a refusal no file check can
# foresee.
HAUL_TOO_FAR = {
    "format_version": 1,
    "name": "haul too far",
    "setup": {"params": "full-scale", "depth_m": 100.0},
    "legs": [
        {"type": "hold", "duration_s": 2.0},
        {"type": "wire", "change_m": -97.5, "rate_mps": 1.0},
        {"type": "hold", "duration_s": 5.0},
    ],
}


def unchecked(data: dict) -> schema.Mission:
    """``data`` parsed without the file's check of the winch plan."""
    check = schema.Mission._check_wire_payout
    schema.Mission._check_wire_payout = lambda self: None  # type: ignore[method-assign]
    try:
        return schema.parse_mission(data)
    finally:
        schema.Mission._check_wire_payout = check  # type: ignore[method-assign]


UNCHECKED_RUN = """
import sys
from missions import schema
schema.Mission._check_wire_payout = lambda self: None
from app.cli import main
sys.argv = ["rov-console", *sys.argv[1:]]
main()
"""


def test_a_leg_the_simulation_refuses_fails_the_mission_and_leaves_it_steppable():
    mission = unchecked(HAUL_TOO_FAR)
    sim = build_simulation(mission)
    assert sim.wire_length_m < 97.5 < 100.0
    driver = MissionDriver(mission, sim)
    result = driver.run_to_end()
    assert result.failed and not result.diverged
    assert "leg 2 (wire) failed" in result.error and "wire length must be in [1, 5000] m" in (
        result.error
    )
    assert [leg.error != "" for leg in result.legs] == [False, True]
    assert not result.legs[1].timed_out, "a refused leg is a failure, not a timeout"
    assert any(e["kind"] == "error" for e in result.events)
    t0 = sim.t_s
    assert len(sim.step(10)) == 10 and sim.t_s == pytest.approx(t0 + 0.1)


def test_the_file_check_refuses_a_winch_plan_beyond_the_wire(tmp_path):
    data = {**HAUL_TOO_FAR, "legs": [{"type": "wire", "change_m": -150.0}]}
    with pytest.raises(schema.MissionError, match=r"legs\[1\] \(wire\)\.change_m.*\[1, 5000\] m"):
        schema.parse_mission(data)


def test_run_reports_a_failed_leg_without_a_traceback(tmp_path):
    import tomli_w

    path = tmp_path / "haul.toml"
    path.write_text(tomli_w.dumps(HAUL_TOO_FAR))
    proc = subprocess.run(
        [sys.executable, "-c", UNCHECKED_RUN, "run", str(path), "--no-progress"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert proc.returncode == 1
    assert "Traceback" not in proc.stdout + proc.stderr
    assert "ERROR: leg 2 (wire) failed" in proc.stdout
    assert "mission FAILED" in proc.stderr


def test_the_console_session_marks_the_mission_failed_and_keeps_running(tmp_path):
    session = Session(prepare_run(unchecked(HAUL_TOO_FAR)), tmp_path)
    for _ in range(200):
        session.advance(50)
        if session.mission_status.state != "running":
            break
    assert session.mission_status.state == "failed"
    assert session.error is None, "a failed leg does not stop the simulation"
    assert any("wire length" in n for n in session.notices)
    t0 = session.sim.t_s
    session.advance(30)
    assert session.sim.t_s == pytest.approx(t0 + 0.3)


def test_the_loop_survives_an_exception_in_a_step_and_health_says_so(tmp_path):
    async def scenario() -> None:
        session = Session(prepare_run(unchecked(HAUL_TOO_FAR), run_legs=False), tmp_path)
        loop = PacedLoop(session, speed=10.0)
        calls = {"n": 0}
        real = session.advance

        def broken(n: int) -> None:
            calls["n"] += 1
            if calls["n"] == 5:
                raise RuntimeError("injected failure")
            real(n)

        session.advance = broken  # type: ignore[method-assign]
        task = asyncio.create_task(loop.run())
        await asyncio.sleep(0.5)
        assert loop.running and loop.health() == "ok"
        assert loop.faults == 1 and loop.paused
        assert "injected failure" in (loop.snapshot.error or "")
        with pytest.raises(Exception, match="injected failure"):
            await loop.call(cmd.Resume())
        ticks = loop.ticks
        await asyncio.sleep(0.2)
        assert loop.ticks > ticks, "the loop goes on ticking (answering commands)"
        loop.stop()
        await task
        assert loop.health() == "stopped"

    asyncio.run(scenario())


def test_reset_after_a_divergence_runs_again_from_a_finite_state(tmp_path):
    async def scenario() -> None:
        mission = schema.parse_mission(
            {**HAUL_TOO_FAR, "legs": [{"type": "hold", "duration_s": 1.0}]}
        )
        session = Session(prepare_run(mission, run_legs=False), tmp_path)
        loop = PacedLoop(session, speed=10.0)
        task = asyncio.create_task(loop.run())
        session.sim.set_push([1e30, 0.0, 0.0])  # nothing a client can send does this
        await asyncio.sleep(0.5)
        assert loop.paused and "diverged" in (loop.snapshot.error or "")
        await loop.call(cmd.StartRun(prepare_run(mission, run_legs=False)))
        await asyncio.sleep(0.4)
        snap = loop.snapshot
        assert not snap.paused and snap.error is None
        # the set-up hangs the tree's centre at 100 m; 1 m covers the heave ringing of the first
        # 0.4 s on the elastic wire (about 0.1 m), far below the 1e20 m of a diverged state
        assert abs(snap.tree_eta_n[2] - 100.0) < 1.0, "the tree hangs where the set-up puts it"
        assert snap.t_s > 0.5
        loop.stop()
        await task

    asyncio.run(scenario())
