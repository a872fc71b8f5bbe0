"""The speed work must not change what a mission computes: a few library missions, run with
their seeds, give the same scored figures and the same final state (plant, observer) as the
values recorded before the rewrite, to 1e-6 relative.

The fixture ``tests/corpus/same_figures.json`` was recorded from the commit the speed branch
started at (901d955, before any kernel change), from the worktree root, with

    python -m tests.test_same_figures --record

Re-record only when a change is meant to move the figures, and say by how much in its commit.

Re-recorded once, on purpose, by the second speed pass (docs/speed.md, "Second pass"): the
EKF correction written for rows of the identity (control.ekf.correct) sums in a different
order than the dense products it replaced. The allocation-free plant step before it left
every figure and final state bit for bit as recorded. What moved: the docking's RMS north
error 0.02479386 -> 0.02479422 m (1.4e-5 relative), RMS east 0.02265973 -> 0.02265967 m
(2.7e-6), RMS heading 3.6e-8 relative, the others below 1e-11; the model-scale EKF mission
below 1.2e-12 relative; the pseudo-inverse mission (no EKF) not at all.

Re-recorded by the sixth speed pass (docs/speed.md): the EKF prediction's Jacobian is written
by hand (``control.ekf.jacobian_phi_into``, was forward differences with a 1e-6 step) and
phi P phi^T skips phi's zeros (was two BLAS products). What moved: the docking's RMS east
error 0.0226605859 -> 0.0226599041 m (3.0e-5 relative), RMS north 0.0247932013 ->
0.0247937167 m (2.1e-5), its landing miss 2.0e-8, the others below 1e-8; the model-scale EKF
mission at most 2.6e-8 (RMS east); the pseudo-inverse mission (no EKF) not at all. The
docking's RMS errors have moved most at each of these re-recordings.

Re-recorded by the eighth speed pass (docs/speed.md): the controller's four 3x3 products
(feedforward ``M @ acc``, the anti-windup's ``A @`` and ``A_inv @``, the bumpless integral's
``A_inv @``) are summed in the kernel (``sim.gnc.mv3_into``) instead of calling OpenBLAS's
``gemv``, whose Haswell kernel fuses multiply and add. What moved: the docking's RMS east
error 0.0226599041 -> 0.0226603819 m (2.1e-5 relative), RMS north 0.0247937167 ->
0.0247932599 m (1.8e-5), RMS heading 1.9e-8, its landing miss 2.4e-12; the model-scale
missions at most 2.2e-14.

Re-recorded by the ninth speed pass (docs/speed.md): a chunk's environment rows are made in
one compiled call (``sim.site.chunk_rows_into``), whose wire entries take libm's logarithm
instead of numpy's (an AVX-512 implementation on machines that have one), ``L * L`` instead
of ``L ** 2``, the chunk's mean current as a sum in order instead of numpy's pairwise sum, and
the crane's distance as a square root of squares instead of OpenBLAS's dot. What moved: the
docking's RMS east error 0.0226603819 -> 0.0226606350 m (1.1e-5 relative), RMS north
0.0247932599 -> 0.0247932977 m (1.5e-6), RMS heading 4.3e-8, the other figures below
1e-12; the model-scale missions' figures below 1e-12, their final plant states at most
6.1e-9.

Re-recorded by the twentieth pass (docs/speed.md), on purpose and not by rounding: each
purpose now draws from its own random stream spawned from the seed (the current's walk, the
sensors' dropouts, their noise, the wave field; before, one generator served them all,
chunk by chunk), and the slow parts of the environment (the wire's entries, the control
model's wire spring) refresh on whole seconds of the step grid, so a run gives the same
numbers however it is cut (``tests/test_any_chunks.py``). Every seeded figure is another
draw of the same noise: the mission with perfect feedback, the pseudo-inverse and a steady
current moved below 1.1e-12 (its final state), the EKF step mission's RMS north 0.298 ->
0.276 m, east 0.279 -> 0.226 m, heading 2.46 -> 2.41 deg, the docking's RMS north 0.0248
-> 0.0254 m, east 0.0227 -> 0.0301 m, heading 0.596 -> 0.527 deg, its landing miss 0.045 ->
0.021 m, contact speed 0.034 -> 0.032 m/s, contact time 411.55 -> 411.48 s.

Re-recorded once more in the same pass, for rounding: the current's walk, the winch and the
crane now go a step at a time from the step before (so the rows agree bit for bit however a
run is cut). The model-scale missions did not move at all; the docking (a walking current,
contact at the landing) at most 1.2e-5 relative (RMS east 0.0301167 -> 0.0301171 m), its
final plant state 3.2e-6 m.
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
