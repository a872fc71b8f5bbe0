"""Automatic landings on the docking frame (issue 11): the failures the issue reported, each
rerun, and the tree staying where the posts hold it once landed."""

import math

import numpy as np
import pytest

from missions import landing, runner, schema
from sim import params, plant

LAYOUT = params.load("full-scale").spec.docking.to_numeric()


def docking_variant(
    heading_deg: float | None = None,
    speed_mps: float | None = None,
    direction_deg: float | None = None,
    center_ne_m: tuple[float, float] | None = None,
    vessel: str = "fixed",
) -> schema.Mission:
    """full-docking-current-0.3 with another frame heading or current; the vessel fixed, as
    when these landings were first reported (``vessel = "auto"``, the default, moves it:
    ``tests/test_vessel_assist.py``)."""
    m = schema.load_mission("full-docking-current-0.3").model_dump(mode="json")
    for leg in m["legs"]:
        if leg["type"] == "dock":
            leg["vessel"] = vessel
    if heading_deg is not None:
        m["setup"]["docking_frame"]["heading_deg"] = heading_deg
    if center_ne_m is not None:
        m["setup"]["docking_frame"]["center_ne_m"] = list(center_ne_m)
    if speed_mps is not None:
        m["setup"]["current"]["speed_mps"] = speed_mps
    if direction_deg is not None:
        m["setup"]["current"]["direction_deg"] = direction_deg
    return schema.parse_mission(m)


def assert_landed_and_held(result: runner.MissionResult, heading_deg: float) -> None:
    """Landed on the frame, and from touchdown to the end of the mission the tree stays with
    its funnels around the posts: heading within the posts' clearance of the frame's (plus
    0.2 deg for the posts' elastic give under the ROV's thrust)."""
    assert not result.failed, result.summary()
    (landing,) = result.landings
    assert landing.success and landing.rests_on == "frame"
    assert landing.rest_miss_m <= LAYOUT.clearance_m + 0.01
    assert result.log is not None
    rows = result.log
    after = rows["t_s"] >= landing.t_contact_s + 60.0
    psi = rows["tree_eta_n"][after, 5]
    err = np.degrees(np.abs((psi - math.radians(heading_deg) + math.pi) % (2 * math.pi) - math.pi))
    assert err.size > 1000
    assert err.max() <= math.degrees(LAYOUT.heading_clearance_rad) + 0.2


def test_frame_at_180_deg_lands_and_stays():
    """Issue 11: with the frame turned 180 deg the tree 'landed' and then turned 26 deg while
    resting on the frame."""
    result = runner.run_mission(docking_variant(heading_deg=180.0))
    assert_landed_and_held(result, 180.0)


@pytest.mark.parametrize("heading_deg", [90.0, -90.0])
def test_forced_landings_the_issue_reported_land_and_stay(heading_deg, monkeypatch):
    """Issue 11: with the frame at 90 or 150 deg the tree ended on the post tops although its
    funnels met them within the capture tolerance; at -90 deg it 'landed' and then turned 44
    deg on the frame. The feasibility check now refuses these (see the next test: they need
    more than 90 % of the thrust); forced past it, the contact guides the tree down and holds
    it there. 150 deg is left out: in this seed's current it needs 112 % of the thrust, and
    forced it saturates for 2 111 s and times out, as the refusal says it would (it landed
    with the draws before each purpose had a stream of its own, when the walking current
    eased enough); 90 and -90 deg need 101 %, at the edge, and land."""
    monkeypatch.setattr(landing, "FEASIBLE_UTILISATION", 5.0)
    result = runner.run_mission(docking_variant(heading_deg=heading_deg))
    (done,) = result.landings
    assert done.miss_m < LAYOUT.tolerance_m  # captured at the post tops, as in the report
    assert_landed_and_held(result, heading_deg)


