"""The vessel's motion at the crane tip (issue 14): RAO limits, the crane tip's heave against
the RAO times the wave spectrum, heave compensation, and the tree following the tip."""

import math

import numpy as np
import pytest

from control.simulation import Simulation
from missions import schema, seaway, setup
from sim import environment as envmod
from sim import params
from sim import vessel as vm

SHIP = vm.CONSTRUCTION_VESSEL


def test_long_waves_carry_the_vessel_with_the_surface():
    """omega -> 0: heave 1 m/m in phase with the crest, surge and sway the particle orbit
    (-i, a quarter period behind), pitch and roll the surface slope (k cos beta, k sin beta)."""
    omega = np.array([0.001])  # r = omega T / 2 pi < 3e-3: the oscillators add < 1e-3
    k = envmod.deep_water_wavenumber(omega)
    beta = math.radians(30.0)
    h = vm.raos(omega, k, beta, SHIP)[0]
    assert h[2] == pytest.approx(1.0, abs=1e-3)
    assert h[0] == pytest.approx(-1j * math.cos(beta), abs=1e-3)
    assert h[1] == pytest.approx(-1j * math.sin(beta), abs=1e-3)
    assert h[3] == pytest.approx(1j * k[0] * math.sin(beta), rel=1e-3)
    assert h[4] == pytest.approx(-1j * k[0] * math.cos(beta), rel=1e-3)


def test_head_sea_raos_at_10_s_by_hand():
    """Head sea (beta = 180 deg), T = 10 s: k = 0.040243 rad/m, k L / 2 = 2.6158, Smith factor
    e^(-k 7.5) = 0.73947, sinc(2.6158) = 0.19187; heave r = 0.7: |1 / (0.51 + 0.28 i)| = 1.7188,
    so |heave| = 0.73947 x 0.19187 x 1.7188 = 0.24387 m/m. Pitch: moment factor
    3 (sin u - u cos u) / u^3 = 0.46335, r = 0.65: |1 / (0.5775 + 0.26 i)| = 1.5790, so
    |pitch| = 0.040243 x 0.73947 x 0.46335 x 1.5790 = 0.021772 rad/m (1.25 deg/m). No roll,
    no sway."""
    omega = np.array([2 * math.pi / 10.0])
    h = vm.raos(omega, envmod.deep_water_wavenumber(omega), math.pi, SHIP)[0]
    assert abs(h[2]) == pytest.approx(0.24387, rel=2e-4)
    assert abs(h[4]) == pytest.approx(0.021772, rel=2e-4)
    assert abs(h[3]) < 1e-17 and abs(h[1]) < 1e-16


@pytest.mark.parametrize("period_s", [8.0, 10.0, 14.0])
def test_crane_tip_heave_matches_rao_times_spectrum(period_s):
    """The tip's vertical RMS over an hour of the synthesised sea against
    sqrt(integral |H_z(omega)|^2 S(omega) d omega) on a fine grid (20 001 points over the
    sea's band, the same band the components cover). Measured over seeds 0-3 and these
    periods: within 2 %; 5 % allows for the sampling of 200 random frequencies."""
    hs = 4.0
    field = envmod.make_wave_field(envmod.WaveParams(hs, period_s, 0.0), np.random.default_rng(0))
    motion = vm.VesselMotion(heading_rad=math.pi)  # bow into the waves
    t = np.arange(0.0, 3600.0, 0.5)
    tip = vm.crane_tip_motion_n(field, t, motion)
    omega_p = 2 * math.pi / period_s
    w = np.linspace(envmod.OMEGA_MIN_PER_PEAK * omega_p, envmod.OMEGA_MAX_PER_PEAK * omega_p, 20001)
    rao_z = vm.crane_tip_raos_n(w, envmod.deep_water_wavenumber(w), 0.0, motion)[:, 2]
    variance = np.trapezoid(np.abs(rao_z) ** 2 * envmod.ittc_spectrum(w, hs, period_s), w)
    assert float(np.std(tip[:, 2])) == pytest.approx(math.sqrt(variance), rel=0.05)
    # the tip moves: at T = 10 s its heave RMS is 0.45 of the sea's elevation RMS (Hs / 4)
    if period_s == 10.0:
        assert float(np.std(tip[:, 2])) == pytest.approx(0.45 * hs / 4.0, rel=0.05)


