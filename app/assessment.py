"""The assessment of a run: named criteria, each with a limit, a weight and a score, and a
weighted total (issue 46).

A criterion measures one figure of the run (``measure``), and scores it 0-100: 100 at or
within its limit, falling linearly to 0 at ``zero_at`` (and 0 beyond). The total is the
weighted mean of the scores of the criteria the run can be judged on (a mission with no
landing is not judged on the landing). The criteria and their defaults, with where each
number comes from:

- ``landing_miss`` [m]: the largest funnel-to-post distance when the funnels reach the post
  tops. Limit: the frame's capture tolerance, funnel mouth radius less post radius (the
  parameter set's ``[docking]``: 0.25 m at full scale, 0.10 m at model scale; the funnels on
  the tree's bottom plate and the guideposts of the thesis, chapter 5 and appendix C, fig. 1-5);
  0 at twice that (a funnel then lands on the post's top, not around it). A mission that
  tried to land and never reached the posts scores 0.
- ``contact_speed`` [m/s]: the tree's downward speed at that moment. Limit: the parameter set's
  ``max_landing_speed_mps`` (0.10 m/s full scale, 0.05 m/s model scale); 0 at twice that.
- ``time_off_tolerance`` [s]: time in the dock legs, before the funnels reach the post tops,
  with the tree further (horizontally) from its reference than the capture tolerance (the
  limit of the console's position alarm, ``app.console.alarms``). Limit 10 s (a gust of
  current answered at once), 0 at 120 s.
- ``time_saturated`` [s]: time with a thruster at 99 % of its thrust or more. Limit 30 s,
  the limit ``app.scores`` has held since the first scores (a thruster at its limit this long
  means the ROV was not in control; thesis 4.2.2 sizes the thrust so the landing needs under
  half of it); 0 at 120 s.
- ``slack_events`` [-]: episodes of slack wire while the tree hangs (before the funnels reach
  the post tops): the tension below 10 % of the static tension, DNV-RP-H103's slack criterion
  (a dynamic drop of more than 90 % of the static tension), as ``missions.seaway`` and the
  console's slack alarm judge it; the static tension is the tree's submerged weight W0.
  Limit 0 (slack wire is to be avoided), 0 at 3 (every slack is followed by a snap load).
- ``alarm_clear_s`` [s]: the longest time an alarm stood before it was answered, i.e. went off
  (one still on at the end counts to the end). The console has no acknowledge button: an alarm
  is answered by removing its cause. Limit 30 s, 0 at 180 s (our choice: no standard gives one;
  the console's own saturation alarm trips after 2 s and the position alarm at once).
- ``time_to_land`` [s]: from the start of the first dock leg to the funnels at the post tops.
  Limit 600 s (the library's full-scale docking takes 290 s by autopilot, appendix C step 6
  asks for the time of a manual landing to compare), 0 at 2 400 s (the library dock leg's
  timeout).

Weights: the landing's miss 3, its speed 2 (these two decide whether the tree and its
connectors are damaged), time off tolerance 2 and slack wire 2 (the hazards on the way
down), time saturated, alarms and time to land 1 each.

The instructor changes them with a TOML file (``--criteria FILE``; the console keeps one in
its recordings folder, ``PUT /api/assessment/criteria``): see docs/formats.md.
"""

from __future__ import annotations

import itertools
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from control.columns import LogRows
from missions.scoring import MissionResult
from sim.docking import DockingFrame, DockingLayout, check_alignment
from sim.params import ParameterSet

FORMAT_VERSION = 1
CRITERIA_FILE = "criteria.toml"
"""The console's criteria, in its recordings folder."""
MAX_FILE_BYTES = 64 * 1024
SLACK_FRACTION = 0.1
"""Slack when the tension is below this share of the static tension (DNV-RP-H103, as
``missions.seaway.SLACK_FRACTION``)."""
FROM_FRAME = None
"""A limit taken from the run's parameter set (capture tolerance, landing-speed limit)."""


@dataclass(frozen=True)
class Definition:
    """What a criterion measures, its unit, its defaults and the range a file may give."""

    name: str
    title: str
    unit: str
    limit: float | None
    """Default limit (None: from the parameter set's docking layout)."""
    zero_at: float | None
    """Default value where the score reaches 0 (None: twice the limit)."""
    weight: float
    limit_max: float
    """Largest limit a file may set (the smallest is 0)."""
    fmt: str = ".2f"


