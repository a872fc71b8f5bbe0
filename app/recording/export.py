"""CSV export of a session: ``session_log.csv`` (every column of ``/session/log``, named,
exact), one file per plot channel (``tree_state.csv`` for ``/tree/state`` ...) and
``events.csv``."""

from __future__ import annotations

import csv
import json
from collections.abc import Iterable, Sequence
from pathlib import Path

from app.recording.reader import read_scan


def _csv_name(topic: str) -> str:
    return topic.strip("/").replace("/", "_") + ".csv"


def _write_csv(path: Path, header: Sequence[str], rows: Iterable[Sequence[object]]) -> Path:
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    return path


def _csv_value(v: object) -> object:
    """Floats as repr (exact round trip), missing numbers as 'nan'."""
    if v is None:
        return "nan"
    return repr(v) if isinstance(v, float) else v


def export_csv(path: str | Path, out_dir: str | Path, *, overwrite: bool = False) -> list[Path]:
    """Write ``session_log.csv`` (all columns of ``/session/log``), one CSV per plot channel
    (``tree_state.csv`` ...; columns = the message's fields) and ``events.csv``. Numbers are
    written exactly (shortest round-trip repr). Refuses to replace files unless ``overwrite``.
    Returns the files written."""
    scan, data = read_scan(path)
    out = Path(out_dir)
    topics = [ch.topic for ch in scan.channels_in_order() if ch.metadata.get("kind") == "numeric"]
    names = ["session_log.csv", *(_csv_name(t) for t in topics), "events.csv"]
    if not overwrite:
        existing = [n for n in names if (out / n).exists()]
        if existing:
            raise FileExistsError(
                f"{out}: would replace {', '.join(existing)} "
                "(choose another folder or allow overwriting)"
            )
    out.mkdir(parents=True, exist_ok=True)
    written = [
        _write_csv(
            out / names[0], data.columns, ([_csv_value(float(v)) for v in r] for r in data.rows)
        )
    ]
    for topic, name in zip(topics, names[1:-1], strict=True):
        decoded = [json.loads(m.data) for m in scan.messages.get(topic, [])]
        header = list(decoded[0]) if decoded else []
        written.append(
            _write_csv(
                out / name, header, ([_csv_value(d.get(k)) for k in header] for d in decoded)
            )
        )
    written.append(
        _write_csv(
            out / names[-1],
            ["t_s", "kind", "text", "data"],
            (
                [_csv_value(e["t_s"]), e["kind"], e["text"], json.dumps(e.get("data", {}))]
                for e in data.events
            ),
        )
    )
    return written
