"""Monte Carlo of automatic landings (issue 11): random current (speed and direction), frame
heading and offset from the crane tip, and seed, at full scale and at model scale; each case is
one mission (hold while the observer converges, then a dock leg) run headless. The summary is
the success rate among the cases the dock leg's feasibility check accepts, with every failure
explained, and how many it refused, each refusal with its reason. A case's dock leg moves the
vessel (``vessel = "auto"``, issue 44) or leaves it (``"fixed"``).

    outcomes = [run_case(c) for c in random_cases(20, "full", seed=1)]
    summary(outcomes)
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass

import numpy as np

from missions import runner, schema


@dataclass(frozen=True)
class ScaleSpec:
    speed_mps: tuple[float, float]
    """Current speed range [m/s]."""
    offset_m: tuple[float, float]
    """Range of the frame's distance from the crane tip [m]."""
    params: str
    depth_m: float
    landing_depth_m: float
    hold_s: float
    lower_rate_mps: float
    timeout_s: float


SCALES = {
    "full": ScaleSpec((0.02, 0.5), (1.0, 5.0), "full-scale", 390.0, 400.0, 120.0, 0.05, 2400.0),
    # the sea trial: 0.014 m/s (HIL) to 0.1 m/s, the frame within 1.5 m of the crane tip
    # (Minerva pushes 40 N sideways against the wire's 50 N per metre at 170 m)
    "model": ScaleSpec((0.014, 0.1), (0.2, 1.5), "model-scale", 170.0, 180.0, 60.0, 0.02, 1800.0),
    # issue 44's draw: full scale, 0.1 to 0.5 m/s, the frame 1-5 m from the crane tip
    "installation": ScaleSpec(
        (0.1, 0.5), (1.0, 5.0), "full-scale", 390.0, 400.0, 120.0, 0.05, 2400.0
    ),
}
CRANE_TIP_NE_M = (1.0, 1.0)


@dataclass(frozen=True)
class Case:
    scale: str
    seed: int
    speed_mps: float
    direction_deg: float
    frame_heading_deg: float
    offset_m: float
    bearing_deg: float
    """Direction of the frame's centre from the crane tip [deg]."""
    vessel: str = "auto"
    """The dock leg's ``vessel``: "auto" moves it, "fixed" leaves it."""


@dataclass(frozen=True)
class Outcome:
    case: Case
    feasible: bool
    success: bool
    verdict: str
    """'landed', 'refused', or what went wrong, in words."""
    utilisation: float
    """The planner's share of the thrust needed over the frame (nan when not reached)."""
    wall_s: float
    vessel_moved_m: float = 0.0
    """How far the dock leg moved the vessel, all its moves added up [m]."""


def random_cases(n: int, scale: str, seed: int, vessel: str = "auto") -> list[Case]:
    """``n`` cases drawn uniformly: speed and offset in the scale's ranges, any current
    direction, frame heading and bearing (the same draws whatever ``vessel``)."""
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {', '.join(SCALES)}, got {scale!r}")
    rng = np.random.default_rng(seed)
    spec = SCALES[scale]
    lo, hi = spec.speed_mps
    olo, ohi = spec.offset_m
    return [
        Case(
            scale,
            int(rng.integers(0, 2**31 - 1)),
            round(float(rng.uniform(lo, hi)), 4),
            round(float(rng.uniform(0.0, 360.0)), 1),
            round(float(rng.uniform(-180.0, 180.0)), 1),
            round(float(rng.uniform(olo, ohi)), 2),
            round(float(rng.uniform(0.0, 360.0)), 1),
            vessel,
        )
        for _ in range(n)
    ]


