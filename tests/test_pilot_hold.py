"""Letting go holds station while the ROV grips the tree (issue 47, item 18).

The console's start (no mission: the parameter set's tree at 400 m, still water), flown with
the pilot page's own commands (``app.console.pilot``): the pilot takes over (P), holds a
stick, lets go or hands back. Gripping the tree, the pilot's hold is the tree controller (the
autopilot's law on the tree's pose) with its reference at rest where the stick was let go.

Bands: the position alarm's, the funnels' capture tolerance (0.25 m at full scale, 0.10 m at
model scale) and 10 deg of heading: "settled" is when the alarm would stay clear.
"""

from __future__ import annotations

import math

import numpy as np

from app.console.alarms import AlarmLimits, AlarmMonitor
from app.console.pilot import PilotDemand, PilotTakeOver
from app.console.session import station_keeping_mission
from control.simulation import Simulation
from missions.setup import build_simulation

HEADING_BAND_DEG = 10.0
"""The position alarm's heading limit (``AlarmLimits.heading_error_deg``)."""


class _Session:
    """What the pilot's commands use of the console's session: its simulation, no mission."""

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim

    def require_live(self, what: str) -> None:
        pass

    def require_no_mission(self, what: str) -> None:
        pass

    def note(self, kind: str, text: str, data: dict) -> None:
        pass


class _Loop:
    def __init__(self, sim: Simulation) -> None:
        self.session = _Session(sim)


def console_start(params: str) -> tuple[Simulation, _Loop]:
    """The console's run without a mission, after the 60 s it settles on its wire."""
    sim = build_simulation(station_keeping_mission(params, 400.0))
    sim.run_for(60.0)
    return sim, _Loop(sim)


def stick(loop: _Loop, surge=0.0, sway=0.0, heave=0.0, yaw=0.0) -> None:
    PilotDemand(surge, sway, heave, yaw).apply(loop)  # type: ignore[arg-type]


def take_over(loop: _Loop, pilot: bool) -> None:
    PilotTakeOver(pilot).apply(loop)  # type: ignore[arg-type]


def settled_at(t: np.ndarray, err: np.ndarray, band: float) -> float:
    """The time after which ``err`` stays within ``band`` (0 if it always was)."""
    out = np.flatnonzero(err > band)
    return 0.0 if out.size == 0 else float(t[out[-1]])


def test_letting_go_of_a_full_surge_holds_the_tree_where_it_was_let_go():
    """Full scale, P, full surge (Shift+W) for 8 s, let go with auto-heading on. Before: the
    free-ROV loop held the ROV alone; the tree swung, its heading drifted 234 deg and 150 s
    later it was still 4.0 m off (peak 5.4 m). Time: the autopilot's own station keeping
    from the same state, the tree controller handed the tree at the moment of release (P),
    settled into the 0.25 m band 60.0 s after it before this change; the hold must do as
    well within half a swing of the tree on its 400 m wire (pi sqrt(L / g) = 20 s): 80 s.
    Measured: 58.7 s, peak 2.8 m, heading within 0.05 deg."""
    sim, loop = console_start("full-scale")
    take_over(loop, True)
    stick(loop, surge=1.0)
    sim.run_for(8.0)
    released = sim.tree_eta_n.copy()
    stick(loop)
    rows = sim.run_for(150.0)
    t = rows.t_s - rows.t_s[0]
    tree = rows["tree_eta_n"]
    err = np.hypot(tree[:, 0] - released[0], tree[:, 1] - released[1])
    heading = np.degrees(np.abs(np.unwrap(tree[:, 5]) - released[5]))
    assert np.all(rows["mode"] == 2)  # still flown by hand: this is the pilot's hold
    assert settled_at(t, err, 0.25) < 80.0
    assert heading.max() < 1.0


