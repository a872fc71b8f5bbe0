"""The debrief of a recorded session: one self-contained HTML file (figures embedded as PNG),
written by ``rov-console report LOG.mcap -o report.html``.

It holds what a trial team or an instructor goes through after a run: the mission's scores
leg by leg (the same table ``rov-console run`` prints, scored from the recorded rows), the
landings, time in saturation and the thrust spent, the pose against the reference, the
top-down track over the docking frame and its posts, forces and thruster use, and every event
(legs, landings, commands with who sent them, alarms) on the time axis.
"""

from __future__ import annotations

import base64
import html
import math
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from app import plots
from app.recording import (
    SessionData,
    load_session,
    recorded_docking_frame,
    recorded_mission_name,
)
from app.recording.notes import notes_of
from control.columns import LogRows
from missions import schema
from missions.scoring import (
    LEG_TABLE_COLUMNS,
    SATURATED,
    LegSpan,
    MissionResult,
    leg_table_rows,
    score,
)
from sim import params as params_mod
from sim.docking import DockingFrame, DockingLayout

LEG_EVENT_KINDS = {"leg": "index", "mission": "leg"}
"""Events that start a leg, and where their leg number is: the mission's own ``leg`` events
(headless runs, and the console since it records them), else the console's ``mission``
events (its recordings before)."""


@dataclass(frozen=True)
class Debrief:
    """What the report shows, before it is laid out (the tests read it)."""

    name: str
    started_utc: str
    runs: list[str]
    """The runs the recording holds, in words ('' each when it holds one); the debrief is of
    the last one that ran a mission's legs."""
    duration_s: float
    complete: bool
    result: MissionResult
    thrust_impulse_newton_s: float
    """Sum over thrusters of the time integral of |force| [N s]: the thrust spent."""
    landings: list[str]
    events: list[dict]
    docking: tuple[DockingFrame, DockingLayout] | None
    setup: dict = field(default_factory=dict)
    """The debriefed run's set-up record (mission, parameter set, seed, ...)."""
    log: LogRows | None = field(default=None, repr=False)
    """The debriefed run's rows."""

    @property
    def t_s(self) -> np.ndarray:
        """Recording time of the debriefed run's rows [s]."""
        return self.log.t_s if self.log is not None else np.zeros(0)


def leg_spans(
    t_s: np.ndarray, events: list[dict], mission: schema.Mission | None = None
) -> list[LegSpan]:
    """Leg spans of the recorded rows from the events that start legs (one span over the
    whole log when there are none); the recorded mission gives the legs' names and which
    legs are scored."""
    starts: list[tuple[int, int, str]] = []
    kinds = {"leg"} if any(e.get("kind") == "leg" for e in events) else {"mission"}
    for e in events:
        key = LEG_EVENT_KINDS.get(str(e.get("kind"))) if e.get("kind") in kinds else None
        data = e.get("data") or {}
        if key is None or key not in data or not isinstance(e.get("t_s"), int | float):
            continue
        row = int(np.searchsorted(t_s, float(e["t_s"])))
        starts.append((row, int(data[key]), str(data.get("type", "leg"))))
    if not starts:
        return [LegSpan(1, "session", "", True, 0, len(t_s), False)]
    misses = {
        (e.get("data") or {}).get("leg"): str(e.get("text", ""))
        for e in events
        if e.get("kind") == "miss"
    }
    end = _mission_end_row(t_s, events, starts[-1][0])
    spans = []
    for k, (row, index, kind) in enumerate(starts):
        stop = starts[k + 1][0] if k + 1 < len(starts) else end
        leg = mission.legs[index - 1] if mission and 0 < index <= len(mission.legs) else None
        name, scored = (leg.name, leg.score) if leg is not None else ("", True)
        if stop > row:
            spans.append(
                LegSpan(index, kind, name, scored, row, stop, False, misses.get(index, ""))
            )
    return spans


def _mission_end_row(t_s: np.ndarray, events: list[dict], last_start: int) -> int:
    """Where the mission's legs end: at the console's "mission ... completed" (or failed,
    aborted) event after the last leg's start, else at the end of the log (a headless run
    ends with its mission; the console's run holds station after it)."""
    for e in events:
        t = e.get("t_s")
        if e.get("kind") == "mission" and "state" in (e.get("data") or {}):
            if isinstance(t, int | float):
                row = int(np.searchsorted(t_s, float(t), side="right"))
                if row > last_start:
                    return min(row, len(t_s))
    return len(t_s)