DEFINITIONS: tuple[Definition, ...] = (
    Definition("landing_miss", "landing miss", "m", FROM_FRAME, None, 3.0, 10.0, ".3f"),
    Definition("contact_speed", "contact speed", "m/s", FROM_FRAME, None, 2.0, 5.0, ".3f"),
    Definition(
        "time_off_tolerance",
        "time off the funnels' tolerance",
        "s",
        10.0,
        120.0,
        2.0,
        3600.0,
        ".1f",
    ),
    Definition("time_saturated", "time saturated", "s", 30.0, 120.0, 1.0, 3600.0, ".1f"),
    Definition("slack_events", "slack-wire events", "-", 0.0, 3.0, 2.0, 100.0, ".0f"),
    Definition(
        "alarm_clear_s", "longest alarm before cleared", "s", 30.0, 180.0, 1.0, 3600.0, ".1f"
    ),
    Definition("time_to_land", "time to land", "s", 600.0, 2400.0, 1.0, 86400.0, ".0f"),
)
BY_NAME = {d.name: d for d in DEFINITIONS}
WEIGHT_MAX = 100.0


class CriteriaError(ValueError):
    """A criteria file or request is invalid: one line per problem, naming the field and what
    is allowed."""


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class CriterionSpec(_Model):
    """One criterion in a file: any field left out keeps its default."""

    limit: float | None = Field(default=None, ge=0.0, allow_inf_nan=False)
    zero_at: float | None = Field(default=None, ge=0.0, allow_inf_nan=False)
    weight: float | None = Field(default=None, ge=0.0, le=WEIGHT_MAX, allow_inf_nan=False)


class CriteriaSpec(_Model):
    """A criteria file: ``format_version = 1`` and a ``[criteria.NAME]`` table per criterion
    changed."""

    format_version: int = Field(default=FORMAT_VERSION, ge=FORMAT_VERSION, le=FORMAT_VERSION)
    criteria: dict[str, CriterionSpec] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _known(self) -> CriteriaSpec:
        for name, spec in self.criteria.items():
            d = BY_NAME.get(name)
            if d is None:
                raise ValueError(
                    f"criteria.{name}: no such criterion (one of {', '.join(BY_NAME)})"
                )
            if spec.limit is not None and spec.limit > d.limit_max:
                raise ValueError(
                    f"criteria.{name}.limit: {spec.limit:g} {d.unit} is outside 0 to "
                    f"{d.limit_max:g} {d.unit}"
                )
            limit = spec.limit if spec.limit is not None else d.limit
            if spec.zero_at is not None and limit is not None and spec.zero_at <= limit:
                raise ValueError(
                    f"criteria.{name}.zero_at: {spec.zero_at:g} {d.unit} must be above the "
                    f"limit ({limit:g} {d.unit})"
                )
        return self


@dataclass(frozen=True)
class Criterion:
    """A criterion as used: its definition and the limit, zero and weight in force (limit and
    zero None: from the run's parameter set)."""

    definition: Definition
    limit: float | None
    zero_at: float | None
    weight: float

    @property
    def name(self) -> str:
        return self.definition.name


@dataclass(frozen=True)
class Criteria:
    """The criteria in force, in ``DEFINITIONS``' order."""

    items: tuple[Criterion, ...]

    def __iter__(self):
        return iter(self.items)

    def to_toml(self) -> str:
        """The whole set as a criteria file (every field written; a limit from the parameter
        set left out with a comment)."""
        lines = [f"format_version = {FORMAT_VERSION}", ""]
        for c in self.items:
            d = c.definition
            lines.append(f"[criteria.{c.name}]  # {d.title} [{d.unit}]")
            if c.limit is None:
                lines.append("# limit: the parameter set's (leave out to keep it)")
            else:
                lines.append(f"limit = {c.limit:g}")
            if c.zero_at is not None:
                lines.append(f"zero_at = {c.zero_at:g}")
            lines.append(f"weight = {c.weight:g}")
            lines.append("")
        return "\n".join(lines)

    def as_dict(self) -> list[dict]:
        return [
            {
                "name": c.name,
                "title": c.definition.title,
                "unit": c.definition.unit,
                "limit": c.limit,
                "zero_at": c.zero_at,
                "weight": c.weight,
                "limit_max": c.definition.limit_max,
            }
            for c in self.items
        ]


