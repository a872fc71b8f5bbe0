"""A request of several chunks has each chunk write its rows straight into the request's array
(``loop.run_chunk_into``, ``loop.run_open_chunk_into``) instead of into a new array copied
there afterwards: the same rows, bit for bit, as the chunks run one request each (the same
chunks, so the same draws), and every column a step leaves unwritten is zero whatever the
array held before."""

from __future__ import annotations

import math

import numpy as np
import pytest

from control import loop
from control.columns import LAYOUT, M_MAX
from control.simulation import Simulation
from sim import environment as envmod
from sim import params, sensors

CURRENT = envmod.CurrentParams(
    speed_mps=0.2,
    direction_rad=math.radians(225.0),
    speed_min_mps=0.1,
    speed_max_mps=0.3,
    direction_min_rad=math.radians(200.0),
    direction_max_rad=math.radians(250.0),
    speed_walk_mps_per_sqrt_s=0.01,
    direction_walk_rad_per_sqrt_s=0.01,
)


def _sim(control: bool) -> Simulation:
    sim = Simulation(
        params.load("model-scale"), tree_depth_m=50.0, current=CURRENT, control=control, seed=5
    )
    if control:
        sim.set_target(0.5, -0.3, math.radians(20.0))
    else:
        sim.set_thruster_speeds(np.linspace(-5.0, 5.0, sim.n_thrusters))
    return sim


@pytest.mark.parametrize("control", [True, False], ids=["closed loop", "open loop"])
def test_a_request_of_several_chunks_gives_the_rows_of_its_chunks_run_one_by_one(
    control: bool,
) -> None:
    whole, parts = _sim(control), _sim(control)
    whole.chunk_steps = parts.chunk_steps = 40
    # chunks of 40, 40, 20 (a chunk ends on the whole second, REFRESH_S) and 30 into one
    # array of 130 rows
    rows = whole.step(130)
    pieces = [parts.step(k).data for k in (40, 40, 20, 30)]  # each chunk its own new array
    assert rows.data.shape == (130, loop.N_LOG)
    assert np.array_equal(rows.data, np.vstack(pieces))
    assert np.array_equal(whole.plant_state, parts.plant_state)
    assert np.all(rows["wire_tension"] > 0.0)  # the rows are filled in, not left zero


def _chunk_args(sim: Simulation, env: np.ndarray) -> tuple:
    """``run_chunk``'s arguments for the next len(env) steps of ``sim``, with a copy of its
    signal checks' state (the kernel updates that in place)."""
    n = env.shape[0]
    quality = type(sim.Q)(*(a.copy() for a in sim.Q))
    noise = np.zeros((n, sensors.N_Y))  # noiseless samples, every sensor fresh every step
    fresh = np.ones((n, sensors.N_SENSORS), dtype=np.bool_)
    return (
        sim.step_index, sim.x, sim.held_y, sim.xhat, sim.P_cov, sim.cs, sim.target, env, noise,
        fresh, sim.arrays, sim.C, quality, sim.dt_s,
    )  # fmt: skip


def test_the_rows_written_into_an_array_are_zeroed_first() -> None:
    """The thruster slots beyond the ROV's (and other columns a step leaves alone) are never
    written by a step; written into an array full of NaN they must come out 0.0, as in a new
    array of zeros, and every other number as ``run_chunk`` gives it."""
    sim = _sim(True)
    sim.step(3)
    env = sim._environment_chunk(20)
    x_new, _, _, _, _, log_new, done_new = loop.run_chunk(*_chunk_args(sim, env))
    into = np.full((20, loop.N_LOG), np.nan)
    x_into, _, _, _, _, done_into = loop.run_chunk_into(*_chunk_args(sim, env), into)
    assert done_new == done_into == 20
    assert not np.isnan(into).any()
    unused = LAYOUT.take(into, "thruster_force")[:, sim.n_thrusters :]
    assert unused.shape == (20, M_MAX - sim.n_thrusters) and unused.size > 0
    assert np.all(unused == 0.0)
    assert np.array_equal(into, log_new)
    assert np.array_equal(x_into, x_new)
