"""ROV sensors (thesis section 2.6): white noise plus a zero-order hold at each sensor's rate,
with random dropouts of a sample (acoustic fixes that do not arrive).

The measurement vector ``y`` (11 numbers) is laid out as

    [north, east, down (position fix of the ROV origin, NED, m), depth (m), heading (rad),
     u, v, w (DVL, ROV axes, m/s), p, q, r (gyro, ROV axes, rad/s)]

Sensor k samples on plant steps that are whole multiples of its decimation (plant rate / sensor
rate, which must be an integer). Noise and dropouts are drawn up front from seeded generators
(``draw_noise`` for a chunk of steps; a simulation's ``NoiseStream`` in blocks ahead of its
chunks, the same numbers), so a run is reproducible and the compiled loop stays free of Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sim.gnc import JIT, JIT_NOALLOC, ssa_scalar
from sim.params import SensorsSpec

POSITION, DEPTH, COMPASS, DVL, GYRO = 0, 1, 2, 3, 4
SENSOR_NAMES = ("position", "depth", "compass", "dvl", "gyro")
N_SENSORS = 5
N_Y = 11
Y_POS = slice(0, 3)
Y_DEPTH = 3
Y_PSI = 4
Y_DVL = slice(5, 8)
Y_GYRO = slice(8, 11)
# Which sensor feeds each entry of y.
Y_SENSOR = np.array([POSITION] * 3 + [DEPTH, COMPASS] + [DVL] * 3 + [GYRO] * 3)
# Each sensor's entries lie side by side, in the sensors' order: sensor k feeds
# y[Y_FIRST[k]:Y_END[k]] (the signal checks loop over those instead of all of y).
Y_FIRST = np.searchsorted(Y_SENSOR, np.arange(N_SENSORS), side="left")
Y_END = np.searchsorted(Y_SENSOR, np.arange(N_SENSORS), side="right")
assert all((Y_SENSOR[Y_FIRST[k] : Y_END[k]] == k).all() for k in range(N_SENSORS))
assert int((Y_END - Y_FIRST).sum()) == N_Y


@dataclass(frozen=True)
class SensorConfig:
    """Numeric sensor settings for a given plant step."""

    decimation: NDArray[np.int64]
    """Plant steps between samples, per sensor (5,)."""
    noise_std: NDArray[np.float64]
    """1-sigma noise per entry of y (11,) [m, m, rad, m/s, rad/s]."""
    dropout_probability: NDArray[np.float64]
    """Probability that a due sample is lost, per sensor (5,)."""

    @cached_property
    def pattern_key(self) -> tuple[tuple[int, ...], int]:
        """(decimations, their common period): ``draw_noise``'s key for the sampling pattern,
        worked out once instead of every chunk."""
        decimation = tuple(int(d) for d in self.decimation)
        return decimation, math.lcm(*decimation)


def sensor_config(spec: SensorsSpec, dt: float) -> SensorConfig:
    """Build the numeric settings; every rate must divide the plant rate exactly."""
    decimation = np.zeros(N_SENSORS, dtype=np.int64)
    noise = np.zeros(N_Y)
    dropout = np.zeros(N_SENSORS)
    for k, name in enumerate(SENSOR_NAMES):
        s = getattr(spec, name)
        ratio = 1.0 / (s.rate_hz * dt)
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"sensors.{name}.rate_hz = {s.rate_hz} Hz must divide the plant "
                f"rate {1.0 / dt:g} Hz into a whole number of steps"
            )
        decimation[k] = int(round(ratio))
        noise[Y_SENSOR == k] = s.noise_std
        dropout[k] = s.dropout_probability
    return SensorConfig(decimation, noise, dropout)


@dataclass(frozen=True)
class NoiseChunk:
    """Pre-drawn randomness for steps [first_step, first_step + n)."""

    noise: NDArray[np.float64]
    """(n, 11) noise to add when a sample is taken."""
    fresh: NDArray[np.bool_]
    """(n, 5) True where sensor k delivers a new sample at that step."""


@lru_cache(maxsize=64)
def _due_pattern(decimation: tuple[int, ...], phase: int, n: int) -> NDArray[np.bool_]:
    """(n, 5) True where sensor k samples, for the n steps from a step whose index is
    ``phase`` modulo the sensors' common period (the pattern repeats with it: kept, read-only,
    instead of made again for every chunk)."""
    steps = phase + np.arange(n)
    due = (steps[:, None] % np.array(decimation)[None, :]) == 0
    due.flags.writeable = False
    return due


def draw_noise(
    cfg: SensorConfig,
    dropouts: np.random.Generator,
    normals: np.random.Generator,
    first_step: int,
    n: int,
) -> NoiseChunk:
    """Draw the noise and the sample/dropout pattern for n steps: n x N_SENSORS uniforms from
    ``dropouts`` (a sample is kept where its uniform is at least the sensor's dropout
    probability) and n x N_Y standard normals from ``normals``, scaled by each output's noise
    standard deviation. Each generator is read in step order, so n steps drawn at once or in
    pieces get the same numbers (the simulator gives each purpose a stream of its own)."""
    decimation, period = cfg.pattern_key
    due = _due_pattern(decimation, first_step % period, n)
    uniforms = dropouts.random((n, N_SENSORS))
    noise = normals.standard_normal((n, N_Y))
    fresh = np.empty((n, N_SENSORS), dtype=np.bool_)
    # the normals scaled in place
    _scale_and_keep_into(noise, fresh, noise, uniforms, due, cfg.noise_std, cfg.dropout_probability)
    return NoiseChunk(noise=noise, fresh=fresh)


class NoiseStream:
    """``draw_noise`` for a run's steps in order, drawn ahead in blocks of ``BLOCK_STEPS``
    steps: each generator is read in step order as ``draw_noise`` reads it (``dropouts``
    N_SENSORS uniforms a step, ``normals`` N_Y standard normals), so ``take(cfg, k, n)`` for
    consecutive pieces gives the numbers ``draw_noise`` gives for them, bit for bit, however
    the run is cut. The draws are made in compiled code (numba's ``Generator`` methods run
    numpy's algorithms on the generator's own state: the same numbers), in blocks, so a
    call's cost is shared by many steps. The generators must not be read by anyone else
    while the stream holds them."""

    BLOCK_STEPS = 2048
    """Steps drawn at a time (2048 x 16 numbers, 256 kB)."""

    def __init__(self, dropouts: np.random.Generator, normals: np.random.Generator) -> None:
        self.dropouts = dropouts
        self.normals = normals
        self._uniforms = np.empty((0, N_SENSORS))
        self._normals = np.empty((0, N_Y))
        self._at = 0  # the next step's row in the block

    def take(self, cfg: SensorConfig, first_step: int, n: int) -> NoiseChunk:
        """The next n steps' noise and sample pattern (steps first_step ...)."""
        decimation, period = cfg.pattern_key
        due = _due_pattern(decimation, first_step % period, n)
        noise = np.empty((n, N_Y))
        fresh = np.empty((n, N_SENSORS), dtype=np.bool_)
        done = 0
        while done < n:
            if self._at == self._normals.shape[0]:
                if self._normals.shape[0] == 0:
                    self._uniforms = np.empty((self.BLOCK_STEPS, N_SENSORS))
                    self._normals = np.empty((self.BLOCK_STEPS, N_Y))
                _draw_block_into(self._normals, self._uniforms, self.dropouts, self.normals)
                self._at = 0
            k = min(n - done, self._normals.shape[0] - self._at)
            a, b = self._at, self._at + k
            _scale_and_keep_into(
                noise[done : done + k],
                fresh[done : done + k],
                self._normals[a:b],
                self._uniforms[a:b],
                due[done : done + k],
                cfg.noise_std,
                cfg.dropout_probability,
            )
            self._at = b
            done += k
        return NoiseChunk(noise=noise, fresh=fresh)


