"""The operability table: a mission's landing over a grid of sea states, each cell judged
against named limits; the allowable Hs for each peak period and wave heading (issue 44).

A cell is (Hs, Tp, wave heading relative to the vessel). Its runs are runs of a campaign
(``missions.campaign``) whose base mission is the planner's own with the vessel's heading
pinned and the current set, and whose grid varies ``wave_height_m``, ``wave_period_s`` and
``wave_direction_deg`` (the vessel's heading plus the cell's relative heading); run *i* is
seed *i mod seeds* of point *i div seeds*, so ``campaign rerun`` reproduces any cell's run.

The wave heading relative to the vessel is ``sim.vessel``'s beta: the angle from the bow to
where the waves travel towards, clockwise: 180 deg a head sea, 90 deg waves travelling to
starboard (the crane's side), 0 a following sea.

Each run is judged against ``LIMITS`` in their order, which is the order they happen in a
landing: the wire slackens and snaps while the tree is lowered, contact speed and miss are at
the contact, saturation is counted over the approach, and the mission's own verdict comes
last. A cell's ``limiting`` is the first limit any of its seeds exceeds. Nothing here knows
about Dask (``app.planning`` runs the campaign).
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace

from missions import campaign as cm
from missions import schema
from missions.seaway import SLACK_FRACTION, LandingScenario
from sim import params as params_mod

SATURATION_LIMIT_S = 30.0
"""Time with a thruster at its limit a landing may take [s]: the assessment's own criterion
(``app.scores.SATURATION_LIMIT``, thesis 4.2.2: a thruster this long at its limit means the
ROV is not in control of the tree)."""
SNAP_LIMIT_RATIO = 2.0
"""Largest snap load after a slack wire, over the static tension W0: the rigging's design
dynamic amplification. DNV-RP-H103 asks that snap loads be avoided and, where the wire may go
slack, that they be computed and kept within the rigging's capacity; 2.0 W0 is this
project's assumption of that capacity, not a number from the standard: give your rigging's
own (``--limit snap_load=RATIO``)."""
NEAR_BAND = (0.8, 1.25)
"""A cell is near a limit when a measured criterion lies within this band of its limit
(value over limit), or it is the last cell within the limits or the first beyond them on its
Hs column: those cells run every seed."""


@dataclass(frozen=True)
class Limit:
    """A named limit a landing keeps: a run exceeds it when ``column``'s value is above
    ``value`` (``landed``: when the mission failed)."""

    name: str
    value: float
    unit: str
    column: str
    source: str

    def measured(self, row: dict) -> float:
        """The row's value of this criterion (NaN: no figure)."""
        if self.name == "landed":
            return 0.0 if row.get("success") else 1.0
        v = row.get(self.column)
        if v is None:
            return math.nan
        return float(v)

    def exceeded(self, row: dict) -> bool:
        """A missing figure exceeds nothing: a landing that never made contact fails
        ``landed``, the last limit, instead."""
        v = self.measured(row)
        return math.isfinite(v) and v > self.value

    def ratio(self, row: dict) -> float:
        """Measured over limit (NaN for counts and verdicts, which have no margin)."""
        if self.name in ("slack_wire", "landed") or self.value <= 0.0:
            return math.nan
        return self.measured(row) / self.value

    def as_dict(self) -> dict:
        return {"name": self.name, "value": self.value, "unit": self.unit, "source": self.source}


def limits_for(params: str, overrides: dict[str, float] | None = None) -> tuple[Limit, ...]:
    """The named limits for a parameter set (its docking geometry gives the contact speed and
    the capture tolerance), in the order they are judged; ``overrides`` replaces values by
    name (ValueError naming an unknown one)."""
    layout = params_mod.load(params).spec.docking.to_numeric()
    limits = (
        Limit(
            "slack_wire",
            0.0,
            "episodes",
            "slack_events",
            f"DNV-RP-H103 slack sling criterion: the tension below {SLACK_FRACTION:g} of the "
            "static (a dynamic drop of more than 90 % of it), counted from the hover to the "
            "first contact (missions.seaway.SLACK_FRACTION)",
        ),
        Limit(
            "snap_load",
            SNAP_LIMIT_RATIO,
            "x W0",
            "snap_ratio",
            "DNV-RP-H103: snap loads after a slack wire kept within the rigging's capacity; "
            f"{SNAP_LIMIT_RATIO:g} W0 is an assumed design dynamic amplification "
            "(missions.operability.SNAP_LIMIT_RATIO)",
        ),
        Limit(
            "contact_speed",
            float(layout.max_landing_speed_mps),
            "m/s",
            "contact_speed_mps",
            f"the docking frame's landing-speed limit ({params}: docking."
            "max_landing_speed_mps, thesis chapter 5)",
        ),
        Limit(
            "miss",
            round(float(layout.tolerance_m), 9),
            "m",
            "miss_m",
            f"the funnels' capture tolerance at contact, mouth radius less post radius "
            f"({params}: docking.funnel_mouth_radius_m - post_radius_m)",
        ),
        Limit(
            "saturation",
            SATURATION_LIMIT_S,
            "s",
            "saturated_time_s",
            "time with a thruster at 99 % or more: the assessment's criterion "
            "(app.scores.SATURATION_LIMIT, thesis 4.2.2)",
        ),
        Limit(
            "landed",
            0.0,
            "",
            "success",
            "the mission's own verdict: landed, no leg timed out or refused, no divergence",
        ),
    )
    by_name = {lim.name: lim for lim in limits}
    for name, value in (overrides or {}).items():
        if name not in by_name or name == "landed":
            named = ", ".join(n for n in by_name if n != "landed")
            raise ValueError(f"--limit {name}: no such limit; the limits are {named}")
        if not (math.isfinite(value) or value == math.inf) or value < 0.0:
            raise ValueError(f"--limit {name}={value}: a limit must be >= 0")
        by_name[name] = replace(
            by_name[name], value=value, source=by_name[name].source + " (set on the command line)"
        )
    return tuple(by_name[lim.name] for lim in limits)


