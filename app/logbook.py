"""A logbook entry for one recorded session: the trainee, the date, the mission, each
criterion of the assessment with its limit, weight, value and score, the total, and the
instructor's sign-off (name, signature, date, remarks), as PDF and CSV (issue 46). It is laid
out as a page of an ROV pilot's logbook (IMCA's competence scheme keeps such logbooks, signed
by the supervisor who saw the work).

``rov-console logbook RECORDING -o entry.pdf --csv entry.csv`` writes it.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from app.assessment import Assessment, Criteria, RunFacts, assess, measure
from app.report import Debrief, debrief
from sim import params as params_mod

NOT_RECORDED = "(not recorded)"
CSV_COLUMNS = (
    "trainee",
    "date_utc",
    "mission",
    "recording",
    "criterion",
    "title",
    "unit",
    "limit",
    "zero_at",
    "weight",
    "value",
    "score",
    "total",
    "instructor",
    "signature",
    "signed_date",
    "remarks",
)
"""One row per criterion, then a row ``criterion = total``; the sign-off columns are left
empty for the instructor to fill in."""


@dataclass(frozen=True)
class Entry:
    """What a logbook entry says."""

    trainee: str
    date_utc: str
    mission: str
    recording: str
    params_name: str
    verdict: str
    """The mission's own verdict in words (landed, failed: why)."""
    faults: str
    """The instructor's faults that acted, in words ('' none)."""
    assessment: Assessment
    criteria_source: str = "the built-in defaults"
    """Where the criteria came from (a file's name, or the defaults)."""


def facts_of(d: Debrief) -> RunFacts:
    """What the assessment needs, from a recording's debrief: its docking frame, and the tree
    of the recorded parameter set."""
    frame, layout = d.docking if d.docking is not None else (None, None)
    half_h = weight = ps = None
    spec = d.setup.get("params")
    if isinstance(spec, dict):
        try:
            ps = params_mod.build(params_mod.ParameterSetSpec.model_validate(spec))
        except ValueError:
            ps = None
        if ps is not None:
            half_h = float(ps.tree.dimensions_m[2]) / 2.0
            weight = float(ps.tree.submerged_weight_newton)
            layout = layout or ps.spec.docking.to_numeric()
    feedback = (d.setup.get("settings") or {}).get("feedback", "ekf")
    dt_s = float(d.setup.get("dt_s") or 0.0)
    t = d.t_s
    every_step = len(t) > 1 and float(np.median(np.diff(t))) <= 1.5 * dt_s
    return RunFacts(
        d.result, d.events, frame, layout, half_h, weight, ps, feedback == "ekf", every_step
    )


def _faults(events: list[dict]) -> str:
    return "; ".join(
        str(e.get("text", "")).removeprefix("fault: ")
        for e in events
        if e.get("kind") == "fault" and str(e.get("text", "")).startswith("fault: ")
    )


def entry_of(
    path: Path,
    criteria: Criteria,
    trainee: str | None = None,
    criteria_source: str = "the built-in defaults",
) -> Entry:
    """The logbook entry of a recording (its last run that flew a mission's legs)."""
    d = debrief(path)
    facts = facts_of(d)
    values = measure(facts)
    result = d.result
    if result.failed:
        verdict = "failed" + (f": {result.error}" if result.error else "")
    else:
        verdict = "completed"
    if d.landings:
        verdict += "; " + "; ".join(d.landings)
    return Entry(
        trainee=trainee or _trainee_of(path) or NOT_RECORDED,
        date_utc=(d.started_utc or "")[:19].replace("T", " "),
        mission=d.setup.get("mission_name") or d.name or NOT_RECORDED,
        recording=path.name,
        params_name=str(d.setup.get("params_name") or ""),
        verdict=verdict,
        faults=_faults(d.events),
        assessment=assess(values, criteria, facts.layout),
        criteria_source=criteria_source,
    )


def _trainee_of(path: Path) -> str | None:
    """Who flew the recording, from the scores database beside it (the console stores each
    mission it ran with its recording's file name, ``run --trainee`` with its path)."""
    from app import scores as store

    db = path.parent / "scores.sqlite"
    try:
        rows = store.history(db)
    except ValueError:
        return None
    for r in rows:
        if r.log_file and Path(r.log_file).name == path.name:
            return r.trainee
    return None


def _num(v: float | None, fmt: str = "g") -> str:
    if v is None:
        return ""
    if math.isinf(v):
        return "inf"
    return f"{v:{fmt}}"


def csv_text(entry: Entry) -> str:
    """The entry as CSV (``CSV_COLUMNS``)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    head = [entry.trainee, entry.date_utc, entry.mission, entry.recording]
    sign = ["", "", "", ""]
    total = _num(entry.assessment.total, ".1f")
    for c in entry.assessment.criteria:
        w.writerow(
            [
                *head,
                c.name,
                c.title,
                c.unit,
                _num(c.limit),
                _num(c.zero_at),
                _num(c.weight),
                _num(c.value, ".6g"),
                _num(c.score, ".1f"),
                total,
                *sign,
            ]
        )
    w.writerow([*head, "total", "weighted total", "0-100", "", "", "", "", total, total, *sign])
    return out.getvalue()


def write_csv(entry: Entry, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(csv_text(entry), encoding="utf-8")


def _latin1(text: str) -> str:
    """The PDF's core fonts hold Latin-1 only: anything else becomes '?'."""
    return (
        text.replace("\u2013", "-")
        .replace("\u2014", "-")
        .encode("latin-1", "replace")
        .decode("latin-1")
    )


