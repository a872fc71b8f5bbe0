"""What the page writes about a run, as Markdown: the mission's result (the per-leg table that
``rov-console run`` prints, the landings) and the signal-check counters. Pure functions of the
snapshot's parts, so the 3D view only places them and the tests read them without a browser."""

from __future__ import annotations

from missions.scoring import LEG_TABLE_COLUMNS, QUALITY_CHECKS, landing_lines, leg_table_rows
from sim.sensors import SENSOR_NAMES


def _table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell.replace("|", "/") for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def result_markdown(name: str | None, state: str, result: dict) -> str:
    """The finished mission: verdict, landings, per-leg table, warnings and the error."""
    if "legs" not in result:  # the run itself failed before scoring
        return f"**{name}** {state}: {result.get('error', 'no result')}"
    verdict = "FAILED" if result.get("failed") else "completed"
    parts = [f"**{name}** {state}: {verdict}"]
    parts += [f"- {line}" for line in landing_lines(result)]
    parts.append(_table(LEG_TABLE_COLUMNS, leg_table_rows(result)))
    parts += [f"- warning: {w}" for w in result.get("warnings", [])]
    for leg in result["legs"]:
        if leg.get("error"):
            parts.append(f"- leg {leg['index']} ({leg['type']}) failed: {leg['error']}")
    if result.get("error"):
        parts.append(f"**error**: {result['error']}")
    return "\n\n".join(parts)


def counters_markdown(counters: tuple[tuple[int, ...], ...] | None) -> str:
    """Signal-check counters: samples each check refused, a sensor a row."""
    if counters is None:
        return "*signal checks: not recorded*"
    rows = [
        (sensor, *(str(c) for c in row)) for sensor, row in zip(SENSOR_NAMES, counters, strict=True)
    ]
    return "**Signal checks** (samples refused)\n\n" + _table(("sensor", *QUALITY_CHECKS), rows)
