"""Run an operability table on the campaign machinery and write it out.

Two passes over one results folder (``app.campaign.store``'s, so ``campaign rerun`` and
``campaign report`` read it too): the first seed of every cell, then the other seeds of the
cells near a limit (``missions.operability.boundary_points``). Runs go to Dask (a local
cluster kept up for both passes, or ``--scheduler``), or, in process, one after another
(tests, a single cell). A folder made with the same table is reused: runs it holds are not
run again.
"""

from __future__ import annotations

import contextlib
import csv
import json
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from app.campaign import runner, store
from missions import campaign as cm
from missions import operability as op

TABLE_JSON = "operability.json"
CELLS_CSV = "operability.csv"
ALLOWABLE_CSV = "allowable.csv"
FIGURE = "operability.png"


@dataclass(frozen=True)
class Table:
    """A finished table: the plan, the limits, the cells and the allowable Hs."""

    plan: op.Plan
    limits: tuple[op.Limit, ...]
    cells: list[op.Cell]
    allowable: list[op.Allowable]
    out: Path
    mission_hours: float
    """The longest run's simulated time [h]: the landing as simulated."""

    def as_dict(self) -> dict:
        m = self.plan.mission
        c = m.setup.current
        vessel = m.setup.vessel
        return {
            "mission": m.name,
            "results": str(self.out),
            "vessel_heading_deg": self.plan.vessel_heading_deg,
            "vessel_into_waves": self.plan.into_waves,
            "mission_hours": self.mission_hours,
            "heave_compensation": bool(vessel and vessel.heave_compensation),
            "current": {"speed_mps": c.speed_mps, "direction_deg": c.direction_deg},
            "wave_heading_convention": "from the bow to where the waves travel towards, "
            "clockwise: 180 head sea, 90 towards starboard, 0 following",
            "seeds": self.plan.seeds,
            "seed": self.plan.campaign.seed,
            "seed_dependence": op.seed_words(self.cells, self.allowable, self.plan.seeds),
            "limits": [lim.as_dict() for lim in self.limits],
            "grid": {
                "hs_m": list(self.plan.grid.hs_m),
                "tp_s": list(self.plan.grid.tp_s),
                "wave_heading_deg": list(self.plan.grid.heading_deg),
            },
            "cells": [cell.as_dict() for cell in self.cells],
            "allowable": [a.as_dict() for a in self.allowable],
        }


def _run_in_process(p: op.Plan, out: Path, runs: Sequence[int]) -> None:
    done = store.done_runs(out)
    writer = store.PartWriter(out)
    try:
        for index in runs:
            if index not in done:
                writer.add(cm.run_one(p.campaign, p.mission, index))
    finally:
        writer.close()


@contextlib.contextmanager
def _address(scheduler: str | None, workers: int | None) -> Iterator[str]:
    if scheduler:
        yield scheduler
        return
    with runner.local_cluster(workers) as address:
        yield address


def run_table(
    p: op.Plan,
    limits: tuple[op.Limit, ...],
    out: Path,
    scheduler: str | None = None,
    workers: int | None = None,
    in_process: bool = False,
    show_progress: bool = True,
) -> Table:
    """Both passes of the table into ``out`` (reused when it holds the same table)."""
    store.create(out, p.text, p.mission, resume=True)
    first = op.first_pass_runs(p)
    if in_process:
        _run_in_process(p, out, first)
        cells = op.cells_of(p, store.read_rows(out), limits)
        more = _second_pass(p, cells)
        _run_in_process(p, out, more)
    else:
        with _address(scheduler, workers) as address:
            _dask_pass(p, out, first, address, show_progress)
            cells = op.cells_of(p, store.read_rows(out), limits)
            more = _second_pass(p, cells)
            if more:
                _dask_pass(p, out, more, address, show_progress)
    rows = [r for r in store.read_rows(out) if int(r["run"]) in set(first) | set(more)]
    cells = op.cells_of(p, rows, limits)
    hours = max((r["simulated_s"] or 0.0 for r in rows), default=0.0) / 3600.0
    return Table(p, limits, cells, op.allowable(cells), out, round(hours, 4))


def _second_pass(p: op.Plan, cells: list[op.Cell]) -> list[int]:
    near = op.boundary_points(cells)
    return [i for point in sorted(near) for i in p.runs_of(point, 1, p.seeds)]


def _dask_pass(p: op.Plan, out: Path, runs: list[int], address: str, show_progress: bool) -> None:
    runner.run_campaign(
        p.campaign,
        p.mission,
        p.text,
        out,
        scheduler=address,
        resume=True,
        show_progress=show_progress,
        only=runs,
    )


def write_table(table: Table) -> dict[str, Path]:
    """The JSON, the two CSVs and the figure beside the runs; their paths by kind."""
    from app.planning import figures

    out = table.out
    data = table.as_dict()
    (out / TABLE_JSON).write_text(json.dumps(data, indent=1, allow_nan=False) + "\n")
    cells = data["cells"]
    keys = [k for k in cells[0] if k not in ("runs", "exceeded")] + ["exceeded", "runs"]
    with (out / CELLS_CSV).open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for cell in cells:
            row = dict(cell)
            row["exceeded"] = " ".join(cell["exceeded"])
            row["runs"] = " ".join(str(i) for i in cell["runs"])
            w.writerow({k: "" if row[k] is None else row[k] for k in keys})
    with (out / ALLOWABLE_CSV).open("w", newline="") as f:
        allow = data["allowable"]
        w = csv.DictWriter(f, fieldnames=list(allow[0]))
        w.writeheader()
        for a in allow:
            w.writerow({k: "" if v is None else v for k, v in a.items()})
    figures.table_figure(data, out / FIGURE)
    return {
        "json": out / TABLE_JSON,
        "cells": out / CELLS_CSV,
        "allowable": out / ALLOWABLE_CSV,
        "figure": out / FIGURE,
    }


def read_table(path: Path) -> dict:
    """A saved table (``operability.json``, or the folder holding it)."""
    if path.is_dir():
        path = path / TABLE_JSON
    try:
        data = json.loads(path.read_text())
    except OSError as err:
        raise ValueError(f"{path}: cannot read the operability table: {err.strerror}") from None
    except json.JSONDecodeError as err:
        raise ValueError(f"{path}: not an operability table (JSON): {err}") from None
    if not isinstance(data, dict) or not {"mission", "allowable", "current"} <= set(data):
        raise ValueError(f"{path}: not an operability table (no mission, allowable, current)")
    return data
