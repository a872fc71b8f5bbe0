"""Planning campaigns: many runs of one mission over grids and random draws of its parameters.

A campaign file (TOML, ``format_version = 1``) names a base mission (a library name or a
mission file), grids (every combination is a *point*) and random distributions over the
parameters in ``PARAMETERS``, the number of runs at each point and a seed::

    format_version = 1
    name = "docking-vs-current"
    mission = "full-docking-current-0.3"
    seed = 1
    runs_per_point = 20

    [grid]
    current_speed_mps = [0.1, 0.2, 0.3]

    [random.current_direction_deg]
    distribution = "uniform"
    low = 200.0
    high = 250.0

Run ``i`` is point ``i // runs_per_point``; its random draws and its simulation seed come from
``numpy.random.SeedSequence(seed, spawn_key=(i,))`` alone, so any run can be reproduced
without the others (``run_inputs``). ``run_one`` runs it and returns one flat row of inputs
and outcome figures. Nothing here knows about Dask or Parquet (``app.campaign`` does).
"""

from __future__ import annotations

import math
import os
import socket
import time
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from control.config import ALLOCATIONS, FEEDBACKS
from control.simulation import Simulation
from missions import schema
from missions.driver import MissionDriver
from missions.limits import MAX_RUNS_PER_TASK as MAX_RUNS_PER_TASK
from missions.scoring import MissionResult
from missions.seaway import SLACK_WIRES as SLACK_WIRES
from missions.setup import build_simulation
from sim import params as params_mod

FORMAT_VERSION = 1
LIBRARY_DIR = Path(__file__).with_name("campaigns")
MAX_RUNS = 1_000_000


def worker_name() -> str:
    """Who runs: host and process id (a result row says which worker process made it)."""
    return f"{socket.gethostname()}:{os.getpid()}"


class CampaignError(ValueError):
    """A campaign file is invalid; one line per problem, naming the line, the field and what
    is allowed."""


@dataclass(frozen=True)
class Parameter:
    """One parameter a campaign may vary: its unit and allowed range (numbers), or its
    allowed values (choices; None: any name the loader accepts, e.g. a parameter set)."""

    name: str
    unit: str
    low: float = -math.inf
    high: float = math.inf
    choices: tuple[str, ...] | None = None
    text: bool = False
    help: str = ""

    def range_text(self) -> str:
        if self.text:
            return "a name" if self.choices is None else "one of " + ", ".join(self.choices)
        return f"in [{self.low:g}, {self.high:g}] {self.unit}".rstrip()


PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in (
        Parameter("current_speed_mps", "m/s", 0.0, 3.0, help="mean current speed"),
        Parameter("current_direction_deg", "deg", -360.0, 360.0, help="current flows towards"),
        Parameter(
            "depth_m",
            "m",
            6.0,
            4000.0,
            help="tree depth; a docking frame moves with it (same clearance under the tree)",
        ),
        Parameter("wave_height_m", "m", 0.0, 30.0, help="significant wave height (sea state)"),
        Parameter("wave_period_s", "s", 1.0, 40.0, help="peak period"),
        Parameter("wave_direction_deg", "deg", -360.0, 360.0, help="waves travel towards"),
        Parameter("tree_mass_scale", "", 0.1, 5.0, help="tree mass and inertia factor (plant)"),
        Parameter("tree_weight_scale", "", 0.1, 5.0, help="tree submerged weight factor"),
        Parameter("sensor_noise_scale", "", 0.0, 100.0, help="every sensor's noise factor"),
        Parameter("survey_error_north_m", "m", -20.0, 20.0, help="frame's real offset north"),
        Parameter("survey_error_east_m", "m", -20.0, 20.0, help="frame's real offset east"),
        Parameter("kp_scale", "", 0.0, 10.0, help="factor on the parameter set's Kp"),
        Parameter("ki_scale", "", 0.0, 10.0, help="factor on Ki"),
        Parameter("kd_scale", "", 0.0, 10.0, help="factor on Kd"),
        Parameter("params", "", text=True, help="parameter set (tree and ROV): name or file"),
        Parameter("allocation", "", choices=ALLOCATIONS, text=True, help="thrust allocation"),
        Parameter("feedback", "", choices=FEEDBACKS, text=True, help="perfect or EKF"),
    )
}
NUMERIC = tuple(name for name, p in PARAMETERS.items() if not p.text)
TEXT = tuple(name for name, p in PARAMETERS.items() if p.text)
WAVE_PARAMETERS = ("wave_height_m", "wave_period_s", "wave_direction_deg")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


