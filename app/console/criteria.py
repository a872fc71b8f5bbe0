"""The assessment as the console keeps it: the criteria in force and a trainee's runs scored
with them (issue 46), for the HTTP API (``app/api/assessment.py``) and the 3D view's tabs.

The criteria in force are the instructor's ``criteria.toml`` in the recordings folder (the
file format of ``rov-console logbook --criteria``, docs/formats.md), the defaults without
one: they outlast a restart and the command line reads the same file. Every change is
checked by ``app.assessment``'s own validation, whose errors name the field and its range.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from app import scores as store
from app.assessment import (
    CRITERIA_FILE,
    WEIGHT_MAX,
    Assessment,
    Criteria,
    CriteriaError,
    Criterion,
    default_criteria,
    load_criteria,
    parse_criteria,
)
from app.console.session import SCORES_DB

__all__ = [
    "CRITERIA_FILE",
    "WEIGHT_MAX",
    "Assessment",
    "Criteria",
    "CriteriaError",
    "Criterion",
    "RunAssessment",
    "apply_criteria",
    "assessed_runs",
    "criteria_in_force",
    "criteria_path",
    "default_criteria",
    "fields_of",
    "reset_criteria",
    "set_by_instructor",
    "trainees",
]


def criteria_path(recordings_dir: Path) -> Path:
    """Where the console keeps the instructor's criteria."""
    return recordings_dir / CRITERIA_FILE


def set_by_instructor(recordings_dir: Path) -> bool:
    """Whether the instructor's criteria are in force (else the defaults)."""
    return criteria_path(recordings_dir).exists()


def criteria_in_force(recordings_dir: Path) -> Criteria:
    """The console's criteria: the defaults until the instructor sets any (CriteriaError when
    the file was edited by hand and broken)."""
    return load_criteria(criteria_path(recordings_dir))


def fields_of(criteria: Criteria) -> dict:
    """The criteria as a criteria file's fields (those taken from the parameter set left
    out), so one criterion changed in it keeps the others as they are."""
    return {
        "criteria": {
            c.name: {
                k: v
                for k, v in (("limit", c.limit), ("zero_at", c.zero_at), ("weight", c.weight))
                if v is not None
            }
            for c in criteria
        }
    }


def apply_criteria(recordings_dir: Path, data: Mapping, source: str) -> Criteria:
    """Validate a criteria file's fields (criteria left out keep their defaults) and put them
    in force. CriteriaError names each bad field and its range, and nothing changes; OSError
    when the file cannot be written."""
    criteria = parse_criteria(data, source)
    path = criteria_path(recordings_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(criteria.to_toml(), encoding="utf-8")
    return criteria


def reset_criteria(recordings_dir: Path) -> Criteria:
    """The default criteria in force again."""
    criteria_path(recordings_dir).unlink(missing_ok=True)
    return default_criteria()


def trainees(recordings_dir: Path) -> list[str]:
    """The trainees with runs in the scores database, in alphabetical order (ValueError when
    it is not a scores database)."""
    return sorted({s.trainee for s in store.history(recordings_dir / SCORES_DB)}, key=str.lower)


@dataclass(frozen=True)
class RunAssessment:
    """A trainee's stored run, numbered from 1 (the oldest), and its assessment."""

    number: int
    run: store.Score
    assessment: Assessment


def assessed_runs(
    recordings_dir: Path, trainee: str, criteria: Criteria | None = None
) -> list[RunAssessment]:
    """A trainee's runs, oldest first, each scored with ``criteria`` (None: those in force),
    as ``app.scores.trend`` scores them."""
    criteria = criteria if criteria is not None else criteria_in_force(recordings_dir)
    runs = reversed(store.history(recordings_dir / SCORES_DB, trainee))
    return [RunAssessment(i, s, store.assessed(s, criteria)) for i, s in enumerate(runs, start=1)]
