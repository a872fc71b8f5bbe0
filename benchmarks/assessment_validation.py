"""Does the assessment rank clean landings above faulted ones? (issue 46)

A small campaign of automatic landings (the library's full-docking-current-0.3, each case
with its own simulation seed and a current drawn from 0.2-0.35 m/s towards 200-250 deg): each
case flown clean and with instructor faults of several kinds (``control.faults``), each fault
starting during the dock leg. Every run is assessed with the default criteria
(``app.assessment``). Reported: the AUC (the chance that a clean run drawn at random scores
above a faulted one, ties counted half), the share of cases whose clean run scores above each
of its faulted runs, and the totals by fault kind. The figure goes into docs/instructor.md.

    .venv/bin/python benchmarks/assessment_validation.py --cases 20 \
        --plot docs/figures/assessment-validation.png --json

``--json`` prints the summary as one JSON object (``scripts/readme_figures.py``'s
``assessment`` block runs it so). 20 cases are 60 runs of 300-700 simulated seconds each.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

MISSION = "full-docking-current-0.3"
FAULTS: tuple[dict, ...] = (
    {"kind": "thruster_lost", "thruster": 3},
    {"kind": "thruster_weakened", "value": 0.3, "thruster": 4},
    {"kind": "winch_slip", "value": 1.0},
    {"kind": "current_surge", "value": 0.4},
    {"kind": "current_turn", "value": 90.0},
    {"kind": "vessel_drift", "value": 0.3, "direction_deg": 90.0},
    {"kind": "position_wild_points", "value": 5.0},
    {"kind": "compass_bias", "value": 15.0},
    {"kind": "dvl_lost"},
    {"kind": "compass_freeze"},
)
"""The faults drawn from, one kind after another over the cases."""
FAULT_START_S = (150.0, 420.0)
"""A fault starts at a time drawn in this range: from early in the dock leg (which starts at
120 s) to the last metres of the lowering (contact near 410 s clean)."""
FAULT_DURATION_S = 200.0


def _case_mission(case: int, fault: dict | None, rng_seed: int):
    from missions import schema
    from missions.campaign import resolve_mission

    base = resolve_mission(MISSION)
    rng = np.random.default_rng([rng_seed, case])
    speed, direction = rng.uniform(0.2, 0.35), rng.uniform(200.0, 250.0)
    start = rng.uniform(*FAULT_START_S)
    data = base.model_dump()
    data["setup"]["seed"] = case
    data["setup"]["current"]["speed_mps"] = float(speed)
    data["setup"]["current"]["direction_deg"] = float(direction)
    if fault is not None:
        data["faults"] = [{"start_s": float(start), "duration_s": FAULT_DURATION_S, **fault}]
    return schema.Mission.model_validate(data)


def run_case(args: tuple[int, dict | None, int]) -> dict:
    """One run: its assessment's total and criteria values."""
    from app.assessment import assess, default_criteria, facts_of_run, measure
    from missions.driver import MissionDriver
    from missions.setup import build_simulation

    case, fault, rng_seed = args
    mission = _case_mission(case, fault, rng_seed)
    sim = build_simulation(mission)
    result = MissionDriver(mission, sim).run_to_end()
    facts = facts_of_run(result, sim)
    a = assess(measure(facts), default_criteria(), facts.layout)
    return {
        "case": case,
        "fault": (fault or {}).get("kind", ""),
        "fault_start_s": mission.faults[0].start_s if mission.faults else None,
        "total": a.total,
        "landed": not result.failed,
        "scores": {c.name: c.score for c in a.criteria},
        "values": {
            c.name: (None if c.value is None else (c.value if math.isfinite(c.value) else "inf"))
            for c in a.criteria
        },
    }


def auc(clean: list[float], faulted: list[float]) -> float:
    """P(clean > faulted) + P(tie) / 2 over all pairs (the Mann-Whitney U over the product)."""
    c, f = np.asarray(clean)[:, None], np.asarray(faulted)[None, :]
    return float(np.mean((c > f) + 0.5 * (c == f)))


def total_without(scores: dict[str, float | None], left_out: str | None) -> float | None:
    """The weighted total of a run's criterion scores with one criterion left out (None:
    none), with the default weights."""
    from app.assessment import default_criteria

    judged = [
        (c.weight, scores[c.name])
        for c in default_criteria()
        if c.name != left_out and scores.get(c.name) is not None and c.weight > 0
    ]
    weight = sum(w for w, _ in judged)
    return sum(w * (s or 0.0) for w, s in judged) / weight if weight > 0 else None


def auc_without(rows: list[dict], left_out: str) -> float:
    """The AUC with one criterion left out of the totals."""
    clean = [total_without(r["scores"], left_out) or 0.0 for r in rows if not r["fault"]]
    faulted = [total_without(r["scores"], left_out) or 0.0 for r in rows if r["fault"]]
    return auc(clean, faulted)