Finite = Annotated[float, Field(allow_inf_nan=False)]
Value = Annotated[float, Field(allow_inf_nan=False, strict=False)] | str


class Uniform(_Model):
    distribution: Literal["uniform"]
    low: Finite
    high: Finite


class Normal(_Model):
    """Normal draws, clipped to [min, max] (default: the parameter's allowed range)."""

    distribution: Literal["normal"]
    mean: Finite
    std: Finite = Field(ge=0.0)
    min: Finite | None = None
    max: Finite | None = None


class Choice(_Model):
    """One of the values, each equally likely."""

    distribution: Literal["choice"]
    values: list[Value] = Field(min_length=1, max_length=1000)


Distribution = Annotated[Uniform | Normal | Choice, Field(discriminator="distribution")]


class Campaign(_Model):
    format_version: Literal[1] = Field(description="campaign file format version")
    name: str = Field(description="1 to 80 printable characters, no slashes")
    description: str = Field(default="", max_length=2000)
    mission: str = Field(
        min_length=1, max_length=1000, description="library mission name or mission file"
    )
    seed: int = Field(default=0, ge=0, le=2**32 - 1)
    runs_per_point: int = Field(default=1, ge=1, le=100_000)
    grid: dict[str, Annotated[list[Value], Field(min_length=1, max_length=1000)]] = {}
    cases: list[dict[str, Value]] = Field(default=[{}], min_length=1, max_length=1000)
    """Explicit points (e.g. one parameter changed at a time); every case is combined with
    every grid point."""
    random: dict[str, Distribution] = {}

    @field_validator("name")
    @classmethod
    def _name(cls, value: str) -> str:
        return schema._check_name(value, schema.NAME_RE, "name")

    @property
    def points(self) -> int:
        return len(self.cases) * math.prod(len(v) for v in self.grid.values())

    @property
    def runs(self) -> int:
        return self.points * self.runs_per_point

    def point_values(self, point: int) -> dict[str, float | str]:
        """The values of a point: its case, then its grid values (the last grid key varies
        fastest, the case slowest)."""
        out: dict[str, float | str] = {}
        rest = point
        for name, values in reversed(list(self.grid.items())):
            rest, k = divmod(rest, len(values))
            out[name] = values[k]
        return {**self.cases[rest], **dict(reversed(list(out.items())))}


# ------------------------------------------------------------------------------------------
# loading and checking
# ------------------------------------------------------------------------------------------


def _line_of(text: str, loc: tuple) -> int | None:
    """Line (1-based) where the field at ``loc`` stands in the campaign's TOML text."""
    lines = text.splitlines()

    def key_line(key: str, start: int = 0, end: int | None = None) -> int | None:
        for i in range(start, len(lines) if end is None else end):
            stripped = lines[i].strip()
            if stripped.startswith("["):
                if i > start:
                    break
                continue
            if stripped.split("=")[0].strip().strip('"') == key:
                return i
        return None

    def section(name: str) -> int | None:
        for i, ln in enumerate(lines):
            if ln.strip().replace(" ", "").replace('"', "") == f"[{name}]":
                return i
        return None

    if not loc:
        return None
    head = str(loc[0])
    if head == "cases" and len(loc) > 1 and isinstance(loc[1], int):
        headers = [i for i, ln in enumerate(lines) if ln.strip() == "[[cases]]"]
        if loc[1] < len(headers):
            if len(loc) > 2:
                found = key_line(str(loc[2]), headers[loc[1]])
                if found is not None:
                    return found + 1
            return headers[loc[1]] + 1
        found = key_line("cases")
        return None if found is None else found + 1
    if head in ("grid", "random") and len(loc) > 1:
        name = str(loc[1])
        if head == "random":
            sec = section(f"random.{name}")
            if sec is not None:
                if len(loc) > 2 and isinstance(loc[2], str):
                    found = key_line(str(loc[-1]), sec)
                    return (found if found is not None else sec) + 1
                return sec + 1
        sec = section(head)
        if sec is not None:
            found = key_line(name, sec)
            if found is not None:
                return found + 1
        for i, ln in enumerate(lines):  # inline tables: random.x = {...} or grid.x = [...]
            if ln.split("=")[0].strip() in (f"{head}.{name}", name):
                return i + 1
        return None
    found = key_line(head)
    return None if found is None else found + 1


