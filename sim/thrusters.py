"""The thruster model, forward and inverse, in one place (thesis eq. 2.13 and 3.22).

Thruster ``i`` turning at ``n_i`` [rev/s] pushes with

    f_i = k_pos_i n_i^2   for n_i >= 0,        f_i = -k_neg_i n_i^2   for n_i < 0,

its speed saturated at ``|n_i| <= n_max_i``; the inverse is the signed square root with the
coefficient of the force's sign, clipped to the rated speed. Inside the force box
``-k_neg n_max^2 <= f <= k_pos n_max^2`` each undoes the other:
``thrust_from_speed(speed_from_thrust(f)) == f`` (to rounding).

The plant (``sim.plant``), the compiled control loop (``control.loop``) and the allocators
(``control.allocation``) all call these. They are compiled with numba and are also ordinary
Python callables on numpy arrays (float64, shape (m,)).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sim.gnc import JIT, JIT_NOALLOC

FloatArray = NDArray[np.float64]


@njit(**JIT_NOALLOC)
def thrust_of_one(n_rps: float, k_pos: float, k_neg: float, n_max: float) -> float:
    """Thrust [N] of one thruster at propeller speed ``n_rps`` [rev/s], saturated at the rated
    speed: ``k_pos n^2`` forwards, ``-k_neg n^2`` backwards (eq. 2.13 with u = n |n|)."""
    n = min(max(n_rps, -n_max), n_max)
    return k_pos * n * n if n >= 0.0 else -k_neg * n * n


@njit(**JIT_NOALLOC)
def speed_of_one(force_newton: float, k_pos: float, k_neg: float, n_max: float) -> float:
    """Propeller speed [rev/s] giving thrust ``force_newton`` [N]: ``sqrt(f / k_pos)`` for
    ``f >= 0``, ``-sqrt(-f / k_neg)`` below, clipped to ``n_max`` (eq. 3.22)."""
    if force_newton >= 0.0:
        return min(math.sqrt(force_newton / k_pos), n_max)
    return -min(math.sqrt(-force_newton / k_neg), n_max)


@njit(**JIT)
def thrust_from_speed(
    n_rps: FloatArray, k_pos: FloatArray, k_neg: FloatArray, n_max: FloatArray
) -> FloatArray:
    """(m,) thrusts [N] from (m,) propeller speeds [rev/s] (``thrust_of_one`` per thruster)."""
    f = np.empty(n_rps.shape[0])
    thrust_from_speed_into(f, n_rps, k_pos, k_neg, n_max)
    return f


@njit(**JIT_NOALLOC)
def thrust_from_speed_into(
    out: FloatArray, n_rps: FloatArray, k_pos: FloatArray, k_neg: FloatArray, n_max: FloatArray
) -> None:
    """``thrust_from_speed`` into ``out`` (m,), allocating nothing."""
    for i in range(n_rps.shape[0]):
        out[i] = thrust_of_one(n_rps[i], k_pos[i], k_neg[i], n_max[i])


@njit(**JIT)
def speed_from_thrust(
    force_newton: FloatArray, k_pos: FloatArray, k_neg: FloatArray, n_max: FloatArray
) -> FloatArray:
    """(m,) propeller speeds [rev/s] from (m,) thrusts [N] (``speed_of_one`` per thruster)."""
    n = np.empty(force_newton.shape[0])
    speed_from_thrust_into(n, force_newton, k_pos, k_neg, n_max)
    return n


@njit(**JIT_NOALLOC)
def speed_from_thrust_into(
    out: FloatArray,
    force_newton: FloatArray,
    k_pos: FloatArray,
    k_neg: FloatArray,
    n_max: FloatArray,
) -> None:
    """``speed_from_thrust`` into ``out`` (m,), allocating nothing."""
    for i in range(force_newton.shape[0]):
        out[i] = speed_of_one(force_newton[i], k_pos[i], k_neg[i], n_max[i])
