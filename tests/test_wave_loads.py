"""Wave loads (issue 14): linear wave kinematics in finite depth against Airy theory worked by
hand, the dispersion relation, and the Morison load on the tree against a hand calculation."""

import math
import typing

import numpy as np
import pytest
from scipy.optimize import brentq

from control.simulation import Simulation
from missions import schema
from sim import environment as envmod
from sim import params, plant, site
from sim.gnc import Rzyx

FULL = params.load("full-scale")
G = envmod.GRAVITY_MPS2


def _component(period_s: float, amplitude_m: float, water_depth_m: float) -> envmod.WaveField:
    """One regular wave travelling north, phase 0, over a seabed at water_depth_m."""
    omega = 2 * math.pi / period_s
    return envmod.WaveField(
        omega_rad_s=np.array([omega]),
        amplitude_m=np.array([amplitude_m]),
        wavenumber_rad_m=envmod.wavenumber(np.array([omega]), water_depth_m),
        phase_rad=np.array([0.0]),
        direction_rad=0.0,
        water_depth_m=water_depth_m,
    )


def test_dispersion_relation_by_hand_and_by_root_finding():
    """T = 10 s over 30 m: x = k h solves x tanh x = omega^2 h / g = 1.20729. By hand (bisection
    on a pocket calculator) x = 1.3729, wavelength 137.3 m (deep water: 156.1 m)."""
    omega = 2 * math.pi / 10.0
    k = float(envmod.wavenumber(omega, 30.0))
    assert k * 30.0 == pytest.approx(1.3729, abs=1e-4)  # 4 digits worked by hand
    assert 2 * math.pi / k == pytest.approx(137.3, abs=0.05)
    # against a bracketing root finder on the relation itself, to round-off
    root = brentq(lambda kk: G * kk * math.tanh(kk * 30.0) - omega**2, 1e-6, 1.0, xtol=1e-15)
    assert k == pytest.approx(root, rel=1e-12)


@pytest.mark.parametrize("water_depth_m", [1.0, 5.0, 30.0, 200.0, 4000.0])
def test_wavenumber_satisfies_dispersion_over_all_frequencies(water_depth_m):
    omega = np.logspace(-3, 1.5, 300)
    k = envmod.wavenumber(omega, water_depth_m)
    residual = G * k * np.tanh(k * water_depth_m) - omega**2
    np.testing.assert_allclose(residual, 0.0, atol=1e-14 * float(np.max(omega**2)))
    # limits: shallow (k h << 1) k = omega / sqrt(g h) to first order in (k h)^2 / 6; deep k =
    # omega^2 / g up to 2 e^(-2 k h)
    shallow = k * water_depth_m < 0.01
    np.testing.assert_allclose(k[shallow], omega[shallow] / math.sqrt(G * water_depth_m), rtol=2e-5)
    deep = k * water_depth_m > 12.0
    np.testing.assert_allclose(k[deep], omega[deep] ** 2 / G, rtol=1e-10)


def test_deep_water_is_the_limit_of_finite_depth():
    """h = inf is exactly the thesis's deep-water field; a 5 km sea for a 10 s wave (k h = 200)
    differs from it by e^(-2 k (h - z)), far below round-off."""
    t = np.linspace(0.0, 30.0, 61)
    deep = envmod.wave_kinematics_n(_component(10.0, 2.0, math.inf), t, 40.0)
    far = envmod.wave_kinematics_n(_component(10.0, 2.0, 5000.0), t, 40.0)
    np.testing.assert_allclose(far.velocity_n, deep.velocity_n, rtol=0, atol=1e-14)
    np.testing.assert_allclose(far.accel_n, deep.accel_n, rtol=0, atol=1e-14)
    omega = 2 * math.pi / 10.0
    amplitude = omega * 2.0 * math.exp(-(omega**2) / G * 40.0)
    assert np.max(deep.velocity_n[:, 0]) == pytest.approx(amplitude, rel=1e-3)