def _got(value: object) -> str:
    return schema._got(value)


def _problem(source: str, text: str | None, loc: tuple, message: str) -> str:
    line = _line_of(text, loc) if text is not None else None
    field = ""
    for part in loc:
        field += f"[{part + 1}]" if isinstance(part, int) else (("." if field else "") + str(part))
    where = f" line {line}" if line else ""
    return f"{source}{where}: {field or 'campaign'}: {message}"


def _check_value(p: Parameter, value: object) -> str | None:
    """Why a value is not allowed for a parameter (None when it is)."""
    if p.text:
        if not isinstance(value, str):
            return f"must be {p.range_text()}{_got(value)}"
        if p.choices is not None and value not in p.choices:
            return f"must be {p.range_text()}{_got(value)}"
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"must be a number {p.range_text()}{_got(value)}"
    if not p.low <= float(value) <= p.high:
        return f"must be {p.range_text()}{_got(value)}"
    return None


def _unknown(name: str) -> str:
    return f"unknown parameter {name!r}; campaigns can vary: {', '.join(PARAMETERS)}"


def _check(c: Campaign, base: schema.Mission | None) -> list[tuple[tuple, str]]:
    """Checks beyond the types: names, ranges, combinations. Returns (loc, message) pairs."""
    out: list[tuple[tuple, str]] = []
    for name, values in c.grid.items():
        p = PARAMETERS.get(name)
        if p is None:
            out.append((("grid", name), _unknown(name)))
            continue
        for k, v in enumerate(values):
            why = _check_value(p, v)
            if why:
                out.append((("grid", name), f"value {k + 1} {why}"))
                break
    for i, case in enumerate(c.cases):
        for name, v in case.items():
            p = PARAMETERS.get(name)
            if p is None:
                out.append((("cases", i, name), _unknown(name)))
                continue
            why = _check_value(p, v)
            if why:
                out.append((("cases", i, name), why))
            if name in c.grid:
                out.append((("cases", i, name), "is already in [grid]; vary a parameter one way"))
    for name, dist in c.random.items():
        p = PARAMETERS.get(name)
        if p is None:
            out.append((("random", name), _unknown(name)))
            continue
        if name in c.grid or any(name in case for case in c.cases):
            out.append((("random", name), "is already in [grid] or cases; vary it one way"))
        if isinstance(dist, Choice):
            for k, v in enumerate(dist.values):
                why = _check_value(p, v)
                if why:
                    out.append((("random", name, "values"), f"value {k + 1} {why}"))
                    break
            continue
        if p.text:
            out.append((("random", name, "distribution"), "a name can only be drawn by choice"))
            continue
        fields: dict[str, float | None] = (
            {"low": dist.low, "high": dist.high}
            if isinstance(dist, Uniform)
            else {"mean": dist.mean, "min": dist.min, "max": dist.max}
        )
        for key, bound in fields.items():
            if bound is not None:
                why = _check_value(p, bound)
                if why:
                    out.append((("random", name, key), why))
        if isinstance(dist, Uniform) and dist.low > dist.high:
            out.append((("random", name, "high"), f"must be >= low ({dist.low:g})"))
        if isinstance(dist, Normal) and dist.min is not None and dist.max is not None:
            if dist.min > dist.max:
                out.append((("random", name, "max"), f"must be >= min ({dist.min:g})"))
    if c.runs > MAX_RUNS:
        out.append(
            (("runs_per_point",), f"the campaign would have {c.runs} runs; at most {MAX_RUNS}")
        )
    varied = set(c.grid) | set(c.random) | {k for case in c.cases for k in case}
    if base is not None:
        has_frame = base.setup.docking_frame is not None
        for name in ("survey_error_north_m", "survey_error_east_m"):
            if name in varied and not has_frame:
                out.append((_loc_of(c, name), "the base mission has no docking frame to survey"))
        if base.setup.waves is None and varied & set(WAVE_PARAMETERS):
            for name in ("wave_height_m", "wave_period_s"):
                if name not in varied:
                    out.append(
                        (
                            ("grid",),
                            f"the base mission has no waves: give {name} too (grid or random)",
                        )
                    )
        if "depth_m" in varied and base.setup.docking_frame is not None:
            clearance = base.setup.docking_frame.landing_depth_m - base.setup.depth_m
            deepest = _largest(c, "depth_m")
            if deepest is not None and deepest + clearance > PARAMETERS["depth_m"].high:
                out.append(
                    (
                        _loc_of(c, "depth_m"),
                        f"the frame stands {clearance:g} m below the tree: depth_m must "
                        f"stay <= {PARAMETERS['depth_m'].high - clearance:g} m",
                    )
                )
    for where, name, values in _text_values(c, "params"):
        for v in values:
            try:
                params_mod.load_spec(str(v))
            except (ValueError, OSError) as err:
                out.append(((where, name), str(err).splitlines()[0]))
                break
    return out


