"""``rov-console``: the product's command line."""

from __future__ import annotations

import json
import math
import sys
import tempfile
import time
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from app import assessment_cli, headless, shadow_cli, software_version
from app.campaign.cli import campaign_app
from app.log_cli import log_app
from app.planning_cli import operability, window

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    # plain help text: units in brackets ([m], [s]) are units, not terminal markup
    rich_markup_mode=None,
    help="Simulator, control system and console for ROV-assisted tree-on-wire installation.",
)


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"rov-console {software_version()}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            callback=_print_version,
            is_eager=True,
            help="print the version and exit",
        ),
    ] = False,
) -> None:
    """Simulator, control system and console for ROV-assisted tree-on-wire installation."""
    from app.compiling import report_compiles

    report_compiles()  # a first run after a change compiles for tens of seconds: say so


def parse_polar(text: str, what: str, unit: str) -> tuple[float, float]:
    """Parse 'VALUE@DIR_DEG' (direction the thing points towards, from north, clockwise)."""
    try:
        value_s, dir_s = text.split("@")
        value, direction = float(value_s), float(dir_s)
    except ValueError:
        raise typer.BadParameter(
            f"{what} must look like VALUE@DIR_DEG, e.g. 0.1@225 "
            f"({unit} towards 225 deg), got {text!r}"
        ) from None
    if not (math.isfinite(value) and math.isfinite(direction)):
        raise typer.BadParameter(f"{what} must be finite, got {text!r}")
    return value, math.radians(direction)


DEFAULT_SCORES_DB = Path("recordings") / "scores.sqlite"
"""Where scores go by default: beside the console's recordings (``serve --recordings``)."""


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


@app.command()
def simulate(
    params: Annotated[
        str, typer.Option(help="parameter set name (full-scale, model-scale) or a .toml/.json file")
    ] = "full-scale",
    depth: Annotated[float, typer.Option(help="tree depth [m]; the wire length follows")] = 400.0,
    duration: Annotated[float, typer.Option(help="simulated time [s]", min=0.0, max=1.0e6)] = 600.0,
    current: Annotated[str, typer.Option(help="SPEED@DIR_DEG, m/s towards DIR")] = "0.1@225",
    no_rov: Annotated[bool, typer.Option("--no-rov", help="the tree alone")] = False,
    push: Annotated[
        str | None,
        typer.Option(help="NEWTONS@DIR_DEG steady horizontal force on the tree's centre"),
    ] = None,
    waves: Annotated[str | None, typer.Option(help="HS_M@TP_S@DIR_DEG ITTC sea")] = None,
    crane_tip: Annotated[str, typer.Option(help="N,E of the wire's surface point [m]")] = "1,1",
    seed: Annotated[int, typer.Option(help="random seed")] = 0,
) -> None:
    """Run the plant without control and print one JSON object describing where it ends."""
    from control.simulation import Simulation, SimulationDiverged, steady_current
    from sim import environment as envmod
    from sim import params as params_mod

    speed, direction = parse_polar(current, "--current", "m/s")
    if not 0.0 <= speed <= 3.0:
        raise typer.BadParameter(f"--current speed must be in [0, 3] m/s, got {speed}")
    try:
        ct = [float(v) for v in crane_tip.split(",")]
        assert len(ct) == 2
    except (ValueError, AssertionError):
        raise typer.BadParameter(f"--crane-tip must be N,E in metres, got {crane_tip!r}") from None
    wave_params = None
    if waves is not None:
        try:
            hs, tp, wdir = (float(v) for v in waves.split("@"))
            wave_params = envmod.WaveParams(
                significant_height_m=hs, peak_period_s=tp, direction_rad=math.radians(wdir)
            )
        except ValueError as err:
            raise typer.BadParameter(f"--waves must be HS_M@TP_S@DIR_DEG: {err}") from None
    try:
        ps = params_mod.load(params)
        sim = Simulation(
            ps,
            tree_depth_m=depth,
            crane_tip_n=np.array([ct[0], ct[1], 0.0]),
            current=steady_current(speed, direction),
            waves=wave_params,
            has_rov=not no_rov,
            seed=seed,
            control=False,
        )
        if push is not None:
            force, pdir = parse_polar(push, "--push", "N")
            sim.set_push(np.array([force * math.cos(pdir), force * math.sin(pdir), 0.0]))
        t0 = time.perf_counter()
        rows = sim.run_for(duration)
        wall = time.perf_counter() - t0
    except (ValueError, SimulationDiverged) as err:
        _fail(str(err))
        return
    typer.echo(json.dumps(simulation_summary(sim, rows, wall), indent=2))


