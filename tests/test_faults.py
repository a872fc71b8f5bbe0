"""Injected faults (control.faults) act through ``Simulation`` on what the control system sees
and on the environment, each from its own step: their effects, and where the control system's
own checks can see them, the detection."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.console.alarms import AlarmLimits, AlarmMonitor
from control.columns import LogRows
from control.config import ControlSettings
from control.faults import Fault
from control.simulation import Simulation
from sim import params, plant
from sim.sensors import SENSOR_NAMES
from tests.helpers import steady_current

MODEL = params.load("model-scale")
DVL, POSITION = SENSOR_NAMES.index("dvl"), SENSOR_NAMES.index("position")


def ekf_sim(**kwargs) -> Simulation:
    return Simulation(
        MODEL,
        tree_depth_m=100.0,
        current=steady_current(),
        settings=ControlSettings(feedback="ekf"),
        seed=4,
        **kwargs,
    )


def test_dvl_lost_stops_its_samples_for_the_window_and_the_dropout_alarm_sees_it():
    sim = ekf_sim()
    sim.inject_fault(Fault("dvl_lost", start_s=5.0, duration_s=10.0))
    rows = sim.run_for(20.0)
    t, accepted = rows.t_s, rows["accepted"][:, DVL] > 0.5
    inside = (t > 5.0 + 0.01) & (t < 15.0)
    assert not accepted[inside].any(), "no DVL sample accepted while its cable is broken"
    assert accepted[t < 5.0].any() and accepted[t > 15.5].any(), "before and after it is"
    monitor = AlarmMonitor(AlarmLimits.for_params(MODEL), 5, 1.0, uses_sensors=True)
    k = int(np.searchsorted(t, 14.0))
    monitor.update(LogRows(rows.data[:k], rows.n_thrusters), None)
    assert any(a.name == "dropout" and a.active and "dvl" in a.message for a in monitor.state)
    assert sim.active_faults() == []


def test_wild_position_points_are_caught_by_the_signal_check():
    clean, faulty = ekf_sim(), ekf_sim()
    faulty.inject_fault(Fault("position_wild_points", 2.0, 10.0, value=5.0))
    clean.run_for(15.0)
    faulty.run_for(15.0)
    wild = SENSOR_NAMES.index("position"), 1  # check 1: wild point
    assert clean.quality_counters[wild] == 0
    assert faulty.quality_counters[wild] >= 3, "the signal check flags the jumps"


def test_compass_bias_shifts_the_compass_by_the_bias():
    sim = ekf_sim()
    sim.inject_fault(Fault("compass_bias", 1.0, 5.0, value=20.0))
    rows = sim.run_for(4.0)
    psi_meas, psi_rov = rows["y"][-1, 4], rows["rov_eta_n"][-1, 5]
    error = math.degrees(math.remainder(psi_meas - psi_rov, 2 * math.pi))
    # compass noise (appendix B: a fraction of a degree) on top of the 20 deg bias
    assert error == pytest.approx(20.0, abs=2.0)


def test_winch_slip_drops_the_tree_at_once():
    sim = ekf_sim()
    sim.run_for(2.0)
    depth0, length0 = sim.tree_eta_n[2], sim.wire_length_m
    sim.inject_fault(Fault("winch_slip", start_s=3.0, duration_s=1.0, value=0.8))
    rows = sim.run_for(6.0)
    assert sim.wire_length_m == pytest.approx(length0 + 0.8)
    jump = np.diff(rows["wire_rest_length"])
    # paid out in one step (the rest length also holds the wire's own stretch, 0.1 mm more)
    assert jump.max() == pytest.approx(0.8, abs=1e-3), "paid out in one step"
    assert rows.t_s[int(np.argmax(jump)) + 1] == pytest.approx(3.01, abs=1e-9)
    # the tree falls the slip (it rings on the wire's spring: more than half of it at once)
    assert rows["tree_eta_n"][:, 2].max() - depth0 > 0.5


def test_current_turn_and_vessel_drift_move_the_site():
    base = dict(tree_depth_m=100.0, control=False, current=steady_current(0.2, 0.0))
    calm, turned = Simulation(MODEL, **base), Simulation(MODEL, **base)
    turned.inject_fault(Fault("current_turn", 0.0, 300.0, value=90.0))
    start = calm.tree_eta_n[0:2].copy()
    calm.run_for(120.0)
    turned.run_for(120.0)
    # the tree drifts downstream: north in the plain current, east once it turns 90 deg
    d_calm, d_turned = calm.tree_eta_n[0:2] - start, turned.tree_eta_n[0:2] - start
    assert d_calm[0] > 0.3 and abs(d_calm[1]) < 0.05
    assert d_turned[1] > 0.3 and abs(d_turned[0]) < 0.05
    drifting = Simulation(MODEL, tree_depth_m=100.0, control=False)
    tip0 = drifting.crane_tip_n.copy()
    drifting.inject_fault(Fault("vessel_drift", 1.0, 10.0, value=0.1, direction_deg=90.0))
    drifting.run_for(20.0)
    np.testing.assert_allclose(drifting.crane_tip_n - tip0, [0.0, 1.0, 0.0], atol=1e-9)


def test_mount_vector_with_the_wrong_sign_spoils_the_turn_and_is_undone_after():
    """The sea trial's wrong sign of r (thesis 6.2.1): the observer puts the tree on the wrong
    side of the ROV, so a 60 deg turn crawls (about half the heading after 30 s, measured
    43 deg against 21 deg); once the window ends the configured vector is back."""

    def turned(fault: bool) -> tuple[float, Simulation]:
        sim = ekf_sim()
        if fault:
            sim.inject_fault(Fault("mount_sign", 0.0, 30.0))
        sim.set_target(*sim.tree_eta_n[0:2], math.radians(60.0))
        sim.run_for(30.0)
        return math.degrees(sim.tree_eta_n[5]), sim

    good, _ = turned(False)
    bad, sim = turned(True)
    assert good > 35.0 and bad < 0.6 * good
    r = sim.sysm.r_rov_from_tree_tree_m.copy()
    sim.run_for(1.0)
    np.testing.assert_allclose(sim.sysm.r_rov_from_tree_tree_m, -r)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"kind": "gremlins", "start_s": 0, "duration_s": 1}, "fault kind must be one of"),
        ({"kind": "dvl_lost", "start_s": 0, "duration_s": -1}, "duration_s must be in [0"),
        ({"kind": "dvl_lost", "start_s": 0, "duration_s": 0}, "duration_s must be more than 0"),
        ({"kind": "dvl_lost", "start_s": math.nan, "duration_s": 1}, "start_s must be in"),
        ({"kind": "winch_slip", "start_s": 0, "duration_s": 1, "value": 9}, "[0.05, 5] m"),
        ({"kind": "dvl_lost", "start_s": 0, "duration_s": 1, "value": 2}, "takes no value"),
    ],
)
def test_bad_faults_are_refused_naming_the_field(kwargs, words):
    with pytest.raises(ValueError, match=__import__("re").escape(words)):
        Fault(**kwargs)


def test_faults_written_in_a_mission_file_act_and_are_logged_as_events():
    from missions import runner, schema

    text = """
