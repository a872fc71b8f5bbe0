"""A trainee's trend over runs, in the Scores tab: each run's total score (and, on demand,
each criterion's) over the run number as a small uPlot chart (viser's ``add_uplot``: plotly is
not among the console's packages), the assessment's table of a chosen run, and its logbook
entry's links (PDF and CSV, ``/api/recordings/<name>/logbook``, in a tab of their own).

The runs are scored with the criteria in force (``app.console.criteria``), as
``GET /api/scores/trend`` scores them: a change of the criteria re-scores the whole history.
Reading needs no token; the logbook's links carry the console's debrief ticket for a browser
unlocked with the console or instructor token, as the debrief links do (``web.tabs.scores``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import viser.uplot as uplot

from app.console import criteria as in_force
from app.console import md_text
from web.tabs.links import logbook_url, new_tab_link

NO_TRAINEE = "(none)"
TOTAL_COLOUR = "#1c7ed6"
CRITERION_COLOURS = ("#e8590c", "#2f9e44", "#ae3ec9", "#f08c00", "#0c8599", "#c2255c", "#5c940d")
"""One colour per criterion, in ``app.assessment.DEFINITIONS``' order."""
RUN_STEPS = (1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0)
"""The run axis's tick steps: whole runs."""
NAMES = tuple(c.name for c in in_force.default_criteria())


def series_config(per_criterion: bool) -> tuple[uplot.Series, ...]:
    """The run number, the total, and the criteria (shown when ``per_criterion``)."""
    total: uplot.Series = {
        "label": "total",
        "stroke": TOTAL_COLOUR,
        "width": 2,
        "points": {"show": True, "size": 7},
    }
    criteria: list[uplot.Series] = [
        {"label": name, "stroke": colour, "width": 1, "show": per_criterion}
        for name, colour in zip(NAMES, CRITERION_COLOURS, strict=True)
    ]
    return ({"label": "run"}, total, *criteria)


def trend_data(runs: list[in_force.RunAssessment]) -> tuple[np.ndarray, ...]:
    """Run numbers, totals and each criterion's scores (NaN where not judged)."""

    def column(get: Callable[[in_force.RunAssessment], float | None]) -> np.ndarray:
        return np.array([math.nan if (v := get(r)) is None else v for r in runs], dtype=float)

    def score_of(name: str) -> Callable[[in_force.RunAssessment], float | None]:
        return lambda r: next(c.score for c in r.assessment.criteria if c.name == name)

    return (
        np.array([r.number for r in runs], dtype=float),
        column(lambda r: r.assessment.total),
        *(column(score_of(name)) for name in NAMES),
    )


def _cell(v: float | None, fmt: str = ".0f") -> str:
    return "-" if v is None else format(v, fmt)


def run_label(r: in_force.RunAssessment) -> str:
    return f"{r.number}: {r.run.utc[5:16].replace('T', ' ')} {r.run.mission}"


def run_markdown(r: in_force.RunAssessment, api_base: str, ticket: str | None) -> str:
    """A run's assessment (each criterion's value, limit, zero, weight and score, the total)
    and its logbook's links."""
    s = r.run
    faults = f", faults: {md_text(s.faults)}" if s.faults else ""
    lines = [
        f"**run {r.number} of {md_text(s.trainee)}**: {s.utc[:16].replace('T', ' ')} UTC, "
        f"{md_text(s.mission)}, flown by {s.flown_by}{faults}; "
        f"total **{_cell(r.assessment.total, '.1f')}**",
        "",
        "| criterion | value | limit | 0 at | weight | score |",
        "|---|---|---|---|---|---|",
    ]
    for c in r.assessment.criteria:
        measured = c.value is not None and math.isfinite(c.value) and c.unit != "-"
        value = c.value_text() + (f" {c.unit}" if measured else "")
        lines.append(
            f"| {c.name} | {md_text(value)} | {c.limit_text()} | "
            f"{c.zero_text()} | {c.weight:g} | {_cell(c.score)} |"
        )
    lines.append("")
    if not s.log_file:
        lines.append("not recorded: no logbook entry")
    else:
        links = [
            new_tab_link(logbook_url(api_base, s.log_file, ticket), "Logbook (PDF)"),
            new_tab_link(logbook_url(api_base, s.log_file, ticket, "csv"), "Logbook (CSV)"),
        ]
        note = "" if ticket else " (the logbook needs the console token: unlock under Access)"
        lines.append(" · ".join(links) + note)
    return "\n".join(lines)


