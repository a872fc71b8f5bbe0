"""Environmental loads: a bounded random-walk current and a linear irregular sea (thesis 2.5).

Frames and units: NED (x north, y east, z down), SI units, radians. A direction is the
direction the water flows (current) or the waves travel (waves) *towards*, measured from
north, clockwise (thesis 2.51, 2.55-2.56).

Everything here is a pure function, vectorised over time: the simulator asks for whole chunks
of time at once. Randomness enters only through a ``numpy.random.Generator`` argument.

Current (eq. 2.49-2.51): speed and direction each follow a Gaussian random walk kept inside
[min, max] by reflection at the bounds. The walk is computed as the cumulative sum of the
increments folded into the band (a triangle wave of period twice the band width). Folding
the free path is the same process as reflecting step by step, because the increments are
symmetric. The state carries which side of the fold the walk is on, so one long run and the
same run cut into chunks give the same samples (up to round-off).

Waves (eq. 2.52-2.56): a sum of linear components. Each component's amplitude comes from
the two-parameter ITTC (modified Pierson-Moskowitz) spectrum, with a random phase and a random
frequency inside its own band (so the sea never repeats exactly, and the sum of A_k^2 / 2 is
an unbiased estimate of the spectrum's variance). In deep water (the thesis's eq. 2.52-2.56)
the wave number is omega^2 / g and the velocity decays as exp(-k z), z the depth (positive
down). With a finite water depth h the wave number solves omega^2 = g k tanh(k h) and the
velocity decays as cosh(k (h - z)) / sinh(k h) (horizontal) and sinh(k (h - z)) / sinh(k h)
(vertical) (linear Airy theory, as in any text on ocean waves).

How the waves load a body (``WAVE_LOADS``) is chosen with the sea: ``drag`` (only the relative
velocity enters, through the damping: what table 4.1 of the thesis behaves like) or
``morison`` (also the added mass and the Froude-Krylov force on the water's acceleration).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from sim.gnc import JIT_NOALLOC

GRAVITY_MPS2 = 9.81
"""Acceleration of gravity [m/s^2] (MODEL_NOTES, conventions)."""

OMEGA_MIN_PER_PEAK = 0.5
"""Lowest wave frequency / peak frequency [-]. The ITTC spectrum holds the fraction
exp(-1.25 / 0.5^4) = exp(-20) = 2e-9 of its variance below it."""

OMEGA_MAX_PER_PEAK = 6.0
"""Highest wave frequency / peak frequency [-]. Above it the ITTC spectrum holds the fraction
1 - exp(-1.25 / 6^4) = 9.6e-4 of the elevation variance and erf(sqrt(1.25 / 6^4)) = 3.5 % of
the horizontal velocity variance at the surface; at 10 m depth and more, for peak periods of
10 s and longer, the velocity part lost is below 1e-4."""

_BLOCK_ELEMENTS = 1 << 21
"""Largest (time x component) phase matrix built at once [-]; bounds memory for long records."""

WAVE_LOADS = ("drag", "morison")
"""How waves load the tree and the ROV:

- ``drag``: the water velocity enters only through the relative velocity (damping on
  nu - nu_c); the water's acceleration is not applied. Table 4.1 of the thesis behaves like
  this (MODEL_NOTES, second round: its T = 10 s figure and its growth with H_s).
- ``morison``: as ``drag``, plus the inertia part of Morison's equation on the water's
  acceleration a: the added mass M_A a and the Froude-Krylov force rho V a (the pressure
  gradient of the undisturbed wave, rho V = m - W0 / g for the tree, B / g for the ROV).
  The physically complete load; at 100 m the tree's Keulegan-Carpenter number is about 3 to 5,
  so inertia dominates."""

DEFAULT_WAVE_LOAD = "morison"
"""The default wave load: the complete one, because an installation is planned with these
numbers; ``drag`` reproduces the thesis's table 4.1 and is chosen explicitly for that."""

