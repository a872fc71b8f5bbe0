"""The top of one browser's panel: the status line, the pilot's readout, the alarms, the
message line (what the last action did), the operations log and the thrusters' bars."""

from __future__ import annotations

import html
import time
from typing import Any, Literal

import numpy as np
import viser

from app.console import (
    SATURATED,
    Snapshot,
    alarm_meaning,
    alarm_title,
    heading_text,
    md_code,
    md_text,
    trainee_view,
)
from web import geometry as geo

BarColor = Literal["red", "orange", "blue"]


def bar_color(utilisation: float) -> BarColor:
    if utilisation >= SATURATED:
        return "red"
    return "orange" if utilisation >= 0.8 else "blue"


KILLED_KIND = "thruster_lost"
WEAKENED_KIND = "thruster_weakened"


def thruster_states(snap: Snapshot) -> dict[int, str]:
    """What the instructor did to each thruster now (1-based number -> 'killed' or
    'weakened to 40 %'), from the active faults (in a replay, those the recording's events
    say were active then: ``app.console.replay.recorded_faults``)."""
    states: dict[int, str] = {}
    for f in snap.faults:
        if f.state != "active":
            continue
        if f.kind == KILLED_KIND:
            states[f.thruster] = "killed"
        elif f.kind == WEAKENED_KIND and states.get(f.thruster) != "killed":
            states[f.thruster] = f"weakened to {100 * f.value:.0f} %"
    return states


def thruster_row_html(number: int, utilisation: float, force_newton: float, state: str) -> str:
    """One thruster: its name, a bar from the middle (right: forward thrust, left: reverse)
    and the signed share of its limit; a killed thruster shows 'killed' and no bar (the
    control system may still ask it for full thrust, which it cannot give)."""
    share = min(max(utilisation, 0.0), 1.0)
    sign = -1.0 if force_newton < 0.0 else 1.0
    killed = state == "killed"
    color = "#888" if killed else bar_color(utilisation)
    width = 0.0 if killed else 50.0 * share
    left = 50.0 if sign > 0 else 50.0 - width
    percent = round(100 * share)
    text = "killed" if killed else f"{sign * percent:+.0f} %" if percent else "0 %"
    note = f" ({html.escape(state)})" if state and not killed else ""
    track = "#eee" if not killed else "repeating-linear-gradient(45deg,#ddd 0 4px,#bbb 4px 8px)"
    return (
        f"<div data-thruster='{number}' data-state='{'killed' if killed else 'on'}' "
        "style='display:flex;align-items:center;gap:6px;font-size:12px;line-height:18px'>"
        f"<span style='width:2em;font-weight:600'>T{number}</span>"
        f"<span style='position:relative;flex:1;height:10px;background:{track};"
        "border-radius:3px'>"
        "<span style='position:absolute;left:50%;top:-2px;bottom:-2px;width:1px;"
        "background:#666'></span>"
        f"<span style='position:absolute;top:0;bottom:0;left:{left:.1f}%;width:{width:.1f}%;"
        f"background:{color};border-radius:2px'></span></span>"
        f"<span style='min-width:4.2em;text-align:right;"
        f"color:{'#c0392b' if killed else 'inherit'}'>{text}</span>"
        + (f"<span style='font-size:11px;color:#b9770e'>{note}</span>" if note else "")
        + "</div>"
    )


def thrusters_html(snap: Snapshot) -> str:
    """The thrusters' bars, signed and named, with the instructor's kills and weakenings."""
    states = thruster_states(snap)
    rows = "".join(
        thruster_row_html(i + 1, u, f, states.get(i + 1, ""))
        for i, (u, f) in enumerate(
            zip(snap.thruster_utilisation, snap.thruster_force_newton, strict=False)
        )
    )
    legend = (
        "<div style='display:flex;font-size:11px;color:#777;padding-left:2.6em;"
        "padding-right:4.6em'><span style='flex:1'>&larr; reverse</span>"
        "<span>forward &rarr;</span></div>"
    )
    return f"<div>{legend}{rows}</div>"


def next_due(due: float, period: float, now: float) -> float:
    """The next time an every-``period`` update is due: one period after the last due time
    (not after now: frames come every 50 ms, and counting from the frame that did the update
    rounded each period up to the next frame, 0.2 s to 0.25 s), or one period from now when
    more than a period behind (no burst of catch-up updates)."""
    due += period
    return due if due > now - period else now + period


