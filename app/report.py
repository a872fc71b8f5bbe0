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
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from app import plots
from app.recording import load_session, recorded_docking_frame, recorded_mission_name
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
"""Events that start a leg, and where their leg number is: headless runs write ``leg``
events, the console ``mission`` events."""


@dataclass(frozen=True)
class Debrief:
    """What the report shows, before it is laid out (the tests read it)."""

    name: str
    started_utc: str
    duration_s: float
    complete: bool
    result: MissionResult
    thrust_impulse_newton_s: float
    """Sum over thrusters of the time integral of |force| [N s]: the thrust spent."""
    landings: list[str]
    events: list[dict]
    docking: tuple[DockingFrame, DockingLayout] | None


def leg_spans(
    t_s: np.ndarray, events: list[dict], mission: schema.Mission | None = None
) -> list[LegSpan]:
    """Leg spans of the recorded rows from the events that start legs (one span over the
    whole log when there are none); the recorded mission gives the legs' names and which
    legs are scored."""
    starts: list[tuple[int, int, str]] = []
    for e in events:
        key = LEG_EVENT_KINDS.get(str(e.get("kind")))
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
    spans = []
    for k, (row, index, kind) in enumerate(starts):
        stop = starts[k + 1][0] if k + 1 < len(starts) else len(t_s)
        leg = mission.legs[index - 1] if mission and 0 < index <= len(mission.legs) else None
        name, scored = (leg.name, leg.score) if leg is not None else ("", True)
        if stop > row:
            spans.append(
                LegSpan(index, kind, name, scored, row, stop, False, misses.get(index, ""))
            )
    return spans


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
    rows: LogRows = data.log
    if len(rows) < 2:
        raise ValueError(f"{path}: the log holds {len(rows)} rows; a debrief needs two or more")
    t = rows.t_s
    dt_s = float(np.median(np.diff(t)))
    meta = data.metadata or {}
    name = recorded_mission_name(meta, Path(path).stem)
    ps = _params(meta)
    docking = _docking(meta, ps)
    tree_size = float(max(ps.tree.dimensions_m)) if ps is not None else 3.6
    spans = leg_spans(t, data.events, _mission(meta))
    result = score(name, rows, spans, dt_s, tree_size, False, [])
    force = np.abs(rows["thruster_force"])
    impulse = float(np.sum(np.trapezoid(force, t, axis=0))) if len(t) > 1 else 0.0
    landings = [str(e.get("text", "")) for e in data.events if e.get("kind") == "landing"]
    return Debrief(
        name=name,
        started_utc=str(meta.get("started_utc", "")),
        duration_s=float(t[-1] - t[0]),
        complete=bool(data.complete),
        result=result,
        thrust_impulse_newton_s=impulse,
        landings=landings,
        events=list(data.events),
        docking=docking,
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


def _png(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(path.stem)}" src="data:image/png;base64,{data}">'


def _table(header: tuple[str, ...], rows: Sequence[tuple[str, ...]]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def render_html(d: Debrief) -> str:
    """The report as one HTML page (figures inline)."""
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
        images = "".join(f"<figure>{_png(p)}</figure>" for p in figures)
    events = [
        (
            f"{e.get('t_s', math.nan):.2f}",
            str(e.get("kind", "")),
            str((e.get("data") or {}).get("who", "")),
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
<h2>Scores</h2>
{_table(LEG_TABLE_COLUMNS, leg_table_rows(summary))}
{_table(("figure", "value"), figures_rows)}
<h2>Landings</h2><ul>{landings}</ul>
<h2>Figures</h2>
{images}
<h2>Events</h2>
{_table(("t [s]", "kind", "who", "what"), events)}
</body></html>
"""


def write_report(log_path: str | Path, out_path: str | Path) -> Debrief:
    """Debrief ``log_path`` into ``out_path`` (its folder is made when missing)."""
    d = debrief(log_path)
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(render_html(d), encoding="utf-8")
    return d
