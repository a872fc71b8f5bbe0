"""Scores of flown missions, kept in an embedded SQLite database (one file, no server).

Each finished mission is one row: who flew it (the trainee), the mission, when, where its log
is, and its figures: landed or not (the funnel tolerance and the landing-speed limit), time
to the first contact, miss, heading error and contact speed at it, RMS errors, time saturated
and thrust spent. The console writes a row when a mission it runs ends; ``rov-console run
--trainee NAME`` writes one for a headless run; ``rov-console scores`` lists them.
"""

from __future__ import annotations

import json
import math
import sqlite3
from contextlib import closing
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from app.assessment import Assessment, Criteria, FrameLimits, RunFacts, assess, measure
from missions.scoring import MissionResult

SCHEMA = """
CREATE TABLE IF NOT EXISTS runs (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    utc TEXT NOT NULL,
    trainee TEXT NOT NULL,
    mission TEXT NOT NULL,
    source TEXT NOT NULL,
    log_file TEXT,
    passed INTEGER NOT NULL,
    landed INTEGER,
    time_to_dock_s REAL,
    miss_m REAL,
    heading_error_deg REAL,
    contact_speed_mps REAL,
    rms_north_m REAL,
    rms_east_m REAL,
    rms_heading_deg REAL,
    saturated_s REAL,
    thrust_newton_s REAL,
    faults TEXT NOT NULL DEFAULT '',
    manual_share REAL NOT NULL DEFAULT 0,
    flown_by TEXT NOT NULL DEFAULT 'autopilot',
    criteria_failed TEXT NOT NULL DEFAULT '',
    assessment TEXT NOT NULL DEFAULT ''
)
"""
ADDED_COLUMNS = {
    "manual_share": "REAL NOT NULL DEFAULT 0",
    "flown_by": "TEXT NOT NULL DEFAULT 'autopilot'",
    "criteria_failed": "TEXT NOT NULL DEFAULT ''",
    "assessment": "TEXT NOT NULL DEFAULT ''",
}
"""Columns added since the first version: a database written before gets them on opening
(its runs count as flown by the autopilot: there was no manual mode then)."""
MODE_MANUAL = 2
"""The log's ``mode`` column while the pilot flies by hand (the supervisor's manual mode)."""
HAND_SHARE = 0.9
"""A run with at least this share of its time in manual mode was flown by hand."""
AUTOPILOT_SHARE = 0.1
"""A run with at most this share in manual mode was flown by the autopilot (a pilot who takes
the sticks for a moment does not make it a hand-flown run); between the two it is mixed."""
FLOWN_BY = ("autopilot", "hand", "mixed")
COLUMNS = (
    "id",
    "utc",
    "trainee",
    "mission",
    "source",
    "log_file",
    "passed",
    "landed",
    "time_to_dock_s",
    "miss_m",
    "heading_error_deg",
    "contact_speed_mps",
    "rms_north_m",
    "rms_east_m",
    "rms_heading_deg",
    "saturated_s",
    "thrust_newton_s",
    "faults",
    "manual_share",
    "flown_by",
    "criteria_failed",
    "assessment",
)
NAME_MAX = 60


@dataclass(frozen=True)
class Score:
    """One row of the database."""

    id: int
    utc: str
    trainee: str
    mission: str
    source: str
    log_file: str | None
    passed: bool
    landed: bool | None
    """None: the mission has no landing."""
    time_to_dock_s: float | None
    miss_m: float | None
    heading_error_deg: float | None
    contact_speed_mps: float | None
    rms_north_m: float
    rms_east_m: float
    rms_heading_deg: float
    saturated_s: float
    thrust_newton_s: float | None
    faults: str
    manual_share: float = 0.0
    """Share of the run's time the pilot flew by hand (the log's mode column = 2)."""
    flown_by: str = "autopilot"
    """autopilot, hand or mixed (``flown_by``)."""
    criteria_failed: str = ""
    """The run's criteria (``CRITERIA``) it failed, in words ('; '-separated; '' none)."""
    assessment: str = ""
    """The assessment's measured values (``app.assessment.measure``) and the frame's limits,
    as JSON (``assessment_values``); '' for runs stored before there was one."""

    @property
    def verdict(self) -> str:
        """'pass', 'fail', with ', faulted' when instructor faults acted and the criteria
        that failed: a landing after a 9 m excursion does not pass unremarked."""
        words = "pass" if self.passed and not self.criteria_failed else "fail"
        if self.faults:
            words += ", faulted"
        return words + (f": {self.criteria_failed}" if self.criteria_failed else "")


