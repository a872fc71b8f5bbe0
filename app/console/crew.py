"""The crew's stations beside the pilot: what the winch station and the supervisor's station
show, built from a ``Snapshot`` (read by the API's sockets, never the loop itself).

- The winch operator (``GET /winch``) pays out, hauls in, stops and switches the heave
  compensation, reading the wire tension, the tree's height over the post tops and its
  vertical speed, the slack-wire and snap-load alarms, and a winch slip when the payout
  jumps without a command (``SlipWatch``: an instructor's ``winch_slip`` seen as the
  operator sees it, on the payout counter; the control system is not told).
- The supervisor (``GET /supervisor``) watches the state, every alarm, the crew on station
  and the operations log, and may pause and resume the run, nothing else.

Each station signs in with a name; the operations log names it "winch (Name)" or
"supervisor (Name)" (``station_actor``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from app.console.operations import trainee_view
from app.console.pilot import pilot_name
from app.console.snapshot import Snapshot, advice_line
from app.console.texts import alarm_title

WINCH_ALARMS = ("wire_slack", "wire_snap")
"""The alarms the winch operator answers (DNV-RP-H103's slack and snap criteria)."""
SLIP_SHOW_S = 30.0
"""How long the winch station shows a slip after it [s of simulation]."""
SLIP_MARGIN_M = 0.02
"""Payout change beyond the winch's own travel that counts as a slip [m] (the smallest
injected slip is 0.05 m)."""
OPERATIONS_SHOWN = 15
"""Operations-log entries the supervisor's station shows (the newest)."""


def station_name(name: object, role: str) -> str:
    """A crew member's name as the operations log shows it, or ValueError naming the field."""
    try:
        return pilot_name(name)
    except ValueError as err:
        raise ValueError(str(err).replace("pilot name", f"{role} name")) from None


def station_actor(role: str, name: str) -> str:
    """Who the operations log names: 'winch (Anna)', 'supervisor (Ola)'."""
    return f"{role} ({name})"


@dataclass
class SlipWatch:
    """Finds payout jumps the winch's own motion cannot explain (one per station socket)."""

    _last: tuple[float, float] | None = None
    """(time [s], payout [m]) of the last status."""
    _text: str | None = None
    _until_s: float = -math.inf
    _run: int = -1
    """The run (``SceneInfo.version``) the last status came from."""

    def update(self, t_s: float, payout_m: float, rate_mps: float, run: int = 0) -> str | None:
        """The slip to show now (None: none): a payout change larger than the winch can
        travel since the last call plus ``SLIP_MARGIN_M``, within one ``run`` (a new run,
        a mission started or the run reset, hangs the tree anew: no slip)."""
        if run != self._run:
            self._run, self._last, self._text = run, None, None
        if self._last is not None and t_s >= self._last[0]:
            t0, p0 = self._last
            jump = payout_m - p0
            if abs(jump) > rate_mps * (t_s - t0) + SLIP_MARGIN_M:
                self._text = (
                    f"winch slip: the payout jumped {jump:+.2f} m at {t_s:.1f} s with no "
                    "command; stop the winch and watch the tension"
                )
                self._until_s = t_s + SLIP_SHOW_S
        self._last = (t_s, payout_m)
        if self._text is not None and t_s > self._until_s:
            self._text = None
        return self._text


def height_above_posts_m(snap: Snapshot) -> float:
    """The tree's bottom over the docking frame's post tops [m] (negative: below them)."""
    scene = snap.scene
    bottom = snap.tree_eta_n[2] + 0.5 * scene.tree_dimensions_m[2]
    return float(scene.frame.post_top_depth_m(scene.layout) - bottom)


def _alarm_dicts(snap: Snapshot, names: tuple[str, ...] | None) -> list[dict[str, object]]:
    return [
        {"name": a.name, "title": alarm_title(a.name), "active": a.active, "message": a.message}
        for a in snap.alarms
        if names is None or a.name in names
    ]


def _tension(snap: Snapshot) -> dict[str, float | None]:
    tension = snap.wire_tension_newton
    weight = snap.scene.tree_weight_newton
    return {
        "tension_kn": None if tension is None else tension / 1e3,
        "tension_share": None if tension is None or weight <= 0.0 else tension / weight,
    }


def winch_status(snap: Snapshot, slips: SlipWatch) -> dict[str, object]:
    """What the winch station shows (sent twice or more a second)."""
    w = snap.winch
    running = snap.mission.state == "running"
    out: dict[str, object] = {
        "t_s": snap.t_s,
        "paused": snap.paused,
        **_tension(snap),
        "height_above_posts_m": height_above_posts_m(snap),
        "frame_in_mission": snap.scene.frame_in_mission,
        "alarms": _alarm_dicts(snap, WINCH_ALARMS),
        "mission": snap.mission.name if running else None,
        "slip": None,
    }
    if w is not None:
        out |= {
            "payout_m": w.payout_m,
            "target_m": w.target_m,
            "rate_mps": w.rate_mps,
            "moving": w.moving,
            "heave_compensation": w.heave_compensation,
            "down_speed_mps": w.tree_down_speed_mps,
            "slip": slips.update(snap.t_s, w.payout_m, w.rate_mps, snap.scene.version),
        }
    return out


def supervisor_status(snap: Snapshot, crew: dict[str, str | None]) -> dict[str, object]:
    """What the supervisor's station shows: the state, every alarm, who is on which station,
    the vessel advice of a dock leg, and the operations log as the trainees see it (the
    instructor's faults left out)."""
    m = snap.mission
    w = snap.winch
    return {
        "t_s": snap.t_s,
        "paused": snap.paused,
        "speed": snap.speed,
        "mode": snap.mode,
        "mission": {
            "name": m.name,
            "state": m.state,
            "leg": None if m.leg_index is None else f"{m.leg_index}/{m.legs_total} {m.leg_type}",
        },
        "tree_depth_m": snap.tree_eta_n[2],
        "height_above_posts_m": height_above_posts_m(snap),
        **_tension(snap),
        "payout_m": None if w is None else w.payout_m,
        "alarms": _alarm_dicts(snap, None),
        "crew": crew,
        "operations": [
            {"t_s": op.t_s, "who": op.who, "action": op.action, "outcome": op.outcome}
            for op in trainee_view(snap.operations)[-OPERATIONS_SHOWN:]
        ],
        "error": snap.error,
        "vessel_advice": advice_line(snap),
    }
