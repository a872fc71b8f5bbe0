"""Signal quality checks in front of the observer (thesis section 2.6.3, fig. 2.10).

Each fresh sample of each sensor goes through four tests; a sample that fails the range,
wild-point or frozen test is not given to the observer (the observer coasts on its model), and
every failure is counted so the operator can see which sensor misbehaves:

- range: every value inside the sensor's physical range;
- wild point: the jump from the last accepted sample is larger than the threshold plus the
  largest plausible motion since then;
- frozen: the value repeated exactly for ``frozen_count`` samples in a row (only armed for a
  sensor that has noise; a noiseless simulated sensor repeats legitimately when still);
- variance: the variance of the last ``window`` first differences is far above what the
  sensor's noise explains (flagged and counted, the sample is still used).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sim.gnc import JIT, ssa_scalar
from sim.sensors import N_SENSORS, Y_SENSOR

RANGE, WILD, FROZEN, VARIANCE = 0, 1, 2, 3
CHECK_NAMES = ("range", "wild_point", "frozen", "variance")
WINDOW = 10


@dataclass(frozen=True)
class QualityConfig:
    """Thresholds per entry of y (11,) and per sensor (5,)."""

    lo: NDArray[np.float64]
    """(11,) lowest plausible value."""
    hi: NDArray[np.float64]
    """(11,) highest plausible value."""
    wild_jump: NDArray[np.float64]
    """(11,) jump beyond which a sample is a wild point, on top of the motion allowance."""
    max_rate: NDArray[np.float64]
    """(11,) largest plausible rate of change, per second (motion allowance)."""
    frozen_count: NDArray[np.int64]
    """(5,) identical samples in a row that mean a frozen sensor (0 = test off)."""
    variance_limit: NDArray[np.float64]
    """(11,) largest plausible variance of first differences."""


def quality_config(noise_std: NDArray[np.float64], dt: float) -> QualityConfig:
    """Default thresholds from the sensors' noise (sim.sensors.SensorConfig.noise_std)."""
    big = 1.0e4
    lo = np.array([-big, -big, -10.0, -10.0, -np.pi, -5, -5, -5, -2, -2, -2])
    hi = np.array([big, big, 6000.0, 6000.0, np.pi, 5, 5, 5, 2, 2, 2])
    # a wild point is more than 8 sigma (and at least a small floor) away from the last one
    floor = np.array([0.5, 0.5, 0.5, 0.5, 0.05, 0.1, 0.1, 0.1, 0.05, 0.05, 0.05])
    wild = np.maximum(8.0 * noise_std, floor)
    max_rate = np.array([2.0, 2.0, 1.0, 1.0, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5])
    has_noise = np.array([np.any(noise_std[Y_SENSOR == k] > 0) for k in range(N_SENSORS)])
    frozen = np.where(has_noise, 5, 0).astype(np.int64)
    # differences of white noise have variance 2 sigma^2; 25x that is far outside chance
    variance = np.maximum(50.0 * noise_std**2, (0.1 * floor) ** 2)
    del dt
    return QualityConfig(lo, hi, wild, max_rate, frozen, variance)


@njit(inline="always", **JIT)
def variance(h: np.ndarray) -> float:
    """``h.var()`` of a 1-D array, numba's operations in numba's order (the mean a sum from
    0.0 in index order over the length, then the squared deviations' sum the same way over
    the length), in plain loops: the same bits at half the cost of the method's iterator."""
    n = h.shape[0]
    c = 0.0
    for j in range(n):
        c += h[j]
    m = c / n
    ssd = 0.0
    for j in range(n):
        v = h[j] - m
        ssd += v * v
    return ssd / n


@njit(inline="always", **JIT)
def check_sample(
    k: int,
    y: np.ndarray,
    t: float,
    last: np.ndarray,
    last_t: np.ndarray,
    repeat: np.ndarray,
    hist: np.ndarray,
    counters: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    wild: np.ndarray,
    max_rate: np.ndarray,
    frozen_count: np.ndarray,
    var_limit: np.ndarray,
    y_first: np.ndarray,
    y_end: np.ndarray,
) -> bool:
    """Check a fresh sample of sensor k (its entries ``y[y_first[k]:y_end[k]]``,
    ``sim.sensors.Y_FIRST``, ``Y_END``). Updates the check state in place (last accepted
    values, their time, repeat count, difference history, counters (5, 4)) and returns True
    when the sample may go to the observer."""
    a, b = y_first[k], y_end[k]
    ok = True
    same = True
    for i in range(a, b):
        if y[i] < lo[i] or y[i] > hi[i]:
            ok = False
        if y[i] != last[i]:
            same = False
    if not ok:
        counters[k, RANGE] += 1
        return False
    seen = last_t[k] >= 0.0
    if seen:
        gap = t - last_t[k]
        for i in range(a, b):
            d = ssa_scalar(y[i] - last[i]) if i == 4 else y[i] - last[i]
            if abs(d) > wild[i] + max_rate[i] * gap:
                counters[k, WILD] += 1
                return False
    repeat[k] = repeat[k] + 1 if same else 0
    if frozen_count[k] > 0 and repeat[k] >= frozen_count[k]:
        counters[k, FROZEN] += 1
        return False
    # variance of first differences over the last WINDOW accepted samples; then the sample
    # becomes the last accepted one
    flagged = False
    for i in range(a, b):
        d = ssa_scalar(y[i] - last[i]) if i == 4 else y[i] - last[i]
        h = hist[i]
        for j in range(WINDOW - 1):
            h[j] = h[j + 1]
        h[WINDOW - 1] = d if seen else 0.0
        if variance(h) > var_limit[i]:
            flagged = True
        last[i] = y[i]
    if flagged:
        counters[k, VARIANCE] += 1
    last_t[k] = t
    return True
