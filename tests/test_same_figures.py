"""Changes for speed or structure must not change what a mission computes: a few library
missions, run with their seeds, give the same scored figures and the same final state
(plant, observer) as recorded in ``tests/corpus/same_figures.json``, to 1e-6 relative.

Record with

    python -m tests.test_same_figures --record

only when a change is meant to move the figures, in a commit of its own that says by how
much and why; ``git log -- tests/corpus/same_figures.json`` lists every re-recording (the
EKF's corrections and prediction summed in other orders, the controller's products summed in
the kernel, each random purpose given its own stream: each moved the docking's RMS errors by
at most 3e-5 relative, except the last, which drew other noise on purpose).
"""

from __future__ import annotations

import json
import math
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from missions import schema
from missions.driver import MissionDriver
from missions.setup import build_simulation

FIXTURE = Path(__file__).parent / "corpus" / "same_figures.json"
REL = 1e-6
"""Relative tolerance of the issue (same mission, same seed, same figures to 1e-6)."""
ABS = 1e-9
"""Absolute floor for figures that are (near) zero, where a relative bound means nothing."""


def _library(name: str) -> dict:
    return tomllib.loads((schema.LIBRARY_DIR / f"{name}.toml").read_text())


def _short(name: str, durations: list[float], **setup: object) -> schema.Mission:
    """A library mission with its legs shortened (the first len(durations) legs) and its
    set-up overridden."""
    data = _library(name)
    data["legs"] = data["legs"][: len(durations)]
    for leg, d in zip(data["legs"], durations, strict=True):
        leg["duration_s"] = d
    data["setup"].update(setup)
    data["name"] = f"{name}-short"
    return schema.parse_mission(data)


def cases() -> dict[str, schema.Mission]:
    """The missions compared: model scale with the EKF and the priority allocation, model scale
    with perfect feedback and the pseudo-inverse, and one full-scale docking (EKF, contact)."""
    return {
        "model-step-priority-ekf": _short("model-step-priority", [10.0, 60.0], feedback="ekf"),
        "model-step-pinv": _short("model-step-pinv", [10.0, 40.0]),
        "full-docking-current-0.3": schema.load_mission("full-docking-current-0.3"),
    }


def run_case(mission: schema.Mission) -> dict:
    """Scored figures and the final state of one mission run with its own seed."""
    sim = build_simulation(mission)
    driver = MissionDriver(mission, sim)
    while not driver.done:
        driver.advance()
    r = driver.result()
    figures: dict[str, float] = {
        "rms_north_m": r.rms_north_m,
        "rms_east_m": r.rms_east_m,
        "rms_heading_deg": r.rms_heading_deg,
        "max_thruster_utilisation": r.max_thruster_utilisation,
        "saturated_time_s": r.saturated_time_s,
        "settling_time_s": math.nan if r.settling_time_s is None else r.settling_time_s,
    }
    for i, landing in enumerate(r.landings):
        figures[f"landing{i}_miss_m"] = landing.miss_m
        figures[f"landing{i}_heading_error_deg"] = landing.heading_error_deg
        figures[f"landing{i}_contact_speed_mps"] = landing.contact_speed_mps
        figures[f"landing{i}_t_contact_s"] = landing.t_contact_s
    return {
        "figures": figures,
        "failed": r.failed,
        "t_s": sim.t_s,
        "plant_state": [float(v) for v in sim.plant_state],
        "xhat": [float(v) for v in sim.xhat],
    }


def _close(a: float, b: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return abs(a - b) <= REL * abs(b) + ABS


@pytest.mark.parametrize("name", list(cases()))
def test_mission_gives_the_recorded_figures_and_final_state(name: str) -> None:
    want = json.loads(FIXTURE.read_text())[name]
    got = run_case(cases()[name])
    assert got["failed"] == want["failed"]
    assert got["t_s"] == pytest.approx(want["t_s"], abs=1e-9)
    assert set(got["figures"]) == set(want["figures"])
    for key, b in want["figures"].items():
        a = got["figures"][key]
        assert _close(a, b), f"{name} {key}: {a!r} != recorded {b!r}"
    for field in ("plant_state", "xhat"):
        a, b = np.array(got[field]), np.array(want[field])
        bad = np.abs(a - b) > REL * np.abs(b) + ABS
        assert not bad.any(), f"{name} {field}[{np.flatnonzero(bad)}]: {a[bad]} != {b[bad]}"


def _record() -> None:
    out = {name: run_case(m) for name, m in cases().items()}
    FIXTURE.write_text(json.dumps(out, indent=1, allow_nan=True) + "\n")
    print(f"wrote {FIXTURE}")


if __name__ == "__main__":
    if sys.argv[1:] == ["--record"]:
        _record()
