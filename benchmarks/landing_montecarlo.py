"""Monte Carlo of automatic landings (issue 11): random current, frame heading and offset, and
seeds, at full scale (currents up to 0.5 m/s) and model scale (0.014 to 0.1 m/s). Prints each
case as it lands and then the summary (success rate among the landings the feasibility check
accepts, the failures explained) as JSON.

    python benchmarks/landing_montecarlo.py --full 100 --model 100 --seed 1 --out mc.json
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from itertools import zip_longest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from missions import landing_study


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", type=int, default=20, help="full-scale landings")
    ap.add_argument("--model", type=int, default=20, help="model-scale landings")
    ap.add_argument("--seed", type=int, default=1, help="seed of the case draw")
    ap.add_argument("--out", type=Path, default=None, help="write outcomes and summary here")
    args = ap.parse_args()
    if args.full < 0 or args.model < 0:
        ap.error("--full and --model must be >= 0")
    full = landing_study.random_cases(args.full, "full", args.seed)
    model = landing_study.random_cases(args.model, "model", args.seed + 1)
    # interleaved, so that a run cut short still covers both scales
    cases = [c for pair in zip_longest(full, model) for c in pair if c is not None]
    outcomes = []
    lines = args.out.with_suffix(".jsonl").open("w") if args.out else None
    for k, case in enumerate(cases, 1):
        o = landing_study.run_case(case)
        outcomes.append(o)
        if lines:
            lines.write(json.dumps(asdict(o)) + "\n")
            lines.flush()
        print(
            f"{k:4d}/{len(cases)} {case.scale:5s} {case.speed_mps:.3f} m/s -> "
            f"{case.direction_deg:5.1f} deg, frame {case.frame_heading_deg:6.1f} deg "
            f"{case.offset_m:.2f} m @ {case.bearing_deg:5.1f} deg: {o.verdict[:110]} "
            f"({o.wall_s:.1f} s)",
            flush=True,
        )
    summary = landing_study.summary(outcomes)
    print(
        json.dumps(
            {k: {kk: vv for kk, vv in v.items() if kk != "failures"} for k, v in summary.items()},
            indent=1,
        )
    )
    for scale, s in summary.items():
        for f in s["failures"]:
            print(scale, "FAILED", f["case"], f["why"])
    if args.out:
        args.out.write_text(
            json.dumps({"summary": summary, "outcomes": [asdict(o) for o in outcomes]}, indent=1)
        )


if __name__ == "__main__":
    main()
