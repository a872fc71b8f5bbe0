"""Notes on a session's timeline: what someone saw at a moment ("silt cloud, lost the view").

A note made live (the console's *Add note*, ``POST /api/notes``) is an event of kind
``note`` in the recording, at the present time, with its author. A note made while
reviewing a finished recording goes into a side file beside it, ``NAME.mcap.notes.jsonl``
(one JSON object a line, appended and synced), never into the recording itself: an MCAP
file ends with its summary and footer, so adding a message means writing the file again,
and the recording a team reviews must stay the bytes the session wrote. The side file
travels with the recording; ``read_notes`` returns both kinds, in time order, and the
debrief, the replay and ``rov-console log notes`` read them through it.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import unicodedata
from dataclasses import asdict, dataclass
from pathlib import Path

TEXT_MAX = 500
"""Characters of a note at most (a sentence or two, as a logbook's remarks)."""
AUTHOR_MAX = 60
NOTE_KIND = "note"
"""The kind of a note's event in a recording."""
SIDE_SUFFIX = ".notes.jsonl"


@dataclass(frozen=True)
class Note:
    t_s: float
    """Time on the recording's axis [s]."""
    author: str
    text: str
    source: str
    """"live" (an event of the recording) or "review" (the side file)."""

    def as_dict(self) -> dict:
        return asdict(self)


def _clean(name: str, value: object, most: int) -> str:
    """``value`` as a note's text or author, or ValueError naming the field: text, not empty,
    at most ``most`` characters, no control characters (tab and new line included: a note
    is one line of a table) and no lone surrogates."""
    if not isinstance(value, str):
        raise ValueError(f"{name} must be text, got {type(value).__name__}")
    text = value.strip()
    if not text:
        raise ValueError(f"{name} must not be empty")
    if len(text) > most:
        raise ValueError(f"{name} must be at most {most} characters, got {len(text)}")
    for ch in text:
        if unicodedata.category(ch) in ("Cc", "Cs", "Cf") and ch != "\u200d":
            raise ValueError(
                f"{name} must not hold control characters, got U+{ord(ch):04X} at "
                f"position {text.index(ch) + 1}"
            )
    return text


def note_text(text: object) -> str:
    return _clean("text", text, TEXT_MAX)


def note_author(author: object) -> str:
    return _clean("author", author, AUTHOR_MAX)


def side_file(recording: Path) -> Path:
    """Where the notes added in review of ``recording`` are kept."""
    return recording.with_name(recording.name + SIDE_SUFFIX)


def add_review_note(recording: Path, t_s: float, author: str, text: str, end_s: float) -> Note:
    """Append a note at ``t_s`` of a finished recording (ValueError naming the field: a time
    outside [0, end_s], bad text or author)."""
    if isinstance(t_s, bool) or not isinstance(t_s, int | float) or not math.isfinite(t_s):
        raise ValueError(f"t_s must be a finite number of seconds, got {t_s!r}")
    if not 0.0 <= t_s <= end_s:
        raise ValueError(f"t_s must be in [0, {end_s:.1f}] s (the recording), got {t_s:g}")
    note = Note(float(t_s), note_author(author), note_text(text), "review")
    line = json.dumps({"t_s": note.t_s, "author": note.author, "text": note.text})
    with open(side_file(recording), "a", encoding="utf-8") as f:
        f.write(line + "\n")
        f.flush()
        os.fsync(f.fileno())
    return note


def _side_notes(recording: Path) -> list[Note]:
    """The side file's notes; a line that is not a whole note (a write cut off) is left out."""
    path = side_file(recording)
    if not path.is_file():
        return []
    notes = []
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        try:
            d = json.loads(line)
            notes.append(Note(float(d["t_s"]), str(d["author"]), str(d["text"]), "review"))
        except (ValueError, KeyError, TypeError):
            continue
    return notes


def notes_of(recording: Path, events: list[dict]) -> list[Note]:
    """The notes of a recording: its ``note`` events (``events``, as read) and its side
    file's, in time order."""
    live = [
        Note(
            float(e["t_s"]),
            str((e.get("data") or {}).get("author") or (e.get("data") or {}).get("who") or ""),
            str(e.get("text", "")),
            "live",
        )
        for e in events
        if e.get("kind") == NOTE_KIND and isinstance(e.get("t_s"), int | float)
    ]
    return sorted(live + _side_notes(recording), key=lambda n: n.t_s)


def read_notes(recording: str | Path) -> list[Note]:
    """The notes of a recording file (ValueError naming the file when it cannot be read)."""
    from app.recording.reader import load_session

    path = Path(recording)
    return notes_of(path, load_session(path).events)


def notes_csv(notes: list[Note]) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["t_s", "author", "text", "source"])
    for n in notes:
        writer.writerow([f"{n.t_s:.3f}", n.author, n.text, n.source])
    return out.getvalue()