def judge(row: dict, limits: Sequence[Limit]) -> list[str]:
    """The limits a run exceeds, in the judging order (empty: within every limit)."""
    return [lim.name for lim in limits if lim.exceeded(row)]


# ------------------------------------------------------------------------------------------
# the grid as a campaign
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Grid:
    """The sea states of a table: Hs [m], Tp [s], wave heading relative to the vessel [deg]."""

    hs_m: tuple[float, ...]
    tp_s: tuple[float, ...]
    heading_deg: tuple[float, ...]

    def __post_init__(self) -> None:
        checks = (
            ("--hs", self.hs_m, 0.0, 30.0, False),
            ("--tp", self.tp_s, 1.0, 40.0, True),
            ("--heading", self.heading_deg, 0.0, 360.0, True),
        )
        for option, values, low, high, low_ok in checks:
            if not values:
                raise ValueError(f"{option}: give at least one value")
            for v in values:
                inside = (low <= v if low_ok else low < v) and (
                    v < high if option == "--heading" else v <= high
                )
                if not (math.isfinite(v) and inside):
                    lo = "[" if low_ok else "("
                    hi = ")" if option == "--heading" else "]"
                    raise ValueError(f"{option}: {v:g} is not in {lo}{low:g}, {high:g}{hi}")
            if len(set(values)) != len(values):
                raise ValueError(f"{option}: a value is given twice")

    @property
    def cells(self) -> int:
        return len(self.hs_m) * len(self.tp_s) * len(self.heading_deg)


@dataclass(frozen=True)
class Plan:
    """An operability table's campaign: the pinned mission, the campaign and its text."""

    mission: schema.Mission
    """The planner's mission with the vessel's heading pinned and the current set."""
    campaign: cm.Campaign
    text: str
    vessel_heading_deg: float
    grid: Grid
    seeds: int
    into_waves: bool
    """The mission's vessel turns its bow into the waves (no ``heading_deg``): the table is
    then flown at that heading, and a forecast's waves always meet the bow (180 deg)."""

    def cell_of(self, row: dict) -> tuple[float, float, float]:
        """(Hs, Tp, relative heading) of a result row."""
        rel = (float(row["wave_direction_deg"]) - self.vessel_heading_deg) % 360.0
        return (float(row["wave_height_m"]), float(row["wave_period_s"]), _round_deg(rel))

    def runs_of(self, point: int, first: int, last: int) -> list[int]:
        """Run indices of repetitions ``first`` to ``last - 1`` of a point."""
        return [point * self.seeds + r for r in range(first, min(last, self.seeds))]


def _round_deg(angle: float) -> float:
    """An angle rounded to a millionth of a degree, 360 as 0."""
    a = round(angle % 360.0, 6)
    return 0.0 if a == 360.0 else a