_RATIO_CLIP = 1.0e3
"""Largest omega_p / omega evaluated in the spectrum [-]; beyond it exp(-1.25 r^4) is 0.0."""


# ---------------------------------------------------------------------------------------------
# Validation helpers
# ---------------------------------------------------------------------------------------------


def _require_finite(name: str, value: float) -> None:
    """Raise ValueError naming ``name`` unless ``value`` is a finite real number."""
    if not math.isfinite(value):
        raise ValueError(f"{name} must lie in (-inf, inf) (finite), got {value!r}")


def _require_at_least(name: str, value: float, lower: float, lower_name: str = "") -> None:
    """Raise ValueError naming ``name`` unless ``value`` is finite and >= ``lower``."""
    if not (math.isfinite(value) and value >= lower):
        bound = f"{lower_name}, inf) = [{lower!r}" if lower_name else f"{lower!r}"
        raise ValueError(f"{name} must lie in [{bound}, inf), got {value!r}")


def _require_in_band(
    name: str, value: float, lo_name: str, lo: float, hi_name: str, hi: float
) -> None:
    """Raise ValueError naming ``name`` unless lo <= value <= hi (NaN fails)."""
    if not lo <= value <= hi:
        raise ValueError(
            f"{name} must lie in [{lo_name}, {hi_name}] = [{lo!r}, {hi!r}], got {value!r}"
        )


def _require_sign(name: str, value: int) -> None:
    """Raise ValueError naming ``name`` unless ``value`` is +1 or -1."""
    if value not in (1, -1):
        raise ValueError(f"{name} must be +1 or -1, got {value!r}")


# ---------------------------------------------------------------------------------------------
# Current (eq. 2.49-2.51)
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CurrentParams:
    """Bounded random-walk current at the depth of the tree and ROV (eq. 2.49-2.51)."""

    speed_mps: float
    """Initial (mean) current speed V_c [m/s] (eq. 2.49)."""
    direction_rad: float
    """Initial direction beta_c the current flows towards, from north, clockwise [rad]
    (eq. 2.50; chapter 4 uses 225 deg, towards south-west)."""
    speed_min_mps: float
    """Lower bound V_c,min of the speed [m/s], >= 0 (eq. 2.49)."""
    speed_max_mps: float
    """Upper bound V_c,max of the speed [m/s] (eq. 2.49)."""
    direction_min_rad: float
    """Lower bound beta_c,min of the direction [rad] (eq. 2.50)."""
    direction_max_rad: float
    """Upper bound beta_c,max of the direction [rad] (eq. 2.50)."""
    speed_walk_mps_per_sqrt_s: float = 0.0
    """Intensity of w_1: std of the speed increment over 1 s [m/s/sqrt(s)] (eq. 2.49)."""
    direction_walk_rad_per_sqrt_s: float = 0.0
    """Intensity of w_2: std of the direction increment over 1 s [rad/sqrt(s)] (eq. 2.50)."""

    def __post_init__(self) -> None:
        """Check finiteness, ordered bounds, initial values inside them, intensities >= 0."""
        _require_at_least("speed_min_mps", self.speed_min_mps, 0.0)
        _require_at_least("speed_max_mps", self.speed_max_mps, self.speed_min_mps, "speed_min_mps")
        _require_in_band(
            "speed_mps",
            self.speed_mps,
            "speed_min_mps",
            self.speed_min_mps,
            "speed_max_mps",
            self.speed_max_mps,
        )
        _require_finite("direction_min_rad", self.direction_min_rad)
        _require_at_least(
            "direction_max_rad", self.direction_max_rad, self.direction_min_rad, "direction_min_rad"
        )
        _require_in_band(
            "direction_rad",
            self.direction_rad,
            "direction_min_rad",
            self.direction_min_rad,
            "direction_max_rad",
            self.direction_max_rad,
        )
        _require_at_least("speed_walk_mps_per_sqrt_s", self.speed_walk_mps_per_sqrt_s, 0.0)
        _require_at_least("direction_walk_rad_per_sqrt_s", self.direction_walk_rad_per_sqrt_s, 0.0)


