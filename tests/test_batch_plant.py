"""The batch plant (``sim.batch_plant``) gives every run of a batch exactly, bit for bit, what
the scalar plant step (``sim.plant.rk4_step``) gives that run alone, over every branch of the
plant: gripping or not, the wire slack or taut, the wire force from outside, the wire's mass,
the landing surface with the corners and the posts in contact or not, with and without the
ROV, and headings of 10^5 turns. States and environment rows start
from a built full-scale docking simulation and are perturbed per run.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from missions import schema
from missions.setup import build_simulation
from sim import plant
from sim.batch_plant import make_batch_work, rk4_batch, rk4_batch_into


@functools.cache
def _docking() -> tuple[plant.PlantArrays, np.ndarray, np.ndarray, float]:
    """PlantArrays, a state after 2 s and an environment row of the library's full-scale
    docking mission."""
    sim = build_simulation(schema.load_mission("full-docking-current-0.3"))
    sim.step(200)
    env, _ = sim._chunk_inputs(1)
    return sim.arrays, sim.x.copy(), env[0].copy(), sim.dt_s


def _batch_inputs(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """States (N_STATE, n), propeller speeds (m, n) and environment rows (N_ENV, n), each run
    perturbed on its own and put into one of the plant's branches (by its index, so every
    branch is met when n >= 8; a batch of one or three meets the first ones)."""
    P, x0, env0, _ = _docking()
    rng = np.random.default_rng(seed)
    m = P.thr_T.shape[1]
    x = np.repeat(x0[:, None], n, axis=1)
    env = np.repeat(env0[:, None], n, axis=1)
    x[0:3] += rng.uniform(-0.5, 0.5, (3, n))
    x[3:5] += rng.uniform(-0.05, 0.05, (2, n))
    x[5] += rng.uniform(-math.pi, math.pi, n)
    x[6:9] += rng.uniform(-0.2, 0.2, (3, n))
    x[9:12] += rng.uniform(-0.05, 0.05, (3, n))
    x[12:15] = x[0:3] + rng.uniform(-4.0, 4.0, (3, n))
    x[15:17] = rng.uniform(-0.1, 0.1, (2, n))
    x[17] = x[5] + rng.uniform(-0.3, 0.3, n)
    x[18:24] = rng.uniform(-0.3, 0.3, (6, n))
    n_rps = rng.uniform(-1.2, 1.2, (m, n)) * P.thr_n_max[:, None]
    env[plant.E_VC : plant.E_VC + 3] += rng.uniform(-0.2, 0.2, (3, n))
    env[plant.E_AC : plant.E_AC + 3] = rng.uniform(-0.05, 0.05, (3, n))
    env[plant.E_PUSH : plant.E_PUSH + 3] = rng.uniform(-2e3, 2e3, (3, n))
    half_h = P.tree_half_height
    for r in range(n):
        case = r % 8
        env[plant.E_GRIP, r] = 1.0 if case in (0, 2, 4, 6) else 0.0
        env[plant.E_LAND, r] = 0.0
        env[plant.E_WMASS, r] = 0.0
        env[plant.E_WDAMP, r] = 0.0
        env[plant.E_WEXT, r] = 0.0
        if case == 1:  # slack wire: the tree lifted 3 m above its hang; the seabed 20 m below
            x[2, r] -= 3.0
            env[plant.E_LAND, r] = x[2, r] + 20.0
        elif case == 2:  # the wire force from outside (MoorDyn)
            env[plant.E_WEXT, r] = 1.0
            env[plant.E_FWIRE : plant.E_FWIRE + 3, r] = rng.uniform(-5e4, 5e4, 3)
        elif case == 3:  # elastic wire: mass and damping; the posts' tops twice the batch's
            # contact margin under the tree's bottom (skipped as out of reach, just)
            env[plant.E_WMASS, r] = rng.uniform(100.0, 2000.0)
            env[plant.E_WDAMP, r] = rng.uniform(1e3, 1e5)
            reach = half_h + P.dock_post_height + 2.0 * plant.CONTACT_MARGIN_M
            env[plant.E_LAND, r] = x[2, r] + reach
            env[plant.E_FRAME : plant.E_FRAME + 2, r] = x[0:2, r]
        elif case in (4, 5, 6):  # landing: the bottom plane 2-8 cm above the tree's bottom
            env[plant.E_LAND, r] = x[2, r] + half_h - rng.uniform(0.02, 0.08)
            # the frame under the tree, off by a few cm: posts in the funnels (against the
            # walls), or (case 6) under the bottom plate
            off = 0.05 if case != 6 else 1.0
            env[plant.E_FRAME : plant.E_FRAME + 2, r] = x[0:2, r] + rng.uniform(-off, off, 2)
            env[plant.E_FRAME_PSI, r] = x[5, r] + rng.uniform(-0.02, 0.02)
            x[11, r] = rng.uniform(-0.05, 0.05)
        elif case == 7:  # headings 2e5 and -3e5 rad (sim.trig's large reduction); the frame's
            # posts' tops half the batch's contact margin under the tree's bottom (near enough
            # for the contact code, which finds nothing)
            x[5, r] += 2.0e5
            x[17, r] -= 3.0e5
            margin = 0.5 * plant.CONTACT_MARGIN_M
            env[plant.E_LAND, r] = x[2, r] + half_h + P.dock_post_height + margin
            env[plant.E_FRAME : plant.E_FRAME + 2, r] = x[0:2, r]
    return x, n_rps, env


def _scalar_steps(x, n_rps, env, P, dt, steps: int) -> list[np.ndarray]:
    out = []
    x = x.copy()
    for _ in range(steps):
        for r in range(x.shape[1]):
            x[:, r] = plant.rk4_step(x[:, r].copy(), n_rps[:, r].copy(), env[:, r].copy(), P, dt)
        out.append(x.copy())
    return out


def _contact_sanity(x: np.ndarray, env: np.ndarray, P: plant.PlantArrays) -> tuple[int, int]:
    """How many runs touch the landing surface at a corner, and how many at a post."""
    corners = posts = 0
    for r in range(x.shape[1]):
        if env[plant.E_LAND, r] <= 0.0:
            continue
        R = plant.Rzyx(*x[3:6, r])
        if any(
            x[2, r] + (R @ plant._corner_body(P, j))[2] > env[plant.E_LAND, r] for j in range(4)
        ):
            corners += 1
        for i in range(P.dock_xy.shape[0]):
            kind, pen, _ = plant.post_penetration(plant._post_top(x[:, r], env[:, r], P, i), P)
            if kind != plant.POST_FREE and pen > 0.0:
                posts += 1
                break
    return corners, posts


@pytest.mark.parametrize("n", [1, 3, 64])
@pytest.mark.parametrize("has_rov", [True, False])
def test_batch_equals_scalar_bit_for_bit(n: int, has_rov: bool) -> None:
    P, _, _, dt = _docking()
    P = P._replace(has_rov=has_rov)
    x, n_rps, env = _batch_inputs(n, seed=n)
    if n == 64:
        corners, posts = _contact_sanity(x, env, P)
        assert corners >= 20 and posts >= 8, (corners, posts)  # the contact code is run
    expected = _scalar_steps(x, n_rps, env, P, dt, steps=5)
    work = make_batch_work(n_rps.shape[0])
    xb = x.copy()
    for k in range(5):
        rk4_batch_into(xb, n_rps, env, P, dt, work)
        for r in range(n):
            assert np.array_equal(xb[:, r], expected[k][:, r]), (k, r, r % 8)
    assert np.all(np.isfinite(xb))
    # the state moved (a step that did nothing would match a scalar step that did nothing)
    assert np.all(np.abs(xb - x).max(axis=0) > 0.0)


def test_every_branch_changes_the_result() -> None:
    """The branches the batch is checked over are live: switching each off changes the
    run's step (so the equality above covers them, not one shared path)."""
    P, _, _, dt = _docking()
    x, n_rps, env = _batch_inputs(8, seed=11)
    base = rk4_batch(x, n_rps, env, P, dt)
    for r, col, off in [
        (0, plant.E_GRIP, 0.0),
        (2, plant.E_WEXT, 0.0),
        (3, plant.E_WMASS, 0.0),
        (4, plant.E_LAND, 0.0),
        (6, plant.E_LAND, 0.0),
    ]:
        env2 = env.copy()
        env2[col, r] = off
        moved = rk4_batch(x, n_rps, env2, P, dt)
        assert not np.array_equal(moved[:, r], base[:, r]), (r, col)
        others = [i for i in range(8) if i != r]
        assert np.array_equal(moved[:, others], base[:, others])


