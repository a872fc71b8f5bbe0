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

from app.console import Console, ConsoleSettings
from app.console.alarms import ALARM_NAMES, Alarm, AlarmLimits, AlarmMonitor
from app.console.texts import ALARM_WORDS, alarm_title, heading_text
from control.columns import N_LOG, LogRows
from web.status import alarms_html, status_markdown


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
