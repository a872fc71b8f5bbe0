"""Checks skipped where a prediction says they would fail (``missions.legs.MissionContext.polls``).

A leg waiting for the reference to arrive, or for the winch to stop, polls its condition every
second (every half second while lowering onto a frame). The reference model and the winch are
deterministic, so the polls that would say "not yet" are known in advance; the leg asks for
them in one request instead. These tests hold that to what it promises: the predictor never
counts a poll at whose end the condition holds and is not needlessly short, and missions run
the same step for step, rows, events and leg results, with far fewer requests.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from control import loop, refkernel, simulation
from control.faults import Fault
from control.reference import FirstOrderParams, ThirdOrderParams
from missions import runner, schema
from missions.driver import MissionDriver

DT = 0.01
POLL = 100  # steps in a poll of 1 s


def _first_arrival(kind: int, params: np.ndarray, target: np.ndarray, tol: np.ndarray) -> int:
    """The index of the first poll whose end state is within ``tol`` of the target (rates
    zero), the reference stepped one step at a time as the closed loop steps it."""
    state = np.zeros(9)
    goal = np.concatenate([target, np.zeros(3)])
    for p in range(1000):
        for _ in range(POLL):
            state = refkernel.reference_step(kind, state, target, DT, params)
        if np.all(np.abs(state[0:6] - goal) < tol):
            return p
    raise AssertionError("the reference never arrived")


@pytest.mark.parametrize("kind", [loop.REF_THIRD, loop.REF_FIRST])
def test_the_predictor_counts_only_polls_that_end_away_and_stops_near_the_arrival(kind):
    speeds = [0.1, 0.1, math.radians(2.0)]
    if kind == loop.REF_THIRD:
        params = refkernel.pack_third_order(
            ThirdOrderParams(0.1, 1.0, speeds, [0.01, 0.01, math.radians(0.2)])
        )
    else:
        params = refkernel.pack_first_order(FirstOrderParams(10.0, speeds))
    target = np.array([2.0, -1.0, math.radians(30.0)])
    tol = np.array([1e-3, 1e-3, math.radians(0.01), 1e-4, 1e-4, 1e-5])
    arrival = _first_arrival(kind, params, target, tol)
    goal = np.concatenate([target, np.zeros(3)])
    scratch = np.empty(9)
    away = refkernel.polls_still_away(
        kind, np.zeros(9), target, DT, params, goal, tol, POLL, 1000, scratch
    )
    # every poll counted ends with the reference not arrived (a check that would say no)...
    assert away <= arrival
    # ...and the margin (a millionth of the tolerance) costs at most the poll it lands in
    assert away >= arrival - 1 and arrival > 5
    # a bound on the polls looked at is a bound on the answer
    assert refkernel.polls_still_away(
        kind, np.zeros(9), target, DT, params, goal, tol, POLL, 3, scratch
    ) == min(3, away)


def _driver(text_or_name: str, merge: bool, keep_log: bool = True) -> MissionDriver:
    mission = (
        schema.load_mission(text_or_name)
        if "\n" not in text_or_name
        else schema.parse_text(text_or_name, "<test>")
    )
    sim = runner.build_simulation(mission)
    d = MissionDriver(mission, sim, keep_log=keep_log)
    d.ctx.merge_polls = merge
    return d


def _run(d: MissionDriver) -> tuple[object, int]:
    """The driver run to its end, and how many requests it made of the simulation."""
    asked = 0
    while not d.done:
        d.advance()
        asked += 1
    return d.result(), asked


def _same(a, b) -> None:
    assert a.log is not None and b.log is not None
    assert np.array_equal(a.log.data, b.log.data)  # every row, bit for bit
    assert a.events == b.events
    assert [(x.name, x.timed_out, x.error, x.start_s, x.duration_s) for x in a.legs] == [
        (x.name, x.timed_out, x.error, x.start_s, x.duration_s) for x in b.legs
    ]
    assert a.landings == b.landings
    assert a.rms_north_m == b.rms_north_m and a.final_eta_n == b.final_eta_n


def test_a_docking_runs_the_same_step_for_step_in_a_twentieth_of_the_requests():
    polled, n_polled = _run(_driver("full-docking-current-0.3", merge=False))
    merged, n_merged = _run(_driver("full-docking-current-0.3", merge=True))
    _same(polled, merged)
    assert merged.landings[0].success
    # measured 385 requests polling, 22 merged (the counts are exact for this mission and
    # seed; the bounds leave room for edits of the library mission, and fail if the merging
    # stopped or merged less than half of what it does)
    assert n_polled > 300 and n_merged < 40


TIMEOUTS = """format_version = 1
name = "deadlines between polls"

[setup]
params = "model-scale"
depth_m = 400.0
crane_tip_n = [1.0, 1.0]
feedback = "ekf"
allocation = "priority"
reference = "third"
seed = 3

[setup.current]
speed_mps = 0.1
direction_deg = 225.0

[[legs]]
type = "hold"
duration_s = 10.0

[[legs]]
type = "move"
name = "cut off on its way"
north_m = 2.0
east_m = 0.0
settle_s = 5.0
timeout_s = 7.37

[[legs]]
type = "wire"
name = "pay out"
change_m = 1.0
rate_mps = 0.05
settle_s = 3.0

[[legs]]
type = "wire"
name = "haul in, cut off"
change_m = -1.0
rate_mps = 0.05
settle_s = 3.0
timeout_s = 12.5

