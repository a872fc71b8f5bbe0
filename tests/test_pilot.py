"""Flying by hand (supervisor mode "manual"): the pilot's demand in the ROV's own axes goes
through the same allocation and thruster saturation as the autopilot; released sticks hold
station; switching in and out of it does not make the thrust jump."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from control import loop
from control.config import MODES
from control.simulation import Simulation
from sim import params
from tests.helpers import steady_current

MODEL = params.load("model-scale")


def free_rov(heading_deg: float = 90.0, **kwargs) -> Simulation:
    """The ROV free of the tree, still water, flown by hand from 2 s on."""
    sim = Simulation(
        MODEL,
        tree_depth_m=100.0,
        start_gripping=False,
        tree_heading_rad=math.radians(heading_deg),
        seed=1,
        **kwargs,
    )
    sim.run_for(2.0)
    sim.set_mode("manual")
    return sim


def test_manual_is_mode_code_two():
    assert MODES.index("manual") == loop.MODE_MANUAL == 2
    sim = free_rov()
    assert sim.mode == "manual"
    assert np.all(sim.run_for(0.1)["mode"] == 2)


def test_full_surge_flies_forward_in_the_rovs_own_frame_to_its_drag_limited_speed():
    """Heading 90 deg: forward is east. Full surge alone is the forward capacity; the speed it
    settles at solves X = D_l u + D_nl u |u| (the plant's surge drag, no current)."""
    sim = free_rov(heading_deg=90.0)
    start = sim.rov_eta_n
    sim.set_pilot_demand(1.0, 0.0, 0.0, 0.0)
    rows = sim.run_for(40.0)
    moved = sim.rov_eta_n - start
    assert moved[1] > 20.0  # east, forwards
    assert abs(moved[0]) < 0.01  # no sideways drift in still water
    full = sim.pilot_capacity[1, 0]
    np.testing.assert_allclose(rows["tau_rov_ach_b"][-1, 0], full, rtol=1e-6)
    d_l, d_nl = MODEL.rov.D_l[0], MODEL.rov.D_nl[0]
    u_closed = (-d_l + math.sqrt(d_l**2 + 4.0 * d_nl * full)) / (2.0 * d_nl)
    # 1 %: after 40 s (many surge time constants) the speed is within rounding of its limit
    np.testing.assert_allclose(rows["rov_nu_b"][-1, 0], u_closed, rtol=0.01)
    # heading held (auto-heading on by default) while it goes
    assert abs(math.degrees(sim.rov_eta_n[5]) - 90.0) < 0.1


def test_several_full_sticks_saturate_in_the_allocations_priority():
    """Full surge and full yaw together ask for more than the horizontal thrusters give: the
    priority allocation keeps yaw whole (yaw > sway > surge) and cuts surge; no thruster goes
    beyond its force box."""
    sim = free_rov()
    sim.set_pilot_demand(1.0, 0.0, 0.0, 1.0)
    rows = sim.run_for(1.0)
    cmd, ach = rows["tau_rov_cmd_b"][-1], rows["tau_rov_ach_b"][-1]
    np.testing.assert_allclose(cmd[[0, 5]], sim.pilot_capacity[1, [0, 3]])
    np.testing.assert_allclose(ach[5], cmd[5], rtol=1e-6)
    assert ach[0] < 0.9 * cmd[0]
    assert rows["thruster_utilisation"][-1].max() == pytest.approx(1.0)
    f = rows["thruster_force"][-1, : sim.n_thrusters]
    thr = MODEL.rov.thrusters
    assert np.all(f <= thr.f_max_pos * (1 + 1e-9)) and np.all(f >= -thr.f_max_neg * (1 + 1e-9))


def test_letting_go_holds_station_where_the_sticks_were_released():
    """After 20 s at full surge (1.17 m/s) the sticks are released: the station keeping holds
    the position and heading of that moment. Peak excursion: braking at the full backward
    thrust with no drag would stop the ROV within m v0^2 / (2 F_back) (2.6 m; drag only
    shortens it; measured 1.35 m, more than the 0.86 m of an unsaturated critically damped
    loop at 0.5 rad/s because the braking saturates). After 60 s more it is back within
    0.05 m and 0.2 deg; auto-depth holds the depth of the moment the ROV was taken over
    (the heave stick was never touched), within 0.15 m at speed and 0.01 m at the end."""
    sim = free_rov()
    depth_held = sim.rov_eta_n[2]
    sim.set_pilot_demand(1.0, 0.0, 0.0, 0.0)
    sim.run_for(20.0)
    v0 = float(sim.plant_state[18])
    release = sim.rov_eta_n
    sim.set_pilot_demand(0.0, 0.0, 0.0, 0.0)
    rows = sim.run_for(60.0)
    excursion = np.linalg.norm(rows["rov_eta_n"][:, 0:2] - release[0:2], axis=1)
    mass = (MODEL.rov.M_rb + MODEL.rov.M_a)[0, 0]
    assert excursion.max() < mass * v0**2 / (2.0 * sim.pilot_capacity[0, 0])
    assert excursion[-1] < 0.05
    assert abs(math.degrees(sim.rov_eta_n[5] - release[5])) < 0.2
    assert abs(release[2] - depth_held) < 0.15
    assert abs(sim.rov_eta_n[2] - depth_held) < 0.01


def test_auto_heading_holds_the_heading_under_a_sway_demand():
    """Surge and sway together make a Munk moment that turns a hull: with auto-heading on the
    yaw loop holds the heading (peak 4.8 deg while the speed builds, measured; bound 6 deg),
    with it off a released yaw stick is zero moment and the ROV turns right round."""
    peaks = {}
    for hold in (True, False):
        sim = free_rov()
        sim.set_pilot_holds(hold, True)
        sim.set_pilot_demand(0.5, 0.5, 0.0, 0.0)
        psi0 = sim.rov_eta_n[5]
        rows = sim.run_for(30.0)
        peaks[hold] = np.degrees(np.abs(rows["rov_eta_n"][:, 5] - psi0)).max()
        if not hold:
            assert np.all(rows["tau_rov_cmd_b"][:, 5] == 0.0)
    assert peaks[True] < 6.0
    assert peaks[False] > 90.0


def test_yaw_stick_release_holds_the_heading_of_that_moment():
    """Half yaw stick for 3 s turns the ROV clockwise at about 48 deg/s; released, the
    auto-heading brakes it (overshoot about 32 deg: only 74 N m of yaw moment) and brings it
    back to the heading of the release: within 1 deg after 40 s (the integral creeps the last
    degree in, the free-ROV loop's Ki/Kp = 0.05 1/s)."""
    sim = free_rov(heading_deg=0.0)
    sim.set_pilot_demand(0.0, 0.0, 0.0, 0.5)
    sim.run_for(3.0)
    assert sim.rov_eta_n[5] > math.radians(20.0)  # clockwise seen from above
    sim.set_pilot_demand(0.0, 0.0, 0.0, 0.0)
    psi_release = sim.rov_eta_n[5]
    sim.run_for(40.0)
    assert abs(math.degrees(sim.rov_eta_n[5] - psi_release)) < 1.0


def _jump(sim: Simulation, mode: str) -> tuple[np.ndarray, np.ndarray]:
    """The commanded ROV wrench just before and just after a mode switch."""
    before = sim.run_for(0.05)["tau_rov_cmd_b"][-1]
    sim.set_mode(mode)  # type: ignore[arg-type]
    after = sim.run_for(0.01)["tau_rov_cmd_b"][0]
    return before, after


def test_switching_between_autopilot_and_pilot_is_bumpless_both_ways():
    """On the tree in a 0.1 m/s current (the autopilot pushing against it): to manual and back
    to the tree controller, and free station keeping to manual and back. Surge, sway and yaw
    change by less than 1e-6 N (N m) at the switch, against a per-step change of about 1e-3
    while holding. The tree controller's heave is its constant heave force, so heave steps to
    exactly that."""
    sim = Simulation(MODEL, tree_depth_m=100.0, current=steady_current(), seed=3)
    sim.run_for(30.0)
    for mode in ("manual", "tree"):
        before, after = _jump(sim, mode)
        assert np.abs(after - before)[[0, 1, 5]].max() < 1e-6, mode
        assert abs(before[0]) > 1.0  # it was pushing against the current
        sim.run_for(10.0)
    assert after[2] == sim.C.heave_newton  # the tree controller's constant heave
    sim.set_grip(False)
    sim.set_mode("free")
    sim.run_for(20.0)
    for mode in ("manual", "free"):
        before, after = _jump(sim, mode)
        assert np.abs(after - before).max() < 1e-6, mode
        sim.run_for(10.0)


def test_pilot_demand_outside_full_stick_is_refused_by_name():
    sim = free_rov()
    with pytest.raises(ValueError, match=re.escape("pilot sway must be in [-1, 1]")):
        sim.set_pilot_demand(0.0, 1.5, 0.0, 0.0)
    with pytest.raises(ValueError, match="pilot yaw must be in"):
        sim.set_pilot_demand(0.0, 0.0, 0.0, math.nan)
    with pytest.raises(ValueError, match="depth hold must be true or false"):
        sim.set_pilot_holds(True, "yes")  # type: ignore[arg-type]
    np.testing.assert_array_equal(sim.pilot_demand, np.zeros(4))
    assert sim.pilot_holds == (True, True)
    sim.set_pilot_demand(-0.5, 0.25, 1.0, -1.0)
    np.testing.assert_allclose(sim.pilot_demand, [-0.5, 0.25, 1.0, -1.0])


@pytest.mark.parametrize(
    "psi_deg, shown",
    [(-0.001, 0.0), (359.96, 0.0), (-0.06, 359.9), (90.04, 90.0), (-90.0, 270.0), (720.3, 0.3)],
)
def test_pilot_page_heading_reads_as_a_compass(psi_deg, shown):
    """Defect: a heading a hair west of north read "360.0 deg" on the pilot page."""
    from app.console.pilot import compass_heading_deg

    heading = compass_heading_deg(math.radians(psi_deg))
    # 1e-9 deg: the float error of rounding to 0.1 deg and wrapping (the page shows 0.1 deg)
    assert heading == pytest.approx(shown, abs=1e-9)
    assert 0.0 <= heading < 360.0 and f"{heading:.1f}" != "360.0"