format_version = 1
name = "dvl-cable"
[setup]
params = "model-scale"
depth_m = 100.0
feedback = "ekf"
[[legs]]
type = "hold"
duration_s = 20.0
[[faults]]
kind = "dvl_lost"
start_s = 5.0
duration_s = 8.0
"""
    result = runner.run_mission(schema.parse_text(text, "<test>"))
    faults = [e for e in result.events if e["kind"] == "fault"]
    assert [(e["t_s"], e["text"]) for e in faults] == [
        (5.0, "fault: dvl lost from 5 s for 8 s"),
        (13.0, "fault over: dvl_lost"),
    ]
    assert result.quality_counters is not None
    bad = text.replace('kind = "dvl_lost"', 'kind = "winch_slip"\nvalue = 12.0')
    with pytest.raises(
        ValueError, match=r"faults\[1\]: fault winch_slip value must be in \[0\.05, 5\] m"
    ):
        schema.parse_text(bad, "<test>")


def _held_in_current(fault: Fault | None) -> tuple[LogRows, Simulation]:
    """Station keeping in a 0.15 m/s current for 30 s, then 60 s more (with ``fault``)."""
    sim = Simulation(
        MODEL,
        tree_depth_m=100.0,
        current=steady_current(0.15, 0.0),
        settings=ControlSettings(feedback="ekf"),
        seed=4,
    )
    sim.run_for(30.0)
    if fault is not None:
        sim.inject_fault(fault)
    return sim.run_for(60.0), sim


def test_a_lost_thruster_gives_no_thrust_and_the_others_and_saturation_answer():
    """Thruster 1 (surge, port) lost for 60 s in a current: the plant gets no thrust from it
    whatever speed it is told (the control system is not told and keeps allocating to it), so
    the controller's integral winds it up to saturation, the saturation alarm comes on, and the
    tree drifts further than without the fault (measured 0.99 m against 0.25 m)."""
    clean, _ = _held_in_current(None)
    lost, sim = _held_in_current(Fault("thruster_lost", 30.0, 60.0, thruster=1))
    inside = lost.t_s > 30.5
    speeds = lost["thruster_speed"][inside]
    from sim.thrusters import thrust_from_speed

    a = sim.arrays
    delivered = np.array(
        [thrust_from_speed(n, a.thr_k_pos, a.thr_k_neg, a.thr_n_max) for n in speeds]
    )
    assert np.abs(speeds[:, 0]).max() > 1.0, "it is told to turn"
    assert np.all(delivered[:, 0] == 0.0), "and gives nothing"
    assert np.abs(delivered[:, 1]).max() > 1.0, "the others still push"
    util_clean, util_lost = clean["thruster_utilisation"], lost["thruster_utilisation"]
    assert (util_clean >= 0.99).mean() == 0.0 and (util_lost[:, 0] >= 0.99).mean() > 0.05
    monitor = AlarmMonitor(AlarmLimits.for_params(MODEL), 5, 1.0, uses_sensors=True)
    monitor.update(lost, None)
    assert any(
        a.name == "saturation" and a.active and "thruster 1" in a.message for a in monitor.state
    )

    def drift(rows: LogRows) -> float:
        d = rows["tree_eta_n"][:, 0:2] - rows["tree_eta_n"][0, 0:2]
        return float(np.hypot(d[:, 0], d[:, 1]).max())

    assert drift(lost) > 2.0 * drift(clean)
    sim.run_for(1.0)  # the window is over: the thruster is back
    np.testing.assert_array_equal(sim.arrays.thr_k_pos, plant.plant_arrays(MODEL).thr_k_pos)


def test_a_weakened_thruster_gives_its_share_of_the_thrust():
    """Efficiency 0.4 on thruster 2: the thrust the plant gets for a speed is 0.4 of the
    healthy thruster's (eq. 2.13 with the coefficient scaled), exactly, at every step."""
    rows, sim = _held_in_current(Fault("thruster_weakened", 30.0, 60.0, value=0.4, thruster=2))
    from sim.thrusters import thrust_of_one

    healthy, weak = plant.plant_arrays(MODEL), sim.arrays
    for n in rows["thruster_speed"][rows.t_s > 30.5][::500, 1]:
        args = (healthy.thr_k_pos[1], healthy.thr_k_neg[1], healthy.thr_n_max[1])
        full = thrust_of_one(n, *args)
        got = thrust_of_one(n, weak.thr_k_pos[1], weak.thr_k_neg[1], weak.thr_n_max[1])
        assert got == pytest.approx(0.4 * full, rel=1e-12)
    assert weak.thr_k_pos[0] == healthy.thr_k_pos[0], "the other thrusters are whole"


