"""``rov-console shadow``: the command line of ``app.shadow``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

BAG_SUFFIXES = (".mcap", ".db3")
"""With ``--mapping``, a file of these (or a folder) is a ROS 2 bag, anything else a CSV."""


def _fail(message: str) -> None:
    typer.echo(f"shadow: {message}", err=True)
    raise typer.Exit(code=2)


def _mount(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(abs(v) <= 20.0 for v in values):
        _fail(f"--mount-m {text!r}: three numbers N,E,D within +-20 m (tree axes)")
    return values


def shadow(
    recording: Annotated[
        Path,
        typer.Argument(
            help="a session log (.mcap) of ours; with --mapping a trial's CSV or a ROS 2 bag "
            "(its folder, .mcap or .db3)"
        ),
    ],
    mapping: Annotated[
        Path | None,
        typer.Option(help="the CSV's or bag's mapping file (TOML; docs/formats.md)"),
    ] = None,
    json_out: Annotated[bool, typer.Option("--json", help="one JSON object")] = False,
    out: Annotated[
        Path | None, typer.Option("--out", help="write the shadow as an MCAP the console replays")
    ] = None,
    plot: Annotated[
        Path | None, typer.Option(help="draw estimates and NIS over time to this PNG")
    ] = None,
    mount_m: Annotated[
        str | None,
        typer.Option(
            "--mount-m",
            help="run the observer with this mounting vector, tree axes, N,E,D [m] "
            "(default: the recording's)",
        ),
    ] = None,
) -> None:
    """Run our observer and controller on a recorded trial's measurements (no plant): what
    they estimate and command beside what the recording says, the innovations and the NIS
    against its chi-square band. Exit 0 when the observer was consistent, 1 when its NIS
    left the band, 2 when the file cannot be shadowed."""
    if not recording.exists():
        _fail(f"{recording}: no such file")
    mount = None if mount_m is None else _mount(mount_m)
    from app import shadow as sh

    try:
        if mapping is not None and (recording.is_dir() or recording.suffix in BAG_SUFFIXES):
            source = sh.from_rosbag(recording, mapping)
        elif mapping is not None:
            source = sh.from_csv(recording, mapping)
        elif recording.is_dir():
            _fail(f"{recording}: a folder (a ROS 2 bag needs --mapping)")
        else:
            source = sh.from_recording(recording)
        import numpy as np

        report = sh.shadow(source, None if mount is None else np.array(mount))
    except sh.ShadowError as err:
        _fail(str(err))
        return
    summary = report.summary
    if out is not None:
        try:
            sh.write_recording(report, out)
        except (OSError, ValueError) as err:
            _fail(f"--out {out}: cannot write: {err}")
        summary["out"] = str(out)
    if plot is not None:
        summary["plot"] = str(sh.shadow_figure(report, plot))
    if json_out:
        typer.echo(json.dumps(summary, indent=2))
    else:
        _print(summary)
    if any(s["verdict"] == "above band" for s in summary["nis"].values()):
        raise typer.Exit(code=1)


def _num(v: float | None, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def _print(s: dict) -> None:
    typer.echo(f"{s['source']}: {s['samples']} rows, {s['steps']} control steps of {s['dt_s']} s"
               f"{' (step-exact)' if s['step_exact'] else ''}, mount {s['mount_m']} m")  # fmt: skip
    typer.echo(
        f"  estimate vs recorded: {_num(s['max_estimate_difference_m'], '.3g')} m, "
        f"{_num(s['max_heading_difference_deg'], '.3g')} deg; command vs recorded: "
        f"{_num(s['max_command_difference_newton'], '.3g')} N, "
        f"{_num(s['max_command_difference_newton_m'], '.3g')} N m"
    )
    rms = s["innovation_rms"]
    typer.echo(
        f"  innovations (RMS): north {_num(rms['north_m'], '.3g')} m, east "
        f"{_num(rms['east_m'], '.3g')} m, heading {_num(rms['heading_deg'], '.3g')} deg"
    )
    for name, n in s["nis"].items():
        typer.echo(
            f"  NIS {name} (dim {n['dimension']}, {n['samples']} samples): mean "
            f"{_num(n['mean'], '.3g')}, band {n['band'][0]:.3g}-{n['band'][1]:.3g}: "
            f"{n['verdict']}"
        )
    for note in s["notes"]:
        typer.echo(f"  note: {note}")