@dataclass(frozen=True)
class CurrentState:
    """Current speed and direction at one instant (eq. 2.49-2.50)."""

    speed_mps: float
    """Current speed V_c [m/s] (eq. 2.49)."""
    direction_rad: float
    """Direction beta_c the current flows towards, from north, clockwise [rad] (eq. 2.50)."""
    speed_fold_sign: int = 1
    """+1 or -1 [-]: sign with which the next speed increments enter the reflection fold
    (internal; makes a run cut into chunks equal to one long run)."""
    direction_fold_sign: int = 1
    """+1 or -1 [-]: the same for the direction walk."""

    def __post_init__(self) -> None:
        """Check finite values and fold signs of +1 or -1."""
        _require_finite("speed_mps", self.speed_mps)
        _require_finite("direction_rad", self.direction_rad)
        _require_sign("speed_fold_sign", self.speed_fold_sign)
        _require_sign("direction_fold_sign", self.direction_fold_sign)


class CurrentChunk(NamedTuple):
    """Current over a chunk of ``n_steps`` steps; unpacks as (state, speeds, directions)."""

    state: CurrentState
    """State after the chunk: the value held during the step after the last one."""
    speeds_mps: NDArray[np.float64]
    """Speed held during each step [m/s], shape (n_steps,); entry 0 is the input state's."""
    directions_rad: NDArray[np.float64]
    """Direction held during each step [rad], shape (n_steps,); entry 0 is the input's."""


def initial_current(params: CurrentParams) -> CurrentState:
    """Current state at t = 0: the initial speed and direction of ``params``."""
    return CurrentState(
        speed_mps=float(params.speed_mps), direction_rad=float(params.direction_rad)
    )


@njit(**JIT_NOALLOC)
def _reflected_walk_into(
    out: NDArray[np.float64],
    start: float,
    sign: float,
    scale: float,
    normals: NDArray[np.float64],
    column: int,
    lo: float,
    hi: float,
) -> float:
    """One bounded walk, a step at a time, into ``out`` (n + 1,): out[0] = start, then
    x = out[i] + sign * scale * normals[i, column], reflected into [lo, hi] as a triangle
    wave of period 2 (hi - lo) where it leaves the band (a band of zero width holds lo). A
    reflection that mirrors the step turns ``sign`` over for the steps after it. Returns the
    sign to go on with.

    Each value comes from the one before it, its increment and the sign alone, and the last
    value and the sign are the whole state: a run cut into chunks anywhere gives the same
    numbers, bit for bit, as one long run."""
    width = hi - lo
    v = start + 0.0
    out[0] = v
    for i in range(normals.shape[0]):
        x = v + sign * (scale * normals[i, column])
        if lo <= x <= hi:
            v = x
        elif width <= 0.0:
            v = lo + 0.0
        else:
            m = (x - lo) % (2.0 * width)  # in [0, 2 width): Python's modulo
            if m > width:
                v = min(max(lo + (2.0 * width - m), lo), hi)
                sign = -sign
            else:
                v = min(max(lo + m, lo), hi)
        out[i + 1] = v
    return sign


@njit(**JIT_NOALLOC)
def _walks_into(
    paths: NDArray[np.float64],
    signs: NDArray[np.float64],
    normals: NDArray[np.float64],
    speed: float,
    speed_scale: float,
    speed_lo: float,
    speed_hi: float,
    direction: float,
    direction_scale: float,
    direction_lo: float,
    direction_hi: float,
) -> None:
    """Both walks of ``advance_current`` in one compiled call: the speed's into ``paths[0]``
    from the normals' column 0, the direction's into ``paths[1]`` from column 1 (each as
    ``_reflected_walk_into``), starting with and leaving in ``signs`` their fold signs."""
    signs[0] = _reflected_walk_into(
        paths[0], speed, signs[0], speed_scale, normals, 0, speed_lo, speed_hi
    )
    signs[1] = _reflected_walk_into(
        paths[1], direction, signs[1], direction_scale, normals, 1, direction_lo, direction_hi
    )


