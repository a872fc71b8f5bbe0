"""Control-system behaviours: bumpless gain changes and mode switches, heading-only mode, the
observer coasting through dropouts, signal checks, the system model and the r check."""

import math

import numpy as np
import pytest
from numba import njit

from control import loop, model, quality
from control.config import ControlSettings, Gains
from control.simulation import Simulation
from control.startup import check_mount_vector
from sim import params
from sim.gnc import Hmtrx
from sim.sensors import SENSOR_NAMES, Y_END, Y_FIRST
from tests.helpers import steady_current

MODEL = params.load("model-scale")
FULL = params.load("full-scale")


def test_system_model_mass_is_spd_and_wrench_map_is_the_lever_arm():
    sysm = model.system_model(FULL, 397.0)
    np.testing.assert_allclose(sysm.M, sysm.M.T)
    assert np.linalg.eigvalsh(sysm.M).min() > 0
    # an ROV sway force Y at r = [-2, 0, 0] gives the tree the same Y and a yaw moment
    # r x f = -2 Y (eq. 3.6); the inverse map (eq. 3.7) gives it back
    tau_tree = sysm.rov_to_tree @ np.array([0, 100.0, 0, 0, 0, 0])
    np.testing.assert_allclose(tau_tree[[0, 1, 5]], [0, 100.0, -200.0], atol=1e-9)
    np.testing.assert_allclose(sysm.tree_to_rov @ tau_tree, [0, 100.0, 0, 0, 0, 0], atol=1e-9)
    np.testing.assert_allclose(
        np.linalg.inv(Hmtrx(sysm.r_rov_from_tree_tree_m)),
        Hmtrx(-sysm.r_rov_from_tree_tree_m),
        atol=1e-12,
    )


def test_capacity_matches_the_thrusters():
    """Surge alone with the work-class ROV: the two vectored thrusters at full power give
    2 x 0.9063 x 6550 N; their sway parts cancel and yaw is trimmed by the lateral one."""
    thr = FULL.rov.thrusters
    cap = model.dof_capacity(thr.T, thr.f_max_neg, thr.f_max_pos)
    # rel 1e-3: the LP solver's (HiGHS) feasibility tolerance on the equality rows
    assert cap[0] == pytest.approx(2 * 0.9063 * thr.f_max_pos[2], rel=1e-3)


def test_capacity_is_remembered_per_thruster_set_and_handed_out_as_a_copy():
    """The capacities' linear programs are solved once per thruster set (a campaign's runs
    share one ROV): the same arguments give equal answers that are not one array (a caller
    that writes into its answer cannot change the next caller's), and weaker thrusters give
    a proportionally smaller answer (the memo is keyed on the values, not on the call)."""
    thr = FULL.rov.thrusters
    first = model.dof_capacity(thr.T, thr.f_max_neg, thr.f_max_pos)
    first[:] = -1.0
    again = model.dof_capacity(thr.T, thr.f_max_neg, thr.f_max_pos)
    assert np.all(again > 0.0)
    half = model.dof_capacity(thr.T, 0.5 * thr.f_max_neg, 0.5 * thr.f_max_pos)
    # rel 1e-6: the two programmes are the same up to scale; HiGHS's tolerance is 1e-7 N
    np.testing.assert_allclose(half, 0.5 * again, rtol=1e-6)


