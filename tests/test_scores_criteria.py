"""Scores mark faulted runs and name the criteria a run failed (issue 47, item 21): a
landing after 122 s saturated and an uncommanded 360 deg turn 9 m off the frame scored
"pass, landed"."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from app import scores
from control.columns import LogRows
from missions import schema
from missions.driver import MissionDriver
from missions.scoring import MissionResult
from missions.setup import build_simulation


@pytest.fixture(scope="module")
def clean() -> MissionResult:
    spec = schema.load_mission("full-docking-current-0.3")
    return MissionDriver(spec, build_simulation(spec)).run_to_end()


def _faulted(clean: MissionResult) -> MissionResult:
    """The clean run with the issue's excursion written into its dock leg: the tree 9 m off
    and turning a whole turn for 60 s, thrusters saturated 122 s, a fault injected."""
    assert clean.log is not None
    data = clean.log.data.copy()
    log = LogRows(data, clean.log.n_thrusters, layout=clean.log.layout)
    dock = next(leg for leg in clean.legs if leg.type == "dock")
    t = log.t_s - log.t_s[0]
    window = (t > dock.start_s + 60.0) & (t < dock.start_s + 120.0)
    tree = log.layout.slice("tree_eta_n")
    data[window, tree.start] += 9.0
    data[window, tree.start + 5] += np.linspace(0.0, 2 * np.pi, int(window.sum()))
    fault = {"t_s": 200.0, "kind": "fault", "text": "fault: compass freeze", "data": {}}
    return dataclasses.replace(
        clean, log=log, saturated_time_s=122.0, events=[*clean.events, fault]
    )


def test_a_clean_landing_passes_every_criterion(clean: MissionResult, tmp_path: Path) -> None:
    db = tmp_path / "scores.sqlite"
    scores.record(db, "Anna", clean, "test")
    (row,) = scores.history(db)
    assert row.passed and row.criteria_failed == "" and row.verdict == "pass"


def test_a_faulted_landing_after_an_excursion_does_not_pass_unremarked(
    clean: MissionResult, tmp_path: Path
) -> None:
    db = tmp_path / "scores.sqlite"
    scores.record(db, "Anna", _faulted(clean), "test")
    (row,) = scores.history(db)
    assert row.landed, "it did land"
    assert row.faults == "compass freeze"
    failed = row.criteria_failed
    assert "time saturated 122.0 s > 30 s" in failed
    assert "largest heading error" in failed
    assert "excursion from the reference in a dock leg 9.0 m > 1.5 m" in failed
    assert row.verdict.startswith("fail, faulted: time saturated")
    values = scores.criteria_values(_faulted(clean))
    assert values["largest heading error"] > 170.0