def status_markdown(snap: Snapshot, live: Snapshot) -> str:
    """The status line: live or replay, time, run state, the tree's pose, the mission."""
    tree = snap.tree_eta_n
    m = snap.mission
    leg = f"leg {m.leg_index}/{m.legs_total} {m.leg_type}" if m.leg_index else ""
    state = "paused" if snap.paused else f"running x{snap.speed:g}"
    replaying = snap.source == "replay" and snap.replay is not None
    source = f"REPLAY {md_code(snap.replay.name)}" if replaying and snap.replay else "live"
    # one clock: the run's own time everywhere (a replay's too), the wall clock beside it live
    where = (
        f" ({snap.replay.t_s:.1f} s into the recording)"
        if replaying and snap.replay and abs(snap.replay.t_s - snap.t_s) > 0.05
        else ""
    )
    wall = "" if replaying else time.strftime(", %H:%M:%S UTC", time.gmtime())
    return (
        f"**{source}** t = {snap.t_s:8.1f} s{where}{wall}, {state}  \n"
        + (f"live run goes on: t = {live.t_s:.1f} s  \n" if replaying else "")
        + f"tree N {tree[0]:.2f} m, E {tree[1]:.2f} m, heading "
        f"{heading_text(tree[5])}, mode {snap.mode}  \n"
        f"mission: {md_text(m.name or '-')} ({m.state}) {md_text(leg)}"
        + (f"  \n**{md_text(snap.error)}**" if snap.error else "")
        + (f"  \nrecording {md_code(snap.recording)}" if snap.recording else "")
    )


def alarms_html(snap: Snapshot) -> str:
    """A badge per alarm (red when active), named in words with its meaning as the tooltip,
    and the active alarms' messages."""
    badges = "".join(
        f"<span style='display:inline-block;margin:1px;padding:1px 5px;border-radius:4px;"
        f"color:white;background:{'#c0392b' if a.active else '#27ae60'}' "
        f"title='{html.escape(alarm_meaning(a.name) + (': ' + a.message if a.message else ''))}'>"
        f"{html.escape(alarm_title(a.name))}</span>"
        for a in snap.alarms
    )
    active = html.escape(
        "; ".join(f"{alarm_title(a.name)}: {a.message}" for a in snap.active_alarms)
    )
    return f"<div>{badges}</div>" + (f"<div style='color:#c0392b'>{active}</div>" if active else "")


def operations_markdown(snap: Snapshot) -> str:
    """The latest operations, newest first: time, who, what, outcome (a trainee's view: the
    instructor's commands are left out, ``trainee_view``)."""
    operations = trainee_view(snap.operations)
    if not operations:
        return "*nothing done yet*"
    lines = [
        f"- {op.utc[11:19]} (t {op.t_s:.1f} s) **{md_text(op.who)}**: {md_text(op.action)} "
        f"- {md_text(op.outcome)}"
        for op in reversed(operations[-10:])
    ]
    return "\n".join(lines)


def readout_markdown(snap: Snapshot) -> str:
    """Height over the post tops, distance and heading error to the frame, wire tension."""
    info = snap.scene
    readout = geo.pilot_readout(
        np.array(snap.tree_eta_n),
        info.tree_dimensions_m[2],
        info.frame.center_n,
        info.frame.heading_rad,
        info.frame.post_top_depth_m(info.layout),
        snap.wire_tension_newton,
    )
    return geo.readout_markdown(readout)


def _set(handle: Any, content: str) -> None:
    """Send a text only when it changed."""
    if handle.content != content:
        handle.content = content


class StatusHeader:
    """The status line, readout, alarms and message line of one browser (at the top of its
    panel); ``add_folders`` adds the operations log and the thrusters below the folders that
    come between."""

    def __init__(self, gui: viser.GuiApi) -> None:
        self.gui = gui
        self.status_md = gui.add_markdown("starting...")
        self.readout_md = gui.add_markdown("")
        self.alarms_html = gui.add_html("")
        self.message_md = gui.add_markdown("")

    def say(self, text: str) -> None:
        """Show what the last action did."""
        self.message_md.content = text

    def add_folders(self) -> None:
        gui = self.gui
        with gui.add_folder("Operations log", expand_by_default=False):
            self.operations_md = gui.add_markdown("*nothing done yet*")
        with gui.add_folder("Thrusters (share of each one's limit)"):
            self.thrusters = gui.add_html("")

    def update(self, snap: Snapshot, live: Snapshot) -> None:
        """From what this browser shows (``snap``: the live run or its replay) and the live
        run."""
        _set(self.status_md, status_markdown(snap, live))
        _set(self.readout_md, readout_markdown(snap))
        _set(self.alarms_html, alarms_html(snap))
        self._update_thrusters(snap)
        _set(self.operations_md, operations_markdown(snap))

    def _update_thrusters(self, snap: Snapshot) -> None:
        _set(self.thrusters, thrusters_html(snap))
