"""The lift wire as a MoorDyn line coupled to the plant (``wire = "moordyn"``, issue 14):
static hang, static offset under a steady push, the bounce's period, and bad input."""

import math

import numpy as np
import pytest

from control.simulation import Simulation, steady_current
from missions import schema
from sim import dynamic_wire as dw
from sim import params, plant, site, wire

FULL = params.load("full-scale")
W0 = FULL.tree.submerged_weight_newton
W_WIRE = FULL.wire.submerged_weight_per_length()


def _tree_only(
    model: str, depth_m: float = 100.0, crane_tip_n=(1.0, 1.0, 0.0), current_mps: float = 0.0
) -> Simulation:
    return Simulation(
        FULL,
        tree_depth_m=depth_m,
        control=False,
        has_rov=False,
        wire=model,
        crane_tip_n=crane_tip_n,
        current=steady_current(current_mps, 0.0),
    )


def test_plant_takes_the_outside_wire_force_when_told():
    """With E_WEXT set the plant's own wire is off and E_FWIRE acts at the attachment point:
    zero outside force leaves the tree falling at W0 / (M + A33) (7.5 m/s^2 here, plus the
    Froude-Krylov-free hydro terms, all zero at rest)."""
    sim = _tree_only("quasi-static")
    env = sim._environment_chunk(1)[0]
    x = sim.x.copy()
    m_heave = FULL.tree.M_rb[2, 2] + FULL.tree.M_a[2, 2]
    assert plant.rhs(x, np.zeros(8), env, sim.arrays)[8] == pytest.approx(0.0, abs=1e-6)
    env[plant.E_WEXT] = 1.0
    assert plant.rhs(x, np.zeros(8), env, sim.arrays)[8] == pytest.approx(W0 / m_heave, rel=1e-9)
    env[plant.E_FWIRE + 2] = -W0  # an outside wire holding exactly W0
    assert plant.rhs(x, np.zeros(8), env, sim.arrays)[8] == pytest.approx(0.0, abs=1e-6)


def test_tree_hangs_still_on_the_moordyn_wire_at_100_m():
    """The tree starts where the quasi-static wire holds it; on MoorDyn's line it stays within
    3 mm over 20 s, the tension at the tree is W0 and at the crane tip W0 + w L (the wire's
    own submerged weight), both within the issue's 2 % (measured: 1e-10, the lumped-mass
    line's static stretch is the continuum's exactly: its nodes sample a linear tension)."""
    md = _tree_only("moordyn")
    qs = _tree_only("quasi-static")
    rows = md.run_for(20.0)
    qs.run_for(20.0)
    wire = md.site.mdwire
    assert wire is not None
    assert np.max(np.abs(rows["tree_eta_n"][:, 2] - qs.x[2])) < 3e-3  # tree depth, log column
    assert np.linalg.norm(md.x[0:3] - qs.x[0:3]) < 3e-3
    assert md.wire_tension_newton() == pytest.approx(W0, rel=0.02)
    assert wire.top_tension_newton() == pytest.approx(W0 + W_WIRE * md.wire_length_m, rel=0.02)


def test_steady_push_gives_the_quasi_static_offset_at_100_m():
    """A 10 kN push north on the tree: the quasi-static wire's offset is F / k with
    k = w / ln((W0 + w L) / W0) (eq. 2.30, corrected), 3.1 m at 100 m. Both runs start with
    the tree there (its attachment point F / k north of the crane tip) and the push on: if a
    wire's static offset were off by d, the tree would swing about a point d away and move
    up to 2 d in the 30 s that follow (longer than the 27 s swing period). Both stay within
    2 x 2 % of the offset (measured: quasi-static 0.23 %, moordyn 0.10 %)."""
    push = 1.0e4
    length = 100.0 - FULL.tree.attachment_height_m
    k = wire.horizontal_stiffness(W_WIRE, W0, length)
    offset = push / k
    for model in ("quasi-static", "moordyn"):
        sim = _tree_only(model, crane_tip_n=(1.0 - offset, 1.0, 0.0))
        # the tree where the quasi-static wire holds it against the push: its attachment
        # point F / k north of the crane tip, pitched so that the wire's pull at the
        # attachment point and the push at the centre make no moment
        pitch = math.atan(push / W0)
        sim.x[4] = pitch
        sim.x[0] += offset + FULL.tree.attachment_height_m * math.sin(pitch)
        if sim.site.mdwire is not None:
            # MoorDyn's line from the crane tip to the moved tree
            sim.site.start_moordyn_wire(sim.x, sim.arrays.tree_r_att)
        x0 = sim.x[0:3].copy()
        sim.set_push(np.array([push, 0.0, 0.0]))
        rows = sim.run_for(30.0)
        north = rows["tree_eta_n"][:, 0] - x0[0]
        assert np.max(np.abs(north)) < 2.0 * 0.02 * offset, model


