"""Contact of the tree with the docking frame, its guideposts and the seabed (issue 11), each
against something independent of the contact code: conservation of energy, the gradient of the
contact energy, the geometry of the funnels."""

import math

import numpy as np
import pytest

from control.simulation import Simulation
from sim import params, plant, site
from sim.docking import DockingFrame, check_alignment
from sim.gnc import Rzyx, Tzyx

FULL = params.load("full-scale")
MODEL = params.load("model-scale")
SCALES = {"full": FULL, "model": MODEL}
LAND_M = 100.0
FRAME_PSI = 0.3


def _frame_env(ps: params.ParameterSet, depth_below_landing_m: float) -> np.ndarray:
    """Still water, crane tip over the frame's centre (the origin); the wire long enough to
    hang the tree's bottom ``depth_below_landing_m`` below the landing surface."""
    h = float(ps.tree.dimensions_m[2])
    length = site.wire_length_for_depth(ps, LAND_M - h / 2 + depth_below_landing_m, 0.0, 0.0)
    env = site.wire_environment(ps, length, np.zeros(3), 0.0, 0.0)
    env[plant.E_FRAME : plant.E_FRAME + 2] = 0.0
    env[plant.E_FRAME_PSI] = FRAME_PSI
    env[plant.E_LAND] = LAND_M
    return env


def _energy(x: np.ndarray, env: np.ndarray, P: plant.PlantArrays) -> float:
    """Kinetic energy, wire spring, net weight and contact springs [J]."""
    nu = x[6:12]
    kinetic = 0.5 * nu @ (P.tree_M_rb + P.tree_M_a) @ nu
    p_att = x[0:3] + Rzyx(x[3], x[4], x[5]) @ P.tree_r_att
    pivot, rest = plant.wire_pivot(env, P.tree_W0)
    stretch = max(np.linalg.norm(p_att - pivot) - rest, 0.0)
    wire = 0.5 * env[plant.E_KZ] * stretch**2
    return kinetic + wire - P.tree_W0 * x[2] + plant.contact_energy(x, env, P)


def _drop_state(
    ps: params.ParameterSet, along_m: float, across_m: float, dpsi: float, gentle: float = 1.0
):
    """The tree 2 cm above the post tops, offset in the frame's axes, coming down at 5 cm/s
    while drifting and turning a little (all speeds times ``gentle``)."""
    lay = ps.spec.docking.to_numeric()
    h = float(ps.tree.dimensions_m[2])
    c, s = math.cos(FRAME_PSI), math.sin(FRAME_PSI)
    x = np.zeros(plant.N_STATE)
    x[0], x[1] = c * along_m - s * across_m, s * along_m + c * across_m
    x[2] = LAND_M - lay.post_height_m - h / 2 - 0.02
    x[5] = FRAME_PSI + dpsi
    x[6], x[8], x[11] = 0.02 * gentle, 0.05 * gentle, 0.005 * gentle
    return x


DROPS = {
    # (along, across) in funnel mouth radii, heading error [rad]
    "into the funnels": (0.6, 0.3, 0.02),
    "onto the post tops": (1.6, 0.0, 0.0),
    "onto the lip": (1.05, 0.0, 0.0),
    "onto the seabed": (None, 0.0, 0.0),
}


@pytest.mark.parametrize("scale", SCALES)
@pytest.mark.parametrize("case", DROPS)
def test_contact_never_adds_energy_with_thrusters_off(scale, case):
    """Issue 11: a tree let down onto the frame with no water damping and no thrust: its energy
    (motion, wire, weight, contact springs) never grows. The only slack is RK4's error through
    the contact's kinks: at most 0.22 % of the energy of a 5 cm drop in these cases at 100 Hz;
    we allow 0.5 %. (That the springs give back what they take, the gradient test below.)"""
    ps = SCALES[scale]
    lay = ps.spec.docking.to_numeric()
    P = plant.plant_arrays(ps, has_rov=False)._replace(tree_D_l=np.zeros(6), tree_D_nl=np.zeros(6))
    along, across, dpsi = DROPS[case]
    r = lay.funnel_mouth_radius_m
    along_m = 3.0 * float(lay.frame_size_m[0]) if along is None else along * r
    x0 = _drop_state(ps, along_m, across * r, dpsi)
    env = _frame_env(ps, 0.3)
    states, done = plant.advance(x0, np.zeros(8), np.repeat(env[None], 12000, axis=0), P, 0.01)
    assert done == 12000
    e0 = _energy(x0, env, P)
    e = np.array([_energy(s, env, P) for s in states[::5]])
    scale_j = P.tree_W0 * 0.05
    assert np.max(e - e0) <= 0.005 * scale_j
    # something happened: the contact took at least the energy of the drop
    assert e[-1] < e0 - 0.5 * scale_j


