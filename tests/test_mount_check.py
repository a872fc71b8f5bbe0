"""The live mounting-vector check (app.console.alarms, ``mount_vector``): with r mirrored (the
``mount_sign`` fault, the sea trial's wrong sign) the console says so in words within 30 s of
the first heading change; with the configured r, on the same mission, it stays quiet."""

from __future__ import annotations

from pathlib import Path

from app.console.session import Session, prepare_run
from missions import schema

MISSION = (schema.LIBRARY_DIR / "model-rotation-wrong-r.toml").read_text()


def rotation(fault: bool) -> schema.Mission:
    """The model-scale 180 deg rotation (30 s hold first) with r configured right; with
    ``fault``, the control system is handed the mirrored r for the whole mission."""
    text = MISSION.replace(
        "r_mount_config_m = [2.0, 0.0, 0.0]   # the ROV really sits at [-2, 0, 0]\n", ""
    )
    assert "r_mount_config_m" not in text
    if fault:
        text += '\n[[faults]]\nkind = "mount_sign"\nstart_s = 0.0\nduration_s = 3000.0\n'
    return schema.parse_text(text, "<test>")


def fly(fault: bool, tmp_path: Path) -> tuple[float | None, str, float]:
    """(time the mount alarm first came on or None, its words, when the turn began)."""
    session = Session(prepare_run(rotation(fault)), tmp_path)
    first_on, words, turn_s = None, "", None
    while session.mission_status.state == "running":
        session.advance(50)
        if turn_s is None and session.mission_status.leg_type == "rotate":
            turn_s = session.sim.t_s
        alarm = next(a for a in session.monitor.state if a.name == "mount_vector")
        if alarm.active and first_on is None:
            first_on, words = session.sim.t_s, alarm.message
    assert session.mission_status.state == "completed" and turn_s is not None
    return first_on, words, turn_s


def test_a_mirrored_r_is_flagged_within_30_s_of_the_turn_and_a_right_one_is_not(tmp_path):
    on, words, turn_s = fly(True, tmp_path)
    assert on is not None, "the mirrored r must be flagged"
    assert turn_s < on <= turn_s + 30.0
    assert "mounting vector r looks mirrored" in words and "sign" in words
    quiet, _, _ = fly(False, tmp_path)
    assert quiet is None, "the configured r must not be flagged"
