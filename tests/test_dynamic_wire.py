"""The lift wire as a lumped-mass line (MoorDyn) against the quasi-static wire and the
spring-mass period (issue 14): the line on its own, with the tree as MoorDyn's point, checks the
quasi-static model (the line coupled to the plant: ``tests/test_moordyn_wire.py``)."""

import pytest

from sim import dynamic_wire as dw
from sim import params, wire

FULL = params.load("full-scale")


def test_vertical_period_at_400_m_is_the_spring_mass_estimate():
    """T0 = 2 pi sqrt((M + A33 + m_wire L / 3) / (EA / L)) = 2 pi sqrt(61 198 x 400 / 4e8)
    = 1.554 s; MoorDyn's 20-segment line gives 1.551 s (spectral peak, 0.03 Hz bins near it):
    the issue's bound is 5 %. The estimate is Rayleigh's; the exact rod-with-end-mass root
    differs from it by about m_wire / (45 M), 0.4 % here."""
    t0 = dw.t0_estimate_s(FULL, 400.0)
    assert t0 == pytest.approx(1.554, abs=0.001)
    assert dw.vertical_natural_period_s(dw.HangingLine(FULL, 400.0)) == pytest.approx(t0, rel=0.05)


@pytest.mark.slow
@pytest.mark.parametrize("length_m", [100.0, 1000.0])
def test_vertical_period_at_100_and_1000_m(length_m):
    """Measured 0.762 against 0.761 s (100 m) and 2.555 against 2.556 s (1000 m)."""
    t0 = dw.t0_estimate_s(FULL, length_m)
    assert dw.vertical_natural_period_s(dw.HangingLine(FULL, length_m)) == pytest.approx(
        t0, rel=0.05
    )


@pytest.mark.slow
@pytest.mark.parametrize("length_m", [100.0, 400.0])
def test_static_horizontal_stiffness_matches_the_quasi_static_wire(length_m):
    """A 1 kN pull on the tree's point: MoorDyn's static hang moves it F / k with
    k = w / ln((W0 + w L) / W0) (eq. 2.30, corrected) within 2 % (measured 0.16 % at 100 m,
    0.08 % at 400 m)."""
    pull = 1000.0
    line = dw.HangingLine(FULL, length_m, pull_newton=pull, relax_drag_area_m2=200.0)
    k = wire.horizontal_stiffness(
        FULL.wire.submerged_weight_per_length(), FULL.tree.submerged_weight_newton, length_m
    )
    assert dw.pulled_offset_m(line, relax_s=600.0) == pytest.approx(pull / k, rel=0.02)


def test_hanging_line_checks_its_inputs_and_writes_the_tree():
    with pytest.raises(ValueError, match="length_m must lie in"):
        dw.HangingLine(FULL, 0.5)
    with pytest.raises(ValueError, match="n_segments must lie in"):
        dw.HangingLine(FULL, 100.0, n_segments=1)
    with pytest.raises(ValueError, match="pull_newton must be > 0 N"):
        dw.pulled_offset_m(dw.HangingLine(FULL, 100.0))
    text = dw.HangingLine(FULL, 100.0).input_text(0.0)
    # the tree's point: its mass and the volume that makes its weight in water W0
    assert "2 Free 0.0 0.0 -100.0" in text and " 36000.0 " in text
    volume = (36000.0 * 9.81 - FULL.tree.submerged_weight_newton) / (1025.0 * 9.81)
    assert f" {volume} " in text


CURRENT_MPS = 0.5
"""Steady current of the static current-offset check [m/s] (towards north, uniform over
depth: the quasi-static wire's eq. 2.29 assumes it)."""


@pytest.mark.parametrize(
    "length_m, n_segments",
    [
        (100.0, 10),  # coarse: the same offset as 20 segments to 1e-5 (measured), 4 x cheaper
        (400.0, 20),
    ],
)
def test_current_offset_matches_the_quasi_static_wire(length_m, n_segments):
    """Issue 14's static current offset: in a 0.5 m/s current the tree's point hangs
    downstream of the crane tip by the quasi-static model's eq. 2.29 (corrected) with the
    wire's drag q and the tree's drag as F0: 0.505 m at 100 m, 3.785 m at 400 m. MoorDyn's
    line (the same q on every node, the tree's point given the plant's tree drag at 0.5 m/s)
    within the issue's 2 % (measured +0.079 % and +0.089 %). What is left is the wire's
    stretch, which the closed form leaves out: the stretched line is longer by T / EA, 0.077 %
    at the tree (W0 / EA) to 0.097 % at the top of 400 m, and carries that much more drag
    over that much more height (with EA ten times larger, +0.008 % at 100 m, measured); the
    lumping (10 or 20 segments) and the drag on the normal component only (the wire leans by
    under 1 deg, cos^2 = 1 - 3e-4) are smaller."""
    expected = dw.quasi_static_current_offset_m(FULL, length_m, CURRENT_MPS)
    assert expected == pytest.approx({100.0: 0.505, 400.0: 3.785}[length_m], abs=0.001)
    line = dw.HangingLine(
        FULL,
        length_m,
        n_segments=n_segments,
        relax_drag_area_m2=dw.tree_drag_area_m2(FULL, CURRENT_MPS),
        current_mps=CURRENT_MPS,
    )
    assert dw.current_offset_m(line) == pytest.approx(expected, rel=0.02)


@pytest.mark.slow
def test_current_offset_at_100_m_with_20_segments():
    """The 100 m case with the coupled wire's 20 segments (11 s on a quiet machine, 3 times
    the 10-segment run): measured +0.079 %, as with 10 (the stretch, not the lumping, makes
    the difference)."""
    expected = dw.quasi_static_current_offset_m(FULL, 100.0, CURRENT_MPS)
    line = dw.HangingLine(
        FULL,
        100.0,
        relax_drag_area_m2=dw.tree_drag_area_m2(FULL, CURRENT_MPS),
        current_mps=CURRENT_MPS,
    )
    assert dw.current_offset_m(line) == pytest.approx(expected, rel=0.02)


def test_current_offset_checks_its_inputs():
    line = dw.HangingLine(FULL, 100.0, n_segments=10)
    with pytest.raises(ValueError, match="current_mps must be nonzero"):
        dw.current_offset_m(line)
    with pytest.raises(ValueError, match=r"current_mps must lie in \[-5, 5\], got 7"):
        dw.HangingLine(FULL, 100.0, current_mps=7.0)
    with pytest.raises(ValueError, match="current_mps must be a nonzero speed"):
        dw.tree_drag_area_m2(FULL, 0.0)