@pytest.mark.parametrize("scale", SCALES)
def test_contact_wrench_is_the_gradient_of_the_contact_energy(scale):
    """With damping and friction off, the power of the contact wrench equals minus the rate of
    change of the contact energy along any motion (central difference over 1e-7 s; 1e-4
    relative to the largest power of the set, far above the difference's round-off)."""
    ps = SCALES[scale]
    lay = ps.spec.docking.to_numeric()
    P = plant.plant_arrays(ps, has_rov=False)._replace(contact_c=0.0, post_c=0.0, friction_mu=0.0)
    env = _frame_env(ps, 0.3)
    rng = np.random.default_rng(11)
    r = lay.funnel_mouth_radius_m
    h = float(ps.tree.dimensions_m[2])
    powers, rates = [], []
    for k in range(400):
        x = np.zeros(plant.N_STATE)
        # over the posts (either way round), over the lip, or beside the tree's edge
        along, across = rng.uniform(-1.5 * r, 1.5 * r, size=2)
        if k % 4 == 3:
            along += float(lay.frame_size_m[0])
        turn = FRAME_PSI + (math.pi if k % 5 == 4 else 0.0) + rng.uniform(-0.1, 0.1)
        c, s = math.cos(FRAME_PSI), math.sin(FRAME_PSI)
        x[0], x[1] = c * along - s * across, s * along + c * across
        x[2] = LAND_M - h / 2 - rng.uniform(-0.05, lay.post_height_m + 0.05)
        x[3:5] = rng.uniform(-0.03, 0.03, size=2)
        x[5] = turn
        x[6:12] = rng.normal(size=6) * np.array([0.1, 0.1, 0.1, 0.02, 0.02, 0.05])
        wrench = plant.contact_wrench(x, env, P, Rzyx(x[3], x[4], x[5]))
        power = float(wrench @ x[6:12])
        R = Rzyx(x[3], x[4], x[5])
        eta_dot = np.concatenate([R @ x[6:9], Tzyx(x[3], x[4]) @ x[9:12]])
        eps = 1e-7
        up, down = x.copy(), x.copy()
        up[0:6] += eps * eta_dot
        down[0:6] -= eps * eta_dot
        rate = (plant.contact_energy(up, env, P) - plant.contact_energy(down, env, P)) / (2 * eps)
        powers.append(power)
        rates.append(rate)
    powers_a, rates_a = np.array(powers), np.array(rates)
    assert np.count_nonzero(powers_a) > 100  # most samples touch something
    np.testing.assert_allclose(powers_a, -rates_a, atol=1e-4 * np.abs(powers_a).max())


def _landed_sim(ps: params.ParameterSet, offset_m=(0.0, 0.0), dpsi=0.0) -> Simulation:
    """A tree with its ROV (thrusters off) hanging 0.5 m over a frame that is offset from it,
    then lowered at 0.05 m/s to 0.3 m past the landing surface (as the dock leg does)."""
    lay = ps.spec.docking.to_numeric()
    h = float(ps.tree.dimensions_m[2])
    land = 400.0
    depth = land - lay.post_height_m - h / 2 - 0.5
    sim = Simulation(ps, tree_depth_m=depth, control=False, crane_tip_n=(0.0, 0.0, 0.0))
    sim.run_for(60.0)
    tree = sim.tree_eta_n
    frame = DockingFrame(tree[0:2] - np.asarray(offset_m, float), tree[5] - dpsi, land)
    sim.set_docking_frame(frame)
    sim.winch_to(sim.wire_length_for_depth(land - h / 2) + 0.3, 0.05)
    while not sim.winch_idle:
        sim.run_for(10.0)
    sim.run_for(60.0)
    return sim


def _rest_check(sim: Simulation, ps: params.ParameterSet):
    assert sim.docking_frame is not None
    lay = ps.spec.docking.to_numeric()
    h = float(ps.tree.dimensions_m[2])
    bottom = sim.tree_eta_n[2] + h / 2
    return check_alignment(sim.tree_eta_n, sim.docking_frame, lay), bottom