def auc_alone(rows: list[dict], name: str) -> float:
    """The AUC of one criterion's score alone (a run not judged on it counts 100)."""

    def score(r: dict) -> float:
        value = r["scores"].get(name)
        return 100.0 if value is None else float(value)

    return auc([score(r) for r in rows if not r["fault"]], [score(r) for r in rows if r["fault"]])


def summarise(rows: list[dict]) -> dict:
    clean = {r["case"]: r["total"] for r in rows if not r["fault"]}
    faulted = [r for r in rows if r["fault"]]
    pairs = [(clean[r["case"]], r["total"]) for r in faulted]
    by_kind: dict[str, list[float]] = {}
    fell: dict[str, dict[str, list[float]]] = {}
    for r in faulted:
        by_kind.setdefault(r["fault"], []).append(r["total"])
        for name, score in r["scores"].items():
            if score is not None:
                fell.setdefault(r["fault"], {}).setdefault(name, []).append(score)
    return {
        "mission": MISSION,
        "runs": len(rows),
        "clean": len(clean),
        "faulted": len(faulted),
        "auc": auc(list(clean.values()), [r["total"] for r in faulted]),
        "pairs_ordered": float(np.mean([c > f for c, f in pairs])),
        "pairs_tied": float(np.mean([c == f for c, f in pairs])),
        "clean_total_mean": float(np.mean(list(clean.values()))),
        "clean_total_min": float(np.min(list(clean.values()))),
        "faulted_total_mean": float(np.mean([r["total"] for r in faulted])),
        "by_kind": {k: float(np.mean(v)) for k, v in sorted(by_kind.items())},
        "runs_by_kind": {k: len(v) for k, v in sorted(by_kind.items())},
        "lost_by_kind": {
            kind: {n: float(100.0 - np.mean(v)) for n, v in per.items() if np.mean(v) < 100.0}
            for kind, per in sorted(fell.items())
        },
        "auc_without": {name: auc_without(rows, name) for name in rows[0]["scores"]},
        "auc_alone": {name: auc_alone(rows, name) for name in rows[0]["scores"]},
        "rows": [
            {"case": r["case"], "fault": r["fault"], "total": r["total"], "landed": r["landed"]}
            for r in rows
        ],
    }


def plot(summary: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = summary["rows"]
    kinds = ["clean", *sorted({r["fault"] for r in rows if r["fault"]})]
    fig, ax = plt.subplots(figsize=(8, 4.2), dpi=110)
    for k, kind in enumerate(kinds):
        ys = [r["total"] for r in rows if (r["fault"] or "clean") == kind]
        xs = k + np.linspace(-0.15, 0.15, len(ys)) if len(ys) > 1 else [k]
        ax.scatter(xs, ys, s=28, color="tab:green" if kind == "clean" else "tab:red", zorder=3)
    ax.set_xticks(range(len(kinds)), kinds, rotation=35, ha="right")
    ax.set_ylabel("assessment total (0-100)")
    ax.set_ylim(-3, 103)
    ax.grid(axis="y", alpha=0.4)
    ax.set_title(
        f"{summary['mission']}: {summary['clean']} clean, {summary['faulted']} faulted landings; "
        f"AUC {summary['auc']:.2f}, pairs ordered {summary['pairs_ordered']:.0%}",
        fontsize=9,
    )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=10, help="cases (each clean + 2 faulted)")
    ap.add_argument("--seed", type=int, default=46, help="seed of the currents and fault times")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--json", action="store_true", help="print the summary as JSON")
    ap.add_argument("--plot", type=Path, default=None)
    args = ap.parse_args()
    jobs: list[tuple[int, dict | None, int]] = []
    for case in range(args.cases):
        jobs.append((case, None, args.seed))
        for j in range(2):
            jobs.append((case, FAULTS[(2 * case + j) % len(FAULTS)], args.seed))
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(run_case, jobs))
    summary = summarise(rows)
    summary["wall_s"] = time.perf_counter() - t0
    summary["seed"] = args.seed
    if args.plot:
        plot(summary, args.plot)
    if args.json:
        print(json.dumps(summary, indent=1))
        return
    print(
        f"{summary['runs']} runs in {summary['wall_s']:.0f} s: AUC {summary['auc']:.3f}, "
        f"pairs ordered {summary['pairs_ordered']:.2f} (tied {summary['pairs_tied']:.2f}), "
        f"clean mean {summary['clean_total_mean']:.1f} (min {summary['clean_total_min']:.1f}), "
        f"faulted mean {summary['faulted_total_mean']:.1f}"
    )
    for what in ("without", "alone"):
        print(
            f"  AUC, each criterion {'left out' if what == 'without' else 'alone'}: "
            + ", ".join(f"{n} {v:.3f}" for n, v in summary[f"auc_{what}"].items())
        )
    for kind, mean in summary["by_kind"].items():
        lost = ", ".join(f"{n} -{v:.0f}" for n, v in summary["lost_by_kind"][kind].items())
        print(f"  {kind:22s} mean total {mean:5.1f}  ({lost})")


if __name__ == "__main__":
    main()