def test_a_frozen_compass_repeats_its_heading_and_the_frozen_check_flags_it():
    """Compass frozen from 5 s for 30 s while the tree turns 40 deg: the measured heading stays
    at the value it had while the true heading changes, and the signal check's frozen counter
    (identical samples in a row) counts the compass's samples, so the observer stops using
    them; once thawed the compass follows the heading again."""
    sim = ekf_sim()
    sim.inject_fault(Fault("compass_freeze", 5.0, 30.0))
    sim.set_target(*sim.tree_eta_n[0:2], math.radians(40.0))
    rows = sim.run_for(40.0)
    t, psi_meas, psi_rov = rows.t_s, rows["y"][:, 4], rows["rov_eta_n"][:, 5]
    inside = (t > 5.2) & (t < 35.0)
    assert np.ptp(psi_meas[inside]) == 0.0, "held exactly"
    assert np.ptp(psi_rov[inside]) > math.radians(20.0), "while the ROV turns"
    compass = SENSOR_NAMES.index("compass")
    assert sim.quality_counters[compass, 2] > 100, "the frozen check counts it"
    after = t > 36.0
    error = np.abs(np.remainder(psi_meas[after] - psi_rov[after] + np.pi, 2 * np.pi) - np.pi)
    # thawed, it measures again: noise of a fraction of a degree, plus up to about 3 deg of
    # sample-and-hold lag while the ROV still turns between two compass samples
    assert np.median(error) < math.radians(1.0)


def test_thruster_faults_name_a_thruster_the_rov_has():
    sim = ekf_sim()
    with pytest.raises(ValueError, match=r"fault thruster must be in \[1, 5\]"):
        sim.inject_fault(Fault("thruster_lost", 0.0, 1.0, thruster=6))
    with pytest.raises(ValueError, match="names no thruster"):
        Fault("dvl_lost", 0.0, 1.0, thruster=2)


def test_thruster_faults_in_a_mission_file_name_their_thruster():
    from missions import schema, setup

    text = """
format_version = 1
name = "weak-thruster"
[setup]
params = "model-scale"
depth_m = 100.0
[[legs]]
type = "hold"
duration_s = 1.0
[[faults]]
kind = "thruster_weakened"
start_s = 0.0
duration_s = 5.0
value = 0.5
thruster = 2
"""
    sim = setup.build_simulation(schema.parse_text(text, "<test>"))
    assert [(f.kind, f.thruster, f.value) for f in sim.faults] == [("thruster_weakened", 2, 0.5)]
    with pytest.raises(ValueError, match=r"faults\[1\]: fault thruster must be a thruster number"):
        schema.parse_text(text.replace("thruster = 2", "thruster = 40"), "<test>")
    with pytest.raises(ValueError, match=r"fault thruster must be in \[1, 5\]"):
        setup.build_simulation(
            schema.parse_text(text.replace("thruster = 2", "thruster = 7"), "<t>")
        )
