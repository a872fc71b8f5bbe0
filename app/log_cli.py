"""``rov-console log``: look into session logs (MCAP), export them, recover killed ones.

Exit codes of ``check``: 0 complete, 1 cut off but readable (everything up to the cut is
there), 2 unreadable (not an MCAP file, no header, cannot be opened). ``recover``: 0 written,
2 unreadable or not written.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

EXIT_COMPLETE, EXIT_TRUNCATED, EXIT_UNREADABLE = 0, 1, 2

log_app = typer.Typer(
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,
    help="Session logs (MCAP): check what a file holds, export it as CSV, recover a killed "
    "recording.",
)

FileArg = Annotated[Path, typer.Argument(help="session log (.mcap)", show_default=False)]


def _print_report(report: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console(width=110, highlight=False)
    status = report["status"].upper()
    console.print(
        f"[bold]{report['file']}[/]: {status} "
        f"({report['intact_bytes']} of {report['file_bytes']} bytes readable)"
    )
    if report["problem"]:
        console.print(f"  {report['problem']}")
    span = report["time_range_s"]
    if span:
        console.print(
            f"  simulation time {span[0]:.2f} .. {span[1]:.2f} s, "
            f"{report['rows']} log rows, {report['events']} events"
        )
    console.print(
        f"  written by: {report['writer'] or '?'}; setup keys: "
        f"{', '.join(report['metadata_keys']) or 'none'}"
    )
    table = Table()
    for col, justify in (
        ("topic", "left"),
        ("schema", "left"),
        ("messages", "right"),
        ("first s", "right"),
        ("last s", "right"),
    ):
        table.add_column(col, justify=justify)  # type: ignore[arg-type]
    for ch in report["channels"]:
        first = "" if ch["first_s"] is None else f"{ch['first_s']:.2f}"
        last = "" if ch["last_s"] is None else f"{ch['last_s']:.2f}"
        table.add_row(ch["topic"], ch["schema"], str(ch["messages"]), first, last)
    console.print(table)


@log_app.command()
def check(
    file: FileArg,
    json_out: Annotated[bool, typer.Option("--json", help="one JSON object")] = False,
) -> None:
    """Say what is in a session log and whether it is complete (exit 0), cut off but readable
    (exit 1) or unreadable (exit 2)."""
    from app.recording import check_session

    try:
        report = check_session(file)
    except ValueError as err:
        if json_out:
            typer.echo(json.dumps({"file": str(file), "status": "unreadable", "problem": str(err)}))
        else:
            typer.echo(f"error: {err}", err=True)
        raise typer.Exit(EXIT_UNREADABLE) from None
    if json_out:
        typer.echo(json.dumps(report, indent=2))
    else:
        _print_report(report)
    raise typer.Exit(EXIT_COMPLETE if report["complete"] else EXIT_TRUNCATED)


@log_app.command()
def export(
    file: FileArg,
    csv: Annotated[
        Path, typer.Option("--csv", help="folder for the CSV files", show_default=False)
    ],
    force: Annotated[bool, typer.Option("--force", help="replace existing CSV files")] = False,
) -> None:
    """Write the numeric channels as CSV: session_log.csv (every log column, exact), one file
    per plot channel, events.csv."""
    from app.recording import export_csv

    try:
        written = export_csv(file, csv, overwrite=force)
    except (ValueError, FileExistsError) as err:
        typer.echo(f"error: {err}", err=True)
        raise typer.Exit(EXIT_UNREADABLE) from None
    except OSError as err:
        typer.echo(f"error: {csv}: {err.strerror or err}", err=True)
        raise typer.Exit(EXIT_UNREADABLE) from None
    for path in written:
        typer.echo(str(path))


@log_app.command()
def recover(
    file: FileArg,
    out: Annotated[
        Path | None,
        typer.Argument(help="the complete file to write (default: NAME-recovered.mcap)"),
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="replace an existing OUT")] = False,
) -> None:
    """Rewrite a killed or cut-off recording as a complete MCAP file (summary and footer)
    that every MCAP reader opens: everything up to the last whole record. FILE is not
    changed."""
    from app.recording.recover import recover_session

    try:
        done = recover_session(file, out, overwrite=force)
    except (ValueError, FileExistsError) as err:
        typer.echo(f"error: {err}", err=True)
        raise typer.Exit(EXIT_UNREADABLE) from None
    except OSError as err:
        typer.echo(f"error: {err.filename or out}: {err.strerror or err}", err=True)
        raise typer.Exit(EXIT_UNREADABLE) from None
    if done.source_complete:
        typer.echo(f"{file} was complete already; copied {done.messages} messages")
    else:
        typer.echo(
            f"{file}: {done.problem}; kept {done.messages} messages, "
            f"left out {done.dropped_bytes} bytes after the last whole record"
        )
    typer.echo(str(done.output))


@log_app.command()
def notes(
    file: FileArg,
    json_out: Annotated[bool, typer.Option("--json", help="a JSON list")] = False,
    csv: Annotated[
        Path | None, typer.Option("--csv", help="also write the notes to this CSV file")
    ] = None,
    add: Annotated[
        str | None, typer.Option("--add", help="add a note (with --at and --author)")
    ] = None,
    at: Annotated[float | None, typer.Option("--at", help="the note's time [s]")] = None,
    author: Annotated[str, typer.Option("--author", help="who writes the note")] = "",
) -> None:
    """List a recording's notes (made live, and added in review beside the file), or add one
    in review (it goes into NAME.mcap.notes.jsonl; the recording is not changed)."""
    from app.recording.notes import add_review_note, notes_csv, read_notes

    try:
        if add is not None:
            if at is None:
                raise ValueError("--add needs --at, the note's time in seconds")
            from app.recording import load_session

            t = load_session(file).log.t_s
            add_review_note(file, at, author or "reviewer", add, float(t[-1]) if len(t) else 0.0)
        found = read_notes(file)
    except ValueError as err:
        typer.echo(f"error: {err}", err=True)
        raise typer.Exit(EXIT_UNREADABLE) from None
    if csv is not None:
        try:
            csv.write_text(notes_csv(found), encoding="utf-8")
        except OSError as err:
            typer.echo(f"error: {csv}: {err.strerror or err}", err=True)
            raise typer.Exit(EXIT_UNREADABLE) from None
    if json_out:
        typer.echo(json.dumps([n.as_dict() for n in found]))
        return
    if not found:
        typer.echo(f"{file}: no notes")
    for n in found:
        by = f" ({n.author})" if n.author else ""
        typer.echo(f"{n.t_s:9.2f} s{by}: {n.text}" + ("  [review]" if n.source == "review" else ""))