@pytest.mark.parametrize("heading_deg, needed_pct", [(90.0, 101), (120.0, 125), (150.0, 112)])
def test_landing_the_rov_cannot_hold_is_refused_with_the_forces(heading_deg, needed_pct):
    """Issue 11: at 120 deg the tree never aligned (2 325 s saturated, the leg timed out).
    Holding the tree over a frame turned 90 to 150 deg in 0.3 m/s needs more than the ROV's
    thrust: the dock leg refuses before it starts, naming the force and moment needed and
    available (the percentages are the planner's own figures, kept here so a change in them
    shows), and the mission fails with that error instead of trying. The current walks from
    0.3 m/s during the first leg's 120 s: 0.284 m/s when the dock leg starts, with the seed's
    draws."""
    result = runner.run_mission(docking_variant(heading_deg=heading_deg))
    assert result.failed and not result.landings
    assert result.error.startswith(
        "leg 2 (dock) failed: landing not feasible in 0.284 m/s towards 226 deg"
    )
    assert "kN m of yaw moment needed" in result.error and "available" in result.error
    assert f"({needed_pct} % of the thrust), more than the 90 % allowed" in result.error
    assert result.legs[1].duration_s < 1.0  # refused at once


def test_weak_current_case_the_issue_reported_lands_and_stays():
    """Issue 11: 0.1 m/s towards 42.9 deg, frame at 129.6 deg at (4.0, 2.5): the funnels met
    the post tops 0.068 m off with 1.3 deg of heading error at 0.032 m/s, the tree stayed on
    the posts and 35 s later wandered 10 m and spun through 2 000 deg."""
    result = runner.run_mission(
        docking_variant(heading_deg=129.6, speed_mps=0.1, direction_deg=42.9)
    )
    (landing,) = result.landings
    assert landing.miss_m < LAYOUT.tolerance_m  # captured, as in the report
    assert_landed_and_held(result, 129.6)
    final = result.final_eta_n
    assert math.hypot(final[0] - 4.0, final[1] - 2.5) < LAYOUT.clearance_m + 0.01


def test_planner_force_is_the_wire_pull_back_in_still_water():
    """The force the planner says holds the tree 2 m north of its hang in still water is the
    wire's horizontal stiffness (eq. 2.30) times 2 m, within 5 % (the pendulum's tilt about
    the attachment point adds about 0.7 %), along surge at heading 0 and with no sway or yaw
    to speak of; at the hang itself nothing is needed."""
    from control.simulation import Simulation
    from sim import params as params_mod
    from sim import site
    from sim import wire as wm

    ps = params_mod.load("full-scale")
    sim = Simulation(ps, tree_depth_m=400.0)
    thrusters = landing.Thrusters(sim)
    env = site.wire_environment(ps, sim.wire_length_for_depth(400.0), sim.crane_tip_n, 0.0, 0.0)
    hang = sim.crane_tip_n
    k = wm.horizontal_stiffness(
        ps.wire.submerged_weight_per_length(), ps.tree.submerged_weight_newton, sim.wire_length_m
    )
    load = landing.pose_load(sim, thrusters, hang[0] + 2.0, hang[1], 0.0, env, 400.0)
    assert load.needed_xyn[0] == pytest.approx(2.0 * k, rel=0.05)
    assert abs(load.needed_xyn[1]) < 0.01 * abs(load.needed_xyn[0])
    # the surge force acts 2 m ahead of the ROV (the tree's centre): no yaw from it
    assert abs(load.needed_xyn[2]) < 0.01 * abs(load.needed_xyn[0])
    assert 0.0 < load.utilisation < 1.0
    still = landing.pose_load(sim, thrusters, hang[0], hang[1], 0.0, env, 400.0)
    assert np.linalg.norm(still.needed_xyn) < 0.01 * abs(load.needed_xyn[0])