[[legs]]
type = "move"
name = "back"
north_m = -2.0
east_m = 0.0
settle_s = 5.0
score = true
"""


def test_deadlines_between_polls_cut_the_same_steps():
    """A move and a winch leg whose deadlines fall between polls (7.37 s and 12.5 s after
    their start): the merged requests stop at the poll where the polled run gave up."""
    polled, n_polled = _run(_driver(TIMEOUTS, merge=False))
    merged, n_merged = _run(_driver(TIMEOUTS, merge=True))
    _same(polled, merged)
    assert [x.timed_out for x in merged.legs] == [False, True, False, True, False]
    assert n_merged < n_polled / 2


def _arrived(sim, goal: np.ndarray, tol: np.ndarray) -> bool:
    """The legs' test of the reference against a goal (pose and rates)."""
    return bool(np.all(np.abs(sim.reference[0:6] - goal) < tol))


def test_the_simulations_predictions_hold_in_its_closed_loop_and_stop_when_they_cannot():
    """Run in the closed loop itself: the winch is still moving after the steps
    ``winch_steps_busy`` counts and idle within the margin's steps after; the reference has
    not arrived after the polls ``reference_polls_away`` counts and has within two more (one
    for the margin, one for the poll it lands in: the kernel-level test above). A fault
    scheduled (a winch slip moves the payout) stops the winch's prediction; a switch into tree
    mode not yet stepped (the reference is reset to the estimate then) stops the
    reference's."""
    d = _driver("full-docking-current-0.3", merge=True)
    sim = d.sim
    sim.winch_to(sim.wire_length_m + 1.0, 0.1)  # 1 m at 1 mm a step: 1 000 steps
    busy = sim.winch_steps_busy()
    assert 996 <= busy < 1000  # the margin is two steps (and the rounding of 1 / 1e-3)
    sim.step(busy)
    assert not sim.winch_idle
    sim.step(1000 + 2 - busy)  # the last step of travel, and one for its rounding
    assert sim.winch_idle
    goal = np.array([5.0, 5.0, 0.0, 0.0, 0.0, 0.0])
    tol = np.full(6, 1e-3)
    sim.set_target(5.0, 5.0, 0.0, heading_mode="absolute")
    sim.set_mode("tree")
    sim.controller_state.last_mode = loop.MODE_FREE
    assert sim.reference_polls_away(goal, tol, POLL, 600) == 0
    sim.controller_state.last_mode = loop.MODE_TREE
    away = sim.reference_polls_away(goal, tol, POLL, 600)
    # the reference cannot get there faster than its speed limit allows (an independent bound)
    v_max = sim.C.ref_params[3, 0:2]
    assert away >= int(np.max(np.abs(goal[0:2] - sim.reference[0:2]) / v_max)) - 2
    sim.step(away * POLL)
    assert not _arrived(sim, goal, tol)
    sim.step(2 * POLL)
    assert _arrived(sim, goal, tol)
    sim.inject_fault(Fault(kind="winch_slip", start_s=1000.0, duration_s=1.0, value=0.1))
    sim.winch_to(sim.wire_length_m + 1.0, 0.1)
    assert sim.winch_steps_busy() == 0


def test_the_simulation_runs_a_merged_request_in_whole_second_chunks():
    """What the merging buys besides fewer requests: where the winch and crane stand still,
    a request of many polls runs in long chunks (``LONG_CHUNK_S``)."""
    d = _driver("full-docking-current-0.3", merge=True, keep_log=False)
    sizes: list[int] = []
    chunk = simulation.Simulation._chunk

    def counted(self, n, out=None):
        sizes.append(n)
        return chunk(self, n, out)

    simulation.Simulation._chunk = counted  # type: ignore[method-assign]
    try:
        _run(d)
    finally:
        simulation.Simulation._chunk = chunk  # type: ignore[method-assign]
    assert sum(sizes) == 50_700
    long_steps = int(simulation.LONG_CHUNK_S / 0.01)
    assert sizes.count(long_steps) > 40  # measured 419 chunks polling, 210 merged
    assert len(sizes) < 260


def test_a_long_request_runs_in_pieces_and_hands_back_all_its_rows():
    """A request of minutes (the merged polls of a move) is stepped in pieces of at most
    ``long_chunk_steps`` (no array of all its rows for the kernel to fault its pages in);
    ``advance()`` still returns every row of the request, and the leg reads the same rows
    joined (``MissionContext.last_log``)."""
    d = _driver("full-docking-current-0.3", merge=True)
    asked: list[int] = []
    step = simulation.Simulation.step

    def counted(self, n):
        asked.append(n)
        return step(self, n)

    simulation.Simulation.step = counted  # type: ignore[method-assign]
    try:
        first = d.advance()  # the 120-s hold: one request
        assert len(first) == 12_000 and max(asked) == d.sim.long_chunk_steps == 500
        assert len(asked) == 24
        assert np.array_equal(d.ctx.last_log.data, first.data)
        previous_last = first.data[-1].copy()
        second = d.advance()
        assert len(second) > 500  # a merged request, in several pieces
        assert np.array_equal(d.ctx.last_log.data, second.data)
        assert np.array_equal(d.ctx.previous_row, previous_last)
    finally:
        simulation.Simulation.step = step  # type: ignore[method-assign]
