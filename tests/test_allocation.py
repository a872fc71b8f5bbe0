"""Tests of control/allocation.py: thruster model, the three allocators, validation.

ROV data (written here on purpose; the project's parameter module owns the real sets):
work-class ROV = thesis appendix B.3 (SF30k, eq. B.14-B.15, thrust coefficients x10, 1500 rpm);
Minerva = appendix B.4 (eq. B.24-B.29), n_max = 23 rev/s (MODEL_NOTES "ROVs").
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.typing import NDArray
from scipy.optimize import linprog

from control.allocation import (
    DEFAULT_DOFS,
    DEFAULT_PRIORITY,
    SURGE,
    SWAY,
    YAW,
    AllocationResult,
    ThrusterConfig,
    allocate_pinv,
    allocate_priority,
    allocate_qp,
    speed_from_thrust,
    thrust_from_speed,
)

RPM_PER_RPS = 60.0


def work_class_rov() -> ThrusterConfig:
    """SF30k work-class ROV, thesis eq. B.14 (K in N/rpm^2, x10) and B.15; 1500 rpm limit."""
    k_rpm = np.array([0.0002911, 0.0008734, 0.0002911, 0.0002911]) * 10.0
    k_rps = k_rpm * RPM_PER_RPS**2  # N/rpm^2 -> N/(rev/s)^2
    return ThrusterConfig(
        T=[
            [0.0, 0.0, 0.9063, 0.9063],
            [1.0, 0.0, -0.4226, 0.4226],
            [0.0, 1.0, 0.0, 0.0],
            [-0.2373, 0.0, -0.4113, 0.4113],
            [0.0, -0.2862, 0.2179, 0.2179],
            [0.4878, 0.0, 0.7639, -0.7639],
        ],
        k_pos=k_rps,
        k_neg=k_rps,
        n_max_rps=np.full(4, 1500.0 / RPM_PER_RPS),
    )


def minerva() -> ThrusterConfig:
    """ROV Minerva, thesis eq. B.24-B.29; T rows surge, sway, heave, yaw put in rows 0, 1, 2, 5."""
    T = np.zeros((6, 5))
    T[[0, 1, 2, 5]] = [
        [0.9848, 0.9848, 0.0, 0.0, 0.0],
        [0.1736, -0.1736, 1.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 1.0, 1.0],
        [-0.3353, 0.3353, 0.166, 0.0, 0.0],
    ]
    return ThrusterConfig(
        T=T,
        k_pos=[0.4149, 0.4149, 0.3334, 0.3342, 0.3342],  # K_fw, K_fw, K_lat, K_down, K_down
        k_neg=[0.1909, 0.1909, 0.3334, 0.2089, 0.2089],  # K_b, K_b, K_lat, K_up, K_up
        n_max_rps=np.full(5, 23.0),
    )


ROVS = {"work_class": work_class_rov(), "minerva": minerva()}
ALLOCATORS = {"pinv": allocate_pinv, "priority": allocate_priority, "qp": allocate_qp}

# Tolerances.
REL_TOL = 1e-6
"""Demand met 'exactly': the brief's 1e-6 relative. Measured: pinv and priority ~1e-15 (round
off), QP ~3e-9 (bias of its 1e-9 regulariser)."""
QP_BIAS = 1e-6
"""QP vs other allocators, as a fraction of the largest thruster force: the QP regulariser
(1e-9 of full scale) may leave each stage this far from its exact optimum, with margin."""


def unit_to_force(config: ThrusterConfig, u: NDArray[np.float64]) -> NDArray[np.float64]:
    """Map u in [-1, 1]^m onto the asymmetric force box: u = +-1 is a thruster at its limit."""
    return np.where(u >= 0.0, u * config.f_max_pos, u * config.f_max_neg)


def units(m: int, bound: float = 1.0) -> st.SearchStrategy[NDArray[np.float64]]:
    return arrays(np.float64, m, elements=st.floats(-bound, bound, allow_nan=False))


def dof_error(result: AllocationResult, tau: NDArray[np.float64], dof: int) -> float:
    return abs(float(tau[dof] - result.tau_achieved[dof]))


# --- thruster model ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", ROVS)
@given(u=units(5))
def test_speed_and_thrust_are_inverse_inside_limits(name: str, u: NDArray[np.float64]) -> None:
    config = ROVS[name]
    u = u[: config.n_thrusters]
    speed = u * config.n_max_rps
    force = thrust_from_speed(config, speed)
    # Round trip through a square and a square root: a few ulps of n_max.
    np.testing.assert_allclose(speed_from_thrust(config, force), speed, rtol=1e-12, atol=1e-12)
    force_in_box = unit_to_force(config, u)
    np.testing.assert_allclose(
        thrust_from_speed(config, speed_from_thrust(config, force_in_box)),
        force_in_box,
        rtol=1e-12,
        atol=1e-9,
    )


def test_minerva_thrusters_are_asymmetric() -> None:
    """B.24-B.28 at 23 rev/s: +-n_max gives K_fw n^2 ahead and -K_b n^2 astern."""
    config = minerva()
    force = thrust_from_speed(config, [23.0, -23.0, -23.0, 23.0, -23.0])
    expected = [0.4149 * 529, -0.1909 * 529, -0.3334 * 529, 0.3342 * 529, -0.2089 * 529]
    np.testing.assert_allclose(force, expected, rtol=1e-12)  # exact products, round off only
    np.testing.assert_allclose(speed_from_thrust(config, expected), [23, -23, -23, 23, -23])


def test_speeds_beyond_the_limit_saturate() -> None:
    config = work_class_rov()
    n_max = config.n_max_rps
    np.testing.assert_allclose(thrust_from_speed(config, 3.0 * n_max), config.f_max_pos)
    np.testing.assert_allclose(thrust_from_speed(config, -3.0 * n_max), -config.f_max_neg)
    np.testing.assert_allclose(speed_from_thrust(config, 2.0 * config.f_max_pos), n_max)


def test_minerva_largest_backward_surge_is_about_200_newton() -> None:
    """MODEL_NOTES: the sea trial saw -200 N as the largest backward surge force, which sets the
    speed limit at about 23 rev/s: 2 K_b 23^2 cos(10 deg) = 198.9 N, so 1 % ("about")."""
    result = allocate_qp(minerva(), [-1000.0, 0, 0, 0, 0, 0])
    assert result.tau_achieved[SURGE] == pytest.approx(-200.0, rel=0.01)


# --- feasible demands are met -----------------------------------------------------------------


@pytest.mark.parametrize("allocator", ALLOCATORS)
@pytest.mark.parametrize("name", ROVS)
@settings(max_examples=60, deadline=None)
@given(u=units(5), scale=st.sampled_from([1.0, 1e-3]), corners=st.booleans())
def test_feasible_demand_is_met(
    allocator: str, name: str, u: NDArray[np.float64], scale: float, corners: bool
) -> None:
    config = ROVS[name]
    u = u[: config.n_thrusters]
    u = np.sign(u) * scale if corners else u * scale  # corners: thrusters at their limits
    tau = config.T @ unit_to_force(config, u)  # roll/pitch rows non-zero: must be ignored
    result = ALLOCATORS[allocator](config, tau)
    dofs = list(DEFAULT_DOFS)
    tol = REL_TOL * np.max(np.abs(tau[dofs])) + 1e-12
    np.testing.assert_allclose(result.tau_achieved[dofs], tau[dofs], rtol=0, atol=tol)
    np.testing.assert_allclose(result.tau_unmet, 0.0, rtol=0, atol=tol)
    assert np.all(result.tau_unmet[[3, 4]] == 0.0)  # roll, pitch are not allocated


@pytest.mark.parametrize("name", ROVS)
@given(u=units(5))
def test_priority_without_saturation_is_the_pseudo_inverse(
    name: str, u: NDArray[np.float64]
) -> None:
    """Recursive null-space allocation from zero ends at the least-norm solution T^+ tau."""
    config = ROVS[name]
    tau = config.T @ unit_to_force(config, u[: config.n_thrusters])
    priority = allocate_priority(config, tau)
    pinv = allocate_pinv(config, tau)
    scale = float(np.max(config.f_max_pos))
    np.testing.assert_allclose(priority.force_newton, pinv.force_newton, rtol=0, atol=1e-9 * scale)


# --- any demand: limits and consistency -------------------------------------------------------


@pytest.mark.parametrize("allocator", ALLOCATORS)
@pytest.mark.parametrize("name", ROVS)
@settings(max_examples=60, deadline=None)
@given(
    tau=arrays(np.float64, 6, elements=st.floats(-1.0, 1.0)),
    magnitude=st.sampled_from([1e1, 1e3, 1e5, 1e7]),
)
def test_any_demand_respects_limits(
    allocator: str, name: str, tau: NDArray[np.float64], magnitude: float
) -> None:
    config = ROVS[name]
    demand = tau * magnitude
    result = ALLOCATORS[allocator](config, demand)
    force = result.force_newton
    assert np.all(force <= config.f_max_pos) and np.all(force >= -config.f_max_neg)
    assert np.all(np.abs(result.speed_rps) <= config.n_max_rps)
    assert np.all((result.utilisation >= 0.0) & (result.utilisation <= 1.0))
    limit = np.where(force >= 0.0, config.f_max_pos, config.f_max_neg)
    np.testing.assert_allclose(result.utilisation, np.abs(force) / limit, rtol=1e-12)
    # The plant turning at the commanded speeds produces the allocated forces (round off).
    np.testing.assert_allclose(
        thrust_from_speed(config, result.speed_rps), force, rtol=1e-12, atol=1e-9
    )
    np.testing.assert_array_equal(result.speed_rps, speed_from_thrust(config, force))
    np.testing.assert_allclose(result.tau_achieved, config.T @ force, rtol=1e-12, atol=1e-9)
    mask = np.isin(np.arange(6), DEFAULT_DOFS)
    np.testing.assert_array_equal(result.tau_unmet[~mask], 0.0)
    np.testing.assert_allclose(
        result.tau_unmet[mask], (demand - result.tau_achieved)[mask], rtol=1e-12, atol=1e-9
    )


# --- the impossible move (thesis section 3.2.5, fig. 4.14-4.15) -------------------------------


def best_sway_given_yaw(config: ThrusterConfig, yaw: float) -> float:
    """Largest sway force with the yaw moment held at ``yaw``, by an LP (independent of the
    allocators' code)."""
    bounds = list(zip(-config.f_max_neg, config.f_max_pos, strict=True))
    lp = linprog(-config.T[SWAY], A_eq=config.T[[YAW]], b_eq=[yaw], bounds=bounds)
    assert lp.status == 0
    return float(-lp.fun)


@pytest.mark.parametrize("yaw", [60.0, -40.0])
def test_impossible_move_keeps_heading_only_with_priority(yaw: float) -> None:
    """Minerva asked for 800 N surge and 600 N sway (far beyond its thrusters) and a yaw moment
    it could give on its own. Clipping the pseudo-inverse loses the heading; prioritised
    allocation gives the yaw moment exactly and then the most sway it can."""
    config = minerva()
    tau = np.array([800.0, 600.0, 0.0, 0.0, 0.0, yaw])
    pinv = allocate_pinv(config, tau)
    assert abs(pinv.tau_achieved[YAW] - yaw) > 0.4 * abs(yaw)  # measured: half, or wrong sign
    best_sway = best_sway_given_yaw(config, yaw)
    for allocate in (allocate_priority, allocate_qp):
        result = allocate(config, tau)
        assert result.tau_achieved[YAW] == pytest.approx(yaw, abs=1e-6)
        # LP solver and QP regulariser are both accurate to ~1e-7 N here.
        assert result.tau_achieved[SWAY] == pytest.approx(best_sway, abs=1e-5)


def test_impossible_yaw_alone_is_the_largest_moment() -> None:
    config = minerva()
    a = config.T[YAW]
    largest = float(np.sum(np.maximum(a * config.f_max_pos, -a * config.f_max_neg)))
    for allocate in (allocate_priority, allocate_qp):
        result = allocate(config, [0, 0, 0, 0, 0, 500.0])
        # Priority: round off; QP: its regulariser bias (QP_BIAS).
        tol = QP_BIAS * float(np.max(config.f_max_pos))
        assert result.tau_achieved[YAW] == pytest.approx(largest, abs=tol)


# --- QP against the priority allocator --------------------------------------------------------


def largest_reach(config: ThrusterConfig, dof: int, demand: float) -> float:
    """Smallest |demand - T[dof] @ f| over the force box (closed form: support function)."""
    a = config.T[dof]
    high = float(np.sum(np.maximum(a * config.f_max_pos, -a * config.f_max_neg)))
    low = float(np.sum(np.minimum(a * config.f_max_pos, -a * config.f_max_neg)))
    return max(demand - high, low - demand, 0.0)


@pytest.mark.parametrize("priority", [DEFAULT_PRIORITY, (SWAY, SURGE, YAW), (SURGE, YAW, SWAY)])
@pytest.mark.parametrize("name", ROVS)
@settings(max_examples=60, deadline=None)
@given(u=units(5, bound=4.0))
def test_qp_delivers_at_least_what_priority_does(
    priority: tuple[int, ...], name: str, u: NDArray[np.float64]
) -> None:
    """Demands up to 4 times the force box: usually infeasible."""
    config = ROVS[name]
    tau = config.T @ unit_to_force(config, u[: config.n_thrusters])
    qp = allocate_qp(config, tau, priority)
    prio = allocate_priority(config, tau, priority)
    tol = QP_BIAS * float(np.max(config.f_max_pos))
    first, second = priority[0], priority[1]
    best_first = largest_reach(config, first, float(tau[first]))
    assert dof_error(qp, tau, first) == pytest.approx(best_first, abs=tol)
    assert dof_error(prio, tau, first) == pytest.approx(best_first, abs=tol)
    assert dof_error(qp, tau, first) <= dof_error(prio, tau, first) + tol
    if abs(dof_error(qp, tau, first) - dof_error(prio, tau, first)) <= tol:
        assert dof_error(qp, tau, second) <= dof_error(prio, tau, second) + tol


# --- validation and purity --------------------------------------------------------------------


def minerva_fields() -> dict[str, object]:
    config = minerva()
    return {
        "T": config.T.copy(),
        "k_pos": config.k_pos.copy(),
        "k_neg": config.k_neg.copy(),
        "n_max_rps": config.n_max_rps.copy(),
    }


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("T", np.zeros((4, 5))),
        ("T", np.full((6, 5), np.nan)),
        ("k_pos", np.ones(4)),
        ("k_neg", [0.2, 0.2, 0.3, 0.0, 0.2]),
        ("n_max_rps", -np.ones(5)),
        ("k_pos", "fast"),
    ],
)
def test_bad_config_names_the_field(field: str, value: object) -> None:
    fields = minerva_fields() | {field: value}
    with pytest.raises(ValueError, match=f"^{field}:"):
        ThrusterConfig(**fields)


