"""What the page writes about a run, as Markdown: the mission's result (the per-leg table that
``rov-console run`` prints, the landings) and the signal-check counters. Pure functions of the
snapshot's parts, so the 3D view only places them and the tests read them without a browser."""

from __future__ import annotations

import html
import math
import re
from pathlib import Path

import numpy as np

from missions.scoring import LEG_TABLE_COLUMNS, QUALITY_CHECKS, landing_lines, leg_table_rows
from sim.sensors import SENSOR_NAMES

_MARKDOWN_PUNCTUATION = re.compile(r"([\\`*_{}\[\]()#+\-.!|~])")


ALARM_WORDS: dict[str, tuple[str, str]] = {
    "saturation": ("thrusters saturated", "a thruster held at its limit for over 2 s"),
    "position_error": (
        "position error",
        "the tree (in free mode the ROV) further from its set point than the mission allows",
    ),
    "wire_slack": ("slack wire", "the wire carries less than its share of the tree's weight"),
    "wire_snap": (
        "snap load",
        "the wire went slack under the hanging tree and tightened again with a jerk",
    ),
    "innovation": (
        "sensors disagree",
        "the sensors' fixes lie further from the observer's prediction than their noise "
        "explains (mean normalised innovation; about 1 is expected)",
    ),
    "dropout": ("sensor dropout", "a sensor has given no accepted fix for several periods"),
    "mount_vector": (
        "mount vector check",
        "the observer's bias says the ROV's mounting vector on the tree is wrong "
        "(the sea trial's wrong sign)",
    ),
}
"""Each alarm's name (``app.console.alarms.ALARM_NAMES``, kept in the API and the recording)
as a person reads it on the page: its title and what it means."""


def alarm_title(name: str) -> str:
    """An alarm as the page names it: 'position_error' -> 'position error'."""
    return ALARM_WORDS.get(name, (name.replace("_", " "), ""))[0]


def alarm_meaning(name: str) -> str:
    """What an alarm means, one line ('' for a name without an explanation)."""
    return ALARM_WORDS.get(name, ("", ""))[1]


def compass_heading_deg(psi_rad: float) -> float:
    """A heading as a compass shows it: in [0, 360) deg at the page's 0.1 deg, so a heading a
    hair west of north reads 0.0, not 360.0."""
    return round(math.degrees(psi_rad), 1) % 360.0 + 0.0


def compass_degrees(psi_rad: np.ndarray, ndigits: int) -> np.ndarray:
    """Headings as a compass shows them, for many at once: in [0, 360) deg at ``ndigits``
    decimals (a heading that rounds to 360 reads 0), as ``compass_heading_deg`` does one."""
    deg = np.round(np.degrees(np.asarray(psi_rad, dtype=float)), ndigits) % 360.0
    return np.where(deg >= 360.0, 0.0, deg) + 0.0


def heading_text(psi_rad: float) -> str:
    """A heading as the page prints it, as a compass shows it: 558.1 -> '198.1 deg'."""
    return f"{compass_heading_deg(psi_rad):.1f} deg"


QUOTE_MAX_CHARS = 60
"""Characters of a client's text an error message quotes back at most."""


def quoted(text: str, limit: int = QUOTE_MAX_CHARS) -> str:
    """``text`` quoted (repr: control characters and lone surrogates escaped) for an error
    message, cut at ``limit`` characters with the whole length said: an answer never echoes
    a long input back ('xxxx...' (4000 characters))."""
    if len(text) <= limit:
        return repr(text)
    return f"{text[:limit]!r}... ({len(text)} characters)"


_ABSOLUTE_PATH = re.compile(r"(?<![\w.:/~-])/[^\s'\"(),;:]+")


def without_server_paths(text: str) -> str:
    """``text`` with each absolute path on this server cut to its file's name
    ('/srv/console/recordings/x.mcap' -> 'x.mcap'): an error tells a client which file, not
    where the server keeps it. A path whose folder does not exist here ('/api/faults', a
    route) is left as it is."""

    def name_only(match: re.Match[str]) -> str:
        path = Path(match.group(0))
        parent = path.parent
        return path.name if parent != Path("/") and parent.is_dir() else match.group(0)

    return _ABSOLUTE_PATH.sub(name_only, text)


def md_text(value: object) -> str:
    """``value`` as text that Markdown shows as itself: the 3D view renders the raw HTML in
    its Markdown, so a name like ``<img onerror=...>`` would run in every viewer's browser.
    HTML's ``& < >`` become entities, Markdown's punctuation is backslash-escaped (no links,
    images, emphasis or table cells made by a name)."""
    return _MARKDOWN_PUNCTUATION.sub(r"\\\1", html.escape(str(value), quote=False))


def md_code(value: object) -> str:
    """``value`` as an inline code span (shown verbatim, raw HTML inert): fenced by one more
    backtick than the longest run of them inside, so no value closes its span early."""
    text = str(value).replace("\n", " ")
    runs = re.findall(r"`+", text)
    fence = "`" * (max((len(r) for r in runs), default=0) + 1)
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{fence}{pad}{text}{pad}{fence}"


def _table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(md_text(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def result_markdown(name: str | None, state: str, result: dict) -> str:
    """The finished mission: verdict, landings, per-leg table, warnings and the error (every
    name and message as text: ``md_text``)."""
    title = f"**{md_text(name)}** {md_text(state)}"
    if "legs" not in result:  # the run itself failed before scoring
        return f"{title}: {md_text(result.get('error', 'no result'))}"
    verdict = "FAILED" if result.get("failed") else "completed"
    parts = [f"{title}: {verdict}"]
    parts += [f"- {md_text(line)}" for line in landing_lines(result)]
    parts.append(_table(LEG_TABLE_COLUMNS, leg_table_rows(result)))
    parts += [f"- warning: {md_text(w)}" for w in result.get("warnings", [])]
    for leg in result["legs"]:
        if leg.get("error"):
            parts.append(
                f"- leg {leg['index']} ({md_text(leg['type'])}) failed: {md_text(leg['error'])}"
            )
    if result.get("error"):
        parts.append(f"**error**: {md_text(result['error'])}")
    return "\n\n".join(parts)


def counters_markdown(counters: tuple[tuple[int, ...], ...] | None) -> str:
    """Signal-check counters: samples each check refused, a sensor a row."""
    if counters is None:
        return "*signal checks: not recorded*"
    rows = [
        (sensor, *(str(c) for c in row)) for sensor, row in zip(SENSOR_NAMES, counters, strict=True)
    ]
    return "**Signal checks** (samples refused)\n\n" + _table(("sensor", *QUALITY_CHECKS), rows)