class TrendPanel:
    """The trend's part of one browser's Scores tab. ``ticket`` gives the debrief ticket when
    this browser is unlocked (None otherwise); ``typed_name`` the name typed under Access."""

    def __init__(
        self,
        gui: Any,
        recordings_dir: Path,
        api_base: str,
        ticket: Callable[[], str | None],
        typed_name: Callable[[], str],
    ) -> None:
        self.recordings_dir = recordings_dir
        self.api_base = api_base
        self.ticket = ticket
        self.typed_name = typed_name
        self.runs: list[in_force.RunAssessment] = []
        with gui.add_folder("Trend over runs"):
            self.trainee = gui.add_dropdown("Trainee", (NO_TRAINEE,), initial_value=NO_TRAINEE)
            self.trainee.on_update(self._on_trainee)
            self.per_criterion = gui.add_checkbox("Per criterion", False)
            self.per_criterion.on_update(lambda _: self._draw())
            self.show_button = gui.add_button("Show trend")
            self.show_button.on_click(lambda _: self.show())
            self.summary_md = gui.add_markdown("")
            empty = np.zeros(0)
            self.plot = gui.add_uplot(
                (empty,) * (2 + len(NAMES)),
                series_config(False),
                scales={"x": {"time": False}, "y": {"auto": False, "range": (0.0, 105.0)}},
                axes=({"label": "run", "incrs": RUN_STEPS}, {"label": "score", "size": 44}),
                height=220,
                visible=False,
            )
            self.run = gui.add_dropdown("Assessed run", (NO_TRAINEE,), initial_value=NO_TRAINEE)
            self.run.on_update(lambda _: self.show_run())
            self.run_md = gui.add_markdown("")
        self.refresh_trainees()

    def refresh_trainees(self) -> list[str]:
        """The trainees of the scores database as the dropdown's options; the one typed under
        Access chosen when it has runs."""
        try:
            names = in_force.trainees(self.recordings_dir)
        except ValueError as err:
            self.summary_md.content = f"**cannot read the scores**: {md_text(err)}"
            names = []
        options = tuple(names) or (NO_TRAINEE,)
        self.trainee.options = options
        typed = " ".join(self.typed_name().split())
        if typed in options:
            self.trainee.value = typed
        elif self.trainee.value not in options:
            self.trainee.value = options[0]
        return names

    def _on_trainee(self, event: Any) -> None:
        if event.client is not None:  # picked in the page, not set by refresh_trainees
            self.show(refresh=False)

    def show(self, refresh: bool = True) -> str:
        """The chosen trainee's trend (the options read again first when ``refresh``);
        returns the summary line."""
        if refresh:
            self.refresh_trainees()
        name = str(self.trainee.value)
        self.runs = []
        if name != NO_TRAINEE:
            try:
                self.runs = in_force.assessed_runs(self.recordings_dir, name)
            except (ValueError, in_force.CriteriaError) as err:
                self.summary_md.content = f"**cannot score the runs**: {md_text(err)}"
                return self.summary_md.content
        if not self.runs:
            text = "no runs stored yet (a mission is scored when it ends)"
        else:
            totals = [r.assessment.total for r in self.runs if r.assessment.total is not None]
            last = _cell(totals[-1], ".1f") if totals else "-"
            best = _cell(max(totals), ".1f") if totals else "-"
            text = (
                f"**{md_text(name)}**: {len(self.runs)} run(s), latest total {last}, "
                f"best {best} (scored with the criteria in force)"
            )
        self.summary_md.content = text
        self._draw()
        labels = tuple(run_label(r) for r in reversed(self.runs)) or (NO_TRAINEE,)
        self.run.options = labels
        self.run.value = labels[0]
        self.show_run()
        return text

    def _draw(self) -> None:
        if not self.runs:
            self.plot.visible = False
            return
        self.plot.series = series_config(bool(self.per_criterion.value))
        self.plot.data = trend_data(self.runs)
        self.plot.visible = True

    def show_run(self) -> None:
        """The chosen run's assessment and logbook links."""
        chosen = [r for r in self.runs if run_label(r) == self.run.value]
        self.run_md.content = (
            run_markdown(chosen[0], self.api_base, self.ticket()) if chosen else ""
        )