def simulation_summary(sim, rows, wall_s: float) -> dict:
    """The JSON answer of ``simulate``: final poses (angles in degrees) and settling."""
    from sim.gnc import ssa

    def eta_deg(eta: np.ndarray) -> list[float]:
        out = [float(v) for v in eta[:3]] + [math.degrees(ssa(float(a))) for a in eta[3:]]
        return [round(v, 6) for v in out]

    x = sim.plant_state
    t_s = rows.t_s
    speeds = np.linalg.norm(rows["tree_nu_b"][:, 0:3], axis=1)
    last = t_s >= t_s[-1] - 60.0 if len(t_s) else np.array([], dtype=bool)
    settled = bool(len(t_s) and t_s[-1] >= 60.0 and np.all(speeds[last] < 1e-3))
    duration = float(t_s[-1]) if len(t_s) else 0.0
    return {
        "params": sim.ps.name,
        "time_s": round(sim.t_s, 6),
        "tree_eta_n": eta_deg(x[0:6]),
        "rov_eta_n": eta_deg(x[12:18]) if sim.has_rov else None,
        "crane_tip_n": [float(v) for v in sim.crane_tip_n],
        "wire_length_m": round(sim.wire_length_m, 4),
        "horizontal_offset_m": round(
            float(np.hypot(x[0] - sim.crane_tip_n[0], x[1] - sim.crane_tip_n[1])), 6
        ),
        "heading_deg": round(math.degrees(ssa(float(x[5]))), 4),
        "wire_tension_newton": round(sim.wire_tension_newton(), 2),
        "tree_speed_mps": float(speeds[-1]) if len(speeds) else 0.0,
        "settled": settled,
        "steps": len(t_s),
        "steps_per_second": round(len(t_s) / wall_s, 1) if wall_s > 0 else None,
        "real_time_factor": round(duration / wall_s, 1) if wall_s > 0 else None,
    }


app.add_typer(log_app, name="log")
app.add_typer(campaign_app, name="campaign")
app.command()(operability)
app.command()(window)
assessment_cli.register(app)  # logbook, trend, criteria
app.command("shadow")(shadow_cli.shadow)

LIST_HELP = "list the library's missions and exit"


def _list_library() -> None:
    from missions import schema

    for n in schema.library_names():
        typer.echo(f"{n:28s} {schema.load_mission(n).description}")


@app.command()
def run(
    mission: Annotated[
        str | None, typer.Argument(help="mission file (TOML) or a library name (see --list)")
    ] = None,
    list_: Annotated[bool, typer.Option("--list", help=LIST_HELP)] = False,
    json_out: Annotated[bool, typer.Option("--json", help="one JSON object")] = False,
    log: Annotated[str | None, typer.Option(help="write the session to this MCAP file")] = None,
    log_rate: Annotated[
        float,
        typer.Option(
            min=0.1, help="rows a second in --log [Hz]; the plant's rate (100) keeps every step"
        ),
    ] = 20.0,
    plots: Annotated[str | None, typer.Option(help="write PNG figures into this folder")] = None,
    seed: Annotated[int | None, typer.Option(help="random seed (default: the file's)")] = None,
    allocation: Annotated[
        str | None, typer.Option(help="pinv | priority | qp (default: the mission file's)")
    ] = None,
    feedback: Annotated[
        str | None, typer.Option(help="perfect | ekf (default: the mission file's)")
    ] = None,
    law: Annotated[
        str | None,
        typer.Option(
            help="thesis (eq. 3.9 alone) | feedforward (with reference feedforward); default: "
            "the mission file's"
        ),
    ] = None,
    progress: Annotated[bool, typer.Option(help="show a progress bar")] = True,
    trainee: Annotated[
        str | None, typer.Option(help="store this run's scores under this trainee's name")
    ] = None,
    scores_db: Annotated[
        Path, typer.Option(help="the scores database (SQLite) --trainee writes to")
    ] = DEFAULT_SCORES_DB,
) -> None:
    """Run a mission headless, faster than real time; exit 1 if it failed."""
    from control.config import ALLOCATIONS, FEEDBACKS, LAWS
    from missions import schema
    from missions.driver import MissionDriver
    from missions.setup import build_simulation

    if list_ or mission is None:
        _list_library()
        return
    _validate_choice("--allocation", allocation, ALLOCATIONS)
    _validate_choice("--feedback", feedback, FEEDBACKS)
    _validate_choice("--law", law, LAWS)
    try:
        spec = schema.load_mission(mission)
        sim = build_simulation(
            spec,
            seed=seed,
            allocation=allocation,  # type: ignore[arg-type]
            feedback=feedback,  # type: ignore[arg-type]
            feedforward=None if law is None else law == "feedforward",
        )
    except ValueError as err:
        _fail(str(err))
        return
    driver = MissionDriver(spec, sim)
    recorder = None
    if log:
        try:
            Path(log).parent.mkdir(parents=True, exist_ok=True)
            recorder = headless.open_recorder(log, spec, sim, seed, numeric_rate_hz=log_rate)
        except OSError as err:
            _fail(f"--log {log}: cannot write: {err.strerror or err}")
            return
    t0 = time.perf_counter()
    try:
        result = headless.drive(driver, recorder, show=progress and not json_out)
    finally:
        if recorder is not None:
            recorder.close()
    wall = time.perf_counter() - t0
    summary = result.summary()
    summary["simulated_s"] = round(sim.t_s, 2)
    summary["real_time_factor"] = round(sim.t_s / wall, 1) if wall > 0 else None
    summary["events"] = result.events
    if log:
        summary["log"] = log
    if plots:
        from app.plots import mission_figures
        from missions.setup import charted_frame

        charted = charted_frame(spec)
        docking = None if charted is None else (charted, sim.ps.spec.docking.to_numeric())
        figures = mission_figures(result, Path(plots), sim.crane_tip_n, docking)
        summary["plots"] = [str(p) for p in figures]
    if trainee is not None:
        from app import scores
        from app.assessment import facts_of_run

        try:
            facts = facts_of_run(result, sim)
            summary["score_id"] = scores.record(scores_db, trainee, result, "run", log, "", facts)
        except (ValueError, OSError) as err:
            _fail(f"--trainee: cannot store the scores in {scores_db}: {err}")
    if json_out:
        typer.echo(json.dumps(summary, indent=2, default=_json_default))
    else:
        _print_result_table(summary)
        _print_landings(summary)
    if result.failed:
        raise typer.Exit(code=1)