def pdf_bytes(entry: Entry) -> bytes:
    """The entry as a one-page A4 PDF (fpdf2, core fonts)."""
    from fpdf import FPDF

    pdf = FPDF(orientation="P", unit="mm", format="A4")
    pdf.set_title(_latin1(f"ROV pilot logbook: {entry.trainee}, {entry.mission}"))
    pdf.set_creator("rov-console logbook")
    pdf.set_auto_page_break(auto=True, margin=15)
    pdf.add_page()
    pdf.set_font("Helvetica", "B", 16)
    pdf.cell(0, 9, "ROV pilot logbook: assessed simulator exercise", new_x="LMARGIN", new_y="NEXT")
    pdf.set_font("Helvetica", "", 9)
    pdf.cell(
        0,
        5,
        "Tree-on-wire installation trainer (rov-console). Entry for the pilot's logbook.",
        new_x="LMARGIN",
        new_y="NEXT",
    )
    pdf.ln(3)
    _details(pdf, entry)
    pdf.ln(4)
    _criteria_table(pdf, entry)
    pdf.ln(3)
    pdf.set_font("Helvetica", "", 8)
    pdf.multi_cell(
        0,
        4,
        _latin1(
            "Each criterion scores 100 at or within its limit, falling linearly to 0 at "
            "'score 0 at'; the total is the weighted mean of the criteria the run could be "
            "judged on (n/a: not judged). Limits, sources and weights: docs/instructor.md."
        ),
        new_x="LMARGIN",
        new_y="NEXT",
    )
    pdf.ln(5)
    _sign_off(pdf)
    return bytes(pdf.output())


def _details(pdf, entry: Entry) -> None:
    rows = (
        ("Trainee", entry.trainee),
        ("Date (UTC)", entry.date_utc),
        ("Mission", entry.mission),
        ("Parameter set", entry.params_name),
        ("Recording", entry.recording),
        ("Mission verdict", entry.verdict),
        ("Instructor's faults", entry.faults or "none"),
        ("Criteria", entry.criteria_source),
    )
    for label, value in rows:
        pdf.set_font("Helvetica", "B", 10)
        pdf.cell(40, 6, label, border=0)
        pdf.set_font("Helvetica", "", 10)
        pdf.multi_cell(0, 6, _latin1(value), new_x="LMARGIN", new_y="NEXT")


TABLE_WIDTHS = (62, 16, 22, 20, 14, 26, 20)
TABLE_HEAD = ("Criterion", "Unit", "Limit", "Score 0 at", "Weight", "Value", "Score")


def _criteria_table(pdf, entry: Entry) -> None:
    pdf.set_font("Helvetica", "B", 10)
    pdf.set_fill_color(220, 226, 235)
    for w, h in zip(TABLE_WIDTHS, TABLE_HEAD, strict=True):
        pdf.cell(w, 7, h, border=1, fill=True, align="C")
    pdf.ln()
    pdf.set_font("Helvetica", "", 10)
    for c in entry.assessment.criteria:
        cells = (
            c.title,
            c.unit,
            c.limit_text(),
            c.zero_text(),
            f"{c.weight:g}",
            c.value_text(),
            "n/a" if c.score is None else f"{c.score:.0f}",
        )
        for k, (w, text) in enumerate(zip(TABLE_WIDTHS, cells, strict=True)):
            pdf.cell(w, 6.5, _latin1(text), border=1, align="L" if k == 0 else "R")
        pdf.ln()
    pdf.set_font("Helvetica", "B", 11)
    total = entry.assessment.total
    pdf.cell(sum(TABLE_WIDTHS[:-1]), 8, "Weighted total (0-100)", border=1, align="R")
    pdf.cell(TABLE_WIDTHS[-1], 8, "n/a" if total is None else f"{total:.0f}", border=1, align="R")
    pdf.ln()


def _sign_off(pdf) -> None:
    pdf.set_font("Helvetica", "B", 12)
    pdf.cell(0, 8, "Instructor's sign-off", new_x="LMARGIN", new_y="NEXT")
    pdf.set_font("Helvetica", "", 10)
    for label in ("Instructor's name", "Signature", "Date"):
        pdf.cell(40, 10, label)
        y = pdf.get_y() + 8
        pdf.line(pdf.get_x(), y, pdf.get_x() + 120, y)
        pdf.ln(11)
    pdf.cell(40, 7, "Remarks", new_x="LMARGIN", new_y="NEXT")
    pdf.rect(pdf.get_x(), pdf.get_y(), 180, 40)
    pdf.ln(42)
    pdf.set_font("Helvetica", "I", 8)
    pdf.cell(
        0,
        5,
        "Competence shown in a simulator, assessed against the criteria above.",
        new_x="LMARGIN",
        new_y="NEXT",
    )


def write_pdf(entry: Entry, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(pdf_bytes(entry))
