"""The plant's step allocates nothing (issue 15), and its work space carries no state.

The allocation count is read from numba's runtime statistics, which are only kept when the
process starts with ``NUMBA_NRT_STATS=1``: each probe runs in a fresh interpreter (all its
cases in one). The
compiled loop below calls a step 1 and 201 times; the two calls of the loop allocate the same
number of blocks (its own set-up only) when the step allocates nothing. The same probe on the
allocating wrapper ``plant.rk4_step`` must see its three arrays per step, so the instrument
is shown to see allocations."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim import params, plant

ROOT = Path(__file__).resolve().parent.parent

_PROBE = """
import json, sys
import numpy as np
from numba import njit
from numba.core.runtime import rtsys
from sim import params, plant
from sim.sensors import Y_SENSOR, sample_into
from control import loop

@njit
def steps_into(x, n, env, P, work, row, y, noise, fresh, reps):
    for k in range(reps):
        plant.rk4_step_into(x, x, n, env, P, 0.01, work)
        sample_into(y, x, y, noise, fresh, Y_SENSOR)
        loop.write_plant_row(row, k * 0.01, x, y, env, P, work)

@njit
def steps_wrapper(x, n, env, P, work, row, y, noise, fresh, reps):
    for k in range(reps):
        x = plant.rk4_step(x, n, env, P, 0.01)

out = {}
for scale in sys.argv[1:]:
    P = plant.plant_arrays(params.load(scale))
    m = P.thr_T.shape[1]
    x = np.zeros(plant.N_STATE)
    x[2] = x[14] = 5.0
    env = np.zeros(plant.N_ENV)
    env[plant.E_KH], env[plant.E_KZ], env[plant.E_LREST] = 1e3, 1e5, 4.0
    env[plant.E_GRIP] = 1.0  # gripper spring on
    env[plant.E_LAND] = 5.0 + P.tree_half_height - 0.01  # the tree's bottom in the seabed
    env[plant.E_WMASS], env[plant.E_WDAMP] = 50.0, 1e3  # elastic wire with its mass, damped
    env[plant.E_AC] = 0.1  # wave acceleration (Froude-Krylov)
    n = np.full(m, 3.0)
    work = plant.make_work(m)
    row = np.zeros(loop.N_LOG)
    y = np.zeros(11)
    noise = np.zeros(11)
    fresh = np.ones(5, dtype=np.bool_)
    out[scale] = {}
    for name, fn in (("into", steps_into), ("wrapper", steps_wrapper)):
        fn(x.copy(), n, env, P, work, row, y, noise, fresh, 1)  # compile
        counts = []
        for reps in (1, 201):
            before = rtsys.get_allocation_stats().alloc
            fn(x.copy(), n, env, P, work, row, y, noise, fresh, reps)
            counts.append(rtsys.get_allocation_stats().alloc - before)
        out[scale][name] = (counts[1] - counts[0]) / 200