def _needed_with_numpy(sim, north, east, psi, env, depth_m):
    """The hold force as ``missions.landing.pose_load`` worked it out before the compiled
    ``sim.plant.hold_needed_xyn``: numpy's products and the plant's two wrench calls."""
    from sim import plant
    from sim.gnc import Rzyx

    arr = sim.arrays
    x = np.zeros(plant.N_STATE)
    x[0:3] = north, east, depth_m
    x[5] = psi
    rot_t = Rzyx(0.0, 0.0, psi)
    rot_m = arr.mount_R
    x[12:15] = x[0:3] + rot_t @ arr.mount_r
    x[17] = psi + math.atan2(rot_m[1, 0], rot_m[0, 0])
    w_tree = plant.tree_wrench(x, env, arr, rot_t)
    w_rov = plant.rov_wrench(x, np.zeros(arr.thr_T.shape[1]), env, arr, rot_t @ rot_m)
    f = rot_m.T @ w_tree[0:3]
    r = -(rot_m.T @ arr.mount_r)
    m_z = (rot_m.T @ w_tree[3:6])[2] + (r[0] * f[1] - r[1] * f[0])
    return -np.array([f[0] + w_rov[0], f[1] + w_rov[1], m_z + w_rov[5]])


def test_compiled_hold_force_is_the_numpy_form():
    """``sim.plant.hold_needed_xyn`` (all of a turn's headings in one compiled call) gives
    the numpy form's forces at 60 poses around the frame in a 0.4 m/s current, to 1e-12 of
    the largest component (the rotations' products are summed in another order than
    OpenBLAS's: the last bits only)."""
    from control.simulation import Simulation
    from sim import params as params_mod
    from sim import plant

    ps = params_mod.load("full-scale")
    sim = Simulation(ps, tree_depth_m=395.0)
    env = landing._environment(sim, 395.0, 0.4, math.radians(200.0))
    rng = np.random.default_rng(3)
    poses = np.column_stack(
        [rng.uniform(-5.0, 5.0, 60), rng.uniform(-5.0, 5.0, 60), rng.uniform(-4.0, 4.0, 60)]
    )
    got = plant.hold_needed_xyn(poses, 395.0, env, sim.arrays)
    for pose, row in zip(poses, got, strict=True):
        want = _needed_with_numpy(sim, *pose, env, 395.0)
        assert np.abs(row - want).max() <= 1e-12 * np.abs(want).max(), (pose, row, want)
    assert np.abs(got).max() > 1e3  # real forces, not zeros


def test_a_small_random_set_of_landings_lands_where_it_is_accepted():
    """Issue 11: a few landings drawn at random (the Monte Carlo's draw, seed 1 at full scale
    and 2 at model scale, as `benchmarks/landing_montecarlo.py --seed 1` draws them): every one
    the feasibility check accepts lands on the frame, and each one refused says why."""
    from missions import landing_study

    cases = landing_study.random_cases(2, "full", 1) + landing_study.random_cases(2, "model", 2)
    outcomes = [landing_study.run_case(c) for c in cases]
    summary = landing_study.summary(outcomes)
    assert sum(s["accepted"] for s in summary.values()) >= 2  # the set tests something
    for s in summary.values():
        assert s["failures"] == []
    for o in outcomes:
        assert o.feasible == (not o.verdict.startswith("refused")), o.verdict
        if not o.feasible:
            assert "of yaw moment needed" in o.verdict and "available" in o.verdict


def test_random_cases_name_an_unknown_scale():
    from missions import landing_study

    known = "full, model, installation"
    with pytest.raises(ValueError, match=f"scale must be one of {known}, got 'huge'"):
        landing_study.random_cases(1, "huge", 0)


def _vectored_four() -> object:
    """A sim stand-in with four horizontal thrusters at 45 deg (one more than the three
    equations: the closed form's two-unknown case) and a vertical one."""
    from types import SimpleNamespace

    c = math.cos(math.pi / 4)
    T = np.zeros((6, 5))
    T[0, :4] = [c, c, -c, -c]
    T[1, :4] = [c, -c, c, -c]
    T[5, :4] = [0.5, -0.5, -0.5, 0.5]
    T[2, 4] = 1.0
    arrays = SimpleNamespace(
        thr_T=T,
        thr_k_pos=np.array([2.0, 2.0, 2.0, 2.0, 1.0]),
        thr_k_neg=np.ones(5),
        thr_n_max=np.full(5, 30.0),
    )
    return SimpleNamespace(arrays=arrays)