def test_heave_compensation_removes_its_share_of_the_vertical_motion_only():
    field = envmod.make_wave_field(envmod.WaveParams(4.0, 10.0, 0.5), np.random.default_rng(1))
    t = np.arange(0.0, 600.0, 0.5)
    free = vm.crane_tip_motion_n(field, t, vm.VesselMotion(heading_rad=2.0))
    compensated = vm.VesselMotion(
        heading_rad=2.0, heave_compensation=True, heave_compensation_efficiency=0.9
    )
    held = vm.crane_tip_motion_n(field, t, compensated)
    np.testing.assert_allclose(held[:, 2], 0.1 * free[:, 2], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(held[:, 0:2], free[:, 0:2], rtol=0, atol=1e-12)
    assert float(np.std(free[:, 0])) > 0.05 and float(np.std(free[:, 1])) > 0.05


def test_vessel_motion_reaches_the_tree_and_is_off_by_default():
    """Tree alone at 100 m under a vessel in a T = 10 s, Hs = 4 m head sea: the wire is stiff
    vertically (EA / L: a 0.8 s bounce), so the tree heaves with the crane tip (RMS within
    10 %), while under a still tip it hardly heaves at all (the wave's own vertical velocity at
    100 m is e^(-4) of the surface's). Without ``vessel`` the run is unchanged."""
    full = params.load("full-scale")
    waves = envmod.WaveParams(4.0, 10.0, 0.0, load="drag")
    motion = vm.VesselMotion(heading_rad=math.pi)
    moving = Simulation(
        full, tree_depth_m=100.0, has_rov=False, control=False, waves=waves, vessel=motion
    )
    still = Simulation(full, tree_depth_m=100.0, has_rov=False, control=False, waves=waves)
    moving.run_for(60.0)
    still.run_for(60.0)
    rows = moving.run_for(300.0)
    rows_still = still.run_for(300.0)
    tip = vm.crane_tip_motion_n(moving.wave_field, 60.0 + 0.01 * np.arange(30000), motion, 1, 1)
    tree_heave = float(np.std(rows["tree_eta_n"][:, 2]))
    assert tree_heave == pytest.approx(float(np.std(tip[:, 2])), rel=0.1)
    assert float(np.std(rows_still["tree_eta_n"][:, 2])) < 0.05 * tree_heave
    # the logged crane tip moves; the mean station does not
    assert float(np.std(rows["crane_tip_ne"][:, 0])) > 0.1
    np.testing.assert_allclose(moving.crane_tip_n, [1.0, 1.0, 0.0])


def test_mission_vessel_defaults_to_head_sea():
    text = """
format_version = 1
name = "v"
[setup]
params = "full-scale"
depth_m = 60.0
[setup.waves]
significant_height_m = 4.0
peak_period_s = 12.0
direction_deg = 30.0
[setup.vessel]
heave_compensation = true
[[legs]]
type = "hold"
duration_s = 1.0
"""
    sim = setup.build_simulation(schema.parse_text(text, "v.toml"))
    assert sim.site.vessel_motion is not None
    assert sim.site.vessel_motion.heading_rad == pytest.approx(math.radians(210.0))
    assert sim.site.vessel_motion.heave_compensation
    assert sim.site.vessel_motion.heave_compensation_efficiency == 0.8


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"heave_compensation_efficiency": 1.2}, "heave_compensation_efficiency must lie in"),
        ({"heading_rad": math.nan}, "heading_rad must be finite"),
    ],
)
def test_bad_vessel_motion_names_the_field(kwargs, message):
    values = {"heading_rad": 0.0, **kwargs}
    with pytest.raises(ValueError, match=message):
        vm.VesselMotion(**values)


def test_bad_vessel_params_name_the_field():
    with pytest.raises(ValueError, match="roll_damping_ratio must lie in"):
        vm.VesselParams(roll_damping_ratio=0.0)
    with pytest.raises(ValueError, match="length_m must lie in"):
        vm.VesselParams(length_m=-1.0)