@dataclass(frozen=True)
class RunPart:
    """The part of a recording one run covers: its set-up and the recording times
    [start_s, stop_s) of its rows and events."""

    setup: dict
    start_s: float
    stop_s: float
    index: int


def recorded_runs(data: SessionData) -> list[RunPart]:
    """The runs of a recording (one when it holds no ``run.N`` records)."""
    setups = data.runs or [data.metadata or {}]
    parts = []
    for k, setup in enumerate(setups):
        start = setup.get("start_t_s") if k else None
        stop = setups[k + 1].get("start_t_s") if k + 1 < len(setups) else None
        parts.append(
            RunPart(
                setup,
                float(start) if isinstance(start, int | float) else -math.inf,
                float(stop) if isinstance(stop, int | float) else math.inf,
                k + 1,
            )
        )
    return parts


def debriefed_run(parts: list[RunPart]) -> RunPart:
    """The run a debrief is of: the last that ran a mission's legs (the last run when
    none did; files before ``legs_run`` was recorded ran theirs)."""
    with_legs = [p for p in parts if p.setup.get("legs_run", True)]
    return (with_legs or parts)[-1]


def _run_words(part: RunPart, name: str) -> str:
    what = "its legs" if part.setup.get("legs_run", True) else "set-up only, holding station"
    start = "start" if math.isinf(part.start_s) else f"{part.start_s:.1f} s"
    stop = "end" if math.isinf(part.stop_s) else f"{part.stop_s:.1f} s"
    return f"run {part.index}: {name} ({what}), {start} to {stop} of the recording"


def _mission(meta: dict) -> schema.Mission | None:
    """The recorded mission file (None when the recording has none that still parses)."""
    text = meta.get("mission_toml")
    if not isinstance(text, str):
        return None
    try:
        return schema.parse_text(text, "<recording>")
    except ValueError:
        return None


def debrief(path: str | Path) -> Debrief:
    """Read a session log and score it (ValueError naming the file when it cannot be read)."""
    data = load_session(path)
    parts = recorded_runs(data)
    part = debriefed_run(parts)
    t_all = data.log.t_s
    keep = (t_all >= part.start_s - 1e-9) & (t_all < part.stop_s - 1e-9)
    rows = LogRows(data.log.data[keep], data.log.n_thrusters, layout=data.log.layout)
    # on the run's own clock, as the console showed it (a run started while recording is on
    # the recording's axis after the one before: 534.7 s there was the console's 110.6 s)
    offset = data.run_offset_s(part.index - 1)
    rows["t_s"][:] -= offset
    if len(rows) < 2:
        raise ValueError(f"{path}: the log holds {len(rows)} rows; a debrief needs two or more")
    t = rows.t_s
    dt_s = float(np.median(np.diff(t)))
    meta = data.metadata or {}
    run = part.setup
    name = recorded_mission_name(run, Path(path).stem)
    ps = _params(meta)
    docking = _docking(run, ps)
    tree_size = float(max(ps.tree.dimensions_m)) if ps is not None else 3.6
    review_notes = [
        {"t_s": n.t_s, "kind": "note", "text": n.text, "data": {"who": n.author, "in": "review"}}
        for n in notes_of(Path(path), [])
    ]
    events = sorted(
        (
            {**e, "t_s": float(e["t_s"]) - offset}
            for e in [*data.events, *review_notes]
            if isinstance(e.get("t_s"), int | float)
            and part.start_s - 1e-9 <= e["t_s"] < part.stop_s - 1e-9
        ),
        key=lambda e: float(e["t_s"]),
    )
    spans = leg_spans(t, events, _mission(run))
    result = score(name, rows, spans, dt_s, tree_size, False, [])
    force = np.abs(rows["thruster_force"])
    impulse = float(np.sum(np.trapezoid(force, t, axis=0))) if len(t) > 1 else 0.0
    landings = [str(e.get("text", "")) for e in events if e.get("kind") == "landing"]
    runs = [_run_words(p, recorded_mission_name(p.setup, "?")) for p in parts]
    return Debrief(
        name=name,
        started_utc=str(meta.get("started_utc", "")),
        runs=runs if len(runs) > 1 else [],
        duration_s=float(t[-1] - t[0]),
        complete=bool(data.complete),
        result=result,
        thrust_impulse_newton_s=impulse,
        landings=landings,
        events=events,
        docking=docking,
        setup=dict(run),
        log=rows,
    )