def default_criteria() -> Criteria:
    return Criteria(tuple(Criterion(d, d.limit, d.zero_at, d.weight) for d in DEFINITIONS))


def criteria_from_spec(spec: CriteriaSpec) -> Criteria:
    out = []
    for d in DEFINITIONS:
        s = spec.criteria.get(d.name, CriterionSpec())
        limit = s.limit if s.limit is not None else d.limit
        zero_at = s.zero_at if s.zero_at is not None else d.zero_at
        if s.limit is not None and s.zero_at is None and d.zero_at is not None:
            zero_at = max(d.zero_at, 2.0 * s.limit) if d.zero_at <= s.limit else d.zero_at
        weight = s.weight if s.weight is not None else d.weight
        out.append(Criterion(d, limit, zero_at, weight))
    return Criteria(tuple(out))


def _problems(err: ValidationError) -> str:
    lines = []
    for e in err.errors():
        where = ".".join(str(p) for p in e["loc"]) or "file"
        msg = str(e["msg"]).removeprefix("Value error, ")
        if e["type"] in ("greater_than_equal", "less_than_equal", "less_than", "greater_than"):
            name = str(e["loc"][-1]) if e["loc"] else ""
            crit = BY_NAME.get(str(e["loc"][1])) if len(e["loc"]) > 2 else None
            if crit is not None and name == "weight":
                msg = f"{e['input']} is outside 0 to {WEIGHT_MAX:g}"
            elif crit is not None and name in ("limit", "zero_at"):
                msg = f"{e['input']} is below 0 {crit.unit}"
            elif name == "format_version":
                msg = f"{e['input']} is not {FORMAT_VERSION} (the only version)"
        elif e["type"] == "extra_forbidden":
            msg = "not a field (limit, zero_at, weight; or format_version, criteria)"
        named = msg.startswith(where) or (where == "file" and msg.startswith("criteria."))
        lines.append(msg if named else f"{where}: {msg}")
    return "\n".join(lines)


def parse_criteria(data: Mapping, source: str = "criteria") -> Criteria:
    """Criteria from a parsed file or request body; CriteriaError names each bad field."""
    try:
        return criteria_from_spec(CriteriaSpec.model_validate(data))
    except ValidationError as err:
        raise CriteriaError(f"invalid criteria in {source}:\n{_problems(err)}") from None


def parse_criteria_text(text: str, source: str = "criteria") -> Criteria:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise CriteriaError(f"invalid criteria in {source}: not TOML ({err})") from None
    return parse_criteria(data, source)


def load_criteria(path: Path | None) -> Criteria:
    """The criteria of a file; the defaults when ``path`` is None or (the console's own file)
    does not exist."""
    if path is None or not path.exists():
        return default_criteria()
    if path.stat().st_size > MAX_FILE_BYTES:
        raise CriteriaError(f"{path}: larger than {MAX_FILE_BYTES} bytes; not a criteria file")
    return parse_criteria_text(path.read_text(encoding="utf-8"), str(path))


# --- measuring a run ---------------------------------------------------------------------


@dataclass(frozen=True)
class RunFacts:
    """What the assessment reads of a run besides its figures: where it was (frame and layout)
    and what the tree weighs. Any of them None: the criteria that need it are not judged."""

    result: MissionResult
    events: list[dict] = field(default_factory=list)
    frame: DockingFrame | None = None
    layout: DockingLayout | None = None
    tree_half_height_m: float | None = None
    weight_newton: float | None = None
    ps: ParameterSet | None = None
    """The run's parameter set: with it, a run that recorded no alarm states (a headless run)
    has its alarms found by the console's own monitor over its rows."""
    uses_sensors: bool = True
    """The run's feedback was the EKF (the innovation and dropout alarms are armed)."""
    every_step: bool = True
    """The rows are every plant step (a run's own log). A recording keeps 20 rows a second,
    which lose most sensor samples' accept flags: the dropout and innovation alarms, which
    read those, are then not replayed."""


def facts_of_run(result: MissionResult, sim: Any) -> RunFacts:
    """What the assessment needs of a run just flown: its events, and the simulation's
    parameter set and docking frame (``control.simulation.Simulation``)."""
    ps = sim.ps
    return RunFacts(
        result,
        result.events,
        sim.docking_frame,
        ps.spec.docking.to_numeric(),
        float(ps.tree.dimensions_m[2]) / 2.0,
        float(ps.tree.submerged_weight_newton),
        ps,
        sim.settings.feedback == "ekf",
    )