def test_gain_change_is_bumpless():
    sim = Simulation(MODEL, tree_depth_m=100.0, current=steady_current())
    sim.run_for(60.0)
    sim.set_target(1.5, 1.0, 0.3)  # a moving reference: errors and rates are not zero
    before = sim.run_for(20.0)["tau_tree_cmd"][-1].copy()
    g = sim.gains
    integral_before = sim.controller_state.tree_integral.copy()
    sim.set_gains(Gains(tuple(2 * v for v in g.kp), g.ki, tuple(3 * v for v in g.kd)))
    after = sim.step(1)["tau_tree_cmd"][0]
    # one step later the command may only move by what one 10 ms step moves it: 2 % of the
    # command (the reference moves 0.6 mm per step) plus 0.5 N of sensor-free round-off
    assert np.abs(after - before).max() < 0.02 * np.abs(before).max() + 0.5
    assert np.array_equal(sim.C.Kp, 2 * np.array(g.kp))
    # the jump that would have happened went into the integral instead (so the test is not
    # passing merely because the errors were zero)
    absorbed = np.abs(sim.controller_state.tree_integral - integral_before).max()
    assert absorbed > 5.0
    assert np.abs(after - before).max() < 0.1 * absorbed


def test_bad_gains_are_refused_with_the_range():
    with pytest.raises(ValueError, match=r"gains.kp\[1\] must be in \[0, 1e\+07\]"):
        Gains((1.0, -2.0, 1.0), (0, 0, 0), (0, 0, 0))
    with pytest.raises(ValueError, match=r"gains.kd\[0\] must be in"):
        Gains((1.0, 1.0, 1.0), (0, 0, 0), (float("nan"), 0, 0))


def test_supervisor_switch_to_free_rov_has_no_thrust_jump_and_keeps_station():
    sim = Simulation(MODEL, tree_depth_m=100.0, current=steady_current(0.05))
    sim.run_for(90.0)
    before = sim.run_for(1.0)["tau_rov_cmd_b"][-1]
    sim.set_grip(False)
    sim.set_mode("free")
    rows = sim.run_for(60.0)
    first = rows["tau_rov_cmd_b"][0]
    assert np.abs(first - before).max() < 2.0  # N, N m: no jump at the hand-over
    assert np.all(rows["mode"] == loop.MODE_FREE)
    assert sim.mode == "free"
    rov = rows["rov_eta_n"]
    # free-flying ROV holds its position (the released tree swings away on its own)
    # 0.3 m: a fifth of Minerva's length; the free controller (0.5 rad/s, critically damped)
    # holds within centimetres of the release point, the margin covers the release transient
    assert np.hypot(rov[-1, 0] - rov[0, 0], rov[-1, 1] - rov[0, 1]) < 0.3
    assert abs(rov[-1, 2] - rov[0, 2]) < 0.3
    # and back onto the tree: the tree controller takes over from the free one without a jump
    sim.set_mode("tree")
    back = sim.step(1)["tau_rov_cmd_b"][0]
    last_free = rows["tau_rov_cmd_b"][-1]
    # 2 N: the same bound as the switch the other way (1 % of Minerva's 200 N reverse thrust)
    assert np.abs(back[[0, 1, 5]] - last_free[[0, 1, 5]]).max() < 2.0


def test_heading_only_mode_holds_heading_and_lets_position_go():
    gains = Gains(tuple(MODEL.gains.kp), tuple(MODEL.gains.ki), tuple(MODEL.gains.kd))
    sim = Simulation(
        MODEL,
        tree_depth_m=100.0,
        current=steady_current(0.1, 90.0),
        settings=ControlSettings(gains=gains.heading_only()),
    )
    sim.set_target(1.0, 1.0, math.radians(30.0))
    rows = sim.run_for(300.0)
    tree = rows["tree_eta_n"]
    # 2 deg: the heading bound for the full-scale square, used here for a hold
    assert abs(math.degrees(tree[-1, 5]) - 30.0) < 2.0
    # no position control: the current (towards east) carries the tree downstream
    # the tree and ROV settle about 0.38 m downstream (their drag over the wire's 100 m
    # stiffness, eq. 2.29-2.30); 0.3 m tells that drift from station keeping, which holds
    # within centimetres
    assert tree[-1, 1] - 1.0 > 0.3
    # no proportional surge/sway action (the terms are P, I, D, FF x [surge, sway, yaw])
    p_terms = rows["control_terms"][:, 0:3]
    assert np.all(p_terms[:, 0:2] == 0.0)
    assert np.any(p_terms[:, 2] != 0.0)  # while the heading loop works