@pytest.mark.parametrize("allocator", ALLOCATORS)
def test_bad_demand_raises(allocator: str) -> None:
    allocate = ALLOCATORS[allocator]
    with pytest.raises(ValueError, match="tau_b"):
        allocate(minerva(), [np.nan, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="tau_b"):
        allocate(minerva(), [0, 0, 0, 0])


def test_bad_dofs_and_priority_raise() -> None:
    config = minerva()
    with pytest.raises(ValueError, match="dofs"):
        allocate_pinv(config, np.zeros(6), dofs=(0, 6))
    with pytest.raises(ValueError, match="priority"):
        allocate_priority(config, np.zeros(6), priority=(5, 5))
    with pytest.raises(ValueError, match="priority"):
        allocate_qp(config, np.zeros(6), priority=())
    with pytest.raises(ValueError, match="speed_rps"):
        thrust_from_speed(config, np.zeros(4))


def test_config_is_an_immutable_copy() -> None:
    fields = minerva_fields()
    config = ThrusterConfig(**fields)
    fields["k_pos"][0] = 99.0  # type: ignore[index]
    assert config.k_pos[0] == 0.4149
    with pytest.raises(ValueError):
        config.k_pos[0] = 1.0


@pytest.mark.parametrize("allocator", ALLOCATORS)
def test_allocators_do_not_modify_arguments(allocator: str) -> None:
    config = minerva()
    tau = np.array([800.0, 600.0, 10.0, 1.0, 2.0, 60.0])
    result = ALLOCATORS[allocator](config, tau)
    np.testing.assert_array_equal(tau, [800.0, 600.0, 10.0, 1.0, 2.0, 60.0])
    with pytest.raises(ValueError):
        result.force_newton[0] = 0.0  # results are read-only


def test_configs_with_the_same_numbers_share_one_priority_plan():
    """Each simulation builds its own ``ThrusterConfig`` (compared by identity); the priority
    plan's tables are kept by the numbers, so a campaign's runs of one ROV build them once.
    A config with other numbers gets its own plan, the same as a plan built afresh."""
    from control import allocation as alloc

    a, b = work_class_rov(), work_class_rov()
    assert a != b  # two objects
    plan_a = alloc._priority_plan(a, DEFAULT_PRIORITY)
    assert alloc._priority_plan(b, DEFAULT_PRIORITY) is plan_a
    other = ThrusterConfig(T=a.T * 1.01, k_pos=a.k_pos, k_neg=a.k_neg, n_max_rps=a.n_max_rps)
    plan_o = alloc._priority_plan(other, DEFAULT_PRIORITY)
    assert plan_o is not plan_a
    fresh = alloc._priority_plan_of.__wrapped__(alloc._SameNumbers(other), DEFAULT_PRIORITY)
    for got, want in ((plan_o.A, fresh.A), (plan_o.D, fresh.D), (plan_o.R, fresh.R)):
        np.testing.assert_array_equal(got, want)
    assert not np.array_equal(plan_o.A, plan_a.A)