def test_finite_depth_kinematics_against_airy_theory():
    """T = 10 s, A = 1 m over 30 m, at 20 m depth (10 m above the bed): horizontal amplitude
    omega A cosh(k 10) / sinh(k 30) = 0.62832 x 1.10656 / 1.84676 = 0.37648 m/s, vertical
    omega A sinh(k 10) / sinh(k 30) = 0.62832 x 0.47378 / 1.84676 = 0.16119 m/s (by hand,
    with k = 1.37292 / 30 = 0.045764 rad/m); deep water would give 0.62832 e^(-0.80486)
    = 0.28095 m/s."""
    field = _component(10.0, 1.0, 30.0)
    omega = 2 * math.pi / 10.0
    t = np.array([0.0, 2.5])  # theta = 0 and pi / 2
    kin = envmod.wave_kinematics_n(field, t, 20.0)
    u_amp, w_amp = 0.37648, 0.16119
    # theta = pi / 2: u = +u_amp (crest), w = 0; theta = 0: u = 0, w (down) = -w_amp (rising)
    assert kin.velocity_n[1, 0] == pytest.approx(u_amp, rel=1e-4)
    assert kin.velocity_n[0, 2] == pytest.approx(-w_amp, rel=1e-4)
    assert abs(kin.velocity_n[0, 0]) < 1e-12 and abs(kin.velocity_n[1, 2]) < 1e-12
    # accelerations: omega times the amplitudes, a quarter period ahead
    assert kin.accel_n[0, 0] == pytest.approx(omega * u_amp, rel=1e-4)
    assert kin.accel_n[1, 2] == pytest.approx(omega * w_amp, rel=1e-4)
    # and the same from cosh and sinh directly, to round-off
    k = float(field.wavenumber_rad_m[0])
    along, vertical = envmod.depth_factors(np.array([k]), 20.0, 30.0)
    assert along[0] == pytest.approx(math.cosh(k * 10.0) / math.sinh(k * 30.0), rel=1e-13)
    assert vertical[0] == pytest.approx(math.sinh(k * 10.0) / math.sinh(k * 30.0), rel=1e-13)
    # at the bed the vertical velocity vanishes
    at_bed = envmod.wave_kinematics_n(field, t, 30.0)
    assert np.max(np.abs(at_bed.velocity_n[:, 2])) < 1e-15


def test_near_the_bed_long_waves_move_faster_than_deep_water_theory_says():
    """MODEL_NOTES (second round): near the seabed the finite-depth velocity at T = 20 to 30 s
    is 1.7 to 1.9 times the deep-water value. At 100 m over a 110 m seabed: cosh(k 10) /
    sinh(k 110) over e^(-k0 100)."""
    ratios = []
    for period in (20.0, 30.0):
        omega = np.array([2 * math.pi / period])
        k = envmod.wavenumber(omega, 110.0)
        finite, _ = envmod.depth_factors(k, 100.0, 110.0)
        deep, _ = envmod.depth_factors(envmod.deep_water_wavenumber(omega), 100.0, math.inf)
        ratios.append(float(finite[0] / deep[0]))
    assert 1.6 < ratios[0] < ratios[1] < 2.0


def test_kinematics_reject_a_point_below_the_seabed():
    with pytest.raises(ValueError, match=r"^depth_m must lie in \[0, water_depth_m\]"):
        envmod.wave_kinematics_n(_component(10.0, 1.0, 30.0), np.zeros(2), 30.5)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"load": "inertia"}, r"^load must be one of drag, morison, got 'inertia'"),
        ({"water_depth_m": 0.5}, r"^water_depth_m must lie in \[1, inf\]"),
        ({"water_depth_m": math.nan}, r"^water_depth_m must lie in \[1, inf\]"),
    ],
)
def test_bad_wave_load_or_water_depth_names_the_field(kwargs, message):
    with pytest.raises(ValueError, match=message):
        envmod.WaveParams(8.0, 10.0, 0.0, **kwargs)


def test_mission_file_and_sim_share_the_wave_loads():
    assert typing.get_args(schema.WaveLoad) == envmod.WAVE_LOADS
    assert envmod.DEFAULT_WAVE_LOAD in envmod.WAVE_LOADS


def _tree_at_rest(heading_rad: float) -> np.ndarray:
    x = np.zeros(plant.N_STATE)
    x[0:3] = [1.0, 1.0, 100.0]
    x[5] = heading_rad
    return x