def advance_current(
    state: CurrentState,
    params: CurrentParams,
    dt_s: float,
    n_steps: int,
    rng: np.random.Generator,
) -> CurrentChunk:
    """Advance the bounded random-walk current by ``n_steps`` steps of ``dt_s`` (eq. 2.49-2.50).

    V(k+1) = V(k) + sigma_V sqrt(dt) N(0, 1), reflected at [V_min, V_max]; the same for the
    direction. Always draws exactly 2 n_steps standard normals (one (n_steps, 2) array, row
    k = step k), whatever the intensities, and walks a step at a time from the state
    (``_reflected_walk_into``), so a run cut into chunks gives the same numbers, bit for bit,
    as one long run. Zero intensities keep both values exactly constant.

    Returns a CurrentChunk (state, speeds_mps (n_steps,), directions_rad (n_steps,)).
    """
    _require_finite("dt_s", dt_s)
    if dt_s <= 0.0:
        raise ValueError(f"dt_s must lie in (0, inf), got {dt_s!r}")
    if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)) or n_steps < 0:
        raise ValueError(f"n_steps must be an integer in [0, inf), got {n_steps!r}")
    _require_in_band(
        "state.speed_mps",
        state.speed_mps,
        "speed_min_mps",
        params.speed_min_mps,
        "speed_max_mps",
        params.speed_max_mps,
    )
    _require_in_band(
        "state.direction_rad",
        state.direction_rad,
        "direction_min_rad",
        params.direction_min_rad,
        "direction_max_rad",
        params.direction_max_rad,
    )
    normals = rng.standard_normal((int(n_steps), 2))
    sqrt_dt = math.sqrt(dt_s)
    paths = np.empty((2, int(n_steps) + 1))
    signs = np.array([float(state.speed_fold_sign), float(state.direction_fold_sign)])
    _walks_into(
        paths,
        signs,
        normals,
        float(state.speed_mps),
        float(params.speed_walk_mps_per_sqrt_s * sqrt_dt),
        float(params.speed_min_mps),
        float(params.speed_max_mps),
        float(state.direction_rad),
        float(params.direction_walk_rad_per_sqrt_s * sqrt_dt),
        float(params.direction_min_rad),
        float(params.direction_max_rad),
    )
    speeds, directions = paths[0], paths[1]
    new_state = CurrentState(float(speeds[-1]), float(directions[-1]), int(signs[0]), int(signs[1]))
    return CurrentChunk(new_state, speeds[:-1], directions[:-1])


def current_velocity_n(speeds: ArrayLike, directions: ArrayLike) -> NDArray[np.float64]:
    """Current velocity in NED [m/s] (eq. 2.51): [V cos(beta), V sin(beta), 0].

    speeds [m/s] and directions [rad, towards, from north, clockwise] broadcast together to a
    shape s; the result has shape s + (3,), e.g. (n, 3) for two (n,) arrays and (3,) for two
    scalars. The vertical current is neglected near the seafloor (section 2.5.1).
    """
    speed, beta = np.broadcast_arrays(
        np.asarray(speeds, dtype=np.float64), np.asarray(directions, dtype=np.float64)
    )
    return np.stack([speed * np.cos(beta), speed * np.sin(beta), np.zeros_like(speed)], axis=-1)