@app.command(hidden=True)
def scenario(
    name: Annotated[str | None, typer.Argument()] = None,
    list_: Annotated[bool, typer.Option("--list")] = False,
    json_out: Annotated[bool, typer.Option("--json")] = False,
    seed: Annotated[int | None, typer.Option()] = None,
    allocation: Annotated[str | None, typer.Option()] = None,
    feedback: Annotated[str | None, typer.Option()] = None,
    law: Annotated[str | None, typer.Option()] = None,
) -> None:
    """Former name of ``run`` (kept so old scripts work)."""
    typer.echo("note: 'scenario' is now 'run'", err=True)
    run(
        mission=name,
        list_=list_,
        json_out=json_out,
        log=None,
        plots=None,
        seed=seed,
        allocation=allocation,
        feedback=feedback,
        law=law,
        progress=False,
    )


def _print_result_table(summary: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    from missions.scoring import LEG_TABLE_COLUMNS, leg_table_rows

    table = Table(
        title=f"{summary['name']}  (simulated {summary['simulated_s']:.0f} s, "
        f"{summary['real_time_factor']}x real time)"
    )
    for col in LEG_TABLE_COLUMNS:
        table.add_column(col, justify="right")
    *legs, scored = leg_table_rows(summary)
    for row in legs:
        table.add_row(*row)
    table.add_row(*scored, style="bold")
    console = Console(width=120)
    console.print(table)
    final = summary["final_eta_n"]
    console.print(
        f"final tree pose: N {final[0]:.3f} m, E {final[1]:.3f} m, D {final[2]:.2f} m, "
        f"heading {final[5]:.2f} deg; settling time "
        f"{summary['settling_time_s']} s; diverged: {summary['diverged']}"
    )
    for w in summary["warnings"]:
        console.print("WARNING: " + w, style="bold red", markup=False)
    for leg in summary["legs"]:
        if leg.get("error") and leg["error"] not in summary.get("error", ""):
            console.print(
                f"FAILED leg {leg['index']} ({leg['type']}): {leg['error']}",
                style="bold red",
                markup=False,
            )
    if summary.get("error"):
        console.print("ERROR: " + summary["error"], style="bold red", markup=False)


def _validate_choice(name: str, value: str | None, allowed: tuple[str, ...]) -> None:
    if value is not None and value not in allowed:
        raise typer.BadParameter(f"{name} must be one of {', '.join(allowed)}, got {value!r}")


def _json_default(value: object) -> object:
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return str(value)


def _print_landings(summary: dict) -> None:
    from missions.scoring import landing_lines

    for line in landing_lines(summary):
        typer.echo(line)
    if summary.get("failed"):
        typer.echo("mission FAILED", err=True)


@app.command()
def scores(
    trainee: Annotated[str | None, typer.Option(help="only this trainee's runs")] = None,
    mission: Annotated[str | None, typer.Option(help="only this mission's runs")] = None,
    best: Annotated[bool, typer.Option("--best", help="the best run of each mission")] = False,
    db: Annotated[Path, typer.Option(help="the scores database (SQLite)")] = DEFAULT_SCORES_DB,
    json_out: Annotated[bool, typer.Option("--json", help="JSON instead of a table")] = False,
    compare: Annotated[
        str | None,
        typer.Option(
            "--compare",
            metavar="MISSION",
            help="the best hand-flown and the best autopilot run of MISSION side by side",
        ),
    ] = None,
) -> None:
    """List stored scores (newest first): who flew which mission when, landed or not, miss,
    heading error and contact speed at the landing, RMS errors, time saturated, and whether
    the autopilot or the pilot's hand flew it."""
    from rich.console import Console
    from rich.table import Table

    from app import scores as store

    try:
        rows = store.history(db, trainee, compare or mission)
    except ValueError as err:
        _fail(str(err))
        return
    if compare is not None:
        _print_comparison(compare, store.compare(rows), json_out, db)
        return
    if best:
        rows = store.best(rows)
    if json_out:
        typer.echo(store.as_json(rows))
        return
    if not rows:
        typer.echo(f"no scores in {db}" + (f" for {trainee}" if trainee else ""))
        return
    table = Table(title=f"scores ({db})")
    for col in (
        "id",
        "when (UTC)",
        "trainee",
        "mission",
        "result",
        "miss m",
        "psi err deg",
        "contact m/s",
        "RMS N m",
        "RMS E m",
        "RMS psi deg",
        "saturated s",
        "flown by",
    ):
        table.add_column(col, justify="right")

    for r in rows:
        verdict = "PASS" if r.passed and not r.criteria_failed else "FAIL"
        if r.landed is not None:
            verdict += ", landed" if r.landed else ", not landed"
        if r.faults:
            verdict += ", faulted"
        if r.criteria_failed:
            verdict += " *"
        table.add_row(
            str(r.id),
            r.utc.replace("T", " ").rstrip("Z"),
            r.trainee,
            r.mission,
            verdict,
            _num(r.miss_m, ".3f"),
            _num(r.heading_error_deg, ".2f"),
            _num(r.contact_speed_mps, ".3f"),
            f"{r.rms_north_m:.4f}",
            f"{r.rms_east_m:.4f}",
            f"{r.rms_heading_deg:.3f}",
            f"{r.saturated_s:.1f}",
            r.flown_by,
        )
    console = Console(width=170)
    console.print(table)
    for r in rows:
        if r.criteria_failed:
            console.print(f"* run {r.id} failed: {r.criteria_failed}", markup=False)


def _num(v: float | None, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


COMPARE_ROWS: tuple[tuple[str, str, str], ...] = (
    ("run id", "id", "d"),
    ("when (UTC)", "utc", ""),
    ("trainee", "trainee", ""),
    ("share by hand", "manual_share", ".0%"),
    ("passed", "passed", ""),
    ("landed", "landed", ""),
    ("time to dock s", "time_to_dock_s", ".1f"),
    ("miss m", "miss_m", ".3f"),
    ("heading error deg", "heading_error_deg", ".2f"),
    ("contact speed m/s", "contact_speed_mps", ".3f"),
    ("RMS north m", "rms_north_m", ".4f"),
    ("RMS east m", "rms_east_m", ".4f"),
    ("RMS heading deg", "rms_heading_deg", ".3f"),
    ("saturated s", "saturated_s", ".1f"),
    ("thrust spent kN s", "thrust_newton_s", ".1f"),
    ("faults", "faults", ""),
)
"""The comparison's rows: (label, Score field, format)."""


def _cell(value: object, fmt: str, field: str) -> str:
    if value is None or value == "":
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if field == "thrust_newton_s":
        return format(float(value) / 1e3, fmt)  # type: ignore[arg-type]
    return format(value, fmt) if fmt else str(value)


def _print_comparison(mission: str, best: dict, json_out: bool, db: Path) -> None:
    """``scores --compare``: the best run of each way of flying, side by side."""
    from rich.console import Console
    from rich.table import Table

    if json_out:
        typer.echo(json.dumps({how: s.__dict__ for how, s in best.items()}, indent=2))
        return
    if not best:
        typer.echo(f"no scores of {mission} in {db}")
        return
    table = Table(title=f"{mission}: best run of each way of flying ({db})")
    table.add_column("figure")
    for how in best:
        table.add_column(f"best {how}", justify="right")
    for label, field, fmt in COMPARE_ROWS:
        table.add_row(label, *(_cell(getattr(s, field), fmt, field) for s in best.values()))
    Console(width=120).print(table)
    for how in ("hand", "autopilot"):
        if how not in best:
            typer.echo(f"no {'hand-flown' if how == 'hand' else 'autopilot'} run of {mission} yet")


@app.command()
def report(
    log: Annotated[
        Path, typer.Argument(help="a session log (.mcap) from run --log or the console")
    ],
    out: Annotated[
        Path, typer.Option("-o", "--out", help="HTML file to write (its folder is made)")
    ] = Path("report.html"),
    compare_with: Annotated[
        Path | None,
        typer.Option("--compare", help="another session log: add a comparison with it"),
    ] = None,
    align: Annotated[
        str, typer.Option(help="with --compare: mission | contact | start | event:WORDS")
    ] = "mission",
) -> None:
    """Write a self-contained debrief of a recorded session: scores per leg, landings, pose
    against reference, the track over the docking frame, forces and thrusters, and every event
    with who did it; with --compare, the run beside another."""
    for path in (log, compare_with):
        if path is not None and not path.is_file():  # before the imports (1.4 s)
            _fail(f"no log file {path}")
    from app.report import write_report

    try:
        if compare_with is None:
            d = write_report(log, out)
        else:
            from app.compare import compare, comparison_html, plot_comparison

            c = compare(log, compare_with, align)
            with tempfile.TemporaryDirectory() as tmp:
                plot = plot_comparison(c, Path(tmp) / "comparison.png")
                d = write_report(log, out, c.a, comparison_html(c, plot))
    except ValueError as err:
        _fail(str(err))
    typer.echo(
        f"{out}: debrief of {d.name} ({d.duration_s:.0f} s, {len(d.result.legs)} legs, "
        f"{len(d.events)} events)"
    )


@app.command("compare")
def compare_runs(
    a: Annotated[Path, typer.Argument(help="the first session log (.mcap): run A")],
    b: Annotated[Path, typer.Argument(help="the second session log (.mcap): run B")],
    align: Annotated[
        str,
        typer.Option(
            help="where to align the runs: mission (its start) | contact (first touch of "
            "the frame) | start (the recordings') | event:WORDS (first event with WORDS)"
        ),
    ] = "mission",
    plot: Annotated[
        Path | None, typer.Option(help="also draw both runs on one time axis into this PNG")
    ] = None,
    json_out: Annotated[bool, typer.Option("--json", help="one JSON object")] = False,
) -> None:
    """Compare two recorded runs: what differs in their set-ups, and figure by figure (RMS
    errors per leg, time saturated, thrust, alarms, the landing) which did better."""
    for path in (a, b):
        if not path.is_file():
            _fail(f"no log file {path}")
    from app.compare import compare, plot_comparison, table_rows

    try:
        c = compare(a, b, align)
        if plot is not None:
            plot.parent.mkdir(parents=True, exist_ok=True)
            plot_comparison(c, plot)
    except ValueError as err:
        _fail(str(err))
    if json_out:
        typer.echo(json.dumps(c.as_dict()))
        return
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    typer.echo(f"A: {c.a.name} ({a})\nB: {c.b.name} ({b})")
    typer.echo(
        f"aligned at {c.aligned.at}: A's {c.aligned.a_s:.1f} s with B's {c.aligned.b_s:.1f} s"
    )
    if c.differs:
        typer.echo("not like for like, the set-ups differ:")
        for line in c.differs:
            typer.echo(f"  {line}")
    table = Table("figure", "A", "B", "better")
    for row in table_rows(c):
        table.add_row(*(escape(cell) for cell in row))
    Console(width=110).print(table)
    if plot is not None:
        typer.echo(f"plot: {plot}")


@app.command()
def study(
    name: Annotated[
        str,
        typer.Argument(
            help="table-4.1 (waves), table-4.2 (robustness) or landing-limit (the largest "
            "sea state a landing from the moving vessel stays within the limits)"
        ),
    ],
    duration: Annotated[
        float, typer.Option(help="table-4.1: seconds per run", min=130.0, max=36000.0)
    ] = 600.0,
    seed: Annotated[
        int | None,
        typer.Option(help="random seed (default 0; landing-limit --mission: the mission's)"),
    ] = None,
    variant: Annotated[
        list[str] | None,
        typer.Option(
            help="table-4.1: how the sea is modelled (repeat for several; default all): "
            "'drag', 'drag, W0 195 kN', 'drag + vessel', 'morison', 'morison + vessel', "
            "'morison + vessel, elastic wire', 'morison + vessel, moordyn wire' (these two "
            "not in the default)"
        ),
    ] = None,
    json_out: Annotated[bool, typer.Option("--json")] = False,
    period: Annotated[
        float | None,
        typer.Option(
            help="landing-limit: peak period Tp [s] (default 10; not with --mission)",
            min=3.0,
            max=25.0,
        ),
    ] = None,
    compensation: Annotated[
        bool | None,
        typer.Option(
            help="landing-limit: the crane's heave compensation (80 %) (default on; not with "
            "--mission)"
        ),
    ] = None,
    mission: Annotated[
        str | None,
        typer.Option(
            help="landing-limit: a library mission or a .toml file whose [setup] gives the "
            "installation (parameter set, plant, docking frame, waves' period and direction, "
            "vessel, wire, current, seed); only Hs is swept"
        ),
    ] = None,
    hs_step: Annotated[
        float, typer.Option(help="landing-limit: Hs step [m]", min=0.1, max=12.0)
    ] = 0.5,
    hs_max: Annotated[
        float, typer.Option(help="landing-limit: largest Hs tried [m]", min=0.1, max=20.0)
    ] = 12.0,
    plot: Annotated[
        Path | None,
        typer.Option(help="landing-limit: PNG of the wire tension of the last landing run"),
    ] = None,
    seeds: Annotated[
        int,
        typer.Option(
            help="landing-limit: sweep this many seas (seeds --seed, --seed + 1, ...) and judge "
            "on the lowest limit: one seed's limit is one sea's",
            min=1,
            max=50,
        ),
    ] = 1,
) -> None:
    """Rerun one of the thesis's studies and print our numbers beside the thesis's.

    table-4.1: each way of modelling the sea side by side (wave load, vessel motion, the
    tree's submerged weight); uncontrolled heading as RMS about its 120 s running mean.
    table-4.2: scored over the thesis's window (turn and square, its law) and over the
    square with the feedforward law."""
    from missions import studies

    if name not in studies.STUDIES:
        raise typer.BadParameter(f"study must be one of {', '.join(studies.STUDIES)}, got {name!r}")
    if name == "landing-limit":
        if mission is not None:
            _mission_landing_limit(
                mission, period, compensation, hs_step, hs_max, seed, plot, json_out, seeds
            )
            return
        _landing_limit(
            10.0 if period is None else period,
            True if compensation is None else compensation,
            hs_step,
            hs_max,
            0 if seed is None else seed,
            plot,
            json_out,
            seeds,
        )
        return
    if mission is not None:
        _fail(f"--mission is for the landing-limit study, not {name}")
    if seeds != 1:
        _fail(f"--seeds is for the landing-limit study, not {name}")
    seed = 0 if seed is None else seed
    if name == "table-4.1":
        try:
            variants = (
                tuple(studies.variant_named(v) for v in (variant or ()))
                or studies.TABLE_4_1_VARIANTS
            )
        except ValueError as err:
            raise typer.BadParameter(f"--variant: {err}") from None
        rows = studies.table_4_1(duration, seed, variants)
    else:
        rows = studies.table_4_2(seed)
    if json_out:
        typer.echo(
            json.dumps(
                [
                    {"case": r.label, "variant": r.variant, "ours": r.ours, "thesis": r.thesis}
                    for r in rows
                ],
                indent=2,
            )
        )
        return
    from rich.console import Console
    from rich.table import Table

    console = Console(width=160)
    columns = list(dict.fromkeys(r.variant for r in rows))
    cases = list(dict.fromkeys(r.label for r in rows))
    by_key = {(r.label, r.variant): r for r in rows}
    quantities = (
        ("north RMS [m]", 0),
        ("east RMS [m]", 1),
        (
            "heading RMS [deg] (uncontrolled: about its 120 s running mean; controlled: "
            "about the set point)"
            if name == "table-4.1"
            else "heading RMS [deg]",
            2,
        ),
    )
    for title, k in quantities:
        table = Table(title=f"{name}: {title}")
        table.add_column("case")
        table.add_column("thesis", justify="right")
        for column in columns:
            table.add_column(column, justify="right")
        for case in cases:
            first = by_key[(case, columns[0])]
            cells = [f"{by_key[(case, c)].ours[k]:.4f}" for c in columns]
            table.add_row(case, f"{first.thesis[k]:.4f}", *cells)
        console.print(table)


def _landing_limit(
    period: float,
    compensation: bool,
    hs_step: float,
    hs_max: float,
    seed: int,
    plot: Path | None,
    json_out: bool,
    seeds: int = 1,
) -> None:
    """Step Hs up (head sea, elastic wire, tree alone on the wire, full scale, 100 m of
    water) until a landing goes slack or touches down faster than the frame allows; with
    ``seeds`` > 1 in as many seas, judged on the lowest limit."""
    from missions import seaway

    if hs_step > hs_max:
        raise typer.BadParameter(f"--hs-step must be at most --hs-max ({hs_max}), got {hs_step}")
    limits = seaway.limits_over_seeds(
        lambda s: seaway.landing_limit(period, compensation, hs_step, hs_max, seed=s),
        seed,
        seeds,
    )
    low = limits[0]
    hs, landings = low.limit_m, low.landings
    if plot is not None:
        seaway.tension_figure(landings[-1], plot)
    if json_out:
        typer.echo(
            json.dumps(_landing_limit_json(hs, landings, limits if seeds > 1 else None), indent=2)
        )
        return
    for x in landings:
        typer.echo(x.words())
    comp = "on" if compensation else "off"
    if seeds > 1:
        typer.echo(seaway.seeds_words(limits))
    typer.echo(
        f"last Hs within the limits at Tp {period:g} s, heave compensation {comp}: {hs:g} m"
        + (f" (the largest tried, {hs_max:g} m)" if landings[-1].within_limits else "")
        + _lowest_of(limits)
    )


def _lowest_of(limits: list) -> str:
    """' (the lowest of N seeds: ...)' after the limit when several seas were swept."""
    if len(limits) == 1:
        return ""
    return f" (the lowest of {len(limits)} seeds: seed {limits[0].seed}'s landings above)"


def _landing_limit_json(hs: float, landings: list, limits: list | None = None) -> dict:
    by_seed = {}
    if limits is not None:
        by_seed = {
            "seed_of_lowest_limit": limits[0].seed,
            "limits_by_seed": [
                {"seed": r.seed, "last_hs_within_limits_m": r.limit_m}
                for r in sorted(limits, key=lambda r: r.seed)
            ],
        }
    return {
        **by_seed,
        "last_hs_within_limits_m": hs,
        "landings": [
            {
                "hs_m": x.significant_height_m,
                "within_limits": x.within_limits,
                "slack_events": x.slack_events,
                "snap_events": x.snap_events,
                "snap_peak_newton": x.snap_peak_newton,
                "snap_estimate_newton": x.snap_estimate_newton,
                "contact_speed_mps": x.contact_speed_mps,
                "min_tension_newton": x.min_tension_newton,
                "max_tension_newton": x.max_tension_newton,
            }
            for x in landings
        ],
    }


def _mission_landing_limit(
    mission: str,
    period: float | None,
    compensation: bool | None,
    hs_step: float,
    hs_max: float,
    seed: int | None,
    plot: Path | None,
    json_out: bool,
    seeds: int = 1,
) -> None:
    """The landing-limit study for the installation a mission's [setup] describes: only Hs
    is swept (in ``seeds`` seas from the seed on, judged on the lowest limit); the mission's
    own Hs is reported beside the limit."""
    from missions import schema, seaway

    if period is not None:
        _fail(
            "--period cannot be given with --mission: the peak period comes from the "
            "mission's setup.waves.peak_period_s (change it there, or drop --mission)"
        )
    if compensation is not None:
        _fail(
            "--compensation/--no-compensation cannot be given with --mission: heave "
            "compensation comes from the mission's setup.vessel.heave_compensation"
        )
    if hs_step > hs_max:
        _fail(f"--hs-step must be at most --hs-max ({hs_max:g}), got {hs_step:g}")
    try:
        spec = schema.load_mission(mission)
        scenario = seaway.LandingScenario.from_mission(spec)
        limits = seaway.limits_over_seeds(
            lambda s: scenario.limit(hs_step, hs_max, seed=s),
            scenario.seed if seed is None else seed,
            seeds,
        )
    except ValueError as err:
        _fail(str(err))
        return
    low = limits[0]
    hs, landings = low.limit_m, low.landings
    if plot is not None:
        seaway.tension_figure(landings[-1], plot)
    verdict = seaway.hs_verdict(scenario.significant_height_m, hs, landings)
    if json_out:
        out = {
            "mission": spec.name,
            "installation": scenario.words(seed),
            "peak_period_s": scenario.peak_period_s,
            "heave_compensation": scenario.heave_compensation,
            "hover_m": scenario.hover_m,
            "lower_rate_mps": scenario.lower_rate_mps,
            "seed": scenario.seed if seed is None else seed,
            "seeds": seeds,
            "mission_hs_m": scenario.significant_height_m,
            "mission_hs_within_limit": scenario.significant_height_m <= hs,
            "verdict": verdict,
        }
        out.update(_landing_limit_json(hs, landings, limits if seeds > 1 else None))
        typer.echo(json.dumps(out, indent=2))
        return
    typer.echo(scenario.words(seed))
    for x in landings:
        typer.echo(x.words())
    if seeds > 1:
        typer.echo(seaway.seeds_words(limits))
    typer.echo(
        f"last Hs within the limits: {hs:g} m"
        + (f" (the largest tried, {hs_max:g} m)" if landings[-1].within_limits else "")
        + _lowest_of(limits)
    )
    typer.echo(verdict)


@app.command()
def serve(
    host: Annotated[str, typer.Option(help="address the API and 3D view bind to")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="HTTP port (API, /docs, telemetry)")] = 8000,
    viser_port: Annotated[int, typer.Option("--viser-port", help="port of the 3D view")] = 8080,
    token: Annotated[
        str | None,
        typer.Option(
            help="token for actions that change the run: at least 16 printable characters, "
            "no spaces (generated and printed if not given)"
        ),
    ] = None,
    instructor_token: Annotated[
        str | None,
        typer.Option(
            "--instructor-token",
            envvar="ROV_CONSOLE_INSTRUCTOR_TOKEN",
            help="the instructor's token (faults): at least 8 printable characters, no "
            "spaces, not the console token; without it the instructor's features are off",
        ),
    ] = None,
    winch_token: Annotated[
        str | None,
        typer.Option(
            "--winch-token",
            envvar="ROV_CONSOLE_WINCH_TOKEN",
            help="the winch station's token (GET /winch: pay out, haul in, stop, heave "
            "compensation): at least 8 printable characters, no spaces, unlike the others",
        ),
    ] = None,
    supervisor_token: Annotated[
        str | None,
        typer.Option(
            "--supervisor-token",
            envvar="ROV_CONSOLE_SUPERVISOR_TOKEN",
            help="the supervisor's token (GET /supervisor: watch, pause, resume): at least 8 "
            "printable characters, no spaces, unlike the others",
        ),
    ] = None,
    params: Annotated[
        str, typer.Option(help="parameter set when no mission is given")
    ] = "full-scale",
    mission: Annotated[
        str | None, typer.Option(help="library mission or .toml to load and start")
    ] = None,
    depth: Annotated[float, typer.Option(help="tree depth without a mission [m]")] = 400.0,
    recordings: Annotated[Path, typer.Option(help="directory for session logs (MCAP)")] = Path(
        "recordings"
    ),
    allow_remote: Annotated[
        bool, typer.Option("--allow-remote", help="allow a non-loopback --host")
    ] = False,
    paused: Annotated[bool, typer.Option("--paused", help="start paused")] = False,
    speed: Annotated[float, typer.Option(help="simulated s per wall s, 0.25..50")] = 1.0,
    behind_proxy: Annotated[
        bool,
        typer.Option(
            "--behind-proxy",
            help="a reverse proxy on this machine stands in front: believe its "
            "X-Forwarded-For (off: the header is ignored, whoever sends it)",
        ),
    ] = False,
    foxglove_port: Annotated[
        int | None,
        typer.Option(
            "--foxglove-port",
            help="also serve the session live to Foxglove or Lichtblick on this port "
            "(read-only, the recording's channels)",
        ),
    ] = None,
) -> None:
    """Serve the operator console: 3D view (viser), HTTP API and telemetry WebSocket."""
    from app.console import ConsoleSettings
    from app.server import serve as run_console

    try:
        settings = ConsoleSettings(
            host=host,
            port=port,
            viser_port=viser_port,
            token=token,
            instructor_token=instructor_token,
            winch_token=winch_token,
            supervisor_token=supervisor_token,
            params=params,
            mission=mission,
            depth_m=depth,
            recordings_dir=recordings,
            allow_remote=allow_remote,
            paused=paused,
            speed=speed,
            behind_proxy=behind_proxy,
            foxglove_port=foxglove_port,
        )
    except ValueError as err:
        raise typer.BadParameter(str(err)) from None
    try:
        run_console(settings)
    except ValueError as err:  # unknown parameter set or invalid mission
        _fail(str(err))


def main() -> None:
    """Entry point of the ``rov-console`` script."""
    try:
        app()
    except KeyboardInterrupt:
        sys.exit(130)


if __name__ == "__main__":
    main()