def trainee_name(text: str) -> str:
    """A trainee's name as stored: spaces folded, at most ``NAME_MAX`` characters;
    ValueError when empty."""
    name = " ".join(str(text).split())[:NAME_MAX]
    if not name:
        raise ValueError("trainee: give a name (letters, at most 60 characters)")
    return name


def thrust_spent(result: MissionResult) -> float | None:
    """Sum over thrusters of the time integral of |force| [N s] (None without the log)."""
    rows = result.log
    if rows is None or len(rows) < 2:
        return None
    return float(np.sum(np.trapezoid(np.abs(rows["thruster_force"]), rows.t_s, axis=0)))


def manual_share(result: MissionResult) -> float:
    """Share of the logged steps flown by hand (mode column = ``MODE_MANUAL``); 0 without a
    log or a mode column (all autopilot)."""
    rows = result.log
    if rows is None or len(rows) == 0:
        return 0.0
    try:
        mode = np.asarray(rows["mode"], float).reshape(len(rows), -1)[:, 0]
    except KeyError:
        return 0.0
    return float(np.mean(np.round(mode) == MODE_MANUAL))


def faults_of(result: MissionResult) -> str:
    """The faults that acted during the mission, from its events ('; '-separated)."""
    texts = [
        str(e.get("text", "")).removeprefix("fault: ")
        for e in result.events
        if e.get("kind") == "fault" and str(e.get("text", "")).startswith("fault: ")
    ]
    return "; ".join(texts)


@dataclass(frozen=True)
class Criterion:
    """A limit a good run keeps, besides the mission's own verdict."""

    name: str
    limit: float
    unit: str


SATURATION_LIMIT = Criterion("time saturated", 30.0, "s")
"""A thruster at its limit this long means the ROV was not in control (thesis 4.2.2)."""
HEADING_LIMIT = Criterion("largest heading error", 20.0, "deg")
"""Tree heading off its reference by more than this: an uncommanded turn."""
DOCK_EXCURSION_LIMIT = Criterion("largest excursion from the reference in a dock leg", 1.5, "m")
"""Tree this far (horizontally) from where the dock leg wants it: not over the frame."""
CRITERIA = (SATURATION_LIMIT, HEADING_LIMIT, DOCK_EXCURSION_LIMIT)


def criteria_values(result: MissionResult) -> dict[str, float]:
    """Each criterion's value for a run (NaN when the log does not tell)."""
    out = dict.fromkeys((c.name for c in CRITERIA), math.nan)
    out[SATURATION_LIMIT.name] = float(result.saturated_time_s)
    rows = result.log
    if rows is None or len(rows) == 0:
        return out
    tree, ref = rows["tree_eta_n"], rows["eta_ref_n"]
    heading = np.angle(np.exp(1j * (tree[:, 5] - ref[:, 2])))
    out[HEADING_LIMIT.name] = float(np.degrees(np.max(np.abs(heading))))
    off = np.hypot(tree[:, 0] - ref[:, 0], tree[:, 1] - ref[:, 1])
    t = rows.t_s - float(rows.t_s[0])
    docks = [leg for leg in result.legs if leg.type == "dock"]
    if docks:
        in_dock = np.zeros(len(rows), dtype=bool)
        for leg in docks:
            in_dock |= (t >= leg.start_s - 1e-9) & (t < leg.start_s + leg.duration_s - 1e-9)
        if np.any(in_dock):
            out[DOCK_EXCURSION_LIMIT.name] = float(np.max(off[in_dock]))
    return out


