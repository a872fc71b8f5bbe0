"""``rov-console campaign``: run a campaign file, rerun one of its runs, report its results.

    rov-console campaign FILE.toml [--out DIR] [--scheduler ADDRESS] [--resume]
    rov-console campaign rerun RESULTS ROW [--log run.mcap]
    rov-console campaign report RESULTS
    rov-console campaign list

``campaign FILE.toml`` is short for ``campaign run FILE.toml``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Annotated, Any

import typer
from typer.core import TyperGroup

from missions.limits import MAX_RUNS_PER_TASK


class _RunByDefault(TyperGroup):
    """A group whose first argument, when it is not one of its commands, is a campaign file
    for ``run``."""

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h"):
            args = ["run", *args]
        return super().parse_args(ctx, args)


campaign_app = typer.Typer(
    cls=_RunByDefault,
    no_args_is_help=True,
    rich_markup_mode=None,
    help="Planning campaigns: Monte Carlo runs and sweeps of a mission on Dask. "
    "'campaign FILE.toml' runs a campaign file (short for 'campaign run FILE.toml').",
)


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


@campaign_app.command("run")
def run_command(
    file: Annotated[str, typer.Argument(help="campaign file (TOML) or a library name")],
    out: Annotated[
        Path | None,
        typer.Option(help="results folder (default: campaign-results/<campaign name>)"),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option(
            help="address of a running Dask scheduler (tcp://host:port); default: a local "
            "cluster with one worker process per core"
        ),
    ] = None,
    workers: Annotated[
        int | None,
        typer.Option(min=1, max=256, help="local cluster: worker processes (default: cores)"),
    ] = None,
    resume: Annotated[
        bool, typer.Option("--resume", help="continue RESULTS: run only the runs without a row")
    ] = False,
    progress: Annotated[bool, typer.Option(help="show the progress bar")] = True,
    runs_per_task: Annotated[
        int | None,
        typer.Option(
            min=1,
            max=MAX_RUNS_PER_TASK,
            help="runs per task, run one after another (default: tasks shrinking to one run "
            f"towards the end, so that the workers finish together; at most {MAX_RUNS_PER_TASK})",
        ),
    ] = None,
    limit: Annotated[
        int | None,
        typer.Option(
            "--limit",
            "--runs",
            min=1,
            help="run at most N runs for a quick look: the first run of every point, then the "
            "second, ...; --resume later runs the rest",
        ),
    ] = None,
) -> None:
    """Run every run of a campaign (or ``--limit N`` of them) on Dask; rows go to Parquet as
    they finish; then report."""
    from app.campaign import report, runner, store
    from missions import campaign as cm

    try:
        campaign, base, text = cm.load_campaign(file)
    except cm.CampaignError as err:
        _fail(str(err))
        return
    out = out or Path("campaign-results") / campaign.name
    typer.echo(
        f"campaign {campaign.name}: {campaign.runs} runs ({campaign.points} points x "
        f"{campaign.runs_per_point}) of {base.name} -> {out}"
        + ("" if limit is None else f"; this time at most {limit} of them (--limit)")
    )
    try:
        p = runner.run_campaign(
            campaign,
            base,
            text,
            out,
            scheduler=scheduler,
            workers=workers,
            resume=resume,
            show_progress=progress,
            per_task=runs_per_task,
            limit=limit,
        )
    except cm.CampaignError as err:
        _fail(str(err))
        return
    except KeyboardInterrupt:
        typer.echo(
            f"interrupted: {len(store.done_runs(out))} of {campaign.runs} runs have rows in "
            f"{out}; run again with --resume to run the rest",
            err=True,
        )
        raise typer.Exit(code=130) from None
    except OSError as err:
        if scheduler:
            _fail(f"--scheduler {scheduler}: cannot reach the scheduler: {err}")
        _fail(f"{out}: {err}")
        return
    rate = f"{p.simulated_s / p.wall_s:.0f}" if p.wall_s > 0 else "-"
    typer.echo(
        f"{p.done}/{p.total} runs have rows; failed {p.failed}, errors {p.errors}, "
        f"resubmitted after a lost worker {p.resubmitted}; this session simulated "
        f"{p.simulated_s:.0f} s in {p.wall_s:.1f} s wall ({rate} simulated s per wall s)"
    )
    rows = store.read_rows(out)
    _print_report(report.make_report(campaign, rows, out), out)


@campaign_app.command("report")
def report_command(
    results: Annotated[Path, typer.Argument(help="a campaign's results folder")],
) -> None:
    """Tables and the envelope figure of a results folder (written there again)."""
    from app.campaign import report, store
    from missions import campaign as cm

    try:
        campaign, _, _ = store.open_results(results)
    except (cm.CampaignError, ValueError) as err:
        _fail(str(err))
        return
    _print_report(report.make_report(campaign, store.read_rows(results), results), results)


def _print_report(rep, out: Path) -> None:
    from rich.console import Console
    from rich.table import Table

    from app.campaign import report

    console = Console(width=160)
    table = Table(title="runs per point")
    for col in report.POINT_COLUMNS:
        if col == "point":
            table.add_column(col, overflow="fold", min_width=24)
        else:
            table.add_column(col, justify="right")
    for row in rep.points:
        table.add_row(*row)
    console.print(table)
    console.print(
        f"success: {rep.overall.successes}/{rep.overall.runs} = {rep.overall.text()} "
        "(95 % Wilson interval)",
        markup=False,
    )
    causes = Table(title="failed runs by cause (and the runs that succeeded)")
    for col in report.FAILURE_COLUMNS:
        causes.add_column(col)
    for row in report.failure_table(rep.rows):
        causes.add_row(*row)
    console.print(causes)
    env = Table(title="operability envelope: currents with >= 95 % success")
    for col in report.ENVELOPE_COLUMNS:
        env.add_column(col)
    for row in report.envelope_table(rep.envelope):
        env.add_row(*row)
    console.print(env)
    console.print(f"written: {out / 'report.md'}" + (f", {rep.figure}" if rep.figure else ""))


@campaign_app.command("rerun")
def rerun_command(
    results: Annotated[Path, typer.Argument(help="a campaign's results folder")],
    row: Annotated[int, typer.Argument(help="the run's index (column 'run')")],
    log: Annotated[str | None, typer.Option(help="write the run to this MCAP file")] = None,
    json_out: Annotated[bool, typer.Option("--json", help="one JSON object")] = False,
) -> None:
    """Run one run of a campaign again, alone, and check it gives the same figures; exit 1 if
    a figure differs."""
    from app import headless
    from app.campaign import runner
    from missions import campaign as cm
    from missions.driver import MissionDriver

    try:
        stored, inputs, mission, sim = runner.rerun(results, row)
    except (cm.CampaignError, ValueError) as err:
        _fail(str(err))
        return
    driver = MissionDriver(mission, sim)
    recorder = None
    if log:
        try:
            Path(log).parent.mkdir(parents=True, exist_ok=True)
            recorder = headless.open_recorder(log, mission, sim, inputs["sim_seed"])
        except OSError as err:
            _fail(f"--log {log}: cannot write: {err.strerror or err}")
            return
    t0 = time.perf_counter()
    try:
        result = headless.drive(driver, recorder, show=not json_out)
    finally:
        if recorder is not None:
            recorder.close()
    can_slack = sim.wire_model in cm.SLACK_WIRES
    figures = cm.outcome_row(result, sim.t_s, time.perf_counter() - t0, can_slack)
    # a row stored before a column was added has no figure of it to compare
    compare = {
        k: (stored[k], figures[k], cm.same_figure(stored[k], figures[k]))
        for k in cm.FIGURES
        if k in stored
    }
    same = all(ok for _, _, ok in compare.values())
    if json_out:
        typer.echo(
            json.dumps(
                {
                    "run": row,
                    "inputs": inputs,
                    "figures": {k: v[1] for k, v in compare.items()},
                    "stored": {k: v[0] for k, v in compare.items()},
                    "reproduced": same,
                    "log": log,
                },
                indent=2,
                default=lambda v: None if isinstance(v, float) else str(v),
            )
        )
    else:
        typer.echo(
            f"run {row} of {mission.name}: "
            + ", ".join(f"{k}={v}" for k, v in inputs.items() if k in ("point", "sim_seed"))
        )
        for k, (a, b, ok) in compare.items():
            typer.echo(f"  {k:26s} {a!s:>22} {b!s:>22} {'' if ok else '  DIFFERS'}")
        typer.echo("reproduced: every figure the same" if same else "NOT reproduced")
        if log:
            typer.echo(f"log: {log}")
    if not same:
        raise typer.Exit(code=1)


@campaign_app.command("list")
def list_command() -> None:
    """The library's campaign files."""
    from missions import campaign as cm

    for name in cm.library_names():
        c, _, _ = cm.load_campaign(name)
        typer.echo(f"{name:30s} {c.runs:5d} runs  {c.description}")
