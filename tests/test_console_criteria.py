"""The console's criteria in force (``app.console.criteria``), which the API and the page share,
and the page's pure parts of the trend (``web.tabs.trend``, ``web.tabs.links``): no server,
no browser."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from app import scores
from app.assessment import (
    FrameLimits,
    RunFacts,
    default_criteria,
    parse_criteria,
    parse_criteria_text,
)
from app.console import SCORES_DB
from app.console import criteria as in_force
from missions.scoring import LandingResult, MissionResult
from web.tabs.links import logbook_url
from web.tabs.trend import NAMES, run_markdown, trend_data

STRICT = "[criteria.time_saturated]\nlimit = 10\nzero_at = 40\nweight = 4\n"


def _store(folder: Path, trainee: str, saturated_s: float, log_file: str | None) -> None:
    landing = LandingResult(True, 0.1, 1.0, -0.04, "frame", 40.0)
    result = MissionResult(
        "dock-drill", [], 0.01, 0.02, 0.5, 0.4, saturated_s, None, [0.0] * 6, False, [], {},
        [landing],
    )  # fmt: skip
    facts = RunFacts(result, [], layout=FrameLimits(0.25, 0.1))  # type: ignore[arg-type]
    scores.record(folder / SCORES_DB, trainee, result, "console", log_file, facts=facts)


def _fields(text: str) -> dict:
    return in_force.fields_of(parse_criteria_text(text))


def test_a_refused_change_writes_nothing_and_keeps_the_criteria_in_force(tmp_path: Path) -> None:
    strict = in_force.apply_criteria(tmp_path, _fields(STRICT), "the page")
    written = in_force.criteria_path(tmp_path).read_text()
    bad = in_force.fields_of(strict)
    bad["criteria"]["time_saturated"]["weight"] = 500
    with pytest.raises(in_force.CriteriaError, match="time_saturated.weight: 500 is outside 0"):
        in_force.apply_criteria(tmp_path, bad, "the page")
    assert in_force.criteria_path(tmp_path).read_text() == written
    assert in_force.criteria_in_force(tmp_path) == strict
    assert in_force.reset_criteria(tmp_path) == default_criteria()
    assert not in_force.set_by_instructor(tmp_path)


@pytest.mark.parametrize("text", ["", STRICT, "[criteria.landing_miss]\nlimit = 0.3\n"])
def test_the_fields_of_criteria_give_the_same_criteria_back(text: str) -> None:
    criteria = parse_criteria_text(text)
    assert parse_criteria(in_force.fields_of(criteria)) == criteria


def test_the_runs_are_scored_as_the_apis_trend_scores_them(tmp_path: Path) -> None:
    for saturated_s in (60.0, 20.0):
        _store(tmp_path, "Anna", saturated_s, "drill.mcap")
    _store(tmp_path, "Ola", 5.0, None)
    assert in_force.trainees(tmp_path) == ["Anna", "Ola"]
    in_force.apply_criteria(tmp_path, _fields(STRICT), "the page")
    runs = in_force.assessed_runs(tmp_path, "Anna")
    trend = scores.trend(tmp_path / SCORES_DB, "Anna", in_force.criteria_in_force(tmp_path))
    assert [r.number for r in runs] == [1, 2]
    assert [r.assessment.total for r in runs] == [p.total for p in trend]

    x, total, *per = trend_data(runs)
    assert list(x) == [1.0, 2.0] and list(total) == [p.total for p in trend]
    assert len(per) == len(NAMES)
    assert np.isnan(per[NAMES.index("slack_events")]).all(), "not judged: a gap, not a 0"

    text = run_markdown(runs[1], "http://127.0.0.1:8000", "TICKET")
    assert "Logbook (PDF)" in text and "drill.mcap/logbook?ticket=TICKET" in text
    (ola,) = in_force.assessed_runs(tmp_path, "Ola")
    assert "no logbook entry" in run_markdown(ola, "http://h", None)
    assert math.isclose(ola.assessment.total or 0.0, 100.0)


def test_a_logbook_link_carries_the_ticket_and_the_format() -> None:
    base = "http://127.0.0.1:8000"
    assert logbook_url(base, "a b.mcap") == f"{base}/api/recordings/a%20b.mcap/logbook"
    assert logbook_url(base, "a.mcap", "t/1", "csv").endswith("logbook?format=csv&ticket=t%2F1")
