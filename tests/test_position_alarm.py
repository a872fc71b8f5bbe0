"""The console's position alarm waits for a run to settle (issue 47, item 26: position_error
fired during the calm observer hold)."""

from __future__ import annotations

import dataclasses

from app.console.alarms import SETTLE_S, AlarmLimits, AlarmMonitor
from control.columns import LogRows
from control.simulation import Simulation
from missions.schema import load_mission
from missions.setup import build_simulation

POSITION = 1  # position_error's place in AlarmMonitor.state


def observer_hold() -> Simulation:
    """model-square-ekf-400, whose first leg holds 60 s while the observer converges."""
    return build_simulation(load_mission("model-square-ekf-400"))


def editable(rows: LogRows) -> LogRows:
    """The same rows in an array of their own, to move the tree in."""
    return dataclasses.replace(rows, data=rows.data.copy())


def watch(sim: Simulation, limits: AlarmLimits, seconds: int) -> tuple[AlarmMonitor, list[bool]]:
    """The alarm monitor fed a second of rows at a time, as the console's loop feeds it."""
    monitor = AlarmMonitor(limits, sim.n_thrusters, 1.0, uses_sensors=True)
    on = []
    for _ in range(seconds):
        rows = sim.run_for(1.0)
        on.append(monitor.update(rows, None, sim.free_setpoint_n)[POSITION].active)
    return monitor, on


def test_the_start_of_a_run_is_not_a_position_error():
    """Why it fired: a run starts with the current (0.1 m/s) flowing against a controller
    whose integral and observer bias start at zero, and its reference at the hook-up
    estimate, 0.16 m from the tree: the tree is blown 0.45 m off in the first 16 s and
    brought back within the 0.10 m capture tolerance by 40 s. Armed from the first row (the
    limits before this change) the alarm is on from the first second to the 37th; armed once
    settled (the console's, ``AlarmLimits.for_params``) it stays clear, and is armed by the
    end."""
    sim = observer_hold()
    limits = AlarmLimits.for_params(sim.ps)
    assert limits.position_arm_s == SETTLE_S
    _, before = watch(observer_hold(), dataclasses.replace(limits, position_arm_s=0.0), 60)
    assert sum(before) > 20
    monitor, on = watch(sim, limits, 60)
    assert not any(on)
    rows = editable(sim.run_for(1.0))
    rows["tree_eta_n"][-1, 0] += 0.3  # armed now: a tree 0.3 m off is an alarm again
    assert monitor.update(rows, None, sim.free_setpoint_n)[POSITION].active


def test_a_run_that_never_settles_is_alarmed_after_the_settling_time():
    """A tree kept 0.3 m off its reference from the start: quiet while the run may still
    settle, on once ``SETTLE_S`` has passed."""
    sim = observer_hold()
    monitor = AlarmMonitor(AlarmLimits.for_params(sim.ps), sim.n_thrusters, 1.0, True)
    states = []
    for _ in range(int(SETTLE_S) + 2):
        rows = editable(sim.run_for(1.0))
        rows["tree_eta_n"][:, 0] = rows["eta_ref_n"][:, 0] + 0.3
        states.append(monitor.update(rows, None, sim.free_setpoint_n)[POSITION].active)
    assert not any(states[: int(SETTLE_S) - 1]) and states[-1]
