"""Start-up check of the mounting vector r (tree origin -> ROV origin, tree axes).

The sea trial failed because r was entered with the wrong sign (thesis section 6.2.1). At
start-up the tree hangs still under the vessel's crane tip (within the wire's drag offset), and
the ROV's position fix and compass are known, so the configured r predicts where the tree is:

    p_tree = p_rov - R(psi_tree) r

If that prediction is far from the hang point while the same r with the opposite sign puts the
tree where it hangs, the sign is almost certainly wrong, and the operator is told before the
controller is trusted. The check needs |r| large enough to tell the two apart from the fix's
noise; with a short r it says it cannot decide. A configured r that puts the tree outside the
plausible hang area is reported in any case.

The observer's start is here too: at the run's start (``initial_estimate``) and at the grip
(``hookup_estimate``), from the ROV's measurements moved to the tree through r.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from control import loop
from sim import site
from sim import wire as wm
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class StartupReport:
    """Outcome of the start-up geometry check."""

    checked: bool
    """False when the geometry cannot tell a sign error apart (|r| too short)."""
    residual_m: float
    """Distance from the hang point of the tree position that the configured r predicts [m]."""
    residual_flipped_m: float
    """The same with -r [m]."""
    warnings: list[str] = field(default_factory=list)


def hang_tolerance_m(
    ps: ParameterSet, wire_length_m: float, fix_noise_m: float, current_speed_mps: float
) -> float:
    """How far from the crane tip the still tree may plausibly hang: the drag offset of the wire
    and tree (eq. 2.29) in the measured current with 50 % margin on its speed, plus three sigma
    of the position fix and 0.3 m for the vessel's own position keeping."""
    speed = 1.5 * abs(current_speed_mps)
    w = ps.wire.submerged_weight_per_length()
    w0 = ps.tree.submerged_weight_newton
    q = ps.wire.drag_per_length(speed)
    offset = wm.horizontal_offset(q, w, w0, wire_length_m, site.tree_drag_force(ps, speed))
    return abs(offset) + 3.0 * fix_noise_m + 0.3


def check_mount_vector(
    y: NDArray[np.float64],
    r_config: NDArray[np.float64],
    crane_tip_n: NDArray[np.float64],
    wire_length_m: float,
    ps: ParameterSet,
    current_speed_mps: float,
) -> StartupReport:
    """Compare the configured r with the measured geometry (see the module docstring)."""
    psi_tree = float(y[4]) - ps.mount.psi_rov_from_tree_rad
    c, s = math.cos(psi_tree), math.sin(psi_tree)
    r_ne = np.array([c * r_config[0] - s * r_config[1], s * r_config[0] + c * r_config[1]])
    hang = np.asarray(crane_tip_n[0:2], float)
    residual = float(np.linalg.norm(y[0:2] - r_ne - hang))
    flipped = float(np.linalg.norm(y[0:2] + r_ne - hang))
    tol = hang_tolerance_m(ps, wire_length_m, ps.sensors.position.noise_std, current_speed_mps)
    # r and -r predict tree positions 2|r| apart: the check can tell them apart only when that
    # is well above the noise of one fix (6 sigma)
    checked = bool(2.0 * float(np.linalg.norm(r_ne)) > 6.0 * ps.sensors.position.noise_std)
    warnings: list[str] = []
    if checked and residual > tol and flipped < residual:
        r_txt = ", ".join(f"{v:g}" for v in r_config)
        warnings.append(
            f"mount vector r_rov_from_tree_tree_m = [{r_txt}] looks like it has the wrong sign: "
            f"with it the ROV's position fix puts the tree {residual:.2f} m from where it hangs "
            f"under the crane tip, with the opposite sign {flipped:.2f} m "
            f"(tolerance {tol:.2f} m). Check the direction FROM the tree's origin TO the ROV."
        )
    elif checked and residual > tol:
        warnings.append(
            f"the ROV's position fix puts the tree {residual:.2f} m from where it should hang "
            f"(tolerance {tol:.2f} m): check the mount vector and the crane-tip position"
        )
    return StartupReport(checked, residual, flipped, warnings)


def initial_estimate(
    held_y: FloatArray, C: loop.ControlArrays, ps: ParameterSet
) -> tuple[FloatArray, FloatArray]:
    """EKF start, (x0 (9,), P0 (9, 9)): the first measurements ``held_y`` moved to the tree
    origin, at rest, no bias."""
    ne, psi, _, _ = loop.tree_measurements(held_y, held_y[4] - C.psi_rel, C)
    x0 = np.zeros(9)
    x0[0:2] = ne
    x0[2] = psi
    p0 = np.diag(
        [
            1.0,
            1.0,
            0.01,
            0.01,
            0.01,
            1e-4,
            *(np.asarray(ps.spec.observer.process_force_std) ** 2),
        ]
    )
    return x0, p0


def hookup_estimate(
    held_y: FloatArray, C: loop.ControlArrays, ps: ParameterSet, t_s: float, last_fix_s: float
) -> tuple[FloatArray, FloatArray]:
    """EKF start at the grip at ``t_s``, (x0 (9,), P0 (9, 9)): the tree's pose and velocity
    are the ROV's, moved to the tree's origin through r (eq. 3.4-3.6), each with the variance
    of the sensor it comes from; the bias starts at zero with its configured spread.

    The held position fix, taken at ``last_fix_s`` (< 0: none yet), can be up to one fix
    interval old: it is carried forward over its age with the DVL's velocity, and its
    variance grows by the DVL's over that age. A start with loose pose variances but the
    gyro's tight rate variance is what made the filter run away at the grip: the wire spring
    couples the position to the yaw acceleration (the tree and ROV's mass matrix has sway-yaw
    terms), so after a few steps the gyro's corrections moved the east estimate by metres."""
    psi_hat = held_y[4] - C.psi_rel
    ne, psi, uv, rate = loop.tree_measurements(held_y, psi_hat, C)
    c, s = math.cos(psi), math.sin(psi)
    vel_n = np.array([c * uv[0] - s * uv[1], s * uv[0] + c * uv[1]])
    age_s = max(t_s - last_fix_s, 0.0) if last_fix_s >= 0.0 else 0.0
    x0 = np.zeros(9)
    x0[0:2] = ne + age_s * vel_n
    x0[2] = psi
    x0[3:5] = uv
    x0[5] = rate
    pos_var = C.r_pos + age_s**2 * C.r_dvl
    p0 = np.diag(
        [
            pos_var,
            pos_var,
            C.r_psi,
            C.r_dvl,
            C.r_dvl,
            C.r_gyro,
            *(np.asarray(ps.spec.observer.process_force_std) ** 2),
        ]
    )
    return x0, p0
