"""A campaign's results folder: the campaign as run, its base mission, and the rows.

    RESULTS/campaign.toml      the campaign file's text, as run
    RESULTS/mission.toml       the base mission it was run on
    RESULTS/runs/part-*.parquet  rows, one per run, written in batches as runs finish

Each part is written to a temporary name and renamed, so an interrupted campaign leaves only
whole parts; the rows of a results folder are all parts together (a run that appears twice
counts once: the first row read).
"""

from __future__ import annotations

import math
import os
import time
import uuid
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from missions import campaign as cm
from missions import schema

CAMPAIGN_FILE = "campaign.toml"
MISSION_FILE = "mission.toml"
RUNS_DIR = "runs"

_TYPES = {"bool": pa.bool_(), "int": pa.int64(), "float": pa.float64(), "str": pa.string()}


def arrow_schema() -> pa.Schema:
    """Columns of a result row: run, point, repetition, sim_seed, every parameter, every
    outcome."""
    fields = [pa.field(k, pa.int64()) for k in ("run", "point", "repetition", "sim_seed")]
    fields += [
        pa.field(name, pa.string() if p.text else pa.float64()) for name, p in cm.PARAMETERS.items()
    ]
    fields += [pa.field(name, _TYPES[kind]) for name, kind in cm.OUTCOMES.items()]
    return pa.schema(fields)


def create(out: Path, text: str, base: schema.Mission, resume: bool) -> None:
    """Make (or, with ``resume``, reopen) a results folder for a campaign's text."""
    stored = out / CAMPAIGN_FILE
    if stored.is_file():
        if not resume:
            raise cm.CampaignError(
                f"{out} already holds campaign results: add --resume to run what is missing, "
                "or choose another --out"
            )
        if stored.read_text() != text:
            raise cm.CampaignError(
                f"{out} holds the results of a different campaign file; --resume needs the "
                "same file (or choose another --out)"
            )
        return
    if out.exists() and any(out.iterdir()):
        raise cm.CampaignError(f"{out} is not empty and holds no campaign; choose another --out")
    (out / RUNS_DIR).mkdir(parents=True, exist_ok=True)
    (out / MISSION_FILE).write_text(schema.dump_mission(base))
    stored.write_text(text)


def open_results(out: Path) -> tuple[cm.Campaign, schema.Mission, str]:
    """The campaign, base mission and campaign text a results folder was made with."""
    if not (out / CAMPAIGN_FILE).is_file():
        raise cm.CampaignError(f"{out} is not a campaign results folder (no {CAMPAIGN_FILE})")
    text = (out / CAMPAIGN_FILE).read_text()
    base = schema.load_mission(out / MISSION_FILE)
    campaign = cm.parse_stored(text, str(out / CAMPAIGN_FILE), base)
    return campaign, base, text


def read_rows(out: Path) -> list[dict]:
    """Every run's row, each run once, in run order."""
    parts = sorted((out / RUNS_DIR).glob("part-*.parquet")) if (out / RUNS_DIR).is_dir() else []
    seen: dict[int, dict] = {}
    for part in parts:
        for row in pq.read_table(part).to_pylist():
            seen.setdefault(int(row["run"]), row)
    return [seen[k] for k in sorted(seen)]


def done_runs(out: Path) -> set[int]:
    parts = sorted((out / RUNS_DIR).glob("part-*.parquet")) if (out / RUNS_DIR).is_dir() else []
    done: set[int] = set()
    for part in parts:
        done.update(int(v) for v in pq.read_table(part, columns=["run"])["run"].to_pylist())
    return done


class PartWriter:
    """Collects rows and writes them as Parquet parts: every ``batch`` rows or every
    ``flush_s`` seconds, whichever comes first, and on ``close``."""

    def __init__(self, out: Path, batch: int = 50, flush_s: float = 5.0) -> None:
        self.dir = out / RUNS_DIR
        self.dir.mkdir(parents=True, exist_ok=True)
        self.batch = batch
        self.flush_s = flush_s
        self.rows: list[dict] = []
        self.schema = arrow_schema()
        self.session = f"{time.strftime('%Y%m%dT%H%M%S')}-{uuid.uuid4().hex[:6]}"
        self.parts = 0
        self.written = 0
        self._last = time.monotonic()

    def add(self, row: dict) -> None:
        self.rows.append(row)
        if len(self.rows) >= self.batch or time.monotonic() - self._last >= self.flush_s:
            self.flush()

    def flush(self) -> None:
        self._last = time.monotonic()
        if not self.rows:
            return
        table = pa.Table.from_pylist([_clean(r) for r in self.rows], schema=self.schema)
        name = self.dir / f"part-{self.session}-{self.parts:05d}.parquet"
        tmp = name.with_suffix(".tmp")
        pq.write_table(table, tmp)
        os.replace(tmp, name)
        self.parts += 1
        self.written += len(self.rows)
        self.rows = []

    def close(self) -> None:
        self.flush()


def _clean(row: dict) -> dict:
    """NaN text parameters (none given) become missing; numbers stay as they are."""
    out = dict(row)
    for name in cm.TEXT:
        v = out.get(name)
        if isinstance(v, float) and math.isnan(v):
            out[name] = None
    return out
