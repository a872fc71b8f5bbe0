"""What the Record tab shows of a review: notes on the replay's scrub bar and in its jump list,
and the comparison of the replayed run with a second one, in Markdown. Pure functions of the
notes and the comparison (the tab wires them to its controls)."""

from __future__ import annotations

from collections.abc import Callable

from app.console import Comparison, Note, md_code, md_text, table_rows

NOTE_JUMP_CHARS = 60
"""Characters of a note's text a jump list entry shows at most (the list above it shows all)."""
ALIGNED_AT = {
    "mission": "the mission's start",
    "contact": "the first contact with the frame",
    "start": "the recordings' starts",
}
"""The moments two runs are aligned at, in words (``event:WORDS`` is said as it is)."""
NOTES_LISTED = 30
"""Notes the tab lists at most (the jump list holds them all)."""


def note_jump(note: Note) -> tuple[float, str]:
    """A note as an entry of the jump list: (time, 'note: <text> (<author>)')."""
    text = note.text if len(note.text) <= NOTE_JUMP_CHARS else note.text[:57] + "..."
    return note.t_s, f"note: {text} ({note.author})"


def with_notes(
    marks: tuple[tuple[float, str], ...],
    jumps: tuple[tuple[float, str], ...],
    notes: list[Note],
    start_s: float,
    end_s: float,
) -> tuple[tuple[tuple[float, str], ...], tuple[tuple[float, str], ...]]:
    """The replay's marks and jumps with its notes (those within the recording) added, in
    time order."""
    inside = [n for n in notes if start_s - 1e-9 <= n.t_s <= end_s + 1e-9]
    out_marks = tuple(sorted([*marks, *((n.t_s, "note") for n in inside)], key=lambda m: m[0]))
    out_jumps = tuple(sorted([*jumps, *(note_jump(n) for n in inside)], key=lambda j: j[0]))
    return out_marks, out_jumps


def notes_markdown(notes: list[Note], run_time_s: Callable[[float], float] | None = None) -> str:
    """The notes of the open replay, one a line: time (the run's own clock when
    ``run_time_s`` maps a recording time to it), author, text, and where it is kept."""
    if not notes:
        return "*No notes in this recording yet.*"
    to_run = run_time_s or (lambda t: t)
    lines = [f"**notes** ({len(notes)}; pick one in *Jump to event* to go there)"]
    for n in notes[-NOTES_LISTED:]:
        where = "recording" if n.source == "live" else "side file"
        lines.append(f"- {to_run(n.t_s):.1f} s, {md_text(n.author)}: {md_text(n.text)} *({where})*")
    return "\n".join(lines)


def comparison_markdown(c: Comparison) -> str:
    """A comparison (``app.compare.Comparison``) for the tab: which run is which, where they
    are aligned, what differs in their set-ups, and the table of figures with the better
    run."""
    a, b, al = c.a, c.b, c.aligned
    lines = [
        f"**A** {md_code(c.a_path.name)} ({md_text(a.name)}, this replay) against "
        f"**B** {md_code(c.b_path.name)} ({md_text(b.name)}, the ghost), "
        f"aligned at {md_text(ALIGNED_AT.get(al.at, al.at))}: A's {al.a_s:.1f} s with B's "
        f"{al.b_s:.1f} s "
        "(each run's own clock).",
        "",
    ]
    differs = c.differs
    if differs:
        lines.append("**Not a like-for-like comparison: the set-ups differ.**")
        lines.append("")
        lines += [f"- {md_text(d)}" for d in differs]
    else:
        lines.append("The same set-up (mission, parameter set, seed, gains).")
    lines += ["", "| figure | A | B | better |", "|---|---|---|---|"]
    lines += ["| " + " | ".join(md_text(cell) for cell in row) + " |" for row in table_rows(c)]
    return "\n".join(lines)
