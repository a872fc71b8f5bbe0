"""The installation vessel's wave-frequency motion and where it puts the crane tip.

The vessel answers each wave component through response amplitude operators (RAOs) for
surge, sway, heave, roll and pitch; the crane tip moves with the translations plus the
rotations acting on the crane's lever arm (small angles). The RAOs come from closed forms of
strip theory for a box-like hull, not from a panel code: each degree of freedom is a
mass-spring-damper (heave, roll, pitch) or a free body following the water (surge, sway),
excited by the wave averaged over the hull:

- the pressure under the keel is that of the wave at the draft T: a factor exp(-k T)
  (the Smith correction of strip theory);
- a force is the pressure averaged along the length L and across the beam B:
  sinc(k L cos(beta) / 2) sinc(k B sin(beta) / 2), and a moment its first moment,
  3 (sin u - u cos u) / u^3 (pitch along L, roll across B). Both tend to 1 in long waves,
  where the vessel follows the surface: heave 1 m per m, pitch and roll the wave slope,
  surge and sway the particles' horizontal orbit (1 m per m in deep water);
- heave, roll and pitch have their own natural period and damping ratio:
  H = excitation / (1 - r^2 + 2 i zeta r), r = omega / omega_n.

This is the textbook shape of a monohull's RAOs (as in Faltinsen, Sea Loads on Ships and
Offshore Structures, 1990; Journee and Massie, Offshore Hydromechanics): long-wave limits
exact, resonance where the
natural periods are, cancellation in waves shorter than the hull. It is not a particular
vessel's RAO table; a user with one can give the periods and damping that match it.

Frames: the vessel's axes x fore, y starboard, z down; angles roll about x (starboard down
positive), pitch about y (bow up positive). beta is the angle from the bow to the direction the
waves travel towards (0: following sea, 180 deg: head sea, 90 deg: waves travelling to
starboard). Elevation zeta = A sin(theta) as in ``sim.environment``; a response is
Im(H A e^{i theta}).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sim import environment as envmod

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class VesselParams:
    """A monohull installation vessel: main dimensions, natural periods, damping, crane.

    Default: a typical 130 m offshore construction vessel with a 250 t offshore crane
    (the size class of e.g. the Normand Oceanic, Skandi Acergy or Seven Viking:
    L 120-160 m, B 25-30 m, T 7-8 m). Each number's reasoning is beside it."""

    length_m: float = 130.0
    """L between perpendiculars [m]: the middle of the 120-160 m class."""
    beam_m: float = 28.0
    """B [m]: L / B about 4.6, usual for construction vessels (L / B 4.5-5.5)."""
    draft_m: float = 7.5
    """Operating draft T [m]: B / T about 3.7 (class range 6.5-8.5 m)."""
    heave_period_s: float = 7.0
    """Heave natural period [s]: 2 pi sqrt((m + A33) / (rho g A_wp)) with m = rho L B T Cb
    (Cb = 0.7), A33 about m, and A_wp = 0.85 L B: 7.0 s."""
    heave_damping_ratio: float = 0.2
    """Heave damping ratio [-]: radiation damping is large in heave for a ship (0.15-0.3 is
    the usual range): the beam-sea heave RAO peaks at 1.3."""
    pitch_period_s: float = 6.5
    """Pitch natural period [s]: close to heave for a ship (k55 about 0.25 L, GM_L about L)."""
    pitch_damping_ratio: float = 0.2
    """Pitch damping ratio [-]: like heave (radiation-dominated)."""
    roll_period_s: float = 14.0
    """Roll natural period [s]: 2 pi k44 / sqrt(g GM) with k44 = 0.4 B = 11.2 m and a crane
    vessel's GM of 2.5 m: 14.2 s."""
    roll_damping_ratio: float = 0.08
    """Roll damping ratio [-]: lightly damped (viscous, bilge keels: 0.05-0.1)."""
    crane_tip_from_centre_m: tuple[float, float, float] = (-20.0, 18.0, -30.0)
    """Lever arm from the motion centre (midships, at the waterline) to the crane tip, vessel
    axes [m]: 20 m aft of midships, 18 m to starboard (4 m outboard of the 14 m half beam, a
    lift over the side) and 30 m above the waterline (boom tip of a 250 t crane)."""

    def __post_init__(self) -> None:
        """Every length and period > 0, damping ratios in (0, 2]."""
        for name in (
            "length_m",
            "beam_m",
            "draft_m",
            "heave_period_s",
            "pitch_period_s",
            "roll_period_s",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must lie in (0, inf), got {value!r}")
        for name in ("heave_damping_ratio", "pitch_damping_ratio", "roll_damping_ratio"):
            value = getattr(self, name)
            if not 0.0 < value <= 2.0:
                raise ValueError(f"{name} must lie in (0, 2], got {value!r}")
        if len(self.crane_tip_from_centre_m) != 3 or not all(
            math.isfinite(v) for v in self.crane_tip_from_centre_m
        ):
            raise ValueError("crane_tip_from_centre_m must be 3 finite numbers [m]")


CONSTRUCTION_VESSEL = VesselParams()
"""The default vessel (see ``VesselParams``)."""


@dataclass(frozen=True)
class VesselMotion:
    """The vessel as a mission sets it up: its RAOs, heading and heave compensation."""

    heading_rad: float
    """Vessel heading, from north, clockwise [rad]."""
    params: VesselParams = CONSTRUCTION_VESSEL
    """Hull, natural periods, damping and crane (``VesselParams``)."""
    heave_compensation: bool = False
    """True: the crane's active heave compensation takes out part of the tip's vertical
    motion."""
    heave_compensation_efficiency: float = 0.8
    """Fraction of the tip's vertical motion the compensation removes [-], in [0, 1]
    (active systems are commonly specified at 80-95 %; 0.8 is the cautious end)."""

    def __post_init__(self) -> None:
        if not math.isfinite(self.heading_rad):
            raise ValueError(f"heading_rad must be finite, got {self.heading_rad!r}")
        eta = self.heave_compensation_efficiency
        if not 0.0 <= eta <= 1.0:
            raise ValueError(f"heave_compensation_efficiency must lie in [0, 1], got {eta!r}")


def _sinc(u: FloatArray) -> FloatArray:
    """sin(u) / u, 1 at u = 0."""
    return np.sinc(u / math.pi)


def _moment_factor(u: FloatArray) -> FloatArray:
    """3 (sin u - u cos u) / u^3: the first moment of a wave over a uniform length, against its
    long-wave limit (1 at u = 0; series 1 - u^2 / 10 below 1e-3)."""
    small = np.abs(u) < 1e-3
    safe = np.where(small, 1.0, u)
    exact = 3.0 * (np.sin(safe) - safe * np.cos(safe)) / safe**3
    return np.where(small, 1.0 - u * u / 10.0, exact)


def _oscillator(omega: FloatArray, period_s: float, zeta: float) -> NDArray[np.complex128]:
    """1 / (1 - r^2 + 2 i zeta r), r = omega T / (2 pi)."""
    r = omega * period_s / (2.0 * math.pi)
    return np.asarray(1.0 / (1.0 - r * r + 2j * zeta * r), dtype=np.complex128)


def raos(
    omega_rad_s: ArrayLike, k_rad_m: ArrayLike, beta_rad: float, vessel: VesselParams
) -> NDArray[np.complex128]:
    """Complex RAOs (n, 5) of [surge, sway, heave (up), roll, pitch] per m of wave amplitude
    [m/m, rad/m] for waves of frequency omega (n,) and wave number k (n,) arriving at
    ``beta_rad`` from the bow (see the module's notes)."""
    omega = np.asarray(omega_rad_s, dtype=np.float64)
    k = np.asarray(k_rad_m, dtype=np.float64)
    cb, sb = math.cos(beta_rad), math.sin(beta_rad)
    along = 0.5 * k * vessel.length_m * cb
    across = 0.5 * k * vessel.beam_m * sb
    smith = np.exp(-k * vessel.draft_m)
    force = smith * _sinc(along) * _sinc(across)
    out = np.empty((omega.shape[0], 5), dtype=np.complex128)
    # the water's horizontal orbit, -A cos(theta) along the waves: -i A e^{i theta}
    out[:, 0] = -1j * cb * force
    out[:, 1] = -1j * sb * force
    out[:, 2] = force * _oscillator(omega, vessel.heave_period_s, vessel.heave_damping_ratio)
    # slopes: pitch follows d zeta / d x_ship = -k cos(beta) A cos(theta), roll follows
    # -d zeta / d y_ship = k sin(beta) A cos(theta)
    roll_exc = 1j * k * sb * smith * _sinc(along) * _moment_factor(across)
    pitch_exc = -1j * k * cb * smith * _moment_factor(along) * _sinc(across)
    out[:, 3] = roll_exc * _oscillator(omega, vessel.roll_period_s, vessel.roll_damping_ratio)
    out[:, 4] = pitch_exc * _oscillator(omega, vessel.pitch_period_s, vessel.pitch_damping_ratio)
    return out


def crane_tip_raos_n(
    omega_rad_s: ArrayLike, k_rad_m: ArrayLike, wave_direction_rad: float, motion: VesselMotion
) -> NDArray[np.complex128]:
    """Complex RAOs (n, 3) of the crane tip's displacement in NED [m/m], heave compensation
    included: the translations plus roll and pitch acting on the lever arm r (small angles,
    theta x r), turned from the vessel's axes to NED."""
    beta = wave_direction_rad - motion.heading_rad
    h = raos(omega_rad_s, k_rad_m, beta, motion.params)
    rx, ry, rz = motion.params.crane_tip_from_centre_m
    roll, pitch = h[:, 3], h[:, 4]
    tip_b = np.empty((h.shape[0], 3), dtype=np.complex128)
    tip_b[:, 0] = h[:, 0] + pitch * rz
    tip_b[:, 1] = h[:, 1] - roll * rz
    tip_b[:, 2] = -h[:, 2] + roll * ry - pitch * rx
    if motion.heave_compensation:
        tip_b[:, 2] *= 1.0 - motion.heave_compensation_efficiency
    c, s = math.cos(motion.heading_rad), math.sin(motion.heading_rad)
    tip_n = np.empty_like(tip_b)
    tip_n[:, 0] = c * tip_b[:, 0] - s * tip_b[:, 1]
    tip_n[:, 1] = s * tip_b[:, 0] + c * tip_b[:, 1]
    tip_n[:, 2] = tip_b[:, 2]
    return tip_n


RAMP_PEAK_PERIODS = 2.0
"""The vessel's motion grows in over this many peak periods of the sea [-] (``ramp_in``).
A simulation starts with the sea already running; without a ramp the crane tip would jump to
its displaced place at t = 0 and start at full speed, and the tree bounce on the wire (to
zero tension in Hs 4 m, Tp 10 s, elastic wire: a false slack). The half-cosine starts the tip
with no displacement and no speed; while it lasts, its own rate adds at most
(pi / (2 T_ramp)) / (2 pi / Tp) = Tp / (4 T_ramp) = 1/8 of the wave-frequency speed with
T_ramp = 2 Tp, and its spectrum lies below about 1.5 / T_ramp (0.075 Hz at Tp 10 s), far
under the wire's axial bounce (0.4 to 1.3 Hz from 1000 m to 100 m). Two periods also keep
the run short: the motion is full after 20 s at Tp 10 s."""


def ramp_time_s(peak_period_s: float) -> float:
    """The ramp's length for a sea of peak period Tp: ``RAMP_PEAK_PERIODS`` Tp [s]."""
    if not (math.isfinite(peak_period_s) and peak_period_s > 0.0):
        raise ValueError(f"peak_period_s must be > 0 s, got {peak_period_s!r}")
    return RAMP_PEAK_PERIODS * float(peak_period_s)


def ramp_in(t_s: ArrayLike, ramp_s: float) -> FloatArray:
    """The ramp's factor at times t_s [s]: (1 - cos(pi t / T_ramp)) / 2 from t = 0 to
    T_ramp, 1 after it (0 before t = 0); ``ramp_s`` 0: 1 throughout (no ramp). Its value and
    slope are continuous at both ends."""
    t = np.asarray(t_s, dtype=np.float64)
    if not (math.isfinite(ramp_s) and ramp_s >= 0.0):
        raise ValueError(f"ramp_s must be >= 0 s, got {ramp_s!r}")
    if ramp_s == 0.0:
        return np.ones_like(t)
    x = np.clip(t / ramp_s, 0.0, 1.0)
    return 0.5 * (1.0 - np.cos(np.pi * x))


@dataclass(frozen=True)
class CompensationRamp:
    """The heave compensation switched on or off while the vessel moves: its share of
    ``efficiency`` goes from ``from_share`` to ``to_share`` (0 off, 1 on) along ``ramp_in``
    over ``ramp_s`` from ``t0_s``. Switched at once, the crane tip's heave would step (by up
    to the compensated part of its displacement) and the tree snap on the wire; a real active
    compensation also fades in and out. The tip's vertical displacement is the uncompensated
    one times ``z_factor`` (the compensation scales only the vertical, ``crane_tip_raos_n``)."""

    t0_s: float
    from_share: float
    to_share: float
    ramp_s: float
    efficiency: float

    def share(self, t_s: ArrayLike) -> FloatArray:
        """The compensation's share at times t_s [s], in [0, 1]."""
        t = np.asarray(t_s, dtype=np.float64)
        return self.from_share + (self.to_share - self.from_share) * ramp_in(
            t - self.t0_s, self.ramp_s
        )

    def z_factor(self, t_s: ArrayLike) -> FloatArray:
        """What is left of the uncompensated vertical displacement at times t_s [-]."""
        return 1.0 - self.efficiency * self.share(t_s)


def crane_tip_motion_n(
    field: envmod.WaveField,
    t_s: ArrayLike,
    motion: VesselMotion,
    north_m: float = 0.0,
    east_m: float = 0.0,
    ramp_s: float = 0.0,
) -> FloatArray:
    """Displacement of the crane tip from its mean position, NED [m], shape (n, 3), at times
    t_s (n,) [s], for the vessel at (north, east): sum over the components of
    Im(H_k A_k e^{i theta_k}) = A_k (Re H_k sin theta_k + Im H_k cos theta_k), times the
    ramp ``ramp_in(t, ramp_s)`` (0: none; a simulation uses ``ramp_time_s`` of its sea)."""
    t = np.asarray(t_s, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"t_s must be 1-D, got shape {t.shape}")
    ramp = ramp_in(t, ramp_s)
    tip = crane_tip_raos_n(field.omega_rad_s, field.wavenumber_rad_m, field.direction_rad, motion)
    weights = np.concatenate(
        [field.amplitude_m[:, None] * tip.real, field.amplitude_m[:, None] * tip.imag], axis=1
    )
    offset = envmod.phase_offset(field, north_m, east_m)
    sin_sum, cos_sum = envmod.harmonic_sums(t, field.omega_rad_s, offset, weights)
    return (sin_sum[:, 0:3] + cos_sum[:, 3:6]) * ramp[:, None]
