"""The campaign report says what the data shows (issue 47, item 25): failure causes whole,
no RMS figures for runs whose scored legs never ran, per-current success with intervals
instead of a limit that assumes success falls with current, and a quick look of a few runs."""

from __future__ import annotations

import math
from pathlib import Path

from app.campaign import report
from missions import campaign as cm
from missions import schema
from missions.driver import MissionDriver
from missions.setup import build_simulation

REFUSED = (
    "leg 2 (dock) failed: landing not feasible in 0.5 m/s towards 135 deg with the frame at "
    "30 deg: holding the tree over it takes 13.1 kN, more than the 90 % allowed"
)


def _row(current: float, ok: bool, **more: object) -> dict:
    base = {"params": "full-scale", "depth_m": 390.0, "current_speed_mps": current}
    outcome = {"success": ok, "landed": ok or None, "diverged": False, "timed_out": False}
    return {**base, **outcome, "simulated_s": 400.0, "error": "", **more}


def test_a_refused_landings_cause_is_whole() -> None:
    """Defect: the cause was cut at 70 characters, "... towards # deg with "."""
    cause = report.failure_cause(_row(0.5, False, landed=None, error=REFUSED))
    assert cause == (
        "leg failed: leg # (dock) failed: landing not feasible in # m/s towards # deg "
        "with the frame at # deg"
    )


def test_runs_whose_scored_legs_never_ran_have_no_rms() -> None:
    """Defect: a landing refused at once scored RMS 0/0, as if flown perfectly."""
    text = """
format_version = 1
name = "refused"
[setup]
params = "full-scale"
depth_m = 390.0
[setup.current]
speed_mps = 0.9
direction_deg = 300.0
[setup.docking_frame]
center_ne_m = [4.0, 2.5]
heading_deg = 30.0
landing_depth_m = 390.5
[[legs]]
type = "hold"
duration_s = 2.0
score = false
[[legs]]
type = "dock"
score = true
"""
    spec = schema.parse_text(text, "<test>")
    result = MissionDriver(spec, build_simulation(spec), keep_log=False).run_to_end(log=False)
    assert "not feasible" in result.error, result.error
    row = cm.outcome_row(result, 2.0, 0.1)
    assert all(math.isnan(row[k]) for k in ("rms_north_m", "rms_east_m", "rms_heading_deg"))
    table = report.point_table(_FakeCampaign(), [{**row, "point": 0, "run": 0}])
    assert table[0][report.POINT_COLUMNS.index("RMS N/E m (mean)")] == "-/-"


class _FakeCampaign:
    def point_values(self, point: int) -> dict:
        return {"current_speed_mps": 0.9}


def test_the_envelope_describes_success_that_rises_with_current() -> None:
    """Issue 47: with the current at 135 deg success rose with speed (0.2: 0/2, 0.35: 1/2,
    0.5: 2/2) and the envelope said "< 0.2 m/s"."""
    rows = [_row(0.2, False), _row(0.2, False), _row(0.35, False), _row(0.35, True)]
    rows += [_row(0.5, True), _row(0.5, True)]
    (env,) = report.envelope(rows)
    assert not env.is_threshold and env.passing == (0.5,)
    words = env.verdict()
    assert "no single limit" in words and "0.5 m/s" in words and "0.2, 0.35 m/s" in words
    assert "<" not in words
    (line,) = report.envelope_table([env])
    lo, hi = cm.wilson_interval(1, 2)
    assert f"0.35: 1/2 ({100 * lo:.0f}-{100 * hi:.0f} %)" in line[3]


def test_a_falling_success_keeps_its_single_limit() -> None:
    rows = [_row(0.1, True)] * 20 + [_row(0.3, True)] * 19 + [_row(0.3, False)]
    rows += [_row(0.5, False)] * 10
    (env,) = report.envelope(rows)
    assert env.is_threshold and env.verdict() == "up to 0.3 m/s"


def test_a_quick_look_takes_one_run_of_every_point_first(tmp_path: Path) -> None:
    c, _, _ = cm.load_campaign("full-docking-vs-current")
    runs = cm.quick_look_runs(c, c.points + 1)
    points = sorted(divmod(i, c.runs_per_point)[0] for i in runs)
    assert len(runs) == c.points + 1 and set(points) == set(range(c.points))
    assert cm.quick_look_runs(c, None) == list(range(c.runs))
