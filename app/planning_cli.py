"""``rov-console operability`` and ``rov-console window``: what an installation engineer hands
over before a lift (issue 44).

    rov-console operability MISSION [--hs 1,2,3,4] [--tp 6,8,10,12] [--heading 180]
        [--current SPEED@DIR] [--seeds N] [--scheduler ADDRESS] [--out DIR] [--json]
    rov-console window MISSION --forecast FILE [--operation-hours H] [--table FILE] [--json]

Exit codes: 0 the table or the timeline was made (with or without a window); 2 a bad input
(a mission, an option, a forecast row), with one line saying which.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated, NoReturn

import typer

RESULTS_DIR = Path("operability-results")
"""Where tables go unless ``--out`` says: one folder per mission."""


def _fail(message: str) -> NoReturn:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def _floats(text: str, option: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        _fail(f"{option} takes numbers separated by commas, got {text!r}")
    if not all(math.isfinite(v) for v in values):
        _fail(f"{option}: every value must be finite, got {text!r}")
    return values


def _current(text: str | None) -> tuple[float, float] | None:
    """SPEED@DIR_DEG (m/s towards DIR, from north) as (speed, direction in [0, 360))."""
    if text is None:
        return None
    speed_s, _, dir_s = text.partition("@")
    try:
        speed, direction = float(speed_s), float(dir_s)
    except ValueError:
        _fail(f"--current must look like SPEED@DIR_DEG, e.g. 0.3@225, got {text!r}")
    if not (math.isfinite(direction) and 0.0 <= speed <= 3.0):
        _fail(f"--current: speed in [0, 3] m/s and a finite direction, got {text!r}")
    return speed, direction % 360.0


def _limits(items: list[str]) -> dict[str, float]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep:
            _fail(f"--limit takes NAME=VALUE (snap_load=2.5), got {item!r}")
    return out


MissionArg = Annotated[str, typer.Argument(help="library mission name or mission file")]
HsOpt = Annotated[str, typer.Option("--hs", help="significant wave heights [m], e.g. 1,2,3,4")]
TpOpt = Annotated[str, typer.Option("--tp", help="peak periods [s], e.g. 6,8,10,12")]
HeadingOpt = Annotated[
    str | None,
    typer.Option(
        "--heading",
        help="wave headings relative to the vessel [deg]: from the bow to where the waves "
        "travel towards, 180 head sea, 90 towards starboard (default: 180 for a vessel "
        "that heads into the waves, else every 45 deg)",
    ),
]


def _build_table(
    mission_name: str,
    hs: str,
    tp: str,
    heading: str | None,
    current: str | None,
    seeds: int,
    seed: int,
    limit: list[str],
    out: Path | None,
    scheduler: str | None,
    workers: int | None,
    in_process: bool,
    progress: bool,
):
    hs_m, tp_s = _floats(hs, "--hs"), _floats(tp, "--tp")  # before the imports (1.4 s)
    given = _floats(heading, "--heading") if heading else None
    overrides = _limits(limit)
    cur = _current(current)
    from app.planning import table as tab
    from missions import operability as op
    from missions import schema

    try:
        mission = schema.load_mission(mission_name)
    except schema.MissionError as err:
        _fail(str(err))
    try:
        grid = op.Grid(hs_m, tp_s, given or op.default_headings(mission))
        p = op.plan(mission, grid, seeds, seed, cur)
        limits = op.limits_for(mission.setup.params, overrides)
    except ValueError as err:
        _fail(str(err))
    folder = out if out is not None else RESULTS_DIR / op.results_name(mission.name)
    try:
        t = tab.run_table(p, limits, folder, scheduler, workers, in_process, progress)
    except ValueError as err:  # a results folder holding another table
        _fail(str(err))
    return t, tab.write_table(t)


def operability(
    mission: MissionArg,
    hs: HsOpt = "1,2,3,4",
    tp: TpOpt = "6,8,10,12",
    heading: HeadingOpt = None,
    current: Annotated[
        str | None, typer.Option(help="SPEED@DIR_DEG, m/s towards DIR (default: the mission's)")
    ] = None,
    seeds: Annotated[
        int,
        typer.Option(min=1, max=50, help="seeds a cell near a limit runs (the others run one)"),
    ] = 1,
    seed: Annotated[int, typer.Option(min=0, max=2**32 - 1, help="the campaign's seed")] = 0,
    limit: Annotated[
        list[str],
        typer.Option(help="NAME=VALUE: a limit other than the standard's, e.g. snap_load=2.5"),
    ] = [],  # noqa: B006 (typer's way of a repeatable option)
    out: Annotated[
        Path | None, typer.Option(help="results folder (default operability-results/MISSION)")
    ] = None,
    scheduler: Annotated[
        str | None, typer.Option(help="a running Dask scheduler (default: a local cluster)")
    ] = None,
    workers: Annotated[
        int | None, typer.Option(min=1, max=256, help="local cluster: worker processes")
    ] = None,
    in_process: Annotated[
        bool, typer.Option("--in-process", help="no Dask: run the cells here, one by one")
    ] = False,
    json_out: Annotated[bool, typer.Option("--json", help="print the table as JSON")] = False,
    progress: Annotated[bool, typer.Option(help="show the progress bar")] = True,
) -> None:
    """The operability table: the mission's landing over a grid of sea states, judged against
    named limits; the allowable Hs per Tp and wave heading as a figure, CSV and JSON."""
    _, paths = _build_table(
        mission,
        hs,
        tp,
        heading,
        current,
        seeds,
        seed,
        limit,
        out,
        scheduler,
        workers,
        in_process,
        progress and not json_out,
    )
    data = json.loads(paths["json"].read_text())
    if json_out:
        typer.echo(json.dumps(data, indent=1))
        return
    _print_table(data, paths)


def _print_table(data: dict, paths: dict[str, Path]) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console(width=120, highlight=False)
    tps = sorted({a["tp_s"] for a in data["allowable"]})
    grid = Table(title=f"{data['mission']}: allowable Hs in m (limiting criterion)")
    grid.add_column("heading [deg]", justify="right")
    for tp in tps:
        grid.add_column(f"Tp {tp:g} s", justify="right")
    allow = {(a["tp_s"], a["wave_heading_deg"]): a for a in data["allowable"]}
    for h in sorted({a["wave_heading_deg"] for a in data["allowable"]}):
        cells = []
        for tp in tps:
            a = allow[(tp, h)]
            more = "+" if a["above_grid"] else ""
            cells.append(f"{a['hs_m']:g}{more} ({a['limiting'] or 'none'})")
        grid.add_row(f"{h:g}", *cells)
    console.print(grid)
    for lim in data["limits"]:
        text = f"  {lim['name']}: {lim['value']:g} {lim['unit']}  ({lim['source']})"
        console.print(text, markup=False)
    console.print(f"seeds: {data['seed_dependence']}", markup=False)
    console.print("written: " + ", ".join(str(p) for p in paths.values()), markup=False)


def window(
    mission: MissionArg,
    forecast: Annotated[Path, typer.Option(help="forecast CSV (see docs/formats.md)")],
    operation_hours: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            help="planned duration T_POP [h] (default: the table's landing as "
            "simulated, rounded up to a whole hour)",
        ),
    ] = None,
    contingency_hours: Annotated[
        float | None,
        typer.Option(min=0.0, help="contingency T_C [h] (default: as long as the operation)"),
    ] = None,
    alpha_table: Annotated[
        str,
        typer.Option(
            help="alpha table: base (DNV's base case: one forecast source, no meteorologist "
            "on site), or a CSV file of the table you work to (a better forecast's)"
        ),
    ] = "base",
    table: Annotated[
        Path | None,
        typer.Option(
            help="a saved operability table (operability.json or its folder; default "
            "operability-results/MISSION, made there first when missing)"
        ),
    ] = None,
    vessel_heading: Annotated[
        float | None,
        typer.Option(help="the vessel's heading [deg] (default: the table's, or into the waves)"),
    ] = None,
    hs: HsOpt = "1,2,3,4",
    tp: TpOpt = "6,8,10,12",
    heading: HeadingOpt = None,
    seeds: Annotated[int, typer.Option(min=1, max=50, help="a table made here: seeds")] = 1,
    scheduler: Annotated[str | None, typer.Option(help="a table made here: Dask")] = None,
    in_process: Annotated[
        bool, typer.Option("--in-process", help="a table made here: no Dask")
    ] = False,
    plot: Annotated[Path | None, typer.Option(help="the timeline figure (PNG)")] = None,
    json_out: Annotated[bool, typer.Option("--json", help="print the timeline as JSON")] = False,
) -> None:
    """The weather window: the forecast against the operability table reduced by DNV-ST-N001's
    alpha factor; a go/no-go timeline and the windows long enough for the operation."""
    from missions import weather_window as ww  # no simulation: a bad file answers at once

    try:
        fc = ww.read_forecast(forecast)
    except ww.ForecastError as err:
        _fail(str(err))
    try:
        alpha = _alpha(alpha_table)
    except ValueError as err:
        _fail(str(err))
    from app.planning import figures
    from app.planning import table as tab
    from missions import operability as op
    from missions import schema

    try:
        m = schema.load_mission(mission)
    except schema.MissionError as err:
        _fail(str(err))
    folder = RESULTS_DIR / op.results_name(m.name)
    source = table if table is not None else folder / tab.TABLE_JSON
    if table is None and not source.is_file():
        _build_table(
            mission,
            hs,
            tp,
            heading,
            None,
            seeds,
            0,
            [],
            folder,
            scheduler,
            None,
            in_process,
            not json_out,
        )
    try:
        data = tab.read_table(source)
    except ValueError as err:
        _fail(str(err))
    if data["mission"] != m.name:
        _fail(f"{source} is the table of {data['mission']!r}, not of {m.name!r}")
    op_hours = operation_hours
    if op_hours is None:
        op_hours = float(max(1, math.ceil(data.get("mission_hours", 1.0) - 1e-9)))
    if op_hours <= 0.0:
        _fail("--operation-hours must be > 0")
    cont = op_hours if contingency_hours is None else contingency_hours
    reference = op_hours + cont
    try:
        alpha.alpha(reference, 1.0)
    except ValueError as err:
        _fail(f"--operation-hours {op_hours:g} + --contingency-hours {cont:g}: {err}")
    into = data.get("vessel_into_waves", False) and vessel_heading is None
    result = _judge(ww, fc, data, alpha, reference, into, vessel_heading)
    result.update(
        mission=m.name,
        table=str(source),
        forecast=str(forecast),
        operation_hours=op_hours,
        contingency_hours=cont,
        reference_hours=reference,
    )
    figure = plot if plot is not None else forecast.with_name(forecast.stem + "-window.png")
    figures.window_figure(result, figure)
    result["figure"] = str(figure)
    if json_out:
        typer.echo(json.dumps(result, indent=1, allow_nan=False))
        return
    _print_window(result)


def _alpha(name: str):
    from missions import weather_window as ww

    if name in ww.ALPHA_TABLES:
        return ww.ALPHA_TABLES[name]
    path = Path(name)
    if path.suffix.lower() == ".csv":
        return ww.read_alpha_table(path)
    raise ValueError(f"--alpha-table {name!r}: one of {', '.join(ww.ALPHA_TABLES)} or a .csv file")


def _judge(ww, fc, data: dict, alpha, reference: float, into: bool, vessel_heading) -> dict:
    """The verdicts as the JSON the command prints (``alpha``: the lowest applied)."""
    vh = (
        None if into else (data["vessel_heading_deg"] if vessel_heading is None else vessel_heading)
    )
    verdicts = ww.judge_hours(fc, data, alpha, reference, vh)
    heading_text = "bow into the waves every hour" if vh is None else f"{vh:g} deg"
    applied = [v.alpha for v in verdicts if v.alpha is not None]
    wins = ww.windows(verdicts, fc.step, reference)
    return {
        "alpha": min(applied) if applied else alpha.alpha(reference, alpha.hs_m[0]),
        "alpha_table": alpha.as_dict(),
        "vessel_heading": heading_text,
        "step_hours": fc.step.total_seconds() / 3600.0,
        "hours": [v.as_dict() for v in verdicts],
        "windows": [w.as_dict() for w in wins],
        "go_spells": [w.as_dict() for w in ww.go_spells(verdicts, fc.step)],
    }


def _print_window(result: dict) -> None:
    a = result["alpha_table"]
    typer.echo(
        f"{result['mission']}: reference period {result['reference_hours']:g} h "
        f"(operation {result['operation_hours']:g} h + contingency "
        f"{result['contingency_hours']:g} h); alpha table {a['table']} ({a['source']}); "
        f"lowest alpha applied {result['alpha']:.3f}; vessel {result['vessel_heading']}"
    )
    for h in result["hours"]:
        mark = "GO   " if h["go"] else "no-go"
        limit = "-" if h["limit_hs_m"] is None else f"{h['limit_hs_m']:.2f}"
        typer.echo(
            f"  {h['time']}  {mark}  Hs {h['hs_m']:5.2f} m  limit {limit:>5} m  "
            f"Tp {h['tp_s']:4.1f} s  {h['reason']}"
        )
    if result["windows"]:
        for w in result["windows"]:
            typer.echo(f"window: {w['start']} to {w['end']} ({w['hours']:g} h)")
    else:
        typer.echo(f"no window of {result['reference_hours']:g} h in the forecast")
    typer.echo(f"figure: {result['figure']}")
