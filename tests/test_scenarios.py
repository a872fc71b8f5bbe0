"""The thesis's chapter-4 scenarios through the control system (issue 3's acceptance figures).

Each runs the library mission of that name, as `rov-console run NAME` does."""

import math

import numpy as np
import pytest

from missions import runner, schema
from sim.gnc import ssa


def run(name, **overrides):
    mission = schema.load_mission(name)
    if overrides:
        mission = mission.model_copy(update={"setup": mission.setup.model_copy(update=overrides)})
    return runner.run_mission(mission)


@pytest.fixture(scope="module")
def square_400():
    return run("full-square-400")


def test_full_scale_square_at_400_m_tracks_within_the_issue_bounds(square_400):
    """Issue 3: RMS position error under 0.10 m and heading under 2 deg over the square."""
    r = square_400
    assert not r.diverged
    assert r.rms_north_m < 0.10 and r.rms_east_m < 0.10
    assert r.rms_heading_deg < 2.0
    # the reference is no slower than 0.05 m/s along the sides
    square = next(leg for leg in r.legs if leg.type == "square")
    rows = slice(int(square.start_s / 0.01), int((square.start_s + square.duration_s) / 0.01))
    speed = np.hypot(*r.log["eta_ref_rate_n"][rows, 0:2].T)
    assert speed.max() >= 0.05
    # and the tree ends where it started the square (back at the crane tip)
    assert math.hypot(r.final_eta_n[0] - 1.0, r.final_eta_n[1] - 1.0) < 0.05


def test_square_at_100_m_is_harder_than_at_400_m(square_400):
    """Thesis 4.1.2: at 100 m the wire is stiffer (3.7x); the same square tracks worse and
    needs larger forces."""
    r100 = run("full-square-100")
    assert not r100.diverged
    assert r100.rms_north_m + r100.rms_east_m > square_400.rms_north_m + square_400.rms_east_m
    f100 = np.abs(r100.log["tau_tree_cmd"][:, 0:2]).max()
    f400 = np.abs(square_400.log["tau_tree_cmd"][:, 0:2]).max()
    assert f100 > 1.5 * f400
    # beyond the ROV at 100 m (README): the square's corners are not reached, and it says so
    assert r100.failed and "did not reach its target" in r100.legs[-1].error
    assert not square_400.failed


def test_full_rotation_turns_360_both_ways_and_returns():
    r = run("full-rotation-400")
    assert not r.diverged
    psi = np.unwrap(r.log["tree_eta_n"][:, 5])
    assert np.degrees(psi.max() - psi[0]) > 350.0  # it really went once round
    assert abs(r.final_eta_n[5]) < 1.0
    assert r.rms_heading_deg < 2.0


def test_model_scale_square_with_sensors_and_ekf():
    """Issue 3: RMS north and east under 0.10 m, heading under 4 deg (thesis: ~0.07 m,
    2.8 deg)."""
    r = run("model-square-ekf-400")
    assert not r.diverged
    assert r.rms_north_m < 0.10 and r.rms_east_m < 0.10
    assert r.rms_heading_deg < 4.0


def test_impossible_step_loses_heading_with_pinv_and_holds_it_with_priority():
    """Thesis 4.2.2 / issue 3: 5 m N, 5 m E, heading 90 deg at model scale."""
    pinv = run("model-step-pinv")
    prio = run("model-step-priority")
    for r in (pinv, prio):
        assert r.saturated_time_s > 60.0  # it really is impossible: thrusters saturate

    def err(r):
        """Heading error [deg] from the start of the step leg on."""
        first = int(r.legs[1].start_s / 0.01)
        psi = r.log["tree_eta_n"][first:, 5]
        psi_ref = r.log["eta_ref_n"][first:, 2]
        return np.degrees(np.abs(ssa(psi - psi_ref)))

    # priority: heading held within 10 deg once the turn is done (after 60 s)
    assert err(prio)[6000:].max() < 10.0
    # pinv: the heading is lost (off by far more than 10 deg at some point)
    assert err(pinv).max() > 30.0


@pytest.mark.parametrize(
    "name",
    [
        "model-mass-m50",
        "model-mass-m20",
        "model-mass-p20",
        "model-mass-p50",
        "model-weight-m50",
        "model-weight-m20",
        "model-weight-p20",
        "model-weight-p50",
    ],
)
def test_robust_to_tree_mass_and_weight_errors(name):
    """Issue 3 / thesis table 4.2: stable, RMS north and east under 0.15 m."""
    r = run(name)
    assert not r.diverged
    assert r.rms_north_m < 0.15 and r.rms_east_m < 0.15


def test_wrong_sign_of_r_fails_to_rotate_and_is_reported():
    """Thesis 6.2.1: r entered with the wrong sign; the tree does not converge in a 180 deg
    rotation, and the start-up check names the suspected sign error."""
    r = run("model-rotation-wrong-r")
    rot = r.legs[1]
    assert rot.rms_heading_deg > 30.0
    assert abs(abs(r.final_eta_n[5]) - 180.0) > 20.0  # not at the 180 deg target
    assert any("looks like it has the wrong sign" in w for w in r.warnings)
    # the reference arrived, the tree did not: the leg and the mission say they failed
    assert r.failed and "did not reach its target" in rot.error and "180.0 deg off" in rot.error
    right = run("model-rotation-wrong-r", r_mount_config_m=None)
    assert not right.warnings
    assert abs(abs(right.final_eta_n[5]) - 180.0) < 2.0
    assert not right.failed and all(leg.error == "" for leg in right.legs)


def test_same_seed_same_result():
    a = run("model-square-ekf-400")
    b = run("model-square-ekf-400")
    np.testing.assert_array_equal(a.log.data, b.log.data)
    c = run("model-square-ekf-400", seed=5)
    assert not np.array_equal(a.log.data, c.log.data)