@njit(**JIT_NOALLOC)
def _draw_block_into(
    normals_out: np.ndarray,
    uniforms_out: np.ndarray,
    dropouts: np.random.Generator,
    normals: np.random.Generator,
) -> None:
    """A block's draws, step by step: N_SENSORS uniforms from ``dropouts``, N_Y standard
    normals from ``normals`` (each generator in the order ``draw_noise``'s arrays take)."""
    for k in range(normals_out.shape[0]):
        for j in range(uniforms_out.shape[1]):
            uniforms_out[k, j] = dropouts.random()
        for i in range(normals_out.shape[1]):
            normals_out[k, i] = normals.standard_normal()


@njit(**JIT_NOALLOC)
def _scale_and_keep_into(
    noise: np.ndarray,
    fresh: np.ndarray,
    normals: np.ndarray,
    uniforms: np.ndarray,
    due: np.ndarray,
    noise_std: np.ndarray,
    dropout: np.ndarray,
) -> None:
    """The arithmetic on the draws in one compiled call (three numpy operations and their
    temporaries cost a single run's closed loop some 0.08 us a step): ``noise[k, i] =
    normals[k, i] * noise_std[i]`` (the product numpy's broadcast makes; ``normals`` may be
    ``noise`` itself) and ``fresh = due & (uniforms >= dropout)``."""
    for k in range(noise.shape[0]):
        for i in range(noise.shape[1]):
            noise[k, i] = normals[k, i] * noise_std[i]
        for j in range(fresh.shape[1]):
            fresh[k, j] = due[k, j] and uniforms[k, j] >= dropout[j]