def _landing(facts: RunFacts) -> dict | None:
    """The first landing: the result's, else the recorded event's data."""
    if facts.result.landings:
        return vars(facts.result.landings[0])
    for e in facts.events:
        if e.get("kind") == "landing" and isinstance(e.get("data"), dict):
            return dict(e["data"])
    return None


def _dock_start_s(facts: RunFacts) -> float | None:
    """Log time the first dock leg started [s]."""
    rows = facts.result.log
    t0 = float(rows.t_s[0]) if rows is not None and len(rows) else 0.0
    for leg in facts.result.legs:
        if leg.type == "dock":
            return t0 + leg.start_s
    for e in facts.events:
        if e.get("kind") == "leg" and (e.get("data") or {}).get("type") == "dock":
            return float(e["t_s"])
    return None


def _contact_row(facts: RunFacts, rows: LogRows) -> int | None:
    """First row with the tree's bottom at or below the post tops (None: never, or unknown)."""
    if facts.frame is None or facts.layout is None or facts.tree_half_height_m is None:
        return None
    bottom = rows["tree_eta_n"][:, 2] + facts.tree_half_height_m
    hits = np.flatnonzero(bottom >= facts.frame.post_top_depth_m(facts.layout))
    return int(hits[0]) if hits.size else None


def _dock_mask(result: MissionResult, rows: LogRows) -> np.ndarray:
    """Rows of the dock legs (none when the mission has none)."""
    t = rows.t_s - float(rows.t_s[0])
    mask = np.zeros(len(rows), dtype=bool)
    for leg in result.legs:
        if leg.type == "dock":
            mask |= (t >= leg.start_s - 1e-9) & (t < leg.start_s + leg.duration_s - 1e-9)
    return mask


def _landing_values(facts: RunFacts, contact_row: int | None) -> dict[str, float]:
    """Landing miss, contact speed and time to land. A mission's landing is its own (the
    result's, or its recorded event); a tree put down with no dock leg (flown by hand) is
    judged from its rows where its bottom reached the post tops, its time to land counted
    from the run's start."""
    rows, out = facts.result.log, {}
    landing = _landing(facts)
    dock_start = _dock_start_s(facts)
    if landing is not None and math.isfinite(float(landing.get("miss_m", math.nan))):
        out["landing_miss"] = float(landing["miss_m"])
        out["contact_speed"] = abs(float(landing.get("contact_speed_mps", math.nan)))
    elif dock_start is None and contact_row is not None and rows is not None:
        assert facts.frame is not None and facts.layout is not None  # _contact_row needs them
        out["landing_miss"] = check_alignment(
            rows["tree_eta_n"][contact_row], facts.frame, facts.layout
        ).miss_m
        out["contact_speed"] = abs(_down_speed_mps(rows, contact_row))
        out["time_to_land"] = float(rows.t_s[contact_row] - rows.t_s[0])
    elif dock_start is not None:
        out["landing_miss"] = out["contact_speed"] = math.inf
    if dock_start is not None:
        if contact_row is not None and rows is not None:
            out["time_to_land"] = float(rows.t_s[contact_row]) - dock_start
        elif landing is not None and math.isfinite(float(landing.get("t_contact_s", math.nan))):
            out["time_to_land"] = float(landing["t_contact_s"]) - dock_start
        else:
            out["time_to_land"] = math.inf
    return out


def _down_speed_mps(rows: LogRows, k: int) -> float:
    """The tree's downward speed arriving at row ``k`` [m/s] (from its depth, row to row)."""
    j = max(k - 1, 0)
    k = max(k, 1)
    down, t = rows["tree_eta_n"][:, 2], rows.t_s
    return float((down[k] - down[j]) / (t[k] - t[j]))


def slack_episodes(tension_newton: np.ndarray, static_newton: float) -> int:
    """Episodes (runs of rows) with the tension below ``SLACK_FRACTION`` of the static."""
    slack = np.asarray(tension_newton, float) < SLACK_FRACTION * static_newton
    return int(np.count_nonzero(slack[1:] & ~slack[:-1]) + (1 if slack.size and slack[0] else 0))