@pytest.mark.parametrize("scale", SCALES)
def test_landed_tree_stays_within_the_posts_clearance_under_full_thrust(scale):
    """Issue 11: a landed tree, its ROV pushing with every thruster at full speed the way that
    turns the tree most, for 10 minutes: no funnel gets further from its post than the bore's
    clearance plus the post's elastic give (its share of the thrust, half the sum of all
    thrusts plus the moment over twice the arm, over the post stiffness: an upper bound, as
    the seabed's friction takes some), so the heading stays within that over the arm (either
    funnel is at least the turn times the arm from its post, whatever the shift)."""
    ps = SCALES[scale]
    lay = ps.spec.docking.to_numeric()
    sim = _landed_sim(ps)
    chk, _ = _rest_check(sim, ps)
    assert chk.miss_m < lay.clearance_m + 0.01
    T = sim.arrays.thr_T
    r_m = sim.arrays.mount_r
    yaw_per_thruster = T[5] + r_m[0] * T[1] - r_m[1] * T[0]
    n = sim.arrays.thr_n_max * np.sign(yaw_per_thruster)
    sim.set_thruster_speeds(n)
    rows = sim.run_for(600.0)
    arm = float(np.min(np.hypot(lay.post_xy_m[:, 0], lay.post_xy_m[:, 1])))
    thrust = np.abs(
        plant.thrust_from_speed(n, sim.arrays.thr_k_pos, sim.arrays.thr_k_neg, sim.arrays.thr_n_max)
    )
    moment = float(np.abs(yaw_per_thruster) @ thrust)
    give_m = (0.5 * thrust.sum() + moment / (2 * arm)) / sim.arrays.post_k
    err = np.degrees(
        np.abs(
            (rows["tree_eta_n"][:, 5] - sim.docking_frame.heading_rad + math.pi) % (2 * math.pi)
            - math.pi
        )
    )
    assert err.max() <= math.degrees((lay.clearance_m + give_m) / arm)
    # it did push: the tree leans against its posts (over half the clearance)
    assert err.max() > 0.5 * math.degrees(lay.heading_clearance_rad)
    chk, bottom = _rest_check(sim, ps)
    assert chk.miss_m < lay.clearance_m + give_m
    assert bottom > 400.0 - 0.05 * lay.post_height_m


@pytest.mark.parametrize("scale", SCALES)
@pytest.mark.parametrize(
    "direction_deg, heading_part", [(0.0, 0.0), (90.0, 0.5), (225.0, 0.9), (300.0, -0.9)]
)
def test_capture_within_tolerance_ends_on_the_frame(scale, direction_deg, heading_part):
    """Issue 11: funnels over the posts within the capture tolerance (here 90 % of it for the
    worst funnel, offset and heading error together) are guided down: the tree ends on the
    landing surface with each funnel around its own post within the bore's clearance."""
    ps = SCALES[scale]
    lay = ps.spec.docking.to_numeric()
    arm = float(np.min(np.hypot(lay.post_xy_m[:, 0], lay.post_xy_m[:, 1])))
    budget = 0.9 * lay.tolerance_m
    dpsi = heading_part * 0.5 * budget / arm
    shift = budget - abs(dpsi) * arm
    a = math.radians(direction_deg)
    sim = _landed_sim(ps, (shift * math.cos(a), shift * math.sin(a)), dpsi)
    chk, bottom = _rest_check(sim, ps)
    assert chk.miss_m <= lay.clearance_m + 0.002
    assert abs(chk.heading_error_deg) <= math.degrees(lay.heading_clearance_rad) + 0.05
    # on the landing surface: sunk in by its 2 % static penetration, not on the post tops
    assert bottom == pytest.approx(400.0 + 0.02 * float(ps.tree.dimensions_m[2]), abs=0.01)


@pytest.mark.parametrize("scale", SCALES)
def test_tree_wrench_skips_the_contact_only_where_it_is_exactly_zero(scale):
    """The tree's wrench computes the contact only for a tree within ``contact_reach`` of the
    landing surface (speed: a docking run hangs far above the frame most of the time). Across
    that edge, and into contact, it is bit for bit the wrench without a landing surface plus
    ``contact_wrench`` (which always computes the corners and posts): so skipping changed no
    number. The depths sweep from 1 m above the reach down to the corners 5 cm in, tilted,
    turning and moving, so that a reach too short (a corner or post skipped while it touches)
    shows. Compared as integers, so that even a zero's sign counts."""
    ps = SCALES[scale]
    P = plant.plant_arrays(ps)
    env = _frame_env(ps, 0.0)
    off = env.copy()
    off[plant.E_LAND] = 0.0
    reach = plant.contact_reach(P)
    h = float(ps.tree.dimensions_m[2])
    edge = LAND_M - reach  # the centre's depth at the edge of reach
    depths = [edge - 1.0, edge - 1e-3, edge, edge + 0.5 * plant.CONTACT_MARGIN_M]
    depths += list(np.linspace(edge + plant.CONTACT_MARGIN_M, LAND_M - h / 2 + 0.05, 9))
    touched = 0
    rng = np.random.default_rng(3)
    for depth in depths:
        x = np.zeros(plant.N_STATE)
        x[0:2] = rng.uniform(-0.3, 0.3, 2)
        x[2] = depth
        x[3:5] = rng.uniform(-0.02, 0.02, 2)
        x[5] = FRAME_PSI + rng.uniform(-0.05, 0.05)
        x[6:12] = rng.uniform(-0.05, 0.05, 6)
        R_t = Rzyx(x[3], x[4], x[5])
        cw = plant.contact_wrench(x, env, P, R_t)
        expected = plant.tree_wrench(x, off, P, R_t) + cw
        got = plant.tree_wrench(x, env, P, R_t)
        assert np.array_equal(got.view(np.int64), expected.view(np.int64)), (depth, got, expected)
        touched += bool(np.any(cw != 0.0))
        if depth < edge:
            assert not np.any(cw != 0.0)
    assert touched >= 3  # the sweep reached into contact