def _loc_of(c: Campaign, name: str) -> tuple:
    """Where a varied parameter is given in the file."""
    if name in c.grid:
        return ("grid", name)
    if name in c.random:
        return ("random", name)
    for i, case in enumerate(c.cases):
        if name in case:
            return ("cases", i, name)
    return (name,)


def _largest(c: Campaign, name: str) -> float | None:
    cased = [float(v) for case in c.cases for k, v in case.items() if k == name]
    if name in c.grid:
        return max(float(v) for v in c.grid[name] if not isinstance(v, str))
    if cased:
        return max(cased)
    dist = c.random.get(name)
    if isinstance(dist, Uniform):
        return dist.high
    if isinstance(dist, Normal):
        return dist.max if dist.max is not None else PARAMETERS[name].high
    if isinstance(dist, Choice):
        return max(float(v) for v in dist.values if not isinstance(v, str))
    return None


def _text_values(c: Campaign, name: str) -> list[tuple[str, str, list]]:
    out: list[tuple[str, str, list]] = []
    if name in c.grid:
        out.append(("grid", name, c.grid[name]))
    dist = c.random.get(name)
    if isinstance(dist, Choice):
        out.append(("random", name, dist.values))
    for case in c.cases:
        if name in case:
            out.append(("cases", name, [case[name]]))
    return out


def _range_message(loc: tuple, kind: str) -> str | None:
    """'must be in [lo, hi]' for a top-level number of the file out of its range."""
    if len(loc) != 1 or kind not in (
        "greater_than_equal",
        "less_than_equal",
        "greater_than",
        "less_than",
        "int_type",
        "int_parsing",
        "int_from_float",
    ):
        return None
    info = Campaign.model_fields.get(str(loc[0]))
    if info is None:
        return None
    lo = next((getattr(m, "ge", None) for m in info.metadata if hasattr(m, "ge")), None)
    hi = next((getattr(m, "le", None) for m in info.metadata if hasattr(m, "le")), None)
    if lo is None or hi is None:
        return None
    return f"must be a whole number in [{lo}, {hi}]"


