"""The elastic lift wire in the plant (issue 14): the wire's first axial mode (a third of its
mass at the tree, axial damping) on the quasi-static spring. Checked against the spring-mass
period T0 (the same estimate MoorDyn's lumped-mass line reproduces in test_dynamic_wire) and
against the quasi-static wire in the static limit."""

import math

import numpy as np
import pytest

from control.simulation import Simulation
from sim import dynamic_wire as dw
from sim import params, site
from sim import wire as wm

FULL = params.load("full-scale")


def _heave_period_s(wire: str, length_depth_m: float) -> tuple[float, Simulation]:
    """Tree alone on its wire, no current: a 10 kN upward push from the still hang, then the
    mean spacing of the depth's upward zero crossings over 12 s."""
    sim = Simulation(FULL, tree_depth_m=length_depth_m, has_rov=False, control=False, wire=wire)
    sim.set_push(np.array([0.0, 0.0, -1.0e4]))
    rows = sim.run_for(12.0)
    z = rows["tree_eta_n"][:, 2]
    t = rows["t_s"]
    z = z - z.mean()
    up = np.flatnonzero((z[:-1] < 0.0) & (z[1:] >= 0.0))
    crossings = t[up] + (t[up + 1] - t[up]) * (-z[up]) / (z[up + 1] - z[up])
    return float(np.mean(np.diff(crossings))), sim


@pytest.mark.parametrize("depth_m", [100.0, 1000.0])
def test_elastic_wire_bounces_at_the_spring_mass_period(depth_m):
    """T0 = 2 pi sqrt((M + A33 + m_wire L / 3) / (EA / L)) within 5 % (the issue's bound):
    simulated 0.751 s against 0.751 s at 100 m and 2.551 against 2.551 s at 1000 m. Without
    the wire's mass (the quasi-static wire) the 1000 m period is 2.386 s, 6.5 % short of T0
    and outside the bound: the test sees the lumped mass."""
    period, sim = _heave_period_s("elastic", depth_m)
    t0 = dw.t0_estimate_s(FULL, sim.wire_length_m)
    assert period == pytest.approx(t0, rel=0.05)
    if depth_m == 1000.0:
        period_qs, _ = _heave_period_s("quasi-static", depth_m)
        assert abs(period_qs / t0 - 1.0) > 0.05
        assert period > period_qs


def test_elastic_wire_static_limit_is_the_quasi_static_wire():
    """Static limit within 2 % (the issue's bound): a steady 300 N push at 100 m gives the
    same offset as the quasi-static wire, and its stiffness is that of eq. 2.30 within 5 %
    (as the quasi-static test_plant check; the excess is the tilt about the attachment
    point); the tension at rest is W0 and a 10 kN lift shortens the hang by 10 kN / k_z."""
    offsets = {}
    for wire in ("quasi-static", "elastic"):
        sim = Simulation(FULL, tree_depth_m=100.0, has_rov=False, control=False, wire=wire)
        sim.set_push(np.array([300.0, 0.0, 0.0]))
        rows = sim.run_for(600.0)
        offsets[wire] = float(np.mean(rows["tree_eta_n"][-3000:, 0]) - 1.0)
        tension = rows["wire_tension"][-3000:].mean()
        assert tension == pytest.approx(FULL.tree.submerged_weight_newton, rel=0.02)
    assert offsets["elastic"] == pytest.approx(offsets["quasi-static"], rel=0.02)
    k_h = wm.horizontal_stiffness(
        FULL.wire.submerged_weight_per_length(),
        FULL.tree.submerged_weight_newton,
        sim.wire_length_m,
    )
    assert 300.0 / offsets["elastic"] == pytest.approx(k_h, rel=0.05)
    # vertical: the mean depth under a 10 kN lift against the still hang
    sim = Simulation(FULL, tree_depth_m=100.0, has_rov=False, control=False, wire="elastic")
    z0 = sim.tree_eta_n[2]
    sim.set_push(np.array([0.0, 0.0, -1.0e4]))
    rows = sim.run_for(60.0)
    rise = z0 - float(np.mean(rows["tree_eta_n"][-2000:, 2]))
    k_z = site.vertical_stiffness(FULL, sim.wire_length_m, 0.0)
    assert 1.0e4 / rise == pytest.approx(k_z, rel=0.02)


def test_wire_option_is_checked():
    with pytest.raises(ValueError, match="wire must be one of quasi-static, elastic"):
        Simulation(FULL, tree_depth_m=100.0, has_rov=False, control=False, wire="rubber")
    with pytest.raises(ValueError, match="wire_damping_ratio must lie in"):
        Simulation(FULL, tree_depth_m=100.0, has_rov=False, control=False, wire_damping_ratio=-0.1)


def test_elastic_wire_damping_decays_the_bounce_at_the_stated_ratio():
    """With the tree's own heave damping removed, the bounce decays at the dashpot's ratio:
    zeta from the logarithmic decrement within 20 % of the 0.02 set (the quadratic-free
    decay of a linear oscillator; 20 % allows the crossing-based amplitude estimate)."""
    tree = FULL.spec.tree.model_copy(
        update=dict(linear_damping=[0.0] * 6, quadratic_damping=[0.0] * 6)
    )
    ps = params.build(FULL.spec.model_copy(update=dict(tree=tree)))
    sim = Simulation(ps, tree_depth_m=400.0, has_rov=False, control=False, wire="elastic")
    sim.set_push(np.array([0.0, 0.0, -1.0e4]))
    rows = sim.run_for(20.0)
    z = rows["tree_eta_n"][:, 2]
    z = z - z[-500:].mean()
    t0 = dw.t0_estimate_s(ps, sim.wire_length_m)
    n_per = int(round(t0 / sim.dt_s))
    peaks = [np.max(np.abs(z[i * n_per : (i + 1) * n_per])) for i in range(1, 9)]
    zeta = math.log(peaks[0] / peaks[-1]) / (2.0 * math.pi * (len(peaks) - 1))
    assert zeta == pytest.approx(0.02, rel=0.2)


@pytest.mark.parametrize("wire", ["quasi-static", "elastic", "moordyn"])
def test_reported_tension_is_the_logged_tension_in_every_wire_model(wire):
    """Defect: ``Simulation.wire_tension_newton`` worked the tension out again with a wire
    formula of its own, without the elastic wire's damping and without the wire's stretch
    under its own weight, so the console's reading and the log disagreed (by the dashpot's
    force while the tree bounced). Now one function gives both: equal to the bit."""
    sim = Simulation(params.load("full-scale"), tree_depth_m=100.0, control=False, wire=wire)
    sim.winch_to(sim.wire_length_m + 0.5, 0.5)  # a moving wire: the dashpot pulls
    for _ in range(3):
        logged = float(sim.step(37)["wire_tension"][-1])
        assert sim.wire_tension_newton() == logged
    assert logged > 0.5 * sim.ps.tree.submerged_weight_newton