def longest_alarm_s(events: list[dict], end_s: float) -> float | None:
    """Longest time an alarm stood before it went off [s], from the recorded ``alarm``
    events (None: the run recorded no alarm states, e.g. a headless run)."""
    on: dict[str, float] = {}
    longest = 0.0
    seen = False
    for e in sorted(
        (e for e in events if e.get("kind") == "alarm"), key=lambda e: float(e.get("t_s", 0))
    ):
        data = e.get("data") or {}
        name, active = data.get("name"), data.get("active")
        if not isinstance(name, str) or not isinstance(active, bool) or name == "mission":
            continue
        seen = True
        t = float(e.get("t_s", 0.0))
        if active:
            on.setdefault(name, t)
        elif name in on:
            longest = max(longest, t - on.pop(name))
    for t in on.values():
        longest = max(longest, end_s - t)
    return longest if seen else None


def measure(facts: RunFacts) -> dict[str, float | None]:
    """Each criterion's value for a run: a number, ``math.inf`` when the run failed it
    outright (a landing tried and never reached), None when the run cannot be judged on it."""
    result, rows = facts.result, facts.result.log
    out: dict[str, float | None] = dict.fromkeys(BY_NAME)
    out["time_saturated"] = float(result.saturated_time_s)
    contact_row = _contact_row(facts, rows) if rows is not None and len(rows) else None
    out.update(_landing_values(facts, contact_row))
    if rows is None or len(rows) < 2:
        return out
    dt = float(np.median(np.diff(rows.t_s)))
    if facts.layout is not None:
        tree, ref = rows["tree_eta_n"], rows["eta_ref_n"]
        off = np.hypot(tree[:, 0] - ref[:, 0], tree[:, 1] - ref[:, 1])
        docking = _dock_mask(result, rows)
        if contact_row is not None:
            docking[contact_row:] = False  # resting on the frame is not flying off the reference
        if docking.any():
            out["time_off_tolerance"] = float(
                np.count_nonzero(docking & (off > facts.layout.tolerance_m)) * dt
            )
    if facts.weight_newton is not None and "wire_tension" in rows.layout.starts:
        hanging = slice(0, contact_row) if contact_row is not None else slice(None)
        tension = np.asarray(rows["wire_tension"], float).reshape(len(rows), -1)[hanging, 0]
        out["slack_events"] = float(slack_episodes(tension, facts.weight_newton))
    end_s = float(rows.t_s[-1])
    out["alarm_clear_s"] = longest_alarm_s(facts.events, end_s)
    if out["alarm_clear_s"] is None and facts.ps is not None:
        out["alarm_clear_s"] = longest_alarm_s(alarm_events(facts, rows), end_s)
    return out


ALARM_BLOCK_S = 0.5
"""The console's monitor is fed rows in blocks this long when it replays a run [s] (the
console feeds it each tick's rows, a few hundredths of a second; the alarms' limits are
seconds)."""


PER_SAMPLE_ALARMS = ("dropout", "innovation")


def alarm_events(facts: RunFacts, rows: LogRows) -> list[dict]:
    """The console's alarms (``app.console.alarms.AlarmMonitor``, the limits it uses for the
    parameter set) over a run's rows, as the ``alarm`` events the console records: on and
    off, with their times. The free-flying ROV's set point and the mount check are not in the
    rows; those two stay off."""
    from app.console.alarms import AlarmLimits, AlarmMonitor

    ps = facts.ps
    assert ps is not None
    support = (
        facts.frame.post_top_depth_m(facts.layout)
        if facts.frame is not None and facts.layout is not None
        else None
    )
    monitor = AlarmMonitor(
        AlarmLimits.for_params(ps),
        len(ps.spec.rov.thrusters.configuration),
        float(ps.tree.submerged_weight_newton),
        uses_sensors=facts.uses_sensors,
        support_depth_m=support,
        tree_half_height_m=float(ps.tree.dimensions_m[2]) / 2.0,
    )
    t = rows.t_s
    edges = np.searchsorted(t, np.arange(t[0], t[-1] + ALARM_BLOCK_S, ALARM_BLOCK_S), "right")
    has_tension = "wire_tension" in rows.layout.starts
    events: list[dict] = []
    state: dict[str, bool] = {}
    for a, b in itertools.pairwise(edges):
        if b <= a:
            continue
        block = replace(rows, data=rows.data[a:b])
        tension = float(np.ravel(block["wire_tension"])[-1]) if has_tension else None
        for alarm in monitor.update(block, tension):
            if not facts.every_step and alarm.name in PER_SAMPLE_ALARMS:
                continue
            if alarm.active != state.get(alarm.name, False):
                state[alarm.name] = alarm.active
                events.append(
                    {
                        "t_s": float(block.t_s[-1]),
                        "kind": "alarm",
                        "text": f"{alarm.name} {'on' if alarm.active else 'off'}",
                        "data": {"name": alarm.name, "active": alarm.active},
                    }
                )
    if not events:  # no alarm at all: answered every one, in no time
        events.append({"t_s": float(t[0]), "kind": "alarm", "data": {"name": "", "active": False}})
    return events


