"""The fourteenth speed pass's comparison: the closed loop (``control_benchmark``'s
configuration) with a chunk's inputs made the old way (numpy forms of ``sim.sensors.draw_noise``
and ``sim.environment.advance_current``, as at commit ``BEFORE``) and the new (one compiled call
each), alternating in one process, and whether both give the same rows bit for bit.

    .venv/bin/python benchmarks/chunk_inputs_ab.py [--rounds 11] [--seconds 150]

The old ``sim/environment.py`` is read from git (``git show BEFORE:...``) into a module of its
own; on this noisy 2-core machine only rounds measured side by side say anything.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.control_benchmark import thesis_current
from control.config import ControlSettings
from control.simulation import Simulation
from sim import environment as envmod
from sim import params, sensors

ROOT = Path(__file__).resolve().parents[1]
BEFORE = "d913b07"
"""The commit before the chunk inputs were compiled (eafeaae)."""


def _old_environment():
    text = subprocess.run(
        ["git", "show", f"{BEFORE}:sim/environment.py"], cwd=ROOT, check=True,
        capture_output=True, text=True,
    ).stdout  # fmt: skip
    path = Path(tempfile.mkdtemp()) / "environment_before.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("environment_before", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def closed_loop_run(
    ps: params.ParameterSet, settings: ControlSettings, seconds: float
) -> tuple[float, np.ndarray]:
    """``control_benchmark``'s closed loop for ``seconds``: (us a step, its log rows)."""
    sim = Simulation(ps, tree_depth_m=400.0, current=thesis_current(), settings=settings)
    sim.set_target(2.0, 2.0, 0.5)
    t0 = time.perf_counter()
    rows = sim.run_for(seconds)
    return (time.perf_counter() - t0) / len(rows) * 1e6, rows.data


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=11)
    parser.add_argument("--seconds", type=float, default=150.0)
    args = parser.parse_args()
    old_env = _old_environment()
    new_forms = (sensors.draw_noise, envmod.advance_current)

    def old_noise(cfg, dropouts, normals, first_step, n):
        decimation, period = cfg.pattern_key
        due = sensors._due_pattern(decimation, first_step % period, n)
        kept = dropouts.random((n, sensors.N_SENSORS)) >= cfg.dropout_probability[None, :]
        noise = normals.standard_normal((n, sensors.N_Y)) * cfg.noise_std[None, :]
        return sensors.NoiseChunk(noise=noise, fresh=due & kept)

    def old_current(state, p, dt, n, rng):
        fields = [getattr(p, f) for f in p.__dataclass_fields__]
        s = state
        old_state = old_env.CurrentState(
            s.speed_mps, s.direction_rad, s.speed_fold_sign, s.direction_fold_sign
        )
        c = old_env.advance_current(old_state, old_env.CurrentParams(*fields), dt, n, rng)
        e = c.state
        return envmod.CurrentChunk(
            envmod.CurrentState(
                e.speed_mps, e.direction_rad, e.speed_fold_sign, e.direction_fold_sign
            ),
            c.speeds_mps,
            c.directions_rad,
        )

    ps = params.load("model-scale")
    settings = ControlSettings(feedback="ekf", allocation="priority", feedforward=True)

    forms = {"before": (old_noise, old_current), "after": new_forms}
    us: dict[str, list[float]] = {"before": [], "after": []}
    rows: dict[str, np.ndarray] = {}
    for label in forms:  # load both ways' kernels before timing
        sensors.draw_noise, envmod.advance_current = forms[label]
        closed_loop_run(ps, settings, 1.0)
    for _ in range(args.rounds):
        for label in forms:
            sensors.draw_noise, envmod.advance_current = forms[label]
            t, rows[label] = closed_loop_run(ps, settings, args.seconds)
            us[label].append(t)
    sensors.draw_noise, envmod.advance_current = new_forms
    for label, values in us.items():
        print(
            f"{label:6s} us a step: best {min(values):.2f}, median {np.median(values):.2f} "
            f"({', '.join(f'{v:.2f}' for v in values)})"
        )
    ratios = ", ".join(f"{a / b:.3f}" for a, b in zip(us["after"], us["before"], strict=True))
    print(f"after / before, round by round: {ratios}")
    same = np.array_equal(rows["before"].view(np.int64), rows["after"].view(np.int64))
    print(f"the same rows bit for bit: {same}")


if __name__ == "__main__":
    main()