# ---------------------------------------------------------------------------------------------
# Waves (eq. 2.52-2.56)
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class WaveParams:
    """Irregular long-crested sea from an ITTC spectrum (section 2.5.2, table 4.1)."""

    significant_height_m: float
    """Significant wave height H_s [m], >= 0 (table 4.1)."""
    peak_period_s: float
    """Peak period T_p = 2 pi / omega_p [s], > 0 (table 4.1 calls it T)."""
    direction_rad: float
    """Direction beta the waves travel towards, from north, clockwise [rad] (eq. 2.55-2.56)."""
    n_components: int = 200
    """Number of wave components n [-], in [10, 5000] (eq. 2.54)."""
    load: str = DEFAULT_WAVE_LOAD
    """How the waves load the bodies, one of ``WAVE_LOADS`` [-]."""
    water_depth_m: float = math.inf
    """Depth of the seabed h [m], in [1, inf]; inf: deep water (the thesis's eq. 2.52-2.56)."""

    def __post_init__(self) -> None:
        """Check H_s >= 0, T_p > 0, finite direction, 10 <= n_components <= 5000, a known
        load and a water depth of at least 1 m."""
        _require_at_least("significant_height_m", self.significant_height_m, 0.0)
        _require_finite("peak_period_s", self.peak_period_s)
        if self.peak_period_s <= 0.0:
            raise ValueError(f"peak_period_s must lie in (0, inf), got {self.peak_period_s!r}")
        _require_finite("direction_rad", self.direction_rad)
        n = self.n_components
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 10 <= n <= 5000:
            raise ValueError(f"n_components must be an integer in [10, 5000], got {n!r}")
        if self.load not in WAVE_LOADS:
            raise ValueError(f"load must be one of {', '.join(WAVE_LOADS)}, got {self.load!r}")
        _require_water_depth(self.water_depth_m)


def _require_water_depth(water_depth_m: float) -> None:
    """Raise ValueError unless 1 <= water_depth_m <= inf (inf: deep water)."""
    if not (isinstance(water_depth_m, (int, float)) and 1.0 <= water_depth_m <= math.inf):
        raise ValueError(f"water_depth_m must lie in [1, inf] (inf: deep), got {water_depth_m!r}")


@dataclass(frozen=True, eq=False)
class WaveField:
    """One realisation of the sea: n linear components (eq. 2.52-2.54), in deep water or over
    a seabed at ``water_depth_m``.

    The arrays are stored as read-only float64 copies of shape (n,).
    """

    omega_rad_s: NDArray[np.float64]
    """Circular frequency omega_k of each component [rad/s], > 0 (eq. 2.53)."""
    amplitude_m: NDArray[np.float64]
    """Amplitude A_k = sqrt(2 S(omega_k) d_omega_k) [m], >= 0 (eq. 2.52)."""
    wavenumber_rad_m: NDArray[np.float64]
    """Wave number k_k [rad/m]: omega^2 = g k tanh(k h) (omega^2 / g in deep water)."""
    phase_rad: NDArray[np.float64]
    """Random phase epsilon_k [rad], uniform in [0, 2 pi) (eq. 2.53)."""
    direction_rad: float
    """Direction beta the waves travel towards, from north, clockwise [rad] (eq. 2.55)."""
    water_depth_m: float = math.inf
    """Depth of the seabed h [m]; inf: deep water."""

    def __post_init__(self) -> None:
        """Store read-only float64 copies; check equal 1-D shapes and finite values."""
        names = ("omega_rad_s", "amplitude_m", "wavenumber_rad_m", "phase_rad")
        for name in names:
            array = np.array(getattr(self, name), dtype=np.float64)
            if array.ndim != 1 or array.shape != np.shape(self.omega_rad_s):
                raise ValueError(f"{name} must be 1-D with the shape of omega_rad_s")
            if not np.all(np.isfinite(array)):
                raise ValueError(f"{name} must be finite")
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        if np.any(self.omega_rad_s <= 0.0):
            raise ValueError("omega_rad_s must lie in (0, inf)")
        if np.any(self.amplitude_m < 0.0):
            raise ValueError("amplitude_m must lie in [0, inf)")
        _require_finite("direction_rad", self.direction_rad)
        _require_water_depth(self.water_depth_m)


class WaveKinematics(NamedTuple):
    """Wave particle kinematics at one point; unpacks as (velocity_n, accel_n)."""

    velocity_n: NDArray[np.float64]
    """Water particle velocity in NED [m/s], shape (n, 3) (eq. 2.53-2.56)."""
    accel_n: NDArray[np.float64]
    """Its exact time derivative in NED [m/s^2], shape (n, 3)."""