@njit(**JIT)
def true_outputs(x: np.ndarray) -> np.ndarray:
    """Noise-free y of the ROV part of a plant state."""
    eta_r, nu_r = x[12:18], x[18:24]
    y = np.empty(11)
    y[0:3] = eta_r[0:3]
    y[3] = eta_r[2]
    y[4] = eta_r[5]
    y[5:8] = nu_r[0:3]
    y[8:11] = nu_r[3:6]
    return y


@njit(**JIT)
def sample(
    x: np.ndarray, held: np.ndarray, noise: np.ndarray, fresh: np.ndarray, y_sensor: np.ndarray
) -> np.ndarray:
    """Zero-order hold: entries whose sensor is fresh take truth + noise, others keep ``held``.
    A NaN noise entry is a frozen sensor: fresh, but repeating its held value (an injected
    fault, control.faults). Heading is wrapped into [-pi, pi) as a compass reports it."""
    out = np.empty(11)
    sample_into(out, x, held, noise, fresh, y_sensor)
    return out


# the plant state's element behind each entry of y (see ``true_outputs``)
_Y_STATE = np.array([12, 13, 14, 14, 17, 18, 19, 20, 21, 22, 23])


@njit(**JIT_NOALLOC)
def sample_into(
    out: np.ndarray,
    x: np.ndarray,
    held: np.ndarray,
    noise: np.ndarray,
    fresh: np.ndarray,
    y_sensor: np.ndarray,
) -> None:
    """``sample`` into ``out`` (11,), allocating nothing; ``out`` may be ``held`` itself."""
    for i in range(11):
        if fresh[y_sensor[i]] and not math.isnan(noise[i]):
            out[i] = x[_Y_STATE[i]] + noise[i]
        else:
            out[i] = held[i]
    out[4] = ssa_scalar(out[4])


@njit(**JIT)
def _sample_series(states, noise, fresh, held, y_sensor):
    ys = np.empty((states.shape[0], 11))
    h = held.copy()
    for k in range(states.shape[0]):
        h = sample(states[k], h, noise[k], fresh[k], y_sensor)
        ys[k] = h
    return ys, h


def sample_series(
    states: NDArray[np.float64], chunk: NoiseChunk, held: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Measurements for a recorded series of states (one per step). Returns (y (n, 11), held)."""
    return _sample_series(states, chunk.noise, chunk.fresh, held, Y_SENSOR)
