"""The tree's submerged weight W0 (issue 14): both readings of the thesis, and what they do to
the wire's horizontal stiffness and so to the square the ROV can reach at 100 m."""

import math

import numpy as np
import pytest

from control import model
from control.simulation import Simulation
from missions import runner, schema, studies
from sim import params, plant, wire

FULL = params.load("full-scale")
SOLID_NEWTON = FULL.tree.submerged_weight_newton
VOLUME_NEWTON = params.submerged_weight_from_volume(36000.0, params.ADDED_MASS_VOLUME_M3)


def test_both_readings_of_the_submerged_weight():
    """36 t of solid steel: 36 000 x 9.81 x (1 - 1025 / 7850) = 307 047 N; 36 t displacing
    the 15.7 m^3 of eq. 2.18: 353 160 - 157 867.4 = 195 292.6 N (by hand)."""
    assert SOLID_NEWTON == pytest.approx(307046.75, abs=0.01)
    assert VOLUME_NEWTON == pytest.approx(195292.6, abs=0.05)
    volume = params.with_submerged_weight(FULL, VOLUME_NEWTON)
    assert volume.tree.submerged_weight_newton == VOLUME_NEWTON
    # the displaced water behind the Froude-Krylov force follows: rho V = 15.7 x 1025
    assert plant.displaced_mass_kg(volume) == pytest.approx(15.7 * 1025.0, rel=1e-12)
    with pytest.raises(params.ParameterError, match="submerged_weight_newton"):
        params.with_submerged_weight(FULL, -1.0)


def _push_offset_m(ps: params.ParameterSet, force_newton: float) -> tuple[float, float]:
    """Tree alone at 100 m pushed east with a steady force: (settled offset [m], wire length)."""
    sim = Simulation(ps, tree_depth_m=100.0, has_rov=False, control=False)
    sim.set_push(np.array([0.0, force_newton, 0.0]))
    tail = sim.run_for(600.0)["tree_eta_n"][-3000:]  # last 30 s; swing period about 27 s
    return float(np.hypot(tail[:, 0] - 1.0, tail[:, 1] - 1.0).mean()), sim.wire_length_m


def test_reachable_square_at_100_m_depends_on_the_submerged_weight():
    """full-square-100: the work-class ROV can push the tree sideways with at most its sway
    capacity (an LP over its thruster limits, through the 2 m lever). The wire pulls back
    k = w / ln((W0 + w L) / W0) per metre (eq. 2.30), so the ROV holds the tree at most
    capacity / k from its hang: 1.21 m with the solid-steel W0 (k = 3253 N/m) and 1.88 m with
    the added-mass volume's (k = 2104 N/m). A 2 m move is out of reach either way, and the
    lighter reading gives 55 % more room (k is nearly W0 / L, the pendulum).

    The plant agrees: pushing the tree alone with that force moves it capacity / k, plus the
    tilt of the tree about its attachment (z_a / W0 per newton: 2.5 % and 3.9 %)."""
    sim = runner.build_simulation(schema.load_mission("full-square-100"))
    thr = sim.ps.rov.thrusters
    capacity = float(
        model.dof_capacity(sim.sysm.rov_to_tree @ thr.T, thr.f_max_neg, thr.f_max_pos)[1]
    )
    assert capacity == pytest.approx(3949.0, abs=1.0)
    reach = {}
    for name, w0 in (("solid", SOLID_NEWTON), ("volume", VOLUME_NEWTON)):
        ps = params.with_submerged_weight(FULL, w0)
        offset, length = _push_offset_m(ps, capacity)
        k = wire.horizontal_stiffness(ps.wire.submerged_weight_per_length(), w0, length)
        reach[name] = capacity / k
        tilt = 1.0 + ps.tree.attachment_height_m * k / w0  # the pendulum's extra compliance
        assert offset == pytest.approx(reach[name] * tilt, rel=0.01)
    assert reach["solid"] == pytest.approx(1.21, abs=0.01)
    assert reach["volume"] == pytest.approx(1.88, abs=0.01)
    assert max(reach.values()) < 2.0  # the 2 m square's first leg is beyond the ROV
    assert reach["volume"] / reach["solid"] == pytest.approx(1.55, abs=0.01)


@pytest.mark.slow
def test_drag_load_with_the_volume_weight_reproduces_table_4_1_uncontrolled_north():
    """Issue 14: the drag load reproduces table 4.1's uncontrolled north RMS within 30 % in all
    four sea states, with the submerged weight of the thesis's added-mass volume (195 kN; the
    wire 35 % softer sideways, the swing period 33.7 s instead of 27.1 s). Measured over 1800 s
    (seeds 0-2 agree within 4 %): 1.03, 1.21, 0.93, 0.82 of the thesis. With the solid-steel
    307 kN, T = 20 s comes out 1.6 times the thesis (the stiffer wire puts the swing nearer
    that sea), so the thesis's runs look like drag forcing on a lighter tree."""
    ps = params.with_submerged_weight(FULL, VOLUME_NEWTON)
    for (period, hs), (thesis_unc, _) in studies.TABLE_4_1.items():
        unc = studies.uncontrolled_case(period, hs, 1800.0, 0, load="drag", ps=ps)
        assert unc[0] == pytest.approx(thesis_unc[0], rel=0.3), (period, hs, unc[0])


def test_volume_reading_lengthens_the_swing_period():
    """The tree's swing on the wire at 100 m: T = 2 pi sqrt(m_eff / k), m_eff = m + A11 plus the
    ROV (whole surge mass), k from eq. 2.30: 27.1 s with 307 kN, 33.7 s with 195 kN."""
    m_rov = FULL.rov.M_rb[0, 0] + FULL.rov.M_a[0, 0]
    m_eff = 36000.0 + 21865.0 + m_rov
    w = FULL.wire.submerged_weight_per_length()
    periods = [
        2 * math.pi * math.sqrt(m_eff / wire.horizontal_stiffness(w, w0, 97.35))
        for w0 in (SOLID_NEWTON, VOLUME_NEWTON)
    ]
    assert periods[0] == pytest.approx(27.1, abs=0.05)
    assert periods[1] == pytest.approx(33.7, abs=0.05)