def deep_water_wavenumber(omega_rad_s: ArrayLike) -> NDArray[np.float64]:
    """Deep-water dispersion k = omega^2 / g [rad/m] for omega [rad/s], any shape."""
    omega = np.asarray(omega_rad_s, dtype=np.float64)
    return omega * omega / GRAVITY_MPS2


def wavenumber(omega_rad_s: ArrayLike, water_depth_m: float = math.inf) -> NDArray[np.float64]:
    """Wave number k [rad/m] of the linear dispersion relation omega^2 = g k tanh(k h).

    omega_rad_s [rad/s] any shape, > 0; water_depth_m h [m] in [1, inf]. Deep water (h = inf)
    gives omega^2 / g exactly. Otherwise Newton's method on x = k h for
    x tanh(x) = y = omega^2 h / g (x tanh x increases with x, so the root is unique), from
    Eckart's approximation x0 = y / sqrt(tanh y) (within 5 % everywhere); stops at a relative
    change below 1e-14 (four to six steps).
    """
    _require_water_depth(water_depth_m)
    omega = np.asarray(omega_rad_s, dtype=np.float64)
    if math.isinf(water_depth_m):
        return deep_water_wavenumber(omega)
    y = omega * omega * water_depth_m / GRAVITY_MPS2
    x = y / np.sqrt(np.tanh(np.maximum(y, 1e-300)))
    for _ in range(50):
        t = np.tanh(x)
        step = (x * t - y) / (t + x * (1.0 - t * t))
        x = x - step
        if np.all(np.abs(step) <= 1e-14 * np.maximum(x, 1e-300)):
            break
    return x / water_depth_m