CURRENT_MPS = 0.5
"""Steady current of the coupled current-offset checks, towards north [m/s]."""


def _current_offset_m(sim: Simulation) -> float:
    """Where the quasi-static model holds the tree's centre in the current, north of the crane
    tip [m]: the attachment point at eq. 2.29 (corrected) with the wire's drag and the tree's
    as F0 (``dw.quasi_static_current_offset_m``), and the centre below it on the line of the
    wire's pull, the tree pitched by atan(F0 / W0) (its drag at the centre, the pull at the
    attachment point: no moment)."""
    f0 = site.tree_drag_force(FULL, CURRENT_MPS)
    pitch = math.atan(f0 / W0)
    attachment = dw.quasi_static_current_offset_m(FULL, sim.wire_length_m, CURRENT_MPS)
    return attachment + FULL.tree.attachment_height_m * math.sin(pitch)


def test_tree_stays_at_the_quasi_static_current_offset_at_100_m():
    """A 0.5 m/s current north on the tree and, for MoorDyn, along the whole wire (uniform
    over depth, as eq. 2.29 takes it). Both runs start with the tree where the quasi-static
    model holds it (0.496 m north of the crane tip) and pitched to match; as in the push test
    above, a static offset off by d would swing the tree about a point d away and move it up
    to 2 d within the 30 s (longer than the 27 s swing period). Both stay within 2 x 2 % of
    the offset (measured: quasi-static 0.001 %, moordyn 0.64 %, the line bowing into the
    current from the still hang it starts in; left to settle for 300 s it ends 0.09 % from the
    quasi-static run, ``test_coupled_run_settles_at_the_quasi_static_current_offset``)."""
    for model in ("quasi-static", "moordyn"):
        sim = _tree_only(model, crane_tip_n=(0.0, 0.0, 0.0), current_mps=CURRENT_MPS)
        offset = _current_offset_m(sim)
        assert offset == pytest.approx(0.496, abs=0.001)
        sim.x[4] = math.atan(site.tree_drag_force(FULL, CURRENT_MPS) / W0)
        sim.x[0] += offset
        if sim.site.mdwire is not None:
            # MoorDyn's line from the crane tip to the moved tree
            sim.site.start_moordyn_wire(sim.x, sim.arrays.tree_r_att)
        rows = sim.run_for(30.0)
        north = rows["tree_eta_n"][:, 0] - offset
        assert np.max(np.abs(north)) < 2.0 * 0.02 * offset, model


@pytest.mark.slow
@pytest.mark.parametrize("depth_m", [100.0, 400.0])
def test_coupled_run_settles_at_the_quasi_static_current_offset(depth_m):
    """From the still hang below the crane tip, a 0.5 m/s current: after 300 s the tree on
    MoorDyn's wire rests where the quasi-static run's does within the issue's 2 % of the
    offset (measured: 0.4960 m against 0.4956 m at 100 m, +0.09 %; 3.7534 m against 3.7505 m
    at 400 m, +0.08 %: the wire's stretch that the closed form leaves out, see
    ``tests/test_dynamic_wire.py``). The quasi-static run ends at its closed form (eq. 2.29
    with the tree's pitch) within 0.5 % (measured 0.01 %; what is left of its swing)."""
    ends = {}
    for model in ("quasi-static", "moordyn"):
        sim = _tree_only(model, depth_m, crane_tip_n=(0.0, 0.0, 0.0), current_mps=CURRENT_MPS)
        north = sim.run_for(300.0)["tree_eta_n"][:, 0]
        assert np.ptp(north[-1000:]) < 1e-3 * north[-1], model  # settled over the last 10 s
        ends[model] = north[-1]
    offset = _current_offset_m(sim)
    assert ends["quasi-static"] == pytest.approx(offset, rel=0.005)
    assert ends["moordyn"] == pytest.approx(ends["quasi-static"], rel=0.02)