def _thrusters(layout: str) -> landing.Thrusters:
    """The thrusters of a library ROV (``full-scale``, ``model-scale``) or of
    ``_vectored_four``."""
    from control.simulation import Simulation
    from sim import params as params_mod

    if layout == "vectored-four":
        return landing.Thrusters(_vectored_four())  # type: ignore[arg-type]
    depth = 400.0 if layout == "full-scale" else 2.0
    return landing.Thrusters(Simulation(params_mod.load(layout), tree_depth_m=depth))


@pytest.mark.parametrize("layout", ["full-scale", "model-scale", "vectored-four"])
def test_closed_form_reach_is_the_linear_programmes_optimum(layout):
    """The thrusters' reach in a direction, in closed form, equals scipy's HiGHS optimum of
    the same linear programme in 500 random directions, to 1e-9 relative (HiGHS's primal
    feasibility tolerance is 1e-7 absolute on forces of 1e2-1e4 N; the two agree to some
    1e-14 in fact), for both ROVs (as many thrusters in the plane as equations) and a
    layout with one thruster more (the two-unknown vertex enumeration)."""
    thrusters = _thrusters(layout)
    assert thrusters._nullity == (1 if layout == "vectored-four" else 0)
    rng = np.random.default_rng(3)
    for _ in range(500):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        assert thrusters.reach(d) == pytest.approx(thrusters._reach_highs(d), rel=1e-9)


@pytest.mark.parametrize("layout", ["full-scale", "model-scale", "vectored-four"])
def test_reach_of_many_directions_is_reach_of_each(layout):
    """``Thrusters.reach_each`` (the landing plan's poses at once) gives each direction's
    ``reach`` bit for bit: 300 random directions, some along a single axis (a thruster's
    p of exactly zero takes the no-limit branch) and one of zero force."""
    thrusters = _thrusters(layout)
    rng = np.random.default_rng(8)
    d = rng.normal(size=(300, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    d[:3] = np.eye(3)
    d[3] = 0.0
    one_by_one = np.array([thrusters.reach(row) for row in d])
    assert np.array_equal(thrusters.reach_each(d), one_by_one)
    assert np.all(one_by_one[4:] > 0.0)
    assert thrusters.reach_each(np.zeros((0, 3))).shape == (0,)


def test_pose_loads_at_once_are_each_poses_load():
    """``pose_loads`` of many poses (one compiled call for the forces, the reaches at once)
    gives each pose what it gives alone: the same needed and available forces, bit for bit,
    over a turn of headings in a 0.4 m/s current."""
    from control.simulation import Simulation
    from sim import params as params_mod

    sim = Simulation(params_mod.load("full-scale"), tree_depth_m=400.0)
    thrusters = landing.Thrusters(sim)
    env = landing._environment(sim, 390.0, 0.4, 0.7)
    poses = np.column_stack(
        [np.full(40, 3.0), np.full(40, -2.0), np.linspace(-math.pi, math.pi, 40)]
    )
    together = landing.pose_loads(sim, thrusters, poses, env, 390.0)
    for pose, load in zip(poses, together, strict=True):
        # one pose, as pose_loads made it pose by pose before (the forces, the norm, reach)
        (needed,) = plant.hold_needed_xyn(pose[None, :].copy(), 390.0, env, sim.arrays)
        unit = needed / float(np.linalg.norm(needed))
        assert np.array_equal(load.needed_xyn, needed)
        assert np.array_equal(load.available_xyn, unit * thrusters.reach(unit))
    assert len({round(load.utilisation, 9) for load in together}) > 20  # the poses differ