def parse_campaign(
    data: dict,
    source: str = "<campaign>",
    text: str | None = None,
    base_dir: Path | None = None,
    base: schema.Mission | None = None,
) -> tuple[Campaign, schema.Mission]:
    """Validate a campaign dictionary and load its base mission (unless ``base`` is given);
    raise CampaignError with one line per problem (line, field, what is allowed)."""
    try:
        c = Campaign.model_validate(data)
    except ValidationError as err:
        problems = []
        for e in err.errors()[:10]:
            loc = tuple(p for p in e["loc"] if p not in ("uniform", "normal", "choice"))
            loc = tuple(p for p in loc if not (isinstance(p, str) and p in ("float", "str")))
            msg = _range_message(loc, e["type"]) or e["msg"].removeprefix("Value error, ")
            problems.append(_problem(source, text, loc, msg + _got(e.get("input"))))
        raise CampaignError("\n".join(problems)) from None
    mission_error = None
    if base is None:
        try:
            base = resolve_mission(c.mission, base_dir)
        except schema.MissionError as err:
            mission_error = str(err)
    problems = [_problem(source, text, loc, msg) for loc, msg in _check(c, base)]
    if mission_error is not None:
        problems.insert(0, _problem(source, text, ("mission",), mission_error))
    if problems:
        raise CampaignError("\n".join(problems))
    assert base is not None
    return c, base


def resolve_mission(name_or_path: str, base_dir: Path | None = None) -> schema.Mission:
    """The base mission: a library name, a path, or a path relative to the campaign file."""
    candidate = Path(name_or_path)
    if base_dir is not None and not candidate.is_absolute():
        beside = base_dir / candidate
        if beside.is_file():
            return schema.load_mission(beside)
    return schema.load_mission(name_or_path)


def parse_text(
    text: str, source: str, base_dir: Path | None = None, base: schema.Mission | None = None
) -> tuple[Campaign, schema.Mission]:
    """A campaign from TOML text; every malformed text is one CampaignError."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise CampaignError(f"{source}: cannot parse: {err}") from None
    except RecursionError:
        raise CampaignError(f"{source}: cannot parse: nested too deeply") from None
    try:
        return parse_campaign(data, source, text, base_dir, base)
    except RecursionError:
        raise CampaignError(f"{source}: nested too deeply") from None


def parse_stored(text: str, source: str, base: schema.Mission) -> Campaign:
    """A campaign as stored with its results, on the base mission stored beside it."""
    return parse_text(text, source, base=base)[0]


def load_campaign(path_or_name: str | Path) -> tuple[Campaign, schema.Mission, str]:
    """A campaign file (or a library campaign by name): the campaign, its base mission and the
    file's text."""
    path, text = schema.read_named_file(
        path_or_name, LIBRARY_DIR, library_names, "campaign", "a campaign", CampaignError
    )
    campaign, base = parse_text(text, str(path), path.parent)
    return campaign, base, text


def library_names() -> list[str]:
    return sorted(p.stem for p in LIBRARY_DIR.glob("*.toml"))


# ------------------------------------------------------------------------------------------
# one run
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class RunInputs:
    """What run ``index`` of a campaign uses: every parameter's value and the seed."""

    index: int
    point: int
    repetition: int
    sim_seed: int
    values: dict[str, float | str]


def base_values(base: schema.Mission) -> dict[str, float | str]:
    """Every parameter's value in the base mission (NaN where it has none, e.g. no waves)."""
    s = base.setup
    frame = s.docking_frame
    return {
        "current_speed_mps": s.current.speed_mps,
        "current_direction_deg": s.current.direction_deg,
        "depth_m": s.depth_m,
        "wave_height_m": s.waves.significant_height_m if s.waves else math.nan,
        "wave_period_s": s.waves.peak_period_s if s.waves else math.nan,
        "wave_direction_deg": s.waves.direction_deg if s.waves else 0.0,
        "tree_mass_scale": s.plant.mass_scale,
        "tree_weight_scale": s.plant.weight_scale,
        "sensor_noise_scale": 1.0,
        "survey_error_north_m": frame.survey_error_ne_m[0] if frame else math.nan,
        "survey_error_east_m": frame.survey_error_ne_m[1] if frame else math.nan,
        "kp_scale": 1.0,
        "ki_scale": 1.0,
        "kd_scale": 1.0,
        "params": s.params,
        "allocation": s.allocation,
        "feedback": s.feedback,
    }