def _bounce_period_s(sim: Simulation, duration_s: float) -> float:
    """Period of the tree's heave after a 10 kN downward step push (spectral peak of the
    depth, Hann window, padded 16 times)."""
    sim.set_push(np.array([0.0, 0.0, 1.0e4]))
    z = sim.run_for(duration_s)["tree_eta_n"][:, 2]
    z = (z - z.mean()) * np.hanning(z.shape[0])
    n = 16 * z.shape[0]
    spectrum = np.abs(np.fft.rfft(z, n=n))
    freqs = np.fft.rfftfreq(n, sim.dt_s)
    return float(1.0 / freqs[1 + int(np.argmax(spectrum[1:]))])


@pytest.mark.parametrize("depth_m", [100.0, 400.0])
def test_bounce_period_in_the_coupled_run_is_t0(depth_m):
    """T0 = 2 pi sqrt((M + A33 + m_wire L / 3) / (EA / L)): 0.76 s at 100 m, 1.55 s at
    400 m; the coupled run's bounce (MoorDyn and the plant taking turns each step) within
    the issue's 5 % (measured -0.9 % and -0.8 %, the spectrum's bins are 0.5 % wide)."""
    sim = _tree_only("moordyn", depth_m)
    t0 = dw.t0_estimate_s(FULL, sim.wire_length_m)
    assert _bounce_period_s(sim, 12.0) == pytest.approx(t0, rel=0.05)


def test_moordyn_wire_refuses_lengths_outside_its_range():
    with pytest.raises(ValueError, match=r"moordyn wire must lie in \[20, 4000\] m, got 7\.4"):
        _tree_only("moordyn", depth_m=10.0)
    sim = _tree_only("moordyn")
    with pytest.raises(ValueError, match=r"wire length must be in \[20, 4000\] m with the moordyn"):
        sim.winch_to(4500.0, 1.0)


def test_mission_with_moordyn_wire_too_shallow_names_the_field():
    text = (
        'format_version = 1\nname = "m"\n[setup]\nparams = "full-scale"\ndepth_m = 10.0\n'
        'wire = "moordyn"\n[[legs]]\ntype = "hold"\nduration_s = 1.0\n'
    )
    with pytest.raises(schema.MissionError) as err:
        schema.parse_text(text, "m.toml")
    assert "setup.depth_m: the moordyn wire needs a tree depth in [25, 4000] m" in str(err.value)
    schema.parse_text(text.replace("10.0", "100.0"), "m.toml")  # deep enough: accepted


def test_coupled_steps_print_nothing(capfd, monkeypatch):
    """MoorDyn logs errors only (``SetVerbosity``) and prints no time per step
    (``disableOutTime``), so its steps need no redirection of standard output (which lost
    other threads' prints while it lasted): a few coupled steps, with file descriptors left
    alone (no ``os.dup2``), and MoorDyn's own Step called directly, leave stdout and
    stderr empty (before: "t = 0 t = 0.01 ..." on every step, hidden by the redirection)."""
    import os

    import moordyn

    sim = _tree_only("moordyn", current_mps=CURRENT_MPS)
    capfd.readouterr()  # the banner MoorDyn prints while reading its input file

    redirections = []
    dup2 = os.dup2
    monkeypatch.setattr(os, "dup2", lambda *a, **k: redirections.append(a) or dup2(*a, **k))
    sim.run_for(0.05)
    monkeypatch.undo()
    assert redirections == []
    md = sim.site.mdwire
    assert md is not None
    end = moordyn.GetPointPos(moordyn.GetPoint(md.system, 2))  # the attachment point
    x = dw.ned_to_moordyn(sim.crane_tip_n) + list(end)
    moordyn.Step(md.system, x, [0.0] * 6, md.t_s, 0.01)
    out, err = capfd.readouterr()
    assert (out, err) == ("", "")
    assert md.t_s == pytest.approx(0.05)
