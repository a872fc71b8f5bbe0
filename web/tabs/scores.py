"""The "Scores" tab, one per browser: the pilot's scores and debriefs.

"Show my scores" reads the scores database (``app.scores``) for the name typed under Access:
the latest runs (who flew them: autopilot, hand or mixed) and the best run of each mission,
each with a link to its debrief when it was recorded. "Debrief" offers the debrief report
(``app.report``, served by the API at ``/api/recordings/<name>/report``) of a finished
recording. "Trend over runs" (``web.tabs.trend``) plots a trainee's totals over their runs,
scored with the assessment's criteria in force, with a run's table and logbook links. Reading
the scores needs no token: nothing here changes the run; a report takes seconds of work, so
its links open it only for a browser unlocked with the console or instructor token (they
carry the console's debrief ticket).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from app.console import SCORES_DB, Console, list_recordings, md_text
from app.console import scores as store
from web.tabs.links import new_tab_link, report_url
from web.tabs.trend import TrendPanel
from web.widgets import Operator

__all__ = ["HISTORY_ROWS", "ScoresTab", "new_tab_link", "report_url", "scores_markdown"]

HISTORY_ROWS = 10


def _cell(v: float | None, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def _verdict(s: store.Score) -> str:
    """The run's verdict as the scores store gives it (pass or FAIL, faulted, the criteria
    it failed with their values and limits) and whether it landed, as page text."""
    head, sep, why = s.verdict.partition(": ")
    text = "pass" if head.startswith("pass") else "FAIL" + head.removeprefix("fail")
    if s.landed is not None:
        text += ", landed" if s.landed else ", not landed"
    return md_text(text + (f": {why}" if sep else ""))


def scores_markdown(
    rows: list[store.Score], api_base: str, name: str, ticket: str | None = None
) -> str:
    """A trainee's latest runs and best run of each mission, as Markdown tables (the debrief
    links carry ``ticket`` when given)."""
    if not rows:
        return f"no scores for **{md_text(name)}** yet (a mission you start is scored when it ends)"

    def table(title: str, scores: list[store.Score]) -> list[str]:
        lines = [
            f"**{title}**",
            "",
            "| when | mission | result | miss m | RMS N/E m | flown by | debrief |",
            "|---|---|---|---|---|---|---|",
        ]
        for s in scores:
            link = (
                new_tab_link(report_url(api_base, s.log_file, ticket), "report")
                if s.log_file
                else "-"
            )
            lines.append(
                f"| {s.utc[5:16].replace('T', ' ')} | {md_text(s.mission)} | {_verdict(s)} | "
                f"{_cell(s.miss_m, '.3f')} | {s.rms_north_m:.3f}/{s.rms_east_m:.3f} | "
                f"{s.flown_by} | {link} |"
            )
        return lines

    lines = table(f"latest runs of {md_text(name)}", rows[:HISTORY_ROWS])
    lines += ["", *table("best run of each mission", store.best(rows))]
    return "\n".join(lines)


class ScoresTab:
    """The scores tab of one browser: the trainee is the name typed under Access."""

    def __init__(self, operator: Operator, console: Console, unlocked: Callable[[], bool]) -> None:
        """``unlocked``: whether this browser is unlocked with the console or the instructor
        token (its debrief links then carry the console's ticket)."""
        self.operator = operator
        self.console = console
        self.unlocked = unlocked
        gui = operator.gui
        settings = self.console.settings
        host = f"[{settings.host}]" if ":" in settings.host else settings.host
        self.api_base = f"http://{host}:{settings.port}"
        self.show_button = gui.add_button("Show my scores")
        self.show_button.on_click(self._on_show)
        self.scores_md = gui.add_markdown("")
        names = self._recording_names()
        self.recording = gui.add_dropdown("Recording", names, initial_value=names[0])
        self.debrief_button = gui.add_button("Debrief")
        self.debrief_button.on_click(self._on_debrief)
        self.debrief_md = gui.add_markdown("")
        self.trend = TrendPanel(
            gui,
            settings.recordings_dir,
            self.api_base,
            self._ticket,
            lambda: str(self.operator.name_text.value),
        )

    def _recording_names(self) -> tuple[str, ...]:
        names = [r["name"] for r in list_recordings(self.console.settings.recordings_dir)]
        return tuple(names) or ("(none)",)

    def show(self) -> str:
        """Fill in the scores of the name typed under Access (and return the text)."""
        name = " ".join(str(self.operator.name_text.value).split())
        if not name:
            text = "enter your name under Access to see your scores"
        else:
            try:
                rows = store.history(self.console.settings.recordings_dir / SCORES_DB, trainee=name)
                text = scores_markdown(
                    rows, self.api_base, store.trainee_name(name), self._ticket()
                )
            except ValueError as err:
                text = f"**cannot read the scores**: {md_text(err)}"
        self.scores_md.content = text
        return text

    def _on_show(self, event: Any) -> None:
        self.show()
        self.trend.refresh_trainees()
        names = self._recording_names()
        self.recording.options = names
        if self.recording.value not in names:
            self.recording.value = names[0]  # type: ignore[misc]

    def _on_debrief(self, event: Any) -> None:
        name = str(self.recording.value)
        names = self._recording_names()
        if name not in names or name == "(none)":
            self.recording.options = names
            self.debrief_md.content = (
                "no finished recording chosen (press Show my scores to refresh)"
            )
            return
        if name == self.console.loop.snapshot.recording:
            self.debrief_md.content = f"**{name}** is being recorded: stop the recording first"
            return
        ticket = self._ticket()
        url = report_url(self.api_base, name, ticket)
        self.debrief_md.content = (
            new_tab_link(url, f"open the debrief of {name}")
            + " "
            + (
                "(opens the report in a new tab; this one stays as it is)"
                if ticket
                else "(the report needs the console token: unlock under Access first)"
            )
        )

    def _ticket(self) -> str | None:
        """The debrief ticket for a browser unlocked with the console or instructor token."""
        return self.console.debrief_ticket() if self.unlocked() else None
