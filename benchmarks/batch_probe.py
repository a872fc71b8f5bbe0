"""Does laying N runs out with the run index innermost pay on this machine? A probe for the
batch stepper (docs/speed.md, "Batch stepper"), measured on two pieces of the step:

1. **Sine and cosine.** numba finds no SVML here, so a loop over runs that calls ``math.sin``
   stays scalar (one libm call per element). ``sim.trig.sincos_poly`` is a sine and cosine the
   compiler can vectorise: Cody-Waite reduction by pi/2, then the minimax polynomials of
   fdlibm's ``__kernel_sin`` and ``__kernel_cos`` on [-pi/4, pi/4], the quadrant chosen by
   selects instead of branches. The probe reports its error against libm in units in the
   last place (over angles in [-100, 100] rad) and the time per element, both ways.
2. **One body's kinematics** (the body-to-NED velocity for each run):
   ``eta_dot = R(phi, theta, psi) nu`` for N runs, once through the plant's own
   ``gnc.Rzyx_into`` and ``gnc.mv3_into`` run after run, once with every row a length-N
   vector and the loops over runs innermost.

    .venv/bin/python benchmarks/batch_probe.py [--runs 64] [--json]

Nothing in the product uses this yet: it sizes the batch stepper before it is written.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sim.gnc import JIT_NOALLOC, Rzyx_into, mv3_into
from sim.trig import sincos_poly


@njit(**JIT_NOALLOC)
def _sincos_libm(x: np.ndarray, s: np.ndarray, c: np.ndarray, reps: int) -> None:
    for _ in range(reps):
        for r in range(x.shape[0]):
            s[r] = math.sin(x[r])
            c[r] = math.cos(x[r])


@njit(**JIT_NOALLOC)
def _sincos_vec(x: np.ndarray, s: np.ndarray, c: np.ndarray, reps: int) -> None:
    for _ in range(reps):
        for r in range(x.shape[0]):
            s[r], c[r] = sincos_poly(x[r])


@njit(**JIT_NOALLOC)
def _kinematics_aos(
    eta: np.ndarray, nu: np.ndarray, out: np.ndarray, R: np.ndarray, reps: int
) -> None:
    """Per run, as the plant does it today: ``gnc.Rzyx_into`` from libm's sines and cosines,
    then ``gnc.mv3_into`` (eta_dot[0:3] = R nu[0:3]), the runs one after the other."""
    for _ in range(reps):
        for r in range(eta.shape[0]):
            Rzyx_into(
                R,
                math.cos(eta[r, 3]),
                math.sin(eta[r, 3]),
                math.cos(eta[r, 4]),
                math.sin(eta[r, 4]),
                math.cos(eta[r, 5]),
                math.sin(eta[r, 5]),
            )
            mv3_into(out[r], R, nu[r, 0:3])


@njit(**JIT_NOALLOC)
def _kinematics_soa(eta: np.ndarray, nu: np.ndarray, out: np.ndarray, reps: int) -> None:
    """The same with every quantity a row of N runs, the loop over runs innermost: Rzyx_into's
    entries written out (a 3x3 per run would be a strided store the loop does not vectorise)
    and summed in mv3_into's order (left to right)."""
    for _ in range(reps):
        for r in range(eta.shape[1]):
            sphi, cphi = sincos_poly(eta[3, r])
            sth, cth = sincos_poly(eta[4, r])
            spsi, cpsi = sincos_poly(eta[5, r])
            u, v, w = nu[0, r], nu[1, r], nu[2, r]
            out[0, r] = (
                cpsi * cth * u
                + (-spsi * cphi + cpsi * sth * sphi) * v
                + (spsi * sphi + cpsi * cphi * sth) * w
            )
            out[1, r] = (
                spsi * cth * u
                + (cpsi * cphi + sphi * sth * spsi) * v
                + (-cpsi * sphi + sth * spsi * cphi) * w
            )
            out[2, r] = -sth * u + cth * sphi * v + cth * cphi * w


def ulp_error(x: np.ndarray) -> tuple[float, float]:
    """Largest error of ``sincos_poly`` against libm (numpy's sin and cos are not libm's on
    every machine, so ``math``'s), in units in the last place of libm's answer."""
    s = np.empty_like(x)
    c = np.empty_like(x)
    _sincos_vec(x, s, c, 1)
    ref_s = np.array([math.sin(v) for v in x])
    ref_c = np.array([math.cos(v) for v in x])
    return (
        float(np.max(np.abs(s - ref_s) / np.spacing(np.abs(ref_s)))),
        float(np.max(np.abs(c - ref_c) / np.spacing(np.abs(ref_c)))),
    )


def _best_ns(fn, args, reps: int, elements: int) -> float:
    fn(*args, 1)  # compile or load
    best = math.inf
    for _ in range(5):
        t0 = time.perf_counter()
        fn(*args, reps)
        best = min(best, time.perf_counter() - t0)
    return best / (reps * elements) * 1e9


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=64, help="runs in the batch")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    n = args.runs
    rng = np.random.default_rng(1)
    x = rng.uniform(-100.0, 100.0, 200_000)
    err_s, err_c = ulp_error(x)
    angles = rng.uniform(-math.pi, math.pi, n)
    s, c = np.empty(n), np.empty(n)
    reps = max(1, 2_000_000 // n)
    libm_ns = _best_ns(_sincos_libm, (angles, s, c), reps, n)
    vec_ns = _best_ns(_sincos_vec, (angles, s, c), reps, n)
    eta = rng.uniform(-0.3, 0.3, (n, 6))
    eta[:, 5] = rng.uniform(-math.pi, math.pi, n)
    nu = rng.normal(size=(n, 6))
    out_aos = np.empty((n, 3))
    out_soa = np.empty((3, n))
    eta_t, nu_t = np.ascontiguousarray(eta.T), np.ascontiguousarray(nu.T)
    aos_ns = _best_ns(_kinematics_aos, (eta, nu, out_aos, np.empty((3, 3))), reps, n)
    soa_ns = _best_ns(_kinematics_soa, (eta_t, nu_t, out_soa), reps, n)
    agree = float(np.max(np.abs(out_aos - out_soa.T)))
    res = {
        "runs": n,
        "sin_max_ulp": err_s,
        "cos_max_ulp": err_c,
        "sincos_libm_ns": libm_ns,
        "sincos_vectorised_ns": vec_ns,
        "kinematics_runs_outer_ns": aos_ns,
        "kinematics_runs_inner_ns": soa_ns,
        "kinematics_largest_difference": agree,
        "load_average": list(os.getloadavg()),
    }
    if args.json:
        print(json.dumps(res))
        return
    print(f"{n} runs, load average {res['load_average']}")
    print(f"sin, cos against libm over [-100, 100] rad: at most {err_s:.2f}, {err_c:.2f} ulp")
    print(f"sine and cosine of one angle: libm {libm_ns:.1f} ns, vectorised {vec_ns:.1f} ns")
    print(
        f"one body's velocity to NED (3 sine-cosine pairs, 3x3 product) per run: runs outer "
        f"{aos_ns:.1f} ns, runs inner {soa_ns:.1f} ns (largest difference {agree:.1e} m/s)"
    )


if __name__ == "__main__":
    main()