def test_observer_coasts_through_position_dropouts():
    spec = MODEL.spec
    sensors = spec.sensors.model_copy(
        update={"position": spec.sensors.position.model_copy(update={"dropout_probability": 0.97})}
    )
    ps = params.build(spec.model_copy(update={"sensors": sensors}))
    sim = Simulation(
        ps,
        tree_depth_m=100.0,
        current=steady_current(),
        settings=ControlSettings(feedback="ekf"),
        seed=3,
    )
    rows = sim.run_for(300.0)
    fixes = rows["accepted"][:, SENSOR_NAMES.index("position")].sum()
    assert 0 < fixes < 20  # 300 fixes due, 97 % lost
    tree = rows["tree_eta_n"]
    err = np.hypot(rows["eta_hat_n"][:, 0] - tree[:, 0], rows["eta_hat_n"][:, 1] - tree[:, 1])
    # DVL, gyro and compass keep the estimate within 0.3 m without position fixes
    # 0.3 m: three times the position fix's noise (0.1 m, parameter set): the estimate without
    # fixes must stay as good as a single raw fix would be
    assert err[3000:].max() < 0.3
    # 0.5 m: the 0.3 m estimate error plus the tree's drift before the integrator catches up
    assert np.hypot(*(tree[-1, 0:2] - 1.0)) < 0.5


def test_signal_checks_count_each_failure():
    noise = np.full(11, 0.1)
    cfg = quality.quality_config(noise, 0.01)
    last = np.zeros(11)
    last_t = -np.ones(5)
    repeat = np.zeros(5, np.int64)
    hist = np.zeros((11, quality.WINDOW))
    counters = np.zeros((5, 4), np.int64)

    def check(k, y, t):
        return quality.check_sample(
            k,
            y,
            t,
            last,
            last_t,
            repeat,
            hist,
            counters,
            cfg.lo,
            cfg.hi,
            cfg.wild_jump,
            cfg.max_rate,
            cfg.frozen_count,
            cfg.variance_limit,
            Y_FIRST,
            Y_END,
        )

    y = np.zeros(11)
    y[0:3] = [10.0, 5.0, 100.0]
    assert check(0, y, 0.0)
    y2 = y.copy()
    y2[0] = 13.0  # a 3 m jump in 1 s: beyond 8 sigma + 2 m/s
    assert not check(0, y2, 1.0)
    assert counters[0, quality.WILD] == 1
    y3 = y.copy()
    y3[2] = 7000.0  # deeper than any plausible site
    assert not check(0, y3, 2.0)
    assert counters[0, quality.RANGE] == 1
    for i in range(6):  # the same value again and again: frozen
        ok = check(0, y, 3.0 + i)
    assert not ok and counters[0, quality.FROZEN] >= 1
    rng = np.random.default_rng(0)
    for i in range(12):  # wildly varying but plausible: flagged, still used
        yv = y.copy()
        yv[0] += rng.normal(0, 1.5)
        check(0, yv, 20.0 + 2 * i)
    assert counters[0, quality.VARIANCE] >= 1


@njit
def _numba_var(h):
    return h.var()


def test_the_checks_variance_is_numbas_method_bit_for_bit():
    # quality.variance replaces ``h.var()`` in the compiled checks: the same bits on
    # histories of differences (tiny, huge, mixed signs, zeros of both signs, exact ties),
    # and the same non-numbers
    rng = np.random.default_rng(3)
    cases = [rng.normal(size=quality.WINDOW) * 10.0 ** rng.integers(-12, 6) for _ in range(2000)]
    cases += [rng.integers(-3, 4, quality.WINDOW).astype(float) * 0.1 for _ in range(200)]
    cases += [
        np.zeros(quality.WINDOW),
        np.full(quality.WINDOW, -0.0),
        np.r_[np.full(quality.WINDOW - 1, 1e300), -1e300],
        np.r_[np.zeros(quality.WINDOW - 1), np.inf],
        np.r_[np.zeros(quality.WINDOW - 1), np.nan],
    ]
    for h in cases:
        want, got = _numba_var(h), quality.variance(h)
        assert np.float64(want).tobytes() == np.float64(got).tobytes() or (
            math.isnan(want) and math.isnan(got)
        ), h
    assert quality.variance(np.arange(4.0)) == 1.25  # (2.25 + 0.25 + 0.25 + 2.25) / 4