def test_a_released_yaw_stops_and_comes_back_as_the_autopilot_would():
    """Full scale, P, half yaw (E) for 4 s, let go (the tree turns at 9.2 deg/s), and the same
    turn handed back to the autopilot at that moment instead. The tree controller's yaw loop
    is overdamped: a turn released at rate r0 coasts at most r0 M_psi / K_d,psi on (36.8 deg
    here; its P term only shortens it). Before: the hold overshot 37.6 deg and was still
    27.7 deg off after 120 s; the hand-back overshot 178 deg (the issue: 48 deg). Measured
    now: both 26.3 deg, back within the alarm's 10 deg after 68 s (the autopilot's 67.5 s;
    the hold must not take more than 5 s longer)."""
    results = {}
    for hand_back in (False, True):
        sim, loop = console_start("full-scale")
        take_over(loop, True)
        stick(loop, yaw=0.5)
        sim.run_for(4.0)
        psi0 = float(sim.tree_eta_n[5])
        r0 = float(sim.plant_state[11])
        if hand_back:
            take_over(loop, False)
        stick(loop)
        rows = sim.run_for(120.0)
        t = rows.t_s - rows.t_s[0]
        past = np.degrees(np.unwrap(rows["tree_eta_n"][:, 5]) - psi0)
        coast_deg = math.degrees(r0 * sim.C.M[2, 2] / sim.C.Kd[2])
        assert past.max() < coast_deg, (hand_back, past.max(), coast_deg)
        results[hand_back] = settled_at(t, np.abs(past), HEADING_BAND_DEG)
    assert results[True] < 90.0
    assert results[False] < results[True] + 5.0


def test_model_scale_hold_keeps_no_standing_offset_and_clears_its_alarm():
    """Model scale, P, full surge for 20 s, let go: the tree is let go 3 m from where the
    wire hangs, whose spring pulls it back with 23 N/m. Before: the hold stopped
    integrating beyond 0.5 m and kept a standing 0.99 m offset (the issue: 1.07 m) with the
    position alarm on. The hold takes the wire's spring at its set point as feedforward, so
    the integral needs only what the spring does not give. Measured: back within the 0.10 m
    band 42.6 s after the release, 0.004 m at the end; the console's position alarm (the ROV
    against its set point while flown by hand) is on during the swing and clear at the end."""
    sim, loop = console_start("model-scale")
    monitor = AlarmMonitor(AlarmLimits.for_params(sim.ps), sim.n_thrusters, 1.0, False)
    take_over(loop, True)
    stick(loop, surge=1.0)
    sim.run_for(20.0)
    released = sim.tree_eta_n.copy()
    stick(loop)
    seen_on = False
    errors = []
    for _ in range(150):
        rows = sim.run_for(1.0)
        seen_on |= monitor.update(rows, None, sim.free_setpoint_n)[1].active
        tree = rows["tree_eta_n"][-1]
        errors.append(math.hypot(tree[0] - released[0], tree[1] - released[1]))
    assert seen_on  # the tree swung more than 0.10 m past where it was let go
    assert not monitor.state[1].active, monitor.state[1].message
    assert max(errors[-30:]) < 0.10
    assert settled_at(np.arange(1.0, 151.0), np.array(errors), 0.10) < 60.0


def test_hand_over_to_the_hold_and_back_is_bumpless_while_the_tree_moves():
    """The autopilot moving the tree (a 2 m step of its target, the reference at 0.05 m/s):
    the pilot takes over with the stick at rest, then hands back. Surge, sway and yaw change
    by less than 1e-6 N (N m) at either switch, though the tree is moving, and the hold
    brakes it where it was taken over: within the alarm's 0.25 m 60 s later."""
    sim, loop = console_start("full-scale")
    north, east, psi = sim.eta_estimate
    sim.set_target(north + 2.0, east, psi)
    sim.run_for(30.0)
    assert abs(sim.plant_state[6]) > 0.02  # the tree is under way
    for pilot in (True, False):
        before = sim.run_for(0.05)["tau_rov_cmd_b"][-1]
        taken = sim.tree_eta_n.copy()
        take_over(loop, pilot)
        rows = sim.run_for(60.0)
        after = rows["tau_rov_cmd_b"][0]
        assert np.abs(after - before)[[0, 1, 5]].max() < 1e-6, pilot
        if pilot:
            tree = rows["tree_eta_n"][-1]
            assert math.hypot(tree[0] - taken[0], tree[1] - taken[1]) < 0.25


def test_the_qp_allocation_holds_the_gripped_tree_with_the_tree_controller_too():
    """The QP allocation's steps run in Python (``control.jobs.run_qp_chunk``): they too tell
    the controller that the ROV grips the tree, so its hold is the tree controller's (which
    logs the tree's wrench; the free-ROV law leaves that column at zero)."""
    sim = build_simulation(station_keeping_mission("model-scale", 400.0), allocation="qp")
    sim.run_for(1.0)
    loop = _Loop(sim)
    take_over(loop, True)
    stick(loop, surge=1.0)
    sim.run_for(0.5)
    stick(loop)
    rows = sim.run_for(0.5)
    assert sim.controller_state.gripping
    assert np.all(rows["mode"] == 2)
    assert np.all(np.abs(rows["tau_tree_cmd"][:, 0]) > 0.0)