def criteria_failed(result: MissionResult) -> str:
    """The criteria a run failed, each with its value and limit ('' when none)."""
    values = criteria_values(result)
    failed = [
        f"{c.name} {values[c.name]:.1f} {c.unit} > {c.limit:g} {c.unit}"
        for c in CRITERIA
        if math.isfinite(values[c.name]) and values[c.name] > c.limit
    ]
    return "; ".join(failed)


def flown_by(share: float) -> str:
    """'hand', 'autopilot' or 'mixed' for a share of time in manual mode."""
    if share >= HAND_SHARE:
        return "hand"
    if share <= AUTOPILOT_SHARE:
        return "autopilot"
    return "mixed"


def _finite(v: float | None) -> float | None:
    return float(v) if v is not None and math.isfinite(v) else None


def record(
    db: Path,
    trainee: str,
    result: MissionResult,
    source: str,
    log_file: str | None = None,
    faults: str = "",
    facts: RunFacts | None = None,
) -> int:
    """Store one finished mission; returns its row id. ``faults``: the faults that were
    active, in words (default: those the mission's events record). ``facts``: what the
    assessment reads besides the result (``app.assessment.facts_of_run``); without them only
    the criteria the result alone tells are measured (landing, saturation, time to land)."""
    landing = result.landings[0] if result.landings else None
    share = manual_share(result)
    values = {
        "utc": datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "trainee": trainee_name(trainee),
        "mission": result.name,
        "source": source,
        "log_file": log_file,
        "passed": int(not result.failed),
        "landed": None if landing is None else int(landing.success),
        "time_to_dock_s": None if landing is None else _finite(landing.t_contact_s),
        "miss_m": None if landing is None else _finite(landing.miss_m),
        "heading_error_deg": None if landing is None else _finite(landing.heading_error_deg),
        "contact_speed_mps": None if landing is None else _finite(landing.contact_speed_mps),
        "rms_north_m": result.rms_north_m,
        "rms_east_m": result.rms_east_m,
        "rms_heading_deg": result.rms_heading_deg,
        "saturated_s": result.saturated_time_s,
        "thrust_newton_s": _finite(thrust_spent(result)),
        "faults": faults or faults_of(result),
        "manual_share": share,
        "flown_by": flown_by(share),
        "criteria_failed": criteria_failed(result),
        "assessment": _assessment_json(facts or RunFacts(result, result.events)),
    }
    db.parent.mkdir(parents=True, exist_ok=True)
    with closing(sqlite3.connect(db)) as con, con:
        _open(con)
        cur = con.execute(
            f"INSERT INTO runs ({', '.join(values)}) VALUES ({', '.join('?' * len(values))})",
            tuple(values.values()),
        )
        return int(cur.lastrowid or 0)


def _assessment_json(facts: RunFacts) -> str:
    values = {
        k: (None if v is None else (v if math.isfinite(v) else "inf"))
        for k, v in measure(facts).items()
    }
    frame = FrameLimits.of(facts.layout)
    return json.dumps({"values": values, "frame": None if frame is None else vars(frame)})


def assessment_values(s: Score) -> tuple[dict[str, float | None], FrameLimits | None]:
    """A stored run's measured values and frame limits. A run stored before the assessment
    gets what its columns tell: the landing's miss and speed and the time saturated."""
    if s.assessment:
        data = json.loads(s.assessment)
        values = {
            k: (math.inf if v == "inf" else (None if v is None else float(v)))
            for k, v in data.get("values", {}).items()
        }
        frame = data.get("frame")
        return values, FrameLimits(**frame) if isinstance(frame, dict) else None
    told: dict[str, float | None] = {"time_saturated": s.saturated_s}
    if s.landed is not None:
        told["landing_miss"] = s.miss_m if s.miss_m is not None else math.inf
        told["contact_speed"] = (
            abs(s.contact_speed_mps) if s.contact_speed_mps is not None else math.inf
        )
    return told, None


