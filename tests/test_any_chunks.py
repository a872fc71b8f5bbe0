"""A run is the same whatever pieces it is stepped in. The console advances a mission a tick
at a time (two steps at 1x), the command line a request at a time (chunks of a second): the
same mission with the same seed must give the same rows in both, so a session flown in the
console can be reproduced from the command line.

Two things used to depend on the cut. One generator served every random draw, chunk by
chunk (the current's walk, then the sensors' dropouts, then their noise), so cutting a run
differently handed each step other numbers: a model-scale mission with seed 3 ended 3.6 cm
apart when advanced 50 steps at a time instead of a request at a time, the full-scale
docking 1.0 cm apart. And the slow parts of the environment (the quasi-static wire's
stiffnesses and drag offset, the control model's wire spring, the point where the waves are
evaluated, the elastic wire's mass and its top's velocity) were brought up to date at each
chunk's start: with the draws separated, the full-scale closed loop below still differed by
mm in the tree's position and hundreds of newtons in the wire's tension between a run in
one chunk and in chunks of seven steps. Now each purpose draws from its own stream spawned
from the seed, the slow parts refresh on the whole seconds of the step grid, and the
current's walk, the winch's payout and the crane's path move a step at a time from where the
step before left them (they restarted their sums at each chunk's start: a rounding
difference, 3e-13 m, that a landing's contact grew to 2.5e-5 relative in the docking's RMS
east error). So the rows agree bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from control.columns import LAYOUT
from control.config import ControlSettings
from control.faults import Fault
from control.simulation import Simulation
from missions.driver import MissionDriver
from missions.schema import load_mission
from missions.setup import build_simulation, vary_tree
from sim import environment as envmod
from sim import params, plant, wire
from tests.test_chunk_into import CURRENT

PIECES = [1, 2, 3, 7, 7, 1, 49, 30, 100, 97, 3, 50, 150, 100]
"""Requests of odd lengths (ending inside and across whole seconds), 600 steps in all."""


def _full_scale(control: bool, **kw: object) -> Simulation:
    sim = Simulation(
        params.load("full-scale"),
        tree_depth_m=400.0,
        current=CURRENT,
        control=control,
        seed=11,
        **kw,  # type: ignore[arg-type]
    )
    if control:
        sim.set_target(0.5, -0.3, math.radians(20.0))
    else:
        sim.set_thruster_speeds(np.linspace(-3.0, 3.0, sim.n_thrusters))
    return sim


def _rows(sim: Simulation, pieces: list[int]) -> np.ndarray:
    return np.vstack([sim.step(k).data for k in pieces])


@pytest.mark.parametrize("control", [True, False], ids=["closed loop", "open loop"])
def test_a_run_stepped_in_odd_pieces_gives_the_rows_of_the_run_in_one_request(
    control: bool,
) -> None:
    """Full scale, a walking current (its speed and direction change every step, so the wire's
    entries differ with every cut that takes them from another moment), 600 steps: in one
    request (chunks of 100), in ``PIECES``, and a winch payout started half-way through a
    second. The same draws and the same arithmetic: bit for bit."""
    assert sum(PIECES) == 600
    whole, cut = _full_scale(control), _full_scale(control)
    a = [whole.step(150).data]
    b = [cut.step(k).data for k in (1, 2, 7, 40, 50, 50)]
    for sim in (whole, cut):
        sim.winch_to(sim.wire_length_m + 0.5, 0.1)
    a.append(whole.step(450).data)
    b += [cut.step(k).data for k in (3, 47, 1, 99, 100, 200)]
    rows_a, rows_b = np.vstack(a), np.vstack(b)
    assert rows_a.shape == rows_b.shape == (600, rows_a.shape[1])
    assert np.array_equal(rows_a, rows_b)
    assert np.array_equal(whole.plant_state, cut.plant_state)
    tension = whole.step(1)["wire_tension"]
    assert np.all(tension > 0.0)


def _chunk_sizes(sim: Simulation, n: int) -> tuple[np.ndarray, list[int]]:
    """Step ``n`` in one request; its rows and the lengths of the chunks it ran in."""
    sizes: list[int] = []
    chunk = sim._chunk

    def counted(k: int, out: np.ndarray | None = None):  # type: ignore[no-untyped-def]
        sizes.append(k)
        return chunk(k, out)

    sim._chunk = counted  # type: ignore[method-assign]
    try:
        rows = sim.step(n).data
    finally:
        del sim._chunk
    return rows, sizes


@pytest.mark.parametrize("control", [True, False], ids=["closed loop", "open loop"])
def test_long_chunks_while_the_winch_and_crane_rest_give_the_rows_of_short_ones(
    control: bool,
) -> None:
    """With the winch and the crane at rest, no sea and no faults, a request runs past whole
    seconds in chunks of up to ``LONG_CHUNK_S`` (the wire's entries refresh at the rows of
    each whole second inside them): 1 234 steps from t = 0.37 s go as 63 steps to the next
    whole second, then 500, 500 and 100, then the 71 left. The walking current changes the
    entries at every refresh, so a refresh missed or taken at another step would show: the
    rows are bit for bit those of the same run in odd pieces (whose chunks never exceed a
    second). With the winch moving, the same chunks (the control model's wire spring rides
    in the chunk's rows: the next test); with the QP allocation, whose steps run in Python on
    the configuration as it is, chunks are a second again while the winch moves."""
    whole, cut = _full_scale(control), _full_scale(control)
    for sim in (whole, cut):
        sim.step(37)
    rows_a, sizes = _chunk_sizes(whole, 1234)
    assert sizes == [63, 500, 500, 100, 71]
    rows_b = _rows(cut, [5, 58, 100, 250, 301, 99, 1, 120, 300])
    assert np.array_equal(rows_a, rows_b)
    assert np.array_equal(whole.plant_state, cut.plant_state)
    whole.winch_to(whole.wire_length_m + 2.0, 0.1)
    _, sizes = _chunk_sizes(whole, 829)
    assert sizes == [29, 500, 300]
    if control:
        whole.set_allocation("qp")
        _, sizes = _chunk_sizes(whole, 229)
        assert sizes == [100, 100, 29]


def _moving(sim: Simulation) -> Simulation:
    """The winch paying out 3 m at 0.2 m/s and the crane moving 2 m at 0.1 m/s from the next
    step on: the control model's wire spring (its stiffness for the payout, its equilibrium
    under the tip) changes at every whole second for 15 s and more."""
    sim.winch_to(sim.wire_length_m + 3.0, 0.2)
    sim.move_vessel(sim.crane_tip_n + np.array([2.0, -0.5, 0.0]), 0.1)
    return sim


def test_long_chunks_while_the_winch_and_crane_move() -> None:
    """With the winch and the crane moving, a request runs past whole seconds in chunks of up
    to ``LONG_CHUNK_S``, the control model's wire spring refreshed at each whole second inside
    them (``ClosedChunk.spring``: ``run_closed_chunk`` runs the pieces between the seconds
    with ``C`` holding each one's spring), and the rows are bit for bit those of the same run in odd
    pieces, whose chunks never pass a whole second. The spring really changed: the
    configuration after the request holds the last second's, not the first's."""
    # the observer and the feedforward use the spring (with the default perfect feedback and
    # no feedforward nothing reads it); the plant's tree 20 % heavier in water than the
    # control model's: the spring is the control model's (its tree's weight), not the plant's
    plant_ps = vary_tree(params.load("full-scale"), 1.0, 1.2)
    kw = {"plant_ps": plant_ps, "settings": ControlSettings(feedback="ekf", feedforward=True)}
    runs = [_moving(_full_scale(True, **kw)) for _ in range(2)]
    for sim in runs:
        sim.step(37)
    k_h0, p_eq0 = runs[0].C.k_h, runs[0].C.p_eq.copy()
    rows_alone, sizes = _chunk_sizes(runs[0], 1234)
    assert sizes == [63, 500, 500, 100, 71]
    rows_cut = _rows(runs[1], [5, 58, 100, 250, 301, 99, 1, 120, 300])
    assert np.array_equal(rows_alone, rows_cut)
    for sim in runs:
        assert np.array_equal(sim.plant_state, runs[1].plant_state)
        assert sim.C.k_h == runs[1].C.k_h and np.array_equal(sim.C.p_eq, runs[1].C.p_eq)
    # the spring the runs end with is the refresh's at step 1 200, their last whole second,
    # worked out here step by step as ``site.chunk_rows_into`` walks the winch and the crane
    # (the same operations in the same order: exact)
    fresh = _full_scale(True, **kw)
    assert fresh.ps.tree.submerged_weight_newton != plant_ps.tree.submerged_weight_newton
    payout, tip, target = fresh.wire_length_m, fresh.crane_tip_n.copy(), fresh.crane_tip_n.copy()
    target += np.array([2.0, -0.5, 0.0])
    winch_step, crane_step = 0.01 * 0.2, 0.01 * 0.1
    for _ in range(1200):  # neither gets there in 12 s (3 m at 0.2 m/s, 2.06 m at 0.1 m/s)
        payout = payout + winch_step
        d = target - tip
        tip = tip + crane_step / math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) * d
    k_h = wire.horizontal_stiffness(
        fresh.plant_ps.wire.submerged_weight_per_length(),
        fresh.ps.tree.submerged_weight_newton,
        payout,
    )
    assert runs[0].C.k_h == k_h < k_h0  # 2.4 m more wire: a softer spring
    assert np.array_equal(runs[0].C.p_eq, tip[0:2])
    assert runs[0].C.p_eq[0] > p_eq0[0] + 1.0  # 1.2 m of the tip's 2.06 m path, northwards


def test_the_elastic_wire_in_a_seaway_with_vessel_motion_is_the_same_in_any_pieces() -> None:
    """The elastic wire (its mass with the payout, its top's velocity from the rows) under a
    moving vessel in waves evaluated at the tree: the other inputs a chunk's start used to
    fix."""
    from sim import vessel as vesselmod

    kw = {
        "waves": envmod.WaveParams(
            significant_height_m=2.5, peak_period_s=8.0, direction_rad=0.4, n_components=40
        ),
        "vessel": vesselmod.VesselMotion(heading_rad=math.radians(200.0)),
        "wire": "elastic",
    }
    whole, cut = _full_scale(True, **kw), _full_scale(True, **kw)
    rows_a = _rows(whole, [600])
    rows_b = _rows(cut, PIECES)
    assert np.array_equal(rows_a, rows_b)
    # the vessel moved the crane tip: the rows carry the seaway, not a still surface
    # (measured 0.090 m of surge in these 6 s, the motion still growing in over its 16 s ramp;
    # 0.02 m is well above nothing and well below what was measured)
    tip_ne = LAYOUT.take(rows_a, "crane_tip_ne")
    assert np.ptp(tip_ne[:, 0]) > 0.02


def test_faults_that_move_the_vessel_and_the_water_are_the_same_in_any_pieces() -> None:
    """A vessel drift (the crane tip walked off a step at a time, the chunk's tip carried into
    the next), a current surge and a compass bias, starting and ending inside whole seconds:
    the rows bit for bit, and the drift really moved the tip: 0.2 m/s for 270 whole steps of
    0.01 s (its edges fall on steps), 0.54 m towards 60 deg (measured 1.3e-14 m off: the
    rounding of 270 sums, so 1e-9 m)."""
    faults = [
        Fault("vessel_drift", 1.55, 2.7, value=0.2, direction_deg=60.0),
        Fault("current_surge", 0.73, 3.0, value=0.1),
        Fault("compass_bias", 2.05, 1.0, value=3.0),
    ]
    whole, cut = _full_scale(True), _full_scale(True)
    for sim in (whole, cut):
        for f in faults:
            sim.inject_fault(f)
    rows_a = _rows(whole, [600])
    rows_b = _rows(cut, PIECES)
    assert np.array_equal(rows_a, rows_b)
    moved = whole.step(1)["crane_tip_ne"][0] - np.array([1.0, 1.0])  # it started at (1, 1)
    expected = 0.54 * np.array([math.cos(math.radians(60.0)), math.sin(math.radians(60.0))])
    np.testing.assert_allclose(moved, expected, rtol=0.0, atol=1e-9)


def test_the_slow_parts_refresh_on_whole_seconds_and_hold_between() -> None:
    """The cut cannot show whether the refresh happens at all (two runs that never refreshed
    would agree too), so it is looked at directly: with a walking current and the winch
    paying out, the wire's held entries and the control model's wire spring are those of
    t = 0 after 0.5 s and after 1.0 s (a chunk from 0.5 to 1.0 s refreshes nothing), and new
    ones after the chunk that starts on t = 1 s."""
    sim = _full_scale(True)
    sim.winch_to(sim.wire_length_m + 5.0, 0.5)
    sim.step(50)
    held_start, k_h_start = sim.site.wire_held.copy(), sim.C.k_h
    sim.step(50)  # 0.5 -> 1.0 s: inside the second
    assert np.array_equal(sim.site.wire_held, held_start) and sim.C.k_h == k_h_start
    sim.step(1)  # starts on t = 1 s
    assert not np.array_equal(sim.site.wire_held, held_start)
    assert sim.C.k_h < k_h_start  # 0.5 m more wire: a softer pendulum


def test_the_elastic_wires_top_moves_at_the_winchs_rate() -> None:
    """The elastic wire's top velocity (E_VPIV) is the second-order backward difference of
    the top's path over the rows. The winch paying out at r = 0.5 m/s moves the top down by
    the payout plus its self-weight stretch, p + w p^2 / (2 EA), a quadratic in time, whose
    backward difference is exact: r (1 + w p / EA) at every row after the first two (the run
    takes the top as still before it). Rounding of positions near 400 m over 2 dt: 1e-9 m/s.
    The crane moving north at 0.2 m/s gives 0.2 m/s north, the same way."""
    sim = _full_scale(False, wire="elastic")
    sim.winch_to(sim.wire_length_m + 10.0, 0.5)
    sim.move_vessel(sim.crane_tip_n + np.array([10.0, 0.0, 0.0]), 0.2)
    env, _ = sim._chunk_inputs(60)
    site_w = sim.site.wire_site
    payout = sim.wire_length_m - 0.5 * 0.01 * np.arange(59, -1, -1)  # after each row's step
    expected_down = 0.5 * (1.0 + site_w.w * payout / site_w.EA)
    vel = env[:, plant.E_VPIV : plant.E_VPIV + 3]
    np.testing.assert_allclose(vel[2:, 2], expected_down[2:], rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(vel[2:, 0], 0.2, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(vel[2:, 1], 0.0, rtol=0.0, atol=1e-9)


def test_each_purpose_draws_from_its_own_stream() -> None:
    """The sensors' noise and the current's walk at a step do not depend on what else draws:
    a sea of 300 wave components (whose frequencies and phases are drawn when the run is set
    up) leaves the same noise, dropouts and current as calm water."""
    model = params.load("model-scale")
    sea = envmod.WaveParams(
        significant_height_m=0.1, peak_period_s=2.0, direction_rad=0.0, n_components=300
    )
    calm = Simulation(model, tree_depth_m=50.0, current=CURRENT, seed=4)
    waves = Simulation(model, tree_depth_m=50.0, current=CURRENT, seed=4, waves=sea)
    for sim in (calm, waves):
        sim.step(37)
    env_c, noise_c = calm._chunk_inputs(60)
    env_w, noise_w = waves._chunk_inputs(60)
    assert np.array_equal(noise_w.noise, noise_c.noise)
    assert np.array_equal(noise_w.fresh, noise_c.fresh)
    assert calm.current_speed_mps == waves.current_speed_mps
    assert not np.array_equal(env_w, env_c)  # the waves are in the other's rows
    other = Simulation(model, tree_depth_m=50.0, current=CURRENT, seed=5)
    other.step(37)
    _, noise_o = other._chunk_inputs(60)
    assert not np.array_equal(noise_o.noise, noise_c.noise)  # another seed, other numbers


def _mission_end(name: str, max_steps: int | None) -> tuple[np.ndarray, dict]:
    mission = load_mission(name)
    sim = build_simulation(mission)
    driver = MissionDriver(mission, sim)
    while not driver.done:
        driver.advance(max_steps)
    return sim.plant_state.copy(), driver.result().summary()


@pytest.mark.parametrize(
    "name, max_steps",
    [
        ("model-square-ekf-400", 2),
        ("model-square-ekf-400", 50),
        ("full-docking-current-0.3", 2),
    ],
    ids=["model square, console tick at 1x", "model square, 50 steps", "docking, console tick"],
)
def test_a_mission_advanced_a_tick_at_a_time_ends_where_the_command_line_run_ends(
    name: str, max_steps: int
) -> None:
    """A mission with its own seed, advanced as the console does at 1x (two steps a tick) or
    50 steps at a time, against the command line's request at a time: the same final plant
    state and the same scored figures, bit for bit. The model-scale square (the EKF, a
    current) and the full-scale docking (a walking current, contact at the landing, where a
    difference of rounding grew to 2.5e-5 relative before the walk and the ramps went a step
    at a time; measured in the console at 50x against `rov-console run`)."""
    x_cli, summary_cli = _mission_end(name, max_steps=None)
    x_tick, summary_tick = _mission_end(name, max_steps=max_steps)
    assert np.array_equal(x_cli, x_tick)
    assert summary_tick == summary_cli