def test_startup_check_accepts_the_right_r_and_flags_the_flipped_one():
    r = np.array([-2.0, 0.0, 0.0])
    y = np.zeros(11)
    y[0:2] = [1.0 - 2.0, 1.0]  # ROV 2 m south of the tree hanging at the crane tip, heading 0
    ok = check_mount_vector(y, r, np.array([1.0, 1.0, 0.0]), 197.0, MODEL, 0.1)
    assert ok.checked and not ok.warnings
    bad = check_mount_vector(y, -r, np.array([1.0, 1.0, 0.0]), 197.0, MODEL, 0.1)
    assert bad.residual_m == pytest.approx(4.0) and bad.residual_flipped_m == pytest.approx(0.0)
    assert "wrong sign" in bad.warnings[0]


def test_full_turn_is_possible_and_short_way_is_default():
    sim = Simulation(FULL, tree_depth_m=400.0)
    sim.run_for(1.0)
    sim.set_target(1.0, 1.0, math.radians(350.0))  # short way: -10 deg
    assert sim.target[2] == pytest.approx(math.radians(-10.0))
    sim.set_target(1.0, 1.0, 2 * math.pi, heading_mode="absolute")
    assert sim.target[2] == pytest.approx(2 * math.pi)
    with pytest.raises(ValueError, match="heading_mode must be"):
        sim.set_target(1.0, 1.0, 0.0, heading_mode="sideways")
    with pytest.raises(ValueError, match="target north_m must be finite"):
        sim.set_target(float("nan"), 1.0, 0.0)


def test_log_rows_carry_the_site_vessel_wire_and_tension():
    """The log holds the crane tip, the wire's payout and its tension each step, so a replay
    shows the vessel where it was and the wire-slack alarm works on recordings too."""
    sim = Simulation(MODEL, tree_depth_m=100.0)
    sim.move_vessel(np.array([3.0, 1.0, 0.0]), speed_mps=0.5)
    rows = sim.run_for(10.0)
    crane = rows["crane_tip_ne"]
    assert crane[0, 0] == pytest.approx(1.0 + 0.5 * 0.01)  # one step at 0.5 m/s
    assert crane[-1, 0] == pytest.approx(3.0)  # arrived after 4 s
    np.testing.assert_allclose(crane[:, 1], 1.0)
    # hanging still, the wire carries the tree's submerged weight less the ROV's net
    # buoyancy (1 % of its weight): within 1 %
    tension = rows["wire_tension"]
    assert tension[0] == pytest.approx(MODEL.tree.submerged_weight_newton, rel=0.01)
    payout = rows["wire_rest_length"][-1]
    sim.winch_to(sim.wire_length_m - 2.0, 0.5)  # haul in 2 m
    hauled = sim.run_for(5.0)["wire_rest_length"]
    # 2 m in 4 s (the self-weight stretch of the shorter wire changes by a millimetre)
    assert hauled[-1] == pytest.approx(payout - 2.0, abs=1e-3)
    assert hauled[0] == pytest.approx(payout - 0.5 * 0.01, abs=1e-6)
    # then pay out at the winch's top speed (2 m/s): the wire runs out faster than the
    # tree can sink on it, goes slack, and the log shows zero tension
    sim.winch_to(sim.wire_length_m + 10.0, 2.0)
    slack = sim.run_for(0.5)["wire_tension"]
    assert slack[0] > 0.0
    assert np.any(slack == 0.0)