def assessed(s: Score, criteria: Criteria) -> Assessment:
    """A stored run scored with ``criteria`` (its values and frame limits as stored)."""
    values, frame = assessment_values(s)
    return assess(values, criteria, frame)


@dataclass(frozen=True)
class TrendPoint:
    """One run of a trainee, scored with the criteria in force."""

    id: int
    utc: str
    mission: str
    flown_by: str
    faults: str
    total: float | None
    scores: dict[str, float | None]


def trend(
    db: Path, trainee: str, criteria: Criteria, mission: str | None = None
) -> list[TrendPoint]:
    """A trainee's runs, oldest first, each assessed again with ``criteria`` (a change of the
    criteria re-scores the whole history: the database keeps values, not scores)."""
    out = []
    for s in reversed(history(db, trainee, mission)):
        a = assessed(s, criteria)
        out.append(
            TrendPoint(
                s.id,
                s.utc,
                s.mission,
                s.flown_by,
                s.faults,
                a.total,
                {c.name: c.score for c in a.criteria},
            )
        )
    return out


def history(db: Path, trainee: str | None = None, mission: str | None = None) -> list[Score]:
    """Stored runs, newest first, of one trainee and/or mission (all when None)."""
    if not db.exists():
        return []
    where, args = [], []
    if trainee:
        where.append("trainee = ?")
        args.append(trainee_name(trainee))
    if mission:
        where.append("mission = ?")
        args.append(mission)
    sql = f"SELECT {', '.join(COLUMNS)} FROM runs"
    sql += (" WHERE " + " AND ".join(where)) if where else ""
    sql += " ORDER BY id DESC"
    try:
        with closing(sqlite3.connect(db)) as con, con:
            _open(con)
            rows = con.execute(sql, args).fetchall()
    except sqlite3.DatabaseError as err:
        raise ValueError(f"{db}: not a scores database ({err})") from None
    return [_score(row) for row in rows]


def _open(con: sqlite3.Connection) -> None:
    """Create the table, or add the columns a database from an earlier version lacks."""
    con.execute(SCHEMA)
    have = {row[1] for row in con.execute("PRAGMA table_info(runs)")}
    for name, decl in ADDED_COLUMNS.items():
        if name not in have:
            con.execute(f"ALTER TABLE runs ADD COLUMN {name} {decl}")


def _score(row: tuple) -> Score:
    r = dict(zip(COLUMNS, row, strict=True))
    r["passed"] = bool(r["passed"])
    r["landed"] = None if r["landed"] is None else bool(r["landed"])
    return Score(**r)


def _best_key(s: Score) -> tuple:
    miss = s.miss_m if s.miss_m is not None else 0.0
    return (not s.passed, miss, math.hypot(s.rms_north_m, s.rms_east_m))


def best(scores: list[Score]) -> list[Score]:
    """The best run of each mission: passed first, then the smallest landing miss, then the
    smallest RMS position error."""

    out: dict[str, Score] = {}
    for s in scores:
        if s.mission not in out or _best_key(s) < _best_key(out[s.mission]):
            out[s.mission] = s
    return sorted(out.values(), key=lambda s: s.mission)


def compare(scores: list[Score]) -> dict[str, Score]:
    """The best run (``best``'s order) of each way of flying present: {flown_by: Score}, in
    the order autopilot, hand, mixed (the same mission flown by hand and by the autopilot,
    side by side: the sea trial's appendix C, step 6)."""
    out = {}
    for how in FLOWN_BY:
        mine = [s for s in scores if s.flown_by == how]
        if mine:
            out[how] = _best_one(mine)
    return out


def _best_one(scores: list[Score]) -> Score:
    return min(scores, key=_best_key)


def as_json(scores: list[Score]) -> str:
    return json.dumps([s.__dict__ for s in scores], indent=2)
