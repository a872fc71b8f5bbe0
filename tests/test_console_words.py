"""Issue 47 item 26 (part): the page reads as words, not code. Headings are printed wrapped
into [0, 360) deg ("heading 558.1 deg" was shown), and alarms are named in words with their
meaning, through one mapping (``app.console.texts.ALARM_WORDS``)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from app.api.plots import rows_json
from app.console import Console, ConsoleSettings
from app.console.alarms import ALARM_NAMES, Alarm, AlarmLimits, AlarmMonitor
from app.console.texts import ALARM_WORDS, alarm_title, heading_text
from control.columns import N_LOG, LogRows
from web.status import alarms_html, status_markdown, thrusters_html


@pytest.fixture(scope="module")
def console(tmp_path_factory: pytest.TempPathFactory) -> Console:
    folder = tmp_path_factory.mktemp("recordings")
    return Console.build(ConsoleSettings(view=False, recordings_dir=folder))


@given(st.floats(-100.0, 100.0, allow_nan=False))
def test_heading_text_is_within_0_to_360(psi_rad: float) -> None:
    deg = float(heading_text(psi_rad).removesuffix(" deg"))
    assert 0.0 <= deg < 360.0
    assert math.cos(math.radians(deg) - psi_rad) == pytest.approx(1.0, abs=1e-4)


def test_status_line_prints_the_heading_wrapped(console: Console) -> None:
    snap = console.loop.snapshot
    eta = list(snap.tree_eta_n)
    eta[5] = math.radians(558.1)
    text = status_markdown(dataclasses.replace(snap, tree_eta_n=tuple(eta)), snap)
    assert "heading 198.1 deg" in text
    assert "558" not in text


def test_every_alarm_has_words_and_a_meaning() -> None:
    assert set(ALARM_WORDS) == set(ALARM_NAMES)
    for name in ALARM_NAMES:
        title, meaning = ALARM_WORDS[name]
        assert "_" not in title and meaning, name
    assert alarm_title("position_error") == "position error"
    assert alarm_title("mount_vector") == "mount vector check"


def test_alarm_badges_and_messages_name_alarms_in_words(console: Console) -> None:
    snap = console.loop.snapshot
    alarms = (
        Alarm("position_error", True, "tree 0.53 m / 1.0 deg off its set point"),
        Alarm("mount_vector", False, ""),
    )
    page = alarms_html(dataclasses.replace(snap, alarms=alarms))
    assert "position error: tree 0.53 m" in page
    assert ">mount vector check<" in page
    assert "position_error" not in page and "mount_vector" not in page


def test_innovation_alarm_says_what_its_number_is() -> None:
    limits = AlarmLimits(position_error_m=0.25, sample_period_s=(1.0, 0.1, 0.1, 0.2, 0.02))
    m = AlarmMonitor(limits, n_thrusters=4, weight_newton=300e3, uses_sensors=True)
    rows = LogRows(np.zeros((400, N_LOG)), n_thrusters=4)
    rows["t_s"][:] = np.arange(1, 401) * 0.01
    rows["accepted"][:] = 1.0
    rows["nis"][:] = 9.3
    m.update(rows, 300e3)
    (alarm,) = (a for a in m.state if a.name == "innovation")
    assert alarm.active
    assert "x expected" not in alarm.message
    assert "normalised innovation 9.3, about 1 expected" in alarm.message


def _thrusters(console: Console, util: tuple, force: tuple, faults: tuple = ()) -> str:
    snap = console.loop.snapshot
    return thrusters_html(
        dataclasses.replace(
            snap, thruster_utilisation=util, thruster_force_newton=force, faults=faults
        )
    )


def test_thruster_bars_are_named_and_signed(console: Console) -> None:
    """Defect (issue 47 item 26): the bars showed magnitude only, with no names: a thruster
    pushing back at 60 % looked like one pushing forward at 60 %."""
    page = _thrusters(console, (0.6, 0.25, 0.0, 1.0), (-6e3, 2.5e3, 0.0, 1e4))
    for number, text in ((1, "-60 %"), (2, "+25 %"), (3, "0 %"), (4, "+100 %")):
        row = page.split(f"data-thruster='{number}'")[1].split("</div>")[0]
        assert f">T{number}<" in row and f">{text}<" in row, row
    # reverse thrust is drawn left of the middle, forward to its right
    assert "left:20.0%;width:30.0%" in page.split("data-thruster='1'")[1]
    assert "left:50.0%;width:12.5%" in page.split("data-thruster='2'")[1]
    assert "reverse" in page and "forward" in page


def test_a_killed_thruster_shows_killed_not_full_red(console: Console) -> None:
    """Defect (issue 47 item 26): a thruster the instructor killed showed 100 % red (the
    control system asked it for all it had, which it could not give)."""
    from app.console import FaultView

    killed = FaultView("thruster_lost", 10.0, 60.0, 0.0, "-", 2, 0.0, "active", "T2 lost")
    weak = FaultView("thruster_weakened", 10.0, 60.0, 0.4, "factor", 3, 0.0, "active", "T3")
    later = FaultView("thruster_lost", 90.0, 60.0, 0.0, "-", 4, 0.0, "scheduled", "T4 lost")
    page = _thrusters(console, (0.1, 1.0, 0.5, 0.2), (1e3, 1e4, 5e3, 2e3), (killed, weak, later))
    row2 = page.split("data-thruster='2'")[1].split("</div>")[0]
    assert "data-thruster='2' data-state='killed'" in page
    assert ">killed<" in row2 and "100 %" not in row2 and "red" not in row2
    row3 = page.split("data-thruster='3'")[1].split("</div>")[0]
    assert "+50 %" in row3 and "weakened to 40 %" in row3
    row4 = page.split("data-thruster='4'")[1].split("</div>")[0]
    assert "killed" not in row4, "a scheduled fault is not on yet"


def test_plot_headings_are_sent_as_compass_degrees() -> None:
    """Defect (issue 47 item 26): the plots page's headings were unwrapped angles
    ('558.1' on its axis) while the rest of the page wraps them into [0, 360)."""
    trend = np.zeros((3, 7))
    trend[:, 0] = [0.0, 0.5, 1.0]
    trend[:, 3] = np.radians([558.1, -0.01, 359.99])
    trend[:, 6] = np.radians([-90.0, 720.0, 10.0])
    rows = rows_json(trend)
    assert [r[3] for r in rows] == pytest.approx([198.1, 359.99, 359.99])
    assert [r[6] for r in rows] == pytest.approx([270.0, 0.0, 10.0])
    assert all(0.0 <= r[c] < 360.0 for r in rows for c in (3, 6))
