"""The weather window: a forecast against an operability table, reduced by DNV-ST-N001's
alpha factor (issue 44).

A weather-restricted operation (DNV-ST-N001, section 2.6) has a reference period
T_R = T_POP + T_C, its planned duration plus a contingency, and its operational limit is
OP_WF = alpha x OP_LIM: the design limit (here the table's allowable Hs for the hour's peak
period and wave heading) times an alpha factor that falls with a longer reference period
and rises with a better forecast (the base case built in, ``ALPHA_TABLES``; the others from
a CSV, ``read_alpha_table``). An hour is *go* when the forecast's Hs
is at most OP_WF there and its current no faster than the table's; a *window* is a run of go
hours at least T_R long.

The forecast is a CSV (``read_forecast``): a header row naming ``FORECAST_COLUMNS`` (more
columns may follow and are ignored), one row per time, evenly spaced and rising. Anything
else is a ``ForecastError`` of one line naming the file's line, the row and the column.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path

G = 9.80665
"""Standard gravity [m/s^2] (the wave steepness check)."""

FORECAST_COLUMNS = ("time", "hs_m", "tp_s", "wave_dir_deg", "current_mps", "current_dir_deg")
RANGES: dict[str, tuple[float, float, str]] = {
    "hs_m": (0.0, 20.0, "m: a forecast Hs above 20 m is more likely feet or centimetres"),
    "tp_s": (1.0, 30.0, "s"),
    "wave_dir_deg": (0.0, 360.0, "deg"),
    "current_mps": (0.0, 3.0, "m/s: knots or cm/s show here"),
    "current_dir_deg": (0.0, 360.0, "deg"),
}
"""Allowed range of each number column (inclusive), with its unit and why."""
MAX_STEEPNESS = 1.0 / 10.0
"""Largest sea steepness 2 pi Hs / (g Tp^2) a forecast may give: DNV-RP-C205 bounds design
sea states at 1/15 (Tp under 8 s) to 1/25 (over 15 s); a sea steeper than 1/10 breaks, so Hs
and Tp cannot both be right (an Hs in feet, a mean period given for Tp)."""


class ForecastError(ValueError):
    """A forecast file that cannot be used: one line naming the line, row and column."""


@dataclass(frozen=True)
class ForecastHour:
    """One row of a forecast, SI and UTC (angles in degrees, as in the file)."""

    time: datetime
    hs_m: float
    tp_s: float
    wave_dir_deg: float
    current_mps: float
    current_dir_deg: float


@dataclass(frozen=True)
class Forecast:
    source: str
    hours: tuple[ForecastHour, ...]
    step: timedelta
    """Time between rows (one row when the forecast has one: an hour)."""


def _where(source: str, line: int, row: int | None, column: str) -> str:
    at = "header" if row is None else f"row {row}"
    return f"{source} line {line} ({at}), column {column}"


def _number(text: str, where: str, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ForecastError(f"{where}: {text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise ForecastError(f"{where}: {text.strip()} is no value (NaN or infinite)")
    low, high, unit = RANGES[column]
    if not low <= value <= high:
        raise ForecastError(f"{where}: {value:g} is outside [{low:g}, {high:g}] {unit}")
    return value


def _time(text: str, where: str) -> datetime:
    try:
        t = datetime.fromisoformat(text.strip())
    except ValueError:
        raise ForecastError(
            f"{where}: {text.strip()!r} is not an ISO 8601 time (2026-03-01T06:00:00Z)"
        ) from None
    if t.tzinfo is None or t.utcoffset() != timedelta(0):
        raise ForecastError(f"{where}: {text.strip()!r} is not in UTC: end it with Z or +00:00")
    return t.astimezone(UTC)


def read_forecast(path: Path) -> Forecast:
    """The forecast CSV at ``path``; ForecastError naming the line, row and column of the
    first problem: a missing column, a value that is not a number or is NaN, out of its
    range (units that cannot be right), a sea steeper than breaking, a time not in ISO 8601
    UTC, not after the row before (unsorted or repeated), or after a gap (a step longer than
    the forecast's first)."""
    source = str(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        raise ForecastError(f"{source}: cannot read the forecast: {err}") from None
    reader = csv.reader(text.splitlines())
    header = next(reader, None)
    if header is None or not any(h.strip() for h in header):
        raise ForecastError(
            f"{_where(source, 1, None, 'time')}: empty file; the header must name "
            + ", ".join(FORECAST_COLUMNS)
        )
    names = [h.strip() for h in header]
    for column in FORECAST_COLUMNS:
        if column not in names:
            raise ForecastError(
                f"{_where(source, 1, None, column)}: missing; the header must name "
                + ", ".join(FORECAST_COLUMNS)
            )
    index = {c: names.index(c) for c in FORECAST_COLUMNS}
    hours: list[ForecastHour] = []
    step: timedelta | None = None
    for row, fields in enumerate(reader, start=1):
        line = reader.line_num
        if not any(f.strip() for f in fields):
            raise ForecastError(f"{_where(source, line, row, 'time')}: empty row")
        hour = _hour(source, line, row, fields, index)
        if hours:
            gap = hour.time - hours[-1].time
            where = _where(source, line, row, "time")
            if gap <= timedelta(0):
                raise ForecastError(
                    f"{where}: {_iso(hour.time)} is not after row {row - 1}'s "
                    f"{_iso(hours[-1].time)}: the times must rise (sorted, none repeated)"
                )
            if step is None:
                step = gap
            elif gap != step:
                raise ForecastError(
                    f"{where}: {_hours(gap)} after row {row - 1} where the forecast's step is "
                    f"{_hours(step)}: a gap or an uneven step"
                )
        hours.append(hour)
    if not hours:
        raise ForecastError(f"{source} line 2 (row 1), column time: the forecast has no rows")
    return Forecast(source, tuple(hours), step or timedelta(hours=1))


def _hour(
    source: str, line: int, row: int, fields: list[str], index: dict[str, int]
) -> ForecastHour:
    values: dict[str, float] = {}
    for column, i in index.items():
        where = _where(source, line, row, column)
        if i >= len(fields) or not fields[i].strip():
            raise ForecastError(f"{where}: no value")
        if column != "time":
            values[column] = _number(fields[i], where, column)
    t = _time(fields[index["time"]], _where(source, line, row, "time"))
    steep = 2.0 * math.pi * values["hs_m"] / (G * values["tp_s"] ** 2)
    if steep > MAX_STEEPNESS:
        raise ForecastError(
            f"{_where(source, line, row, 'hs_m')}: Hs {values['hs_m']:g} m with Tp "
            f"{values['tp_s']:g} s is a sea of steepness 1/{1 / steep:.1f}, steeper than "
            f"breaking (1/{1 / MAX_STEEPNESS:g}): Hs or Tp is in the wrong unit"
        )
    return ForecastHour(time=t, **values)


def _iso(t: datetime) -> str:
    return t.astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _hours(d: timedelta) -> str:
    return f"{d.total_seconds() / 3600:g} h"


# ------------------------------------------------------------------------------------------
# alpha factors
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class AlphaTable:
    """Alpha factors for waves by reference period (rows: up to ``hours_max``) and design
    limit Hs (columns: ``hs_m``, linear between them, the end values beyond)."""

    name: str
    source: str
    hours_max: tuple[float, ...]
    hs_m: tuple[float, ...]
    values: tuple[tuple[float, ...], ...]

    def alpha(self, reference_hours: float, limit_hs_m: float) -> float:
        """alpha for a reference period [h] and a design limit Hs [m]; ValueError beyond
        the longest period (no longer a weather-restricted operation)."""
        row = next((r for r, h in enumerate(self.hours_max) if reference_hours <= h), None)
        if row is None:
            raise ValueError(
                f"a reference period of {reference_hours:g} h is longer than the alpha "
                f"table's {self.hours_max[-1]:g} h: DNV-ST-N001 treats such an operation as "
                "weather-unrestricted (design on extreme-value statistics, not a forecast)"
            )
        v = self.values[row]
        hs = self.hs_m
        if limit_hs_m <= hs[0]:
            return v[0]
        for k in range(1, len(hs)):
            if limit_hs_m <= hs[k]:
                f = (limit_hs_m - hs[k - 1]) / (hs[k] - hs[k - 1])
                return v[k - 1] + f * (v[k] - v[k - 1])
        return v[-1]

    def as_dict(self) -> dict:
        return {
            "table": self.name,
            "source": self.source,
            "reference_hours_max": list(self.hours_max),
            "hs_m": list(self.hs_m),
            "values": [list(r) for r in self.values],
        }


_BASE_SOURCE = (
    "DNV-OS-H101 (2011) Table 4-3, alpha factor for waves, base case (one forecast source, no "
    "meteorologist on site), as DNV-ST-N001 (2016) Sec. 2.6 carries it; typed from the table "
    "as remembered, not checked against a copy of the standard: check it against your "
    "edition, or give the table you work to with --alpha-table FILE.csv"
)
ALPHA_TABLES: dict[str, AlphaTable] = {
    "base": AlphaTable(
        "base",
        _BASE_SOURCE,
        (12.0, 24.0, 36.0, 48.0, 72.0),
        (1.0, 2.0, 4.0, 6.0, 8.0),
        (
            (0.65, 0.76, 0.79, 0.80, 0.80),
            (0.63, 0.73, 0.76, 0.79, 0.80),
            (0.62, 0.71, 0.73, 0.76, 0.78),
            (0.60, 0.68, 0.71, 0.74, 0.76),
            (0.55, 0.63, 0.68, 0.72, 0.74),
        ),
    )
}
"""The alpha-factor table for waves built in (``--alpha-table base``). Only the base case: the
standard's tables for better forecasts (a meteorologist on site, the waves monitored) raise
alpha, and an operation planned on them must use the edition's own numbers, given as a CSV
(``read_alpha_table``)."""


def read_alpha_table(path: Path) -> AlphaTable:
    """An alpha table from a CSV: header ``reference_hours`` then the design Hs of each
    column [m]; a row per reference period (its upper bound [h], rising) with the alphas."""
    source = str(path)
    try:
        lines = list(csv.reader(path.read_text(encoding="utf-8-sig").splitlines()))
    except (OSError, UnicodeDecodeError) as err:
        raise ValueError(f"{source}: cannot read the alpha table: {err}") from None
    if not lines or [c.strip() for c in lines[0]][:1] != ["reference_hours"]:
        raise ValueError(f"{source} line 1: the header must start with reference_hours")
    try:
        hs = tuple(float(c) for c in lines[0][1:])
        rows = [tuple(float(c) for c in r) for r in lines[1:] if any(x.strip() for x in r)]
    except ValueError as err:
        raise ValueError(f"{source}: {err}") from None
    if not hs or not rows or any(len(r) != len(hs) + 1 for r in rows):
        raise ValueError(f"{source}: every row needs reference_hours and one alpha a column")
    if any(not 0.0 < a <= 1.0 for r in rows for a in r[1:]):
        raise ValueError(f"{source}: every alpha must lie in (0, 1]")
    if list(hs) != sorted(set(hs)) or [r[0] for r in rows] != sorted({r[0] for r in rows}):
        raise ValueError(f"{source}: the Hs columns and the reference hours must rise")
    return AlphaTable(
        path.stem,
        f"{source} (the planner's own)",
        tuple(r[0] for r in rows),
        hs,
        tuple(tuple(r[1:]) for r in rows),
    )


# ------------------------------------------------------------------------------------------
# the table's limit at an hour, go / no-go, windows
# ------------------------------------------------------------------------------------------

HEADING_SPAN_MAX_DEG = 90.0
"""Widest arc between two of the table's headings across which a forecast heading counts as
covered (the lower of the two allowables applies); beyond it the hour is no-go."""


def _bracket(values: Sequence[float], x: float) -> tuple[float, ...] | None:
    """The table values around ``x`` (one when it is one of them; None outside)."""
    for v in values:
        if abs(v - x) < 1e-6:
            return (v,)
    below = [v for v in values if v < x]
    above = [v for v in values if v > x]
    if not below or not above:
        return None
    return (max(below), min(above))


def _bracket_heading(values: Sequence[float], x: float) -> tuple[float, ...] | None:
    """The table headings around ``x`` on the circle, no further apart than
    ``HEADING_SPAN_MAX_DEG`` (None: not covered)."""
    x %= 360.0
    for v in values:
        if min(abs(v - x), 360.0 - abs(v - x)) < 1e-6:
            return (v,)
    if len(values) < 2:
        return None
    ordered = sorted(v % 360.0 for v in values)
    for a, b in zip(ordered, [*ordered[1:], ordered[0] + 360.0], strict=True):
        xx = x if x >= a else x + 360.0
        if a < xx < b:
            return (a, b % 360.0) if b - a <= HEADING_SPAN_MAX_DEG else None
    return None


@dataclass(frozen=True)
class Verdict:
    """One forecast hour judged."""

    hour: ForecastHour
    wave_heading_deg: float
    """The waves' heading relative to the vessel (sim.vessel's beta) [deg]."""
    allowable_hs_m: float | None
    alpha: float | None
    limit_hs_m: float | None
    go: bool
    reason: str

    def as_dict(self) -> dict:
        h = self.hour
        return {
            "time": _iso(h.time),
            "go": self.go,
            "hs_m": h.hs_m,
            "tp_s": h.tp_s,
            "wave_dir_deg": h.wave_dir_deg,
            "wave_heading_deg": round(self.wave_heading_deg, 6),
            "current_mps": h.current_mps,
            "allowable_hs_m": self.allowable_hs_m,
            "alpha": None if self.alpha is None else round(self.alpha, 6),
            "limit_hs_m": None if self.limit_hs_m is None else round(self.limit_hs_m, 6),
            "reason": self.reason,
        }


def allowable_at(table: dict, tp_s: float, heading_deg: float) -> tuple[float | None, str]:
    """The table's allowable Hs at a peak period and relative heading: the lowest of the
    table's columns around them (None and why when the table does not cover them)."""
    allow = {(a["tp_s"], a["wave_heading_deg"]): a["hs_m"] for a in table["allowable"]}
    tps = sorted({k[0] for k in allow})
    heads = sorted({k[1] for k in allow})
    tp_near = _bracket(tps, tp_s)
    if tp_near is None:
        return None, f"Tp {tp_s:g} s is outside the table's {tps[0]:g}-{tps[-1]:g} s"
    head_near = _bracket_heading(heads, heading_deg)
    if head_near is None:
        listed = ", ".join(f"{h:g}" for h in heads)
        return None, (
            f"wave heading {heading_deg % 360:g} deg is not covered by the table's headings "
            f"({listed} deg, at most {HEADING_SPAN_MAX_DEG:g} deg apart)"
        )
    return min(allow[(t, h)] for t in tp_near for h in head_near), ""


def judge_hours(
    forecast: Forecast,
    table: dict,
    alpha: AlphaTable,
    reference_hours: float,
    vessel_heading_deg: float | None,
) -> list[Verdict]:
    """Each forecast hour against alpha x the table's allowable Hs and the table's current.
    ``vessel_heading_deg`` None: the vessel turns its bow into each hour's waves (180 deg)."""
    current_max = float(table["current"]["speed_mps"])
    out = []
    for h in forecast.hours:
        heading = h.wave_dir_deg + 180.0 if vessel_heading_deg is None else vessel_heading_deg
        rel = (h.wave_dir_deg - heading) % 360.0
        allowable, why = allowable_at(table, h.tp_s, rel)
        if allowable is None:
            out.append(Verdict(h, rel, None, None, None, False, why))
            continue
        a = alpha.alpha(reference_hours, allowable)
        limit = a * allowable
        reasons = []
        if h.hs_m > limit:
            reasons.append(f"Hs {h.hs_m:g} m above {a:.2f} x {allowable:g} m = {limit:.2f} m")
        if h.current_mps > current_max + 1e-9:
            reasons.append(f"current {h.current_mps:g} m/s above the table's {current_max:g} m/s")
        out.append(Verdict(h, rel, allowable, a, limit, not reasons, "; ".join(reasons)))
    return out


@dataclass(frozen=True)
class Window:
    start: datetime
    end: datetime
    """The end of the last go row's step."""

    @property
    def hours(self) -> float:
        return (self.end - self.start).total_seconds() / 3600.0

    def as_dict(self) -> dict:
        return {"start": _iso(self.start), "end": _iso(self.end), "hours": self.hours}


def go_spells(verdicts: Sequence[Verdict], step: timedelta) -> list[Window]:
    """Every run of consecutive go rows, each row standing for its step."""
    out: list[Window] = []
    start: datetime | None = None
    for k, v in enumerate(verdicts):
        if v.go and start is None:
            start = v.hour.time
        if start is not None and (not v.go or k == len(verdicts) - 1):
            last = v.hour.time if v.go else verdicts[k - 1].hour.time
            out.append(Window(start, last + step))
            start = None
    return out


def windows(verdicts: Sequence[Verdict], step: timedelta, reference_hours: float) -> list[Window]:
    """The runs of go rows at least the reference period long."""
    return [w for w in go_spells(verdicts, step) if w.hours >= reference_hours - 1e-9]