def _params(meta: dict) -> params_mod.ParameterSet | None:
    """The recorded parameter set (None when the recording has none it can rebuild)."""
    try:
        return params_mod.build(params_mod.parse_spec(meta["params"], "<recording>"))
    except (KeyError, TypeError, ValueError):
        return None


def _docking(
    meta: dict, ps: params_mod.ParameterSet | None
) -> tuple[DockingFrame, DockingLayout] | None:
    frame = recorded_docking_frame(meta)
    if frame is None or ps is None:
        return None
    return frame, ps.spec.docking.to_numeric()


def png_html(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(path.stem)}" src="data:image/png;base64,{data}">'


def table_html(header: tuple[str, ...], rows: Sequence[tuple[str, ...]]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _runs_html(runs: list[str]) -> str:
    """The runs of a recording that holds several, and which one the debrief is of."""
    if not runs:
        return ""
    items = "".join(f"<li>{html.escape(r)}</li>" for r in runs)
    return (
        "<p>The recording holds several runs; this debrief is of the last that ran a "
        f"mission's legs (its rows and events only):</p><ul>{items}</ul>"
    )


def render_html(d: Debrief, comparison: str = "") -> str:
    """The report as one HTML page (figures inline); ``comparison``, a section of HTML
    comparing the run with another (``app.compare.comparison_html``), after the scores."""
    r = d.result
    summary = r.summary()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        assert r.log is not None
        figures = [
            plots.pose_figure(r.log, r.legs, out / "pose.png", f"{d.name}: pose"),
            plots.track_figure(
                r.log, out / "track.png", f"{d.name}: north-east track", None, d.docking
            ),
            plots.forces_figure(r.log, r.legs, out / "forces.png", f"{d.name}: forces"),
        ]
        images = "".join(f"<figure>{png_html(p)}</figure>" for p in figures)
    events = [
        (
            f"{e.get('t_s', math.nan):.2f}",
            str(e.get("kind", "")),
            str((e.get("data") or {}).get("author") or (e.get("data") or {}).get("who", "")),
            str(e.get("text", "")),
        )
        for e in d.events
    ]
    figures_rows = [
        ("duration", f"{d.duration_s:.1f} s"),
        ("time with a thruster saturated", f"{r.saturated_time_s:.1f} s (>= {SATURATED:.0%})"),
        ("largest thruster utilisation", f"{r.max_thruster_utilisation:.2f}"),
        ("thrust spent (sum of |force| dt)", f"{d.thrust_impulse_newton_s / 1e3:.1f} kN s"),
        ("log", "complete" if d.complete else "cut off: read up to its last intact record"),
    ]
    landings = "".join(f"<li>{html.escape(x)}</li>" for x in d.landings) or "<li>none</li>"
    notes = [
        (
            f"{e['t_s']:.2f}",
            str((e.get("data") or {}).get("author") or (e.get("data") or {}).get("who", "")),
            str(e.get("text", "")),
            "in review" if (e.get("data") or {}).get("in") == "review" else "live",
        )
        for e in d.events
        if e.get("kind") == "note"
    ]
    notes_html = table_html(("t [s]", "by", "note", "made"), notes) if notes else "<p>none</p>"
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<title>Debrief: {html.escape(d.name)}</title>
<style>
body {{ font-family: sans-serif; margin: 2em; max-width: 1100px; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
th, td {{ border: 1px solid #bbb; padding: 2px 8px; text-align: right; }}
td:nth-child(2), td:nth-child(4) {{ text-align: left; }}
img {{ max-width: 100%; }}
</style></head><body>
<h1>Debrief: {html.escape(d.name)}</h1>
<p>Recorded {html.escape(d.started_utc or "(start time not recorded)")}; report written
{datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")}.</p>
{_runs_html(d.runs)}
<h2>Scores</h2>
{table_html(LEG_TABLE_COLUMNS, leg_table_rows(summary))}
{table_html(("figure", "value"), figures_rows)}
<h2>Landings</h2><ul>{landings}</ul>
<h2>Notes</h2>
{notes_html}
{comparison}
<h2>Figures</h2>
{images}
<h2>Events</h2>
{table_html(("t [s]", "kind", "who", "what"), events)}
</body></html>
"""


def write_report(
    log_path: str | Path, out_path: str | Path, d: Debrief | None = None, comparison: str = ""
) -> Debrief:
    """Debrief ``log_path`` (or write ``d``, its debrief already made) into ``out_path`` (its
    folder is made when missing), with a comparison section when given."""
    d = d if d is not None else debrief(log_path)
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(render_html(d, comparison), encoding="utf-8")
    return d