def test_a_non_finite_run_leaves_the_others_alone() -> None:
    P, _, _, dt = _docking()
    x, n_rps, env = _batch_inputs(16, seed=5)
    x[4, 3] = math.nan  # pitch of run 3
    x[8, 9] = math.inf  # heave speed of run 9
    env[plant.E_PUSH, 12] = math.nan  # push on run 12 (a landing case)
    x[17, 14] = 2.0e6  # ROV heading of run 14 past sim.trig's range: NaN
    expected = _scalar_steps(x, n_rps, env, P, dt, steps=3)[-1]
    work = make_batch_work(n_rps.shape[0])
    for _ in range(3):
        rk4_batch_into(x, n_rps, env, P, dt, work)
    bad = [3, 9, 12, 14]
    for r in range(16):
        assert np.all(np.isfinite(x[:, r])) == (r not in bad), r
        # the bad runs as the scalar step leaves them, NaN for NaN; the others untouched
        assert np.array_equal(x[:, r], expected[:, r], equal_nan=True), r


def test_bad_shapes_are_refused() -> None:
    P, x0, env0, dt = _docking()
    m = P.thr_T.shape[1]
    x = np.repeat(x0[:, None], 2, axis=1)
    env = np.repeat(env0[:, None], 2, axis=1)
    with pytest.raises(ValueError, match=r"n_rps must have shape \(\d+, 2\)"):
        rk4_batch(x, np.zeros((m, 3)), env, P, dt)
    with pytest.raises(ValueError, match=r"env must have shape \(31, 2\)"):
        rk4_batch(x, np.zeros((m, 2)), env[:, :1], P, dt)
    with pytest.raises(ValueError, match=r"x_sb must have shape \(24, runs\)"):
        rk4_batch(x.T, np.zeros((m, 2)), env, P, dt)
    with pytest.raises(ValueError, match="dt must be > 0 s"):
        rk4_batch(x, np.zeros((m, 2)), env, P, 0.0)