def case_mission(case: Case) -> schema.Mission:
    """The mission of one case: the library's docking mission's shape, with its current
    wandering as the library's does (speed band a sixth of the speed, direction +-10 deg)."""
    s = SCALES[case.scale]
    b = math.radians(case.bearing_deg)
    center = [
        round(CRANE_TIP_NE_M[0] + case.offset_m * math.cos(b), 3),
        round(CRANE_TIP_NE_M[1] + case.offset_m * math.sin(b), 3),
    ]
    data = {
        "format_version": 1,
        "name": f"landing-{case.scale}-{case.seed}",
        "setup": {
            "params": s.params,
            "depth_m": s.depth_m,
            "crane_tip_n": list(CRANE_TIP_NE_M),
            "feedback": "ekf",
            "allocation": "priority",
            "reference": "third",
            "feedforward": True,
            "seed": case.seed,
            "current": {
                "speed_mps": case.speed_mps,
                "direction_deg": case.direction_deg,
                "speed_walk_mps_per_sqrt_s": case.speed_mps / 150.0,
                "speed_band_mps": case.speed_mps / 6.0,
                "direction_walk_deg_per_sqrt_s": 0.2,
                "direction_band_deg": 10.0,
            },
            "docking_frame": {
                "center_ne_m": center,
                "heading_deg": case.frame_heading_deg,
                "landing_depth_m": s.landing_depth_m,
            },
        },
        "legs": [
            {"type": "hold", "name": "observer converges", "duration_s": s.hold_s},
            {
                "type": "dock",
                "name": "land",
                "settle_s": 60.0,
                "lower_rate_mps": s.lower_rate_mps,
                "timeout_s": s.timeout_s,
                "vessel": case.vessel,
            },
        ],
    }
    return schema.parse_mission(data)


def run_case(case: Case) -> Outcome:
    """Fly one case and say how it went."""
    t0 = time.perf_counter()
    result = runner.run_mission(case_mission(case))
    wall = time.perf_counter() - t0
    plans = [e for e in result.events if e["kind"] == "dock" and "utilisation" in e["data"]]
    util = float(plans[0]["data"]["utilisation"]) if plans else math.nan
    moved = sum(float(e["data"]["distance_m"]) for e in result.events if e["kind"] == "vessel")
    if "not feasible" in result.error:
        return Outcome(case, False, False, "refused: " + result.error, math.nan, wall)
    if result.landings:
        (landing,) = result.landings
        if landing.success and not result.failed:
            return Outcome(case, True, True, "landed", util, wall, moved)
        verdict = (
            f"rests on the {landing.rests_on}: miss {landing.miss_m:.3f} m and "
            f"{landing.heading_error_deg:.2f} deg at the post tops, "
            f"{landing.contact_speed_mps:.3f} m/s, at rest {landing.rest_miss_m:.3f} m off"
        )
        return Outcome(case, True, False, verdict, util, wall, moved)
    if result.error:
        return Outcome(case, True, False, result.error, util, wall, moved)
    sat = result.saturated_time_s
    verdict = f"not aligned over the frame before the leg's timeout ({sat:.0f} s saturated)"
    return Outcome(case, True, False, verdict, util, wall, moved)


def summary(outcomes: list[Outcome]) -> dict:
    """Success among the accepted cases, per scale (and vessel mode, ``scale/vessel``, when
    the outcomes have more than one), the share of all cases landed, with the failures and
    the refusals listed."""
    out: dict = {}
    modes = {o.case.vessel for o in outcomes}
    groups = sorted({(o.case.scale, o.case.vessel) for o in outcomes})
    for scale, vessel in groups:
        key = scale if len(modes) == 1 else f"{scale}/{vessel}"
        mine = [o for o in outcomes if (o.case.scale, o.case.vessel) == (scale, vessel)]
        accepted = [o for o in mine if o.feasible]
        landed = [o for o in accepted if o.success]
        speeds = [o.case.speed_mps for o in mine]
        offsets = [o.case.offset_m for o in mine]
        out[key] = {
            "scale": scale,
            "vessel": vessel,
            "cases": len(mine),
            "refused": len(mine) - len(accepted),
            "accepted": len(accepted),
            "landed": len(landed),
            "success_rate": len(landed) / len(accepted) if accepted else math.nan,
            "landed_share": len(landed) / len(mine),
            "vessel_moved": sum(1 for o in mine if o.vessel_moved_m > 0.0),
            "vessel_moved_max_m": round(max(o.vessel_moved_m for o in mine), 2),
            "current_mps": [min(speeds), max(speeds)],
            "offset_m": [min(offsets), max(offsets)],
            "wall_s": round(sum(o.wall_s for o in mine), 1),
            "failures": [
                {"case": asdict(o.case), "why": o.verdict} for o in accepted if not o.success
            ],
            "refusals": [
                {"case": asdict(o.case), "why": o.verdict} for o in mine if not o.feasible
            ],
        }
    return out