def pin_mission(
    mission: schema.Mission, current: tuple[float, float] | None = None
) -> tuple[schema.Mission, float]:
    """The mission with its vessel's heading written in (its own, or bow into its waves) and
    the current set (speed m/s, towards deg); and that heading [deg]. ValueError naming the
    field when the mission has nothing to land, no sea, a wire that cannot go slack, or no
    vessel to head."""
    LandingScenario.from_mission(mission)  # frame, waves and a wire that can go slack
    setup = mission.setup
    if setup.vessel is None:
        raise ValueError(
            f"{mission.name}: setup.vessel is missing: the table's wave headings are relative "
            "to the vessel, so the mission needs [setup.vessel] (heading_deg, "
            "heave_compensation)"
        )
    if not any(isinstance(leg, schema.DockLeg) for leg in mission.legs):
        raise ValueError(f"{mission.name}: legs: the table judges a landing: add a dock leg")
    assert setup.waves is not None
    heading = setup.vessel.heading_deg
    if heading is None:
        heading = setup.waves.direction_deg + 180.0
    heading = _round_deg(heading)
    data = mission.model_dump(mode="json")
    data["setup"]["vessel"]["heading_deg"] = heading if heading <= 180.0 else heading - 360.0
    if current is not None:
        data["setup"]["current"]["speed_mps"] = current[0]
        data["setup"]["current"]["direction_deg"] = current[1]
    return schema.parse_mission(data, mission.name), heading


def plan(
    mission: schema.Mission,
    grid: Grid,
    seeds: int = 1,
    seed: int = 0,
    current: tuple[float, float] | None = None,
) -> Plan:
    """The campaign of an operability table: every (Hs, Tp, heading) a point, ``seeds`` runs
    a point (the first run of each in a first pass, the rest where the cell is near a
    limit)."""
    if isinstance(seeds, bool) or not 1 <= seeds <= 50:
        raise ValueError(f"--seeds must be a whole number in [1, 50], got {seeds!r}")
    pinned, heading = pin_mission(mission, current)
    directions = [_round_deg(heading + h) for h in grid.heading_deg]
    lines = [
        "format_version = 1",
        f'name = "operability {results_name(mission.name)}"',
        f'description = "operability table of {results_name(mission.name)}"',
        f'mission = "{results_name(mission.name)}"',
        f"seed = {seed}",
        f"runs_per_point = {seeds}",
        "",
        "[grid]",
        f"wave_height_m = {_toml_list(grid.hs_m)}",
        f"wave_period_s = {_toml_list(grid.tp_s)}",
        f"wave_direction_deg = {_toml_list(directions)}",
        "",
    ]
    text = "\n".join(lines)
    campaign = cm.parse_text(text, f"operability table of {mission.name}", base=pinned)[0]
    into_waves = mission.setup.vessel is not None and mission.setup.vessel.heading_deg is None
    return Plan(pinned, campaign, text, heading, grid, seeds, into_waves)


def default_headings(mission: schema.Mission) -> tuple[float, ...]:
    """The wave headings a table covers unless told: head seas alone for a vessel that turns
    its bow into the waves, else every 45 deg."""
    vessel = mission.setup.vessel
    if vessel is not None and vessel.heading_deg is None:
        return (180.0,)
    return tuple(float(h) for h in range(0, 360, 45))


def results_name(name: str) -> str:
    """A mission's name as a campaign's and a folder's (``schema.NAME_RE``'s characters, at
    most 60)."""
    return re.sub(r"[^\w .,:()+-]", "", name)[:60] or "mission"


def _toml_list(values: Iterable[float]) -> str:
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def first_pass_runs(p: Plan) -> list[int]:
    """The first seed of every cell."""
    return [point * p.seeds for point in range(p.campaign.points)]


# ------------------------------------------------------------------------------------------
# cells and the table
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Cell:
    """One sea state's verdict over the seeds run in it."""

    hs_m: float
    tp_s: float
    wave_heading_deg: float
    point: int
    ok: bool
    limiting: str | None
    """The first limit (in ``LIMITS`` order) any seed exceeds; None when none does."""
    exceeded: tuple[str, ...]
    seeds: int
    seeds_ok: int
    first_seed_ok: bool
    """The verdict of the cell's first seed alone (how the table looks with one seed)."""
    worst: dict[str, float]
    """Each criterion's worst value over the seeds (its column's name)."""
    near_limit: bool
    runs: tuple[int, ...]

    def as_dict(self) -> dict:
        return {
            "hs_m": self.hs_m,
            "tp_s": self.tp_s,
            "wave_heading_deg": self.wave_heading_deg,
            "ok": self.ok,
            "limiting": self.limiting,
            "exceeded": list(self.exceeded),
            "seeds": self.seeds,
            "seeds_ok": self.seeds_ok,
            "first_seed_ok": self.first_seed_ok,
            "near_limit": self.near_limit,
            **{k: _json_number(v) for k, v in self.worst.items()},
            "runs": list(self.runs),
        }


def _json_number(v: float) -> float | None:
    return v if math.isfinite(v) else None