def depth_factors(
    k_rad_m: NDArray[np.float64], depth_m: float, water_depth_m: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Linear-wave decay with depth: (cosh k (h - z) / sinh k h, sinh k (h - z) / sinh k h).

    The first scales the horizontal particle velocity, the second the vertical one, against
    omega A at the surface; z = depth_m (positive down, 0 <= z <= h). Written with
    exponentials, (e^{-k z} +- e^{-k (2 h - z)}) / (1 - e^{-2 k h}), so large k h neither
    overflows nor loses digits; h = inf gives exp(-k z) for both (the thesis's eq. 2.53).
    """
    decay = np.exp(-k_rad_m * depth_m)
    if math.isinf(water_depth_m):
        return decay, decay
    mirror = np.exp(-k_rad_m * (2.0 * water_depth_m - depth_m))
    denominator = -np.expm1(-2.0 * k_rad_m * water_depth_m)
    return (decay + mirror) / denominator, (decay - mirror) / denominator


def ittc_spectrum(
    omega_rad_s: ArrayLike, significant_height_m: float, peak_period_s: float
) -> NDArray[np.float64]:
    """Two-parameter ITTC (modified Pierson-Moskowitz) wave spectrum S(omega) [m^2 s/rad].

    Form used, with omega_p = 2 pi / T_p the peak frequency (Fossen 2011, section 8.2.1):

        S(omega) = A omega^-5 exp(-B omega^-4),  B = (5/4) omega_p^4,  A = B H_s^2 / 4
                 = (5/16) H_s^2 omega_p^4 omega^-5 exp(-(5/4) (omega_p / omega)^4).

    Properties: dS/domega = 0 at omega_p; m0 = A / (4 B) = H_s^2 / 16; the variance below
    omega is m0 exp(-B omega^-4). Periods in the other common forms of the same spectrum:
    zero-crossing T_z = 2 pi sqrt(m0/m2) = (4 / (5 pi))^(1/4) T_p = 0.710 T_p (Fossen's
    A = 4 pi^3 H_s^2 / T_z^4, B = 16 pi^3 / T_z^4) and mean T_1 = 2 pi m0/m1
    = (4/5)^(1/4) / Gamma(3/4) T_p = 0.772 T_p (A = 173 H_s^2 / T_1^4, B = 691 / T_1^4).

    omega_rad_s has any shape; S = 0 for omega <= 0. Returns an array of the same shape.
    """
    _require_at_least("significant_height_m", significant_height_m, 0.0)
    _require_finite("peak_period_s", peak_period_s)
    if peak_period_s <= 0.0:
        raise ValueError(f"peak_period_s must lie in (0, inf), got {peak_period_s!r}")
    omega = np.asarray(omega_rad_s, dtype=np.float64)
    omega_p = 2.0 * math.pi / peak_period_s
    positive = omega > 0.0
    ratio = np.minimum(omega_p / np.where(positive, omega, 1.0), _RATIO_CLIP)
    spectrum = (
        (5.0 / 16.0) * significant_height_m**2 / omega_p * ratio**5 * np.exp(-1.25 * ratio**4)
    )
    return np.where(positive, spectrum, 0.0)


def wave_frequency_bands(params: WaveParams) -> NDArray[np.float64]:
    """Edges of the n equal frequency bands [rad/s], shape (n + 1,).

    The bands cover [OMEGA_MIN_PER_PEAK, OMEGA_MAX_PER_PEAK] times omega_p = 2 pi / T_p;
    component k draws its frequency uniformly inside band k.
    """
    omega_p = 2.0 * math.pi / params.peak_period_s
    return np.linspace(
        OMEGA_MIN_PER_PEAK * omega_p, OMEGA_MAX_PER_PEAK * omega_p, params.n_components + 1
    )


def make_wave_field(params: WaveParams, rng: np.random.Generator) -> WaveField:
    """Draw one sea realisation from the ITTC spectrum (eq. 2.52).

    Component k: frequency omega_k uniform in band k (width d_omega), amplitude
    A_k = sqrt(2 S(omega_k) d_omega) so that A_k^2 / 2 = S(omega_k) d_omega (eq. 2.52), phase
    uniform in [0, 2 pi), wave number from the dispersion relation at the params' water depth
    (omega^2 / g in deep water). Random frequencies make the
    frequencies incommensurate, so the record has no repetition period, and make
    E[sum A_k^2 / 2] equal the spectrum's variance over the bands exactly. H_s = 0 gives zero
    amplitudes. Consumes 2 n uniforms of ``rng`` (n frequencies, then n phases).
    """
    edges = wave_frequency_bands(params)
    width = np.diff(edges)
    omega = edges[:-1] + width * rng.random(params.n_components)
    phase = rng.uniform(0.0, 2.0 * math.pi, params.n_components)
    spectrum = ittc_spectrum(omega, params.significant_height_m, params.peak_period_s)
    return WaveField(
        omega_rad_s=omega,
        amplitude_m=np.sqrt(2.0 * spectrum * width),
        wavenumber_rad_m=wavenumber(omega, params.water_depth_m),
        phase_rad=phase,
        direction_rad=float(params.direction_rad),
        water_depth_m=float(params.water_depth_m),
    )


def harmonic_sums(
    t_s: NDArray[np.float64],
    omega_rad_s: NDArray[np.float64],
    offset_rad: NDArray[np.float64],
    weights: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sums over components of weighted sines and cosines of theta = omega t + offset.

    t_s (n,), omega_rad_s and offset_rad (m,), weights (m, p). Returns (sin(theta) @ weights,
    cos(theta) @ weights), each (n, p). Works through blocks of time to bound memory.
    """
    n = t_s.shape[0]
    sin_sum = np.zeros((n, weights.shape[1]))
    cos_sum = np.zeros((n, weights.shape[1]))
    rows = max(1, _BLOCK_ELEMENTS // max(1, omega_rad_s.shape[0]))
    for start in range(0, n, rows):
        theta = np.outer(t_s[start : start + rows], omega_rad_s) + offset_rad
        sin_sum[start : start + rows] = np.sin(theta) @ weights
        cos_sum[start : start + rows] = np.cos(theta) @ weights
    return sin_sum, cos_sum


def _as_times(t_s: ArrayLike) -> NDArray[np.float64]:
    """Times as a 1-D float64 array [s]; raise ValueError otherwise."""
    t = np.asarray(t_s, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"t_s must be 1-D, got shape {t.shape}")
    return t


def phase_offset(field: WaveField, north_m: float, east_m: float) -> NDArray[np.float64]:
    """Phase of each component at t = 0 at (north, east): epsilon_k - k_k x_along [rad], (m,)."""
    _require_finite("north_m", north_m)
    _require_finite("east_m", east_m)
    along_m = north_m * math.cos(field.direction_rad) + east_m * math.sin(field.direction_rad)
    return field.phase_rad - field.wavenumber_rad_m * along_m


def surface_elevation_m(
    field: WaveField, t_s: ArrayLike, north_m: float = 0.0, east_m: float = 0.0
) -> NDArray[np.float64]:
    """Surface elevation zeta (positive up) [m], shape (n,), at times t_s (n,) [s].

    zeta = sum_k A_k sin(theta_k), theta_k = omega_k t - k_k x_along + epsilon_k, where
    x_along = north cos(beta) + east sin(beta) is the distance along the wave direction.
    Same phase convention as eq. 2.53: the horizontal velocity is in phase with zeta.
    """
    t = _as_times(t_s)
    offset = phase_offset(field, north_m, east_m)
    sin_sum, _ = harmonic_sums(t, field.omega_rad_s, offset, field.amplitude_m[:, None])
    return sin_sum[:, 0]


def wave_kinematics_n(
    field: WaveField,
    t_s: ArrayLike,
    depth_m: float,
    north_m: float = 0.0,
    east_m: float = 0.0,
) -> WaveKinematics:
    """Linear particle velocity and acceleration in NED (eq. 2.53-2.56, finite depth).

    With theta_k as in ``surface_elevation_m``, z = depth_m (positive down, 0 <= z <= h),
    (c_k, s_k) = omega_k A_k ``depth_factors`` (both omega_k A_k exp(-k_k z) in deep water):

        u   = sum c_k sin(theta_k)          horizontal, along beta   (eq. 2.53-2.54)
        w   = -sum s_k cos(theta_k)         vertical, NED z (down); 90 deg out of phase
        du  = sum omega_k c_k cos(theta_k)  exact time derivatives
        dw  = sum omega_k s_k sin(theta_k)

    and velocity_n = [u cos(beta), u sin(beta), w] (eq. 2.55-2.56), likewise accel_n.
    t_s (n,) [s]; returns WaveKinematics(velocity_n (n, 3) [m/s], accel_n (n, 3) [m/s^2]).
    """
    t = _as_times(t_s)
    _require_at_least("depth_m", depth_m, 0.0)
    if depth_m > field.water_depth_m:
        raise ValueError(
            f"depth_m must lie in [0, water_depth_m] = [0, {field.water_depth_m!r}], "
            f"got {depth_m!r}"
        )
    offset = phase_offset(field, north_m, east_m)
    along, vertical = depth_factors(field.wavenumber_rad_m, depth_m, field.water_depth_m)
    speed_h = field.omega_rad_s * field.amplitude_m * along
    speed_v = field.omega_rad_s * field.amplitude_m * vertical
    weights = np.stack(
        [speed_h, field.omega_rad_s * speed_h, speed_v, field.omega_rad_s * speed_v], axis=1
    )
    sin_sum, cos_sum = harmonic_sums(t, field.omega_rad_s, offset, weights)
    cos_b, sin_b = math.cos(field.direction_rad), math.sin(field.direction_rad)
    u, du = sin_sum[:, 0], cos_sum[:, 1]
    velocity_n = np.stack([u * cos_b, u * sin_b, -cos_sum[:, 2]], axis=1)
    accel_n = np.stack([du * cos_b, du * sin_b, sin_sum[:, 3]], axis=1)
    return WaveKinematics(velocity_n, accel_n)
