"""Monte Carlo of automatic landings (issues 11 and 44): random current, frame heading and
offset, and seeds, at full scale (currents up to 0.5 m/s; ``--installation``: 0.1 to 0.5 m/s,
issue 44's draw) and model scale (0.014 to 0.1 m/s, the sea trial's). Prints each case as it
lands and then the summary (landed, refused with the reasons, success rate among the landings
the feasibility check accepts, the failures explained) as JSON; ``--vessel auto,fixed`` flies
every case both ways, the dock leg moving the vessel or not.

    python benchmarks/landing_montecarlo.py --full 100 --model 100 --seed 1 --out mc.json
    python benchmarks/landing_montecarlo.py --full 0 --installation 200 --model 200 \
        --vessel auto,fixed --seed 44 --json
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
    ap.add_argument(
        "--installation", type=int, default=0, help="full-scale landings in 0.1-0.5 m/s"
    )
    ap.add_argument("--vessel", default="auto", help="the dock leg's vessel: auto, fixed or both")
    ap.add_argument("--out", type=Path, default=None, help="write outcomes and summary here")
    ap.add_argument("--json", action="store_true", help="end with the summary as one JSON line")
    args = ap.parse_args()
    if min(args.full, args.model, args.installation) < 0:
        ap.error("--full, --installation and --model must be >= 0")
    modes = args.vessel.split(",")
    if not modes or any(m not in ("auto", "fixed") for m in modes):
        ap.error(f"--vessel must be auto, fixed or both, comma-separated, got {args.vessel!r}")
    cases = []
    for mode in modes:
        full = landing_study.random_cases(args.full, "full", args.seed, mode)
        model = landing_study.random_cases(args.model, "model", args.seed + 1, mode)
        inst = landing_study.random_cases(args.installation, "installation", args.seed + 2, mode)
        # interleaved, so that a run cut short still covers every scale
        cases += [c for t in zip_longest(full, inst, model) for c in t if c is not None]
    outcomes = []
    lines = args.out.with_suffix(".jsonl").open("w") if args.out else None
    for k, case in enumerate(cases, 1):
        o = landing_study.run_case(case)
        outcomes.append(o)
        if lines:
            lines.write(json.dumps(asdict(o)) + "\n")
            lines.flush()
        print(
            f"{k:4d}/{len(cases)} {case.scale:5s} {case.vessel:5s} {case.speed_mps:.3f} m/s -> "
            f"{case.direction_deg:5.1f} deg, frame {case.frame_heading_deg:6.1f} deg "
            f"{case.offset_m:.2f} m @ {case.bearing_deg:5.1f} deg: {o.verdict[:110]} "
            f"({o.wall_s:.1f} s)",
            flush=True,
        )
    summary = landing_study.summary(outcomes)
    lists = ("failures", "refusals")
    print(
        json.dumps(
            {k: {kk: vv for kk, vv in v.items() if kk not in lists} for k, v in summary.items()},
            indent=1,
        )
    )
    for scale, s in summary.items():
        for f in s["failures"]:
            print(scale, "FAILED", f["case"], f["why"])
        for f in s["refusals"]:
            print(scale, "REFUSED", f["case"], f["why"])
    if args.out:
        args.out.write_text(
            json.dumps({"summary": summary, "outcomes": [asdict(o) for o in outcomes]}, indent=1)
        )
    if args.json:
        command = " ".join(["benchmarks/landing_montecarlo.py", *sys.argv[1:]])
        print(json.dumps({"command": command, "seed": args.seed, "summary": summary}))


if __name__ == "__main__":
    main()