# --- scoring -----------------------------------------------------------------------------


class FrameLimitsLike(Protocol):
    """What the limits taken from the parameter set read: a ``DockingLayout`` or a
    ``FrameLimits``."""

    @property
    def tolerance_m(self) -> float: ...

    @property
    def max_landing_speed_mps(self) -> float: ...


@dataclass(frozen=True)
class FrameLimits:
    """The docking layout's two limits alone (what the scores database keeps of a run)."""

    tolerance_m: float
    max_landing_speed_mps: float

    @staticmethod
    def of(layout: FrameLimitsLike | None) -> FrameLimits | None:
        if layout is None:
            return None
        return FrameLimits(float(layout.tolerance_m), float(layout.max_landing_speed_mps))


def limits_for(c: Criterion, layout: FrameLimitsLike | None) -> tuple[float | None, float | None]:
    """The limit and zero in force for a run (a limit from the parameter set needs its
    docking layout: None without)."""
    limit = c.limit
    if limit is None and layout is not None:
        limit = (
            float(layout.tolerance_m)
            if c.name == "landing_miss"
            else float(layout.max_landing_speed_mps)
        )
    if limit is None:
        return None, None
    zero = c.zero_at if c.zero_at is not None else 2.0 * limit
    return round(limit, 9), round(max(zero, limit), 9)


def criterion_score(value: float, limit: float, zero_at: float) -> float:
    """100 at or within the limit, falling linearly to 0 at ``zero_at``, 0 beyond; never
    rising with the value."""
    if not value > limit:  # NaN never comes here: measure gives None instead
        return 100.0
    if value >= zero_at or zero_at <= limit:
        return 0.0
    return 100.0 * (zero_at - value) / (zero_at - limit)


@dataclass(frozen=True)
class CriterionResult:
    name: str
    title: str
    unit: str
    limit: float | None
    zero_at: float | None
    weight: float
    value: float | None
    """None: not judged (the run has no such figure); inf: failed outright."""
    score: float | None

    def value_text(self) -> str:
        d = BY_NAME[self.name]
        if self.value is None:
            return "n/a"
        if math.isinf(self.value):
            return "not landed" if self.name != "time_saturated" else "inf"
        return f"{self.value:{d.fmt}}"

    def limit_text(self) -> str:
        return "n/a" if self.limit is None else f"{self.limit:g}"

    def zero_text(self) -> str:
        return "n/a" if self.zero_at is None else f"{self.zero_at:g}"


@dataclass(frozen=True)
class Assessment:
    """A run's criteria with value and score, and the weighted total (0-100)."""

    criteria: tuple[CriterionResult, ...]
    total: float | None
    """Weighted mean of the judged criteria's scores (None: none judged or all weights 0)."""

    def as_dict(self) -> dict:
        return {
            "total": self.total,
            "criteria": [
                {
                    **vars(c),
                    "value": c.value if c.value is None or math.isfinite(c.value) else None,
                    "failed_outright": c.value is not None and math.isinf(c.value),
                }
                for c in self.criteria
            ],
        }


def assess(
    values: Mapping[str, float | None], criteria: Criteria, layout: FrameLimitsLike | None
) -> Assessment:
    """Score measured values (``measure``) with the criteria in force."""
    out = []
    for c in criteria:
        limit, zero = limits_for(c, layout)
        value = values.get(c.name)
        score = None
        if value is not None and limit is not None and zero is not None:
            score = criterion_score(float(value), limit, zero)
        d = c.definition
        out.append(CriterionResult(c.name, d.title, d.unit, limit, zero, c.weight, value, score))
    judged = [c for c in out if c.score is not None and c.weight > 0]
    weight = sum(c.weight for c in judged)
    total = sum(c.weight * (c.score or 0.0) for c in judged) / weight if weight > 0 else None
    return Assessment(tuple(out), total)