print(json.dumps(out))
"""


def _allocations_per_step(probe: str, *cases: str) -> dict[str, dict[str, float]]:
    """Run a probe script in a fresh interpreter with numba's allocation counter on, for each
    of ``cases`` in turn (one interpreter for all: each would otherwise start and compile the
    probe's loops again, some 8 s); its last line: the allocations per step of each kernel it
    measured, by case."""
    env = dict(os.environ, NUMBA_NRT_STATS="1")
    done = subprocess.run(
        [sys.executable, "-c", probe, *cases],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


SCALES = ("full-scale", "model-scale")


@pytest.fixture(scope="module")
def plant_allocations() -> dict[str, dict[str, float]]:
    return _allocations_per_step(_PROBE, *SCALES)


@pytest.mark.parametrize("scale", SCALES)
def test_plant_step_sensors_and_log_row_allocate_nothing(
    plant_allocations: dict[str, dict[str, float]], scale: str
) -> None:
    per_step = plant_allocations[scale]
    # the allocating wrapper: its state, and the work space's two arrays, every step
    assert per_step["wrapper"] == 3.0
    assert per_step["into"] == 0.0


def _state(rng: np.random.Generator) -> np.ndarray:
    x = rng.normal(0.0, 0.05, plant.N_STATE)
    x[2] = x[14] = 5.0
    return x


def _env(P: plant.PlantArrays, contact: bool) -> np.ndarray:
    env = np.zeros(plant.N_ENV)
    env[plant.E_VC] = 0.2
    env[plant.E_KH], env[plant.E_KZ], env[plant.E_LREST] = 1e3, 1e5, 4.0
    env[plant.E_GRIP] = 1.0
    if contact:
        env[plant.E_LAND] = 5.0 + P.tree_half_height - 0.01
        env[plant.E_WMASS] = 50.0
    return env


@pytest.mark.parametrize("has_rov", [True, False])
def test_a_used_work_space_gives_the_step_of_a_fresh_one(has_rov: bool) -> None:
    """Everything a step reads from its work space it wrote in the same step: a work space
    left over from a different step (contact, gripper, the wire's mass) gives bit for bit the
    step of a fresh one, and stepping the state in place equals stepping into a new array."""
    P = plant.plant_arrays(params.load("model-scale"), has_rov=has_rov)
    m = P.thr_T.shape[1]
    rng = np.random.default_rng(3)
    used = plant.make_work(m)
    x_other = _state(rng)
    plant.rk4_step_into(
        np.empty(plant.N_STATE), x_other, np.full(m, 5.0), _env(P, True), P, 0.01, used
    )
    used.vec[:] += 123.0  # and anything stale at all
    used.mat[:] -= 7.0
    x = _state(rng)
    n = np.full(m, -2.0)
    env = _env(P, False)
    fresh_out = np.empty(plant.N_STATE)
    plant.rk4_step_into(fresh_out, x, n, env, P, 0.01, plant.make_work(m))
    used_out = np.empty(plant.N_STATE)
    plant.rk4_step_into(used_out, x, n, env, P, 0.01, used)
    assert np.array_equal(used_out, fresh_out)
    in_place = x.copy()
    plant.rk4_step_into(in_place, in_place, n, env, P, 0.01, used)
    assert np.array_equal(in_place, fresh_out)
    # and the step moved the state (the comparison is not of two unchanged copies)
    assert not np.array_equal(fresh_out, x)
    if not has_rov:
        xdot = np.full(plant.N_STATE, np.nan)
        plant.rhs_into(xdot, x, np.zeros(6), env, P, used)
        assert np.all(xdot[12:] == 0.0)


_CLOSED_PROBE = """
import json, sys
import numpy as np
from numba import njit
from numba.core.runtime import rtsys
from control import loop
from control.config import ControlSettings
from control.simulation import Simulation
from sim import params, plant

@njit
def wrapper_steps(x, y, xhat, Pc, cs, target, C, Q, fresh, reps):
    row = np.zeros(loop.N_LOG)
    for k in range(reps):
        tau6, xhat, Pc, cs = loop.control_step(
            k * 0.01, x, y, fresh, xhat, Pc, cs, target, C, Q, 0.01, row
        )

out = {}
for case in sys.argv[1:]:
    feedback, allocation, mode = case.split(",")
    settings = ControlSettings(feedback=feedback, allocation=allocation, feedforward=True)
    sim = Simulation(params.load("model-scale"), tree_depth_m=400.0, settings=settings)
    sim.set_target(2.0, 1.0, 0.3)
    sim.step(50)
    sim.set_mode(mode)
    if mode == "manual":
        sim.set_pilot_demand(0.2, 0.0, -0.1, 0.05)
    env, noise = sim._chunk_inputs(201)

    def closed(n):
        loop._closed_steps(
            sim.step_index, sim.x.copy(), sim.held_y.copy(), sim.xhat.copy(), sim.P_cov.copy(),
            sim.cs.copy(), sim.target, env[:n], noise.noise[:n], noise.fresh[:n], sim.arrays,
            sim.C, sim.Q, sim.dt_s, np.zeros((n, loop.N_LOG)), plant.make_work(sim.n_thrusters),
            loop.make_control_work(),
        )

    def wrapper(n):
        wrapper_steps(sim.x, sim.held_y, sim.xhat, sim.P_cov, sim.cs, sim.target, sim.C, sim.Q,
                      noise.fresh[0], n)

    out[case] = {}
    for name, fn in (("closed", closed), ("wrapper", wrapper)):
        fn(1)  # compile
        counts = []
        for reps in (1, 201):
            before = rtsys.get_allocation_stats().alloc
            fn(reps)
            counts.append(rtsys.get_allocation_stats().alloc - before)
        out[case][name] = (counts[1] - counts[0]) / 200
print(json.dumps(out))
"""


CLOSED_CASES = (
    ("ekf", "priority", "tree"),
    ("ekf", "pinv", "free"),
    ("perfect", "priority", "manual"),
)


@pytest.fixture(scope="module")
def closed_allocations() -> dict[str, dict[str, float]]:
    return _allocations_per_step(_CLOSED_PROBE, *(",".join(c) for c in CLOSED_CASES))


@pytest.mark.parametrize(("feedback", "allocation", "mode"), CLOSED_CASES)
def test_closed_loop_step_allocates_nothing(
    closed_allocations: dict[str, dict[str, float]], feedback: str, allocation: str, mode: str
) -> None:
    """The closed loop's step (sensors, signal checks, EKF, reference, controller, allocation,
    thrusters, plant, prediction, log row: ``control.loop._closed_steps``) allocates nothing,
    in each mode; the allocating wrapper ``loop.control_step`` (fresh arrays and a fresh work
    space per call) shows that the probe sees the step's allocations."""
    per_step = closed_allocations[f"{feedback},{allocation},{mode}"]
    # the wrapper's copies of xhat, P, cs, its tau6 and the work space's six arrays
    assert per_step["wrapper"] == 10.0
    assert per_step["closed"] == 0.0