@pytest.mark.parametrize("heading_deg", [0.0, 90.0, 30.0])
def test_morison_inertia_load_on_the_tree_by_hand(heading_deg):
    """The tree at rest in water accelerating 0.1 m/s^2 north: the force is
    (A11 + rho V) a = (21 865 + 36 000 x 1025 / 7850) x 0.1 = (21 865 + 4 700.6) x 0.1
    = 2 656.6 N north (added mass eq. 2.21, displaced water of 36 t of solid steel), turned
    into the tree's axes; nothing else changes (nu = 0: no Coriolis, no drag)."""
    P = plant.plant_arrays(FULL, has_rov=False)
    heading = math.radians(heading_deg)
    x = _tree_at_rest(heading)
    env = site.wire_environment(FULL, 97.0, np.array([1.0, 1.0, 0.0]), 0.0, 0.0)
    still = plant.tree_wrench(x, env, P, Rzyx(0.0, 0.0, heading))
    env[plant.E_AC] = 0.1
    pushed = plant.tree_wrench(x, env, P, Rzyx(0.0, 0.0, heading))
    hand_newton = (21865.0 + 4700.6) * 0.1
    force_b = pushed - still
    expected_b = Rzyx(0.0, 0.0, heading).T @ np.array([hand_newton, 0.0, 0.0])
    np.testing.assert_allclose(force_b[0:3], expected_b, atol=0.01)  # 4700.6 rounded: 6e-3 N
    np.testing.assert_allclose(force_b[3:6], 0.0, atol=1e-9)
    assert P.tree_fk_mass == pytest.approx(36000.0 * 1025.0 / 7850.0, rel=1e-12)


def test_drag_load_on_the_tree_by_hand():
    """Water at 0.5 m/s north past the tree at rest: (D_l + D_nl |u|) u in surge, with the
    damping the drag rules give for the box (its own test is in test_params)."""
    P = plant.plant_arrays(FULL, has_rov=False)
    x = _tree_at_rest(0.0)
    env = site.wire_environment(FULL, 97.0, np.array([1.0, 1.0, 0.0]), 0.0, 0.0)
    still = plant.tree_wrench(x, env, P, np.eye(3))
    env[plant.E_VC] = 0.5
    flowing = plant.tree_wrench(x, env, P, np.eye(3))
    hand = (P.tree_D_l[0] + P.tree_D_nl[0] * 0.5) * 0.5
    assert flowing[0] - still[0] == pytest.approx(hand, rel=1e-12)


def _first_chunk_accel(load: str) -> tuple[np.ndarray, Simulation]:
    waves = envmod.WaveParams(8.0, 10.0, 0.3, load=load)
    sim = Simulation(FULL, tree_depth_m=20.0, control=False, waves=waves, seed=3)
    env = sim._environment_chunk(50)
    return env, sim


def test_drag_mode_gives_the_plant_no_water_acceleration_and_morison_does():
    env_drag, _ = _first_chunk_accel("drag")
    env_mor, sim = _first_chunk_accel("morison")
    assert np.all(env_drag[:, plant.E_AC : plant.E_AC + 3] == 0.0)
    np.testing.assert_array_equal(
        env_drag[:, plant.E_VC : plant.E_VC + 3], env_mor[:, plant.E_VC : plant.E_VC + 3]
    )
    expected = envmod.wave_kinematics_n(sim.wave_field, 0.01 * np.arange(50), 20.0, 1.0, 1.0)
    np.testing.assert_allclose(env_mor[:, plant.E_AC : plant.E_AC + 3], expected.accel_n)
    assert np.max(np.abs(expected.accel_n)) > 0.05  # 8 m sea at 20 m: a real acceleration


def test_mission_water_depth_defaults_to_the_landing_depth():
    from missions import setup

    text = """
format_version = 1
name = "w"
[setup]
params = "full-scale"
depth_m = 60.0
[setup.waves]
significant_height_m = 4.0
peak_period_s = 12.0
direction_deg = 0.0
load = "drag"
[setup.docking_frame]
center_ne_m = [1.0, 1.0]
heading_deg = 0.0
landing_depth_m = 80.0
[[legs]]
type = "hold"
duration_s = 1.0
"""
    mission = schema.parse_text(text, "w.toml")
    sim = setup.build_simulation(mission)
    assert sim.wave_field is not None and sim.wave_field.water_depth_m == 80.0
    assert sim.site.wave_load == "drag"


def test_drag_load_gives_the_thesis_short_sea_and_morison_does_not():
    """Table 4.1, T = 10 s, Hs = 8 m, uncontrolled north RMS 0.0024 m: the drag load gives it
    within 30 % (the issue's bound; seeds move it by about 5 %), the complete Morison load
    about 15 times more (inertia dominates at 100 m: the thesis's figures are drag-only)."""
    from missions import studies

    thesis = studies.TABLE_4_1[(10.0, 8.0)][0][0]
    drag, _ = studies.wave_case(10.0, 8.0, duration_s=600.0, seed=0, load="drag")
    morison, _ = studies.wave_case(10.0, 8.0, duration_s=600.0, seed=0, load="morison")
    assert drag.ours[0] == pytest.approx(thesis, rel=0.3)
    assert morison.ours[0] > 5.0 * thesis