def test_ramp_is_a_half_cosine_with_no_jump_in_value_or_slope():
    """(1 - cos(pi t / T)) / 2: 0 at the start, 1/2 halfway, 1 from T on; its slope is 0 at
    both ends (central differences, step 1e-6 T: slope of order 1e-6) and pi / (2 T) halfway;
    no ramp (0 s) is 1 throughout. Two peak periods of the sea: 20 s at Tp 10 s."""
    T = 20.0
    t = np.array([-1.0, 0.0, 5.0, 10.0, 20.0, 30.0])
    np.testing.assert_allclose(vm.ramp_in(t, T), [0.0, 0.0, 0.5 - 0.5 * math.sqrt(0.5), 0.5, 1, 1])
    h = 1e-6 * T
    for at, slope in ((0.0, 0.0), (T / 2, math.pi / (2 * T)), (T, 0.0)):
        d = (vm.ramp_in(np.array([at + h]), T) - vm.ramp_in(np.array([at - h]), T))[0] / (2 * h)
        assert d == pytest.approx(slope, abs=1e-6)
    np.testing.assert_array_equal(vm.ramp_in(t, 0.0), np.ones(6))
    assert vm.ramp_time_s(10.0) == 20.0
    with pytest.raises(ValueError, match="ramp_s must be >= 0 s"):
        vm.ramp_in(t, -1.0)
    with pytest.raises(ValueError, match="peak_period_s must be > 0 s"):
        vm.ramp_time_s(0.0)


def _hovering(ramp: bool) -> Simulation:
    """Tree alone at 100 m on the elastic wire under a vessel in a T = 10 s, Hs = 4 m head
    sea, no heave compensation; ``ramp`` False: the motion at full size from t = 0."""
    waves = envmod.WaveParams(4.0, 10.0, 0.0, water_depth_m=110.0)
    sim = Simulation(
        params.load("full-scale"),
        tree_depth_m=100.0,
        has_rov=False,
        control=False,
        crane_tip_n=(0.0, 0.0, 0.0),
        waves=waves,
        vessel=vm.VesselMotion(heading_rad=math.pi),
        wire="elastic",
    )
    if not ramp:
        sim.site.vessel_ramp_s = 0.0
    return sim


def test_vessel_motion_ramps_in_and_the_start_gives_no_false_slack():
    """The crane tip starts where the vessel keeps station and its motion grows in over two
    peak periods (20 s): in the first 2 s its surge stays within 10 % of its later RMS
    (the ramp is at most 2.4 % there; measured 0.0009 m against 0.76 m), a tenth of what it
    is without the ramp (measured 0.096 m: this sea's surge happens to be small in those
    2 s, so it is judged against the run without the ramp rather than the later RMS), and
    it grows from the first 10 s to the next.
    The wire, judged from t = 0 (DNV's slack limit, 10 % of W0), has no slack in the first
    60 s and its tension stays above 0.8 W0 (measured 0.874 W0 in this sea, seed 0; over seeds
    0-7 from 0.874 to 0.928 W0, so the bound leaves the sea's randomness room and is still
    eight times DNV's slack limit).
    Without the ramp the tip jumps to its displaced place at t = 0: the wire goes slack at
    once (measured 5 slack episodes in 5 s, snaps to 4.4 W0), which the judgement used to
    leave out for 40 s."""
    w0 = params.load("full-scale").tree.submerged_weight_newton
    sim = _hovering(ramp=True)
    assert sim.vessel_ramp_s == pytest.approx(20.0)
    rows = sim.run_for(60.0)
    t, north = rows.t_s, rows["crane_tip_ne"][:, 0]
    rms = float(np.std(north[t > 20.0]))
    assert rms > 0.1  # the vessel does move
    assert north[0] == 0.0
    early = np.max(np.abs(north[t < 2.0]))
    assert early < 0.1 * rms
    assert np.std(north[t < 10.0]) < 0.5 * np.std(north[(t >= 10.0) & (t < 20.0)])
    watch = seaway.WireWatch(w0)
    watch.feed(t, rows["wire_tension"])
    assert watch.count("slack") == 0
    assert float(np.min(rows["wire_tension"])) > 0.8 * w0

    jumping = _hovering(ramp=False)
    rows = jumping.run_for(5.0)
    assert np.max(np.abs(rows["crane_tip_ne"][rows.t_s < 2.0, 0])) > 10.0 * early
    watch = seaway.WireWatch(w0)
    watch.feed(rows.t_s, rows["wire_tension"])
    assert watch.count("slack") >= 1
