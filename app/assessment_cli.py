"""``rov-console logbook``, ``trend`` and ``criteria``: the assessment on the command line
(issue 46). Registered on the main command line by ``register``; the heavy modules are
imported inside the commands, so ``rov-console --help`` stays quick."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

DEFAULT_SCORES_DB = Path("recordings/scores.sqlite")
CriteriaOption = Annotated[
    Path | None,
    typer.Option(
        "--criteria",
        metavar="FILE",
        help="criteria file (TOML, docs/formats.md); default: the built-in criteria",
    ),
]


def _fail(message: str, code: int = 2) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=code)


def _criteria(path: Path | None):
    from app.assessment import CriteriaError, load_criteria

    if path is not None and not path.is_file():
        _fail(f"--criteria {path}: no such file")
    try:
        return load_criteria(path)
    except CriteriaError as err:
        _fail(str(err))
        raise  # not reached: _fail exits


def logbook(
    recording: Annotated[Path, typer.Argument(help="a session recording (MCAP)")],
    output: Annotated[
        Path | None, typer.Option("-o", "--output", metavar="FILE.pdf", help="the PDF entry")
    ] = None,
    csv_out: Annotated[
        Path | None, typer.Option("--csv", metavar="FILE.csv", help="the entry as CSV")
    ] = None,
    trainee: Annotated[
        str | None,
        typer.Option(help="who flew it (default: the scores database beside the recording)"),
    ] = None,
    criteria: CriteriaOption = None,
) -> None:
    """Write the logbook entry of a recorded session: trainee, date, mission, each criterion
    with its limit, weight, value and score, the total, and the instructor's sign-off fields
    (name, signature, date, remarks)."""
    if output is None and csv_out is None:
        _fail("give -o FILE.pdf, --csv FILE.csv or both")
    if not recording.is_file():
        _fail(f"{recording}: no such file")
    crit = _criteria(criteria)
    from app import logbook as lb

    try:
        source = f"{criteria.name} (file)" if criteria is not None else "the built-in defaults"
        entry = lb.entry_of(recording, crit, trainee, source)
    except ValueError as err:
        _fail(str(err))
        return
    for path, write in ((output, lb.write_pdf), (csv_out, lb.write_csv)):
        if path is None:
            continue
        try:
            write(entry, path)
        except OSError as err:
            _fail(f"{path}: cannot write: {err.strerror or err}")
        typer.echo(f"wrote {path}")
    total = entry.assessment.total
    typer.echo(
        f"{entry.trainee}, {entry.mission}: total "
        + ("n/a" if total is None else f"{total:.0f}")
        + " / 100"
    )


def trend(
    trainee: Annotated[str, typer.Argument(help="the trainee's name, as stored")],
    mission: Annotated[str | None, typer.Option(help="only this mission's runs")] = None,
    db: Annotated[Path, typer.Option(help="the scores database (SQLite)")] = DEFAULT_SCORES_DB,
    criteria: CriteriaOption = None,
    json_out: Annotated[bool, typer.Option("--json", help="JSON instead of a table")] = False,
    plot: Annotated[
        Path | None, typer.Option(metavar="FILE.png", help="draw the totals over the runs")
    ] = None,
) -> None:
    """A trainee's assessment over their runs, oldest first: the total and each criterion's
    score, every run scored with the criteria in force."""
    crit = _criteria(criteria)
    from app import scores as store

    try:
        points = store.trend(db, trainee, crit, mission)
    except ValueError as err:
        _fail(str(err))
        return
    if json_out:
        typer.echo(json.dumps([vars(p) for p in points], indent=2))
        return
    if not points:
        typer.echo(f"no runs of {trainee} in {db}")
        return
    _print_trend(trainee, points, crit)
    if plot is not None:
        draw_trend(trainee, points, plot)
        typer.echo(f"wrote {plot}")


def _print_trend(trainee: str, points, crit) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"assessment trend: {trainee}")
    for col in ("run", "when (UTC)", "mission", "flown by", "total"):
        table.add_column(col, justify="right")
    names = [c.name for c in crit]
    for name in names:
        table.add_column(name.replace("_", " "), justify="right")
    for p in points:
        table.add_row(
            str(p.id),
            p.utc.replace("T", " ").rstrip("Z"),
            p.mission + (" (faulted)" if p.faults else ""),
            p.flown_by,
            "n/a" if p.total is None else f"{p.total:.0f}",
            *("-" if p.scores.get(n) is None else f"{p.scores[n]:.0f}" for n in names),
        )
    Console(width=200).print(table)


def draw_trend(trainee: str, points, path: Path) -> None:
    """The totals over the runs, one marker a run (faulted runs hollow)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    fig, ax = plt.subplots(figsize=(7, 3.2), dpi=110)
    xs = list(range(1, len(points) + 1))
    ys = [float("nan") if p.total is None else p.total for p in points]
    ax.plot(xs, ys, color="tab:blue", lw=1)
    for x, p, y in zip(xs, points, ys, strict=True):
        ax.scatter(
            [x], [y], s=30, facecolors="none" if p.faults else "tab:blue", edgecolors="tab:blue"
        )
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("run (hollow: instructor's faults acted)")
    ax.set_ylabel("total (0-100)")
    ax.set_ylim(-3, 103)
    ax.set_title(f"{trainee}: assessment over {len(points)} runs", fontsize=10)
    ax.grid(alpha=0.4)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)


def criteria_command(
    check: Annotated[
        Path | None, typer.Option("--check", metavar="FILE", help="validate a criteria file")
    ] = None,
) -> None:
    """Print the criteria in force as a criteria file (the defaults, or FILE's after
    ``--check``): each criterion's limit, the value where its score reaches 0, and its
    weight."""
    typer.echo(_criteria(check).to_toml(), nl=False)


def register(app: typer.Typer) -> None:
    """Add the assessment's commands to the main command line."""
    app.command("logbook")(logbook)
    app.command("trend")(trend)
    app.command("criteria")(criteria_command)