def _draw(rng: np.random.Generator, name: str, dist: Uniform | Normal | Choice) -> float | str:
    if isinstance(dist, Uniform):
        return float(rng.uniform(dist.low, dist.high))
    if isinstance(dist, Normal):
        p = PARAMETERS[name]
        lo = p.low if dist.min is None else dist.min
        hi = p.high if dist.max is None else dist.max
        return float(np.clip(rng.normal(dist.mean, dist.std), lo, hi))
    value = dist.values[int(rng.integers(len(dist.values)))]
    return value if isinstance(value, str) else float(value)


def run_inputs(c: Campaign, base: schema.Mission, index: int) -> RunInputs:
    """Run ``index``'s inputs, from (campaign seed, index) alone."""
    if not 0 <= index < c.runs:
        raise CampaignError(f"run {index} is not in this campaign (0 to {c.runs - 1})")
    point, repetition = divmod(index, c.runs_per_point)
    rng = np.random.default_rng(np.random.SeedSequence(c.seed, spawn_key=(index,)))
    sim_seed = int(rng.integers(0, 2**31 - 1))
    values = base_values(base)
    for name, v in c.point_values(point).items():
        values[name] = v if isinstance(v, str) else float(v)
    for name in sorted(c.random):
        values[name] = _draw(rng, name, c.random[name])
    return RunInputs(index, point, repetition, sim_seed, values)


def run_mission_of(base: schema.Mission, inputs: RunInputs) -> schema.Mission:
    """The base mission with a run's values put into its set-up (validated again)."""
    v = inputs.values
    data = base.model_dump(mode="json")
    s = data["setup"]
    s["seed"] = inputs.sim_seed
    s["params"] = v["params"]
    s["allocation"] = v["allocation"]
    s["feedback"] = v["feedback"]
    s["current"]["speed_mps"] = v["current_speed_mps"]
    s["current"]["direction_deg"] = v["current_direction_deg"]
    shift = float(v["depth_m"]) - base.setup.depth_m
    s["depth_m"] = v["depth_m"]
    if not math.isnan(float(v["wave_height_m"])):
        s["waves"] = {
            **(s.get("waves") or {}),
            "significant_height_m": v["wave_height_m"],
            "peak_period_s": v["wave_period_s"],
            "direction_deg": v["wave_direction_deg"],
        }
    s["plant"] = {"mass_scale": v["tree_mass_scale"], "weight_scale": v["tree_weight_scale"]}
    if s.get("docking_frame") is not None:
        s["docking_frame"]["landing_depth_m"] = base.setup.docking_frame.landing_depth_m + shift  # type: ignore[union-attr]
        s["docking_frame"]["survey_error_ne_m"] = [
            v["survey_error_north_m"],
            v["survey_error_east_m"],
        ]
    return schema.parse_mission(data, f"run {inputs.index}")


def run_parameter_set(inputs: RunInputs) -> params_mod.ParameterSet:
    """The run's parameter set: the named one with its sensor noise and gains scaled."""
    v = inputs.values
    spec = params_mod.load_spec(str(v["params"]))
    noise = float(v["sensor_noise_scale"])
    scales = [float(v["kp_scale"]), float(v["ki_scale"]), float(v["kd_scale"])]
    if noise == 1.0 and scales == [1.0, 1.0, 1.0]:
        return params_mod.build(spec)
    sensors = spec.sensors.model_copy(
        update={
            name: getattr(spec.sensors, name).model_copy(
                update={"noise_std": getattr(spec.sensors, name).noise_std * noise}
            )
            for name in type(spec.sensors).model_fields
        }
    )
    gains = spec.gains.model_copy(
        update={
            term: [g * scale for g in getattr(spec.gains, term)]
            for term, scale in zip(("kp", "ki", "kd"), scales, strict=True)
        }
    )
    return params_mod.build(spec.model_copy(update={"sensors": sensors, "gains": gains}))


