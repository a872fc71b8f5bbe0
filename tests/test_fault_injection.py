"""The faults of a run on their own (control.fault_injection), without a simulation."""

import math

import numpy as np
import pytest

from control.fault_injection import FaultInjector
from control.faults import Fault


def test_chunks_end_where_a_fault_starts_or_ends():
    faults = FaultInjector(n_thrusters=4)
    assert faults.steps_to_edge(0.0, 0.01, 100) == 100
    faults.inject(Fault("dvl_lost", start_s=0.25, duration_s=0.5))
    assert faults.steps_to_edge(0.0, 0.01, 100) == 25
    assert faults.steps_to_edge(0.25, 0.01, 100) == 50
    assert faults.steps_to_edge(0.75, 0.01, 100) == 100  # past both edges


def test_surges_and_turns_change_the_current_only_in_their_window():
    faults = FaultInjector(n_thrusters=4)
    faults.inject(Fault("current_surge", start_s=0.02, duration_s=0.02, value=-0.5))
    faults.inject(Fault("current_turn", start_s=0.03, duration_s=1.0, value=90.0))
    t = 0.01 * np.arange(5)
    speeds, dirs = np.full(5, 0.3), np.zeros(5)
    new_speeds, new_dirs = faults.current(t, speeds, dirs)
    assert np.array_equal(new_speeds, [0.3, 0.3, 0.0, 0.0, 0.3])  # never below zero
    np.testing.assert_allclose(new_dirs, [0, 0, 0, math.pi / 2, math.pi / 2])
    assert np.all(speeds == 0.3) and np.all(dirs == 0.0)  # the inputs are left as they were


def test_starts_and_ends_are_logged_once_and_kept_as_events():
    faults = FaultInjector(n_thrusters=4)
    faults.inject(Fault("thruster_weakened", start_s=1.0, duration_s=1.0, value=0.4, thruster=2))
    flipped, factors = faults.before_chunk(1.0, site=None)
    assert not flipped and np.array_equal(factors, [1.0, 0.4, 1.0, 1.0])
    assert faults.active(1.5) == faults.faults
    faults.before_chunk(2.0, site=None)
    log = faults.take_log()
    assert [text.split(":")[0] for _, text in log] == ["fault", "fault over"]
    assert faults.take_log() == [] and faults.events == log


def test_a_thruster_fault_names_a_thruster_the_rov_has():
    with pytest.raises(ValueError, match=r"\[1, 4\]"):
        FaultInjector(n_thrusters=4).inject(Fault("thruster_lost", 0.0, 1.0, thruster=5))
