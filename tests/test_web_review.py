"""What the Record tab shows of a review, without a browser (``web/review.py``): a replay's
notes among its marks and jumps, the notes' list, and a comparison in Markdown saying what
differs when the set-ups differ (the browser test, ``test_review_browser.py``, compares two
runs of one set-up)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

from app.compare import Aligned, Difference
from app.recording.notes import Note
from web.review import comparison_markdown, notes_markdown, with_notes


def test_notes_join_the_marks_and_jumps_in_time_order() -> None:
    notes = [
        Note(12.0, "viewer 3 (Anna)", "silt cloud, lost the view", "live"),
        Note(99.0, "viewer 4", "after the end", "review"),
        Note(5.0, "viewer 4", "x" * 80, "review"),
    ]
    marks, jumps = with_notes(((10.0, "L1"),), ((10.0, "leg 1 (move) started"),), notes, 0, 50)
    assert marks == ((5.0, "note"), (10.0, "L1"), (12.0, "note"))
    assert jumps[0] == (5.0, "note: " + "x" * 57 + "... (viewer 4)")
    assert jumps[2] == (12.0, "note: silt cloud, lost the view (viewer 3 (Anna))")
    listed = notes_markdown(sorted(notes, key=lambda n: n.t_s), lambda t: t - 2.0)
    assert "10.0 s, viewer 3 \\(Anna\\): silt cloud, lost the view *(recording)*" in listed
    assert "*(side file)*" in listed
    assert notes_markdown([]) == "*No notes in this recording yet.*"


def _comparison(differs: list[str]) -> Any:
    run = SimpleNamespace
    return SimpleNamespace(
        a_path=Path("a.mcap"),
        b_path=Path("b.mcap"),
        a=run(name="dock"),
        b=run(name="dock-current"),
        aligned=Aligned("mission", 12.0, 30.5),
        differs=differs,
        differences=[
            Difference("RMS north error", "m", 0.1, 0.3, "a"),
            Difference("landing", "", "landed", "failed", "a"),
        ],
    )


def test_a_comparison_says_what_differs_and_which_run_did_better() -> None:
    text = comparison_markdown(_comparison(["mission: dock against dock-current"]))
    assert "aligned at the mission's start: A's 12.0 s with B's 30.5 s" in text
    assert "**Not a like-for-like comparison: the set-ups differ.**" in text
    assert "- mission: dock against dock\\-current" in text
    assert "| RMS north error \\[m\\] | 0\\.1 | 0\\.3 | A |" in text
    assert "| landing | landed | failed | A |" in text
    same = comparison_markdown(_comparison([]))
    assert "The same set-up" in same and "like-for-like" not in same