def prepare_run(
    c: Campaign, base: schema.Mission, index: int
) -> tuple[RunInputs, schema.Mission, Simulation]:
    """Everything run ``index`` needs, ready to drive (``MissionDriver(mission, sim)``)."""
    inputs = run_inputs(c, base, index)
    mission = run_mission_of(base, inputs)
    sim = build_simulation(mission, params=run_parameter_set(inputs))
    return inputs, mission, sim


OUTCOMES: dict[str, str] = {
    "success": "bool",
    "landed": "bool",
    "landings": "int",
    "landings_ok": "int",
    "miss_m": "float",
    "heading_error_deg": "float",
    "contact_speed_mps": "float",
    "rests_on": "str",
    "rms_north_m": "float",
    "rms_east_m": "float",
    "rms_heading_deg": "float",
    "max_thruster_utilisation": "float",
    "saturated_time_s": "float",
    "settling_time_s": "float",
    "slack_events": "int",
    "snap_ratio": "float",
    "diverged": "bool",
    "timed_out": "bool",
    "simulated_s": "float",
    "wall_s": "float",
    "error": "str",
    "worker": "str",
}
"""Outcome columns of a result row and their types. ``success``: the mission did not fail
(every landing landed, no leg timed out or failed, no divergence). ``landed``: every landing
landed (None when the mission has none). Landing figures are the worst over the landings."""
FIGURES = tuple(k for k in OUTCOMES if k not in ("wall_s", "worker"))
"""Outcomes a rerun must reproduce exactly (all but the wall time and who ran it)."""