def cells_of(p: Plan, rows: Sequence[dict], limits: Sequence[Limit]) -> list[Cell]:
    """The cells from the campaign's rows (each cell's rows over its seeds), in grid order."""
    by_point: dict[int, list[dict]] = {}
    for row in rows:
        by_point.setdefault(int(row["point"]), []).append(row)
    out = []
    for point in sorted(by_point):
        runs = sorted(by_point[point], key=lambda r: int(r["repetition"]))
        hs, tp, rel = p.cell_of(runs[0])
        verdicts = [judge(r, limits) for r in runs]
        exceeded = tuple(lim.name for lim in limits if any(lim.name in v for v in verdicts))
        worst = {}
        for lim in limits:
            if lim.name == "landed":
                continue
            values = [lim.measured(r) for r in runs]
            finite = [v for v in values if math.isfinite(v)]
            worst[lim.column] = max(finite) if finite else math.nan
        ratios = [lim.ratio(r) for lim in limits for r in runs]
        near = any(NEAR_BAND[0] <= x <= NEAR_BAND[1] for x in ratios if math.isfinite(x))
        out.append(
            Cell(
                hs,
                tp,
                rel,
                point,
                not exceeded,
                exceeded[0] if exceeded else None,
                exceeded,
                len(runs),
                sum(not v for v in verdicts),
                not verdicts[0],
                worst,
                near,
                tuple(int(r["run"]) for r in runs),
            )
        )
    return out


def columns(cells: Sequence[Cell]) -> dict[tuple[float, float], list[Cell]]:
    """The cells by (Tp, heading), each column in rising Hs."""
    out: dict[tuple[float, float], list[Cell]] = {}
    for c in cells:
        out.setdefault((c.tp_s, c.wave_heading_deg), []).append(c)
    return {k: sorted(v, key=lambda c: c.hs_m) for k, v in sorted(out.items())}


def boundary_points(cells: Sequence[Cell]) -> set[int]:
    """Points near a limit: a measured criterion within ``NEAR_BAND`` of its limit, or the
    last cell within the limits and the first beyond them on each Hs column."""
    out = {c.point for c in cells if c.near_limit}
    for column in columns(cells).values():
        for below, above in itertools.pairwise(column):
            if below.ok != above.ok:
                out.update((below.point, above.point))
    return out


@dataclass(frozen=True)
class Allowable:
    """The largest Hs of a column up to which every cell is within the limits."""

    tp_s: float
    wave_heading_deg: float
    hs_m: float
    """0 when the lowest Hs of the grid already fails."""
    limiting: str | None
    """What limits it: the first failing cell's limiting criterion (None: no cell failed,
    the allowable Hs is at least the grid's largest)."""
    hs_m_first_seed: float
    """The same from the first seed of each cell alone."""

    def as_dict(self) -> dict:
        return {
            "tp_s": self.tp_s,
            "wave_heading_deg": self.wave_heading_deg,
            "hs_m": self.hs_m,
            "limiting": self.limiting,
            "above_grid": self.limiting is None,
            "hs_m_first_seed": self.hs_m_first_seed,
        }


def allowable(cells: Sequence[Cell]) -> list[Allowable]:
    """The allowable Hs of each (Tp, heading): the largest Hs below the first cell beyond
    the limits (over all its seeds, and over the first seed alone)."""
    out = []
    for (tp, heading), column in columns(cells).items():
        hs = _last_ok(column, lambda c: c.ok)
        hs1 = _last_ok(column, lambda c: c.first_seed_ok)
        first_bad = next((c for c in column if not c.ok), None)
        limiting = first_bad.limiting if first_bad is not None else None
        out.append(Allowable(tp, heading, hs, limiting, hs1))
    return out


def _last_ok(column: Sequence[Cell], ok: Callable[[Cell], bool]) -> float:
    last = 0.0
    for c in column:
        if not ok(c):
            return last
        last = c.hs_m
    return last


def seed_words(cells: Sequence[Cell], table: Sequence[Allowable], seeds: int) -> str:
    """How the table depends on the seeds, in one paragraph."""
    several = [c for c in cells if c.seeds > 1]
    if seeds == 1:
        return (
            "one seed a cell: each cell is one sea; run --seeds 3 or more to judge the cells "
            "near a limit on several"
        )
    if not several:
        return f"no cell was near a limit, so each ran its first seed only (of {seeds})"
    flipped = [c for c in several if c.first_seed_ok and not c.ok]
    moved = [a for a in table if a.hs_m != a.hs_m_first_seed]
    parts = [
        f"{len(several)} of {len(cells)} cells were near a limit and ran {seeds} seeds",
        f"{len(flipped)} of them passed on the first seed but failed on another",
    ]
    if moved:
        each = "; ".join(
            f"Tp {a.tp_s:g} s, heading {a.wave_heading_deg:g} deg: {a.hs_m_first_seed:g} m "
            f"with one seed, {a.hs_m:g} m over the seeds"
            for a in moved
        )
        parts.append(f"the allowable Hs moved in {len(moved)} columns ({each})")
    else:
        parts.append("no allowable Hs moved: the first seed's table stands")
    return "; ".join(parts)