def same_figure(a: object, b: object) -> bool:
    """Two values of a figure are the same (NaN is the same as NaN: no figure either time)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def same_figures(a: dict, b: dict) -> bool:
    """Two rows have the same outcome figures (``FIGURES``)."""
    return all(same_figure(a[k], b[k]) for k in FIGURES)


def wire_before_contact(result: MissionResult, can_slack: bool = True) -> dict:
    """``slack_events`` and ``snap_ratio`` of a run from its ``wire`` events (the mission
    driver's ``missions.seaway.WireWatch``): the lift and the landing, up to the first contact
    with the posts. After it the tree rests on the frame and a heaving crane tip slackens the
    wire by design (the set-down), which is no slack of the lift. A snap counts when the slack
    it follows began before the contact. ``can_slack`` False (the quasi-static wire, a spring
    that pushes as well as pulls): None and NaN, no figures."""
    if not can_slack:
        return {"slack_events": None, "snap_ratio": math.nan}
    contacts = [x.t_contact_s for x in result.landings if math.isfinite(x.t_contact_s)]
    contact = min(contacts) if contacts else math.inf
    slack = 0
    snap_ratio = 0.0
    counted = False
    wire = [e for e in result.events if e.get("kind") == "wire"]
    for e in sorted(wire, key=lambda e: e["t_s"]):
        data = e.get("data", {})
        if data.get("event") == "slack":
            counted = e["t_s"] < contact
            slack += counted
        elif data.get("event") == "snap" and counted:
            snap_ratio = max(snap_ratio, data["tension_newton"] / data["static_newton"])
    return {"slack_events": slack, "snap_ratio": snap_ratio}


def outcome_row(
    result: MissionResult, simulated_s: float, wall_s: float, can_slack: bool = True
) -> dict:
    """The outcome columns of one run, taken from its MissionResult (``can_slack``: the
    run's wire can go slack, ``wire_before_contact``)."""
    lands = list(result.landings)

    def worst(attr: str) -> float:
        vals = [abs(float(getattr(x, attr, math.nan))) for x in lands]
        return max(vals) if vals else math.nan

    error = result.error or next((leg.error for leg in result.legs if leg.error), "")
    ran = result.scored_rows != 0  # the scored legs never ran: no RMS figures, not zeros
    if not error and result.diverged:
        error = "diverged"
    return {
        "success": not result.failed,
        "landed": all(x.success for x in lands) if lands else None,
        "landings": len(lands),
        "landings_ok": sum(bool(x.success) for x in lands),
        "miss_m": worst("miss_m"),
        "heading_error_deg": worst("heading_error_deg"),
        "contact_speed_mps": worst("contact_speed_mps"),
        "rests_on": ",".join(str(getattr(x, "rests_on", "")) for x in lands),
        "rms_north_m": result.rms_north_m if ran else math.nan,
        "rms_east_m": result.rms_east_m if ran else math.nan,
        "rms_heading_deg": result.rms_heading_deg if ran else math.nan,
        "max_thruster_utilisation": result.max_thruster_utilisation,
        "saturated_time_s": result.saturated_time_s,
        "settling_time_s": math.nan if result.settling_time_s is None else result.settling_time_s,
        **wire_before_contact(result, can_slack),
        "diverged": result.diverged,
        "timed_out": any(leg.timed_out for leg in result.legs),
        "simulated_s": simulated_s,
        "wall_s": wall_s,
        "error": error,
        "worker": worker_name(),
    }


def input_row(inputs: RunInputs) -> dict:
    return {
        "run": inputs.index,
        "point": inputs.point,
        "repetition": inputs.repetition,
        "sim_seed": inputs.sim_seed,
        **inputs.values,
    }


def failed_row(inputs: RunInputs, message: str) -> dict:
    """The row of a run that raised: no figures, the error text."""
    row = dict.fromkeys(OUTCOMES)
    row.update(
        worker=worker_name(),
        success=False,
        diverged=False,
        timed_out=False,
        landings=0,
        landings_ok=0,
        error=message[:500],
    )
    return {**input_row(inputs), **row}


def run_one(c: Campaign, base: schema.Mission, index: int) -> dict:
    """Run ``index`` of the campaign to its end: one flat row of its inputs and outcomes. A
    run that raises gives a row with its error text (and success false), never an exception."""
    inputs = run_inputs(c, base, index)
    t0 = time.perf_counter()
    try:
        _, mission, sim = prepare_run(c, base, index)
        result = MissionDriver(mission, sim, keep_log=False).run_to_end(log=False)
    except Exception as err:  # any failure of one run is that run's outcome
        return failed_row(inputs, f"{type(err).__name__}: {err}")
    wall_s = time.perf_counter() - t0
    can_slack = sim.wire_model in SLACK_WIRES
    return {**input_row(inputs), **outcome_row(result, sim.t_s, wall_s, can_slack)}


def quick_look_runs(c: Campaign, limit: int | None) -> list[int]:
    """The runs a campaign limited to ``limit`` runs takes (None: all, in order): the first
    repetition of every point, then the second, and so on, so a few runs cover the grid."""
    if limit is None:
        return list(range(c.runs))
    if limit < 1:
        raise CampaignError(f"limit must be at least 1, got {limit}")
    order = sorted(range(c.runs), key=lambda i: divmod(i, c.runs_per_point)[::-1])
    return sorted(order[:limit])


def run_block(c: Campaign, base: schema.Mission, indices: Sequence[int]) -> list[dict]:
    """Runs ``indices`` of the campaign, one after another (one Dask task: the task's
    overhead shared by the block): one row per run, in order (``run_one``'s)."""
    return [run_one(c, base, index) for index in indices]


# ------------------------------------------------------------------------------------------
# statistics
# ------------------------------------------------------------------------------------------

Z95 = 1.959963984540054
"""Two-sided 95 % quantile of the standard normal distribution."""


def wilson_interval(successes: int, runs: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a success probability (E. B. Wilson, 1927)."""
    if runs <= 0:
        return (0.0, 1.0)
    p = successes / runs
    z2 = z * z
    centre = (p + z2 / (2 * runs)) / (1 + z2 / runs)
    half = z / (1 + z2 / runs) * math.sqrt(p * (1 - p) / runs + z2 / (4 * runs * runs))
    return (max(0.0, centre - half), min(1.0, centre + half))
