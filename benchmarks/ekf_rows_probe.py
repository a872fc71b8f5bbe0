"""Does the observer's prediction pay with the runs innermost? A probe for the batch kernel's
"EKF prediction" pass (docs/speed.md, sixteenth pass), before any of it goes into
``control.batchkernel``.

The batch kernel predicts each run's filter by itself (``control.ekf.predict_into``, run after
run, each run's 9x9 covariance contiguous). This probe writes the same prediction for N runs
at once with the run index last, every quantity a row of N runs and each row computed with
``predict_into``'s operations in its order (the Jacobian's known zeros left out of the products
as there), so each run's numbers are the scalar code's bit for bit (checked here over several
steps). The control model (mass, damping, bias time constants, process noise) is one for all
runs, as in a campaign; the wire spring (``k_h``, ``p_eq``) is each run's own.

It times, per run-step, at ``--runs`` runs:

- ``scalar``: ``predict_into`` run after run (the kernel's way);
- ``rows``: the rows form on states kept with the runs innermost (x (9, N), P (9, 9, N));
- ``rows + copies``: the same with each run's state copied into the rows and back every step
  (the kernel keeps a run's covariance contiguous for its corrections);
- and each part of the rows form alone (the two covariance products, the symmetrising, the
  model's right-hand side and Jacobian, the heading's cosine and sine).

    .venv/bin/python benchmarks/ekf_rows_probe.py [--runs 32] [--rounds 3] [--json]

Nothing in the product uses it: it sizes the lever before it is built.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.control_benchmark import load_text
from control import ekf
from sim.gnc import JIT_NOALLOC

_ROWS = {"inline": "always", **JIT_NOALLOC}


@njit(**_ROWS)
def _rhs_rows(f0, fa, x, c, s, tau, kh, peq, M, Minv, Dl, Dnl, Tb):
    """``ekf._model_rhs_cs_into`` per run into ``f0`` (9, N); ``fa`` (7, N) keeps the wire
    and bias forces fn, fe, the products ax, ay and the generalised forces g0, g1, g2."""
    N = x.shape[1]
    M00, M01, M02, M10, M11, M12 = M[0, 0], M[0, 1], M[0, 2], M[1, 0], M[1, 1], M[1, 2]
    for r in range(N):
        f0[0, r] = c[r] * x[3, r] - s[r] * x[4, r]
        f0[1, r] = s[r] * x[3, r] + c[r] * x[4, r]
        f0[2, r] = x[5, r]
    for r in range(N):
        fa[0, r] = -kh[r] * (x[0, r] - peq[0, r]) + x[6, r]
        fa[1, r] = -kh[r] * (x[1, r] - peq[1, r]) + x[7, r]
    for r in range(N):
        nu0, nu1, nu2 = x[3, r], x[4, r], x[5, r]
        fa[2, r] = M00 * nu0 + M01 * nu1 + M02 * nu2
        fa[3, r] = M10 * nu0 + M11 * nu1 + M12 * nu2
    d0, d1, d2 = Dl[0], Dl[1], Dl[2]
    e0, e1, e2 = Dnl[0], Dnl[1], Dnl[2]
    for r in range(N):
        nu0, nu1, nu2 = x[3, r], x[4, r], x[5, r]
        fn, fe, ax, ay = fa[0, r], fa[1, r], fa[2, r], fa[3, r]
        g0 = tau[0, r] + c[r] * fn + s[r] * fe
        g1 = tau[1, r] - s[r] * fn + c[r] * fe
        g2 = tau[2, r] + x[8, r]
        g0 -= -ay * nu2 + (d0 + e0 * abs(nu0)) * nu0
        g1 -= ax * nu2 + (d1 + e1 * abs(nu1)) * nu1
        g2 -= (ay * nu0 - ax * nu1) + (d2 + e2 * abs(nu2)) * nu2
        fa[4, r] = g0
        fa[5, r] = g1
        fa[6, r] = g2
    for i in range(3):
        m0, m1, m2 = Minv[i, 0], Minv[i, 1], Minv[i, 2]
        for r in range(N):
            acc = 0.0
            acc += m0 * fa[4, r]
            acc += m1 * fa[5, r]
            acc += m2 * fa[6, r]
            f0[3 + i, r] = acc
        tb = Tb[i]
        for r in range(N):
            f0[6 + i, r] = -x[6 + i, r] / tb


@njit(**_ROWS)
def _phi_rows(phi, g, x, c, s, fa, kh, dt, M, Minv, Dl, Dnl, Tb):
    """``ekf.jacobian_phi_into`` per run: the entries of Phi that ``ekf.phi_times_into``
    reads, into ``phi`` (9, 9, N). ``g`` (3, 9, N) holds d(M nu_dot)/dx; its known zeros and
    the 1.0 of the yaw bias are set once (``_work``), so rows 3-5 take the scalar code's
    products, zeros included."""
    N = x.shape[1]
    for r in range(N):
        u, v = x[3, r], x[4, r]
        phi[0, 2, r] = -s[r] * u - c[r] * v
        phi[0, 3, r] = c[r]
        phi[0, 4, r] = -s[r]
        phi[1, 2, r] = c[r] * u - s[r] * v
        phi[1, 3, r] = s[r]
        phi[1, 4, r] = c[r]
    M00, M01, M02, M10, M11, M12 = M[0, 0], M[0, 1], M[0, 2], M[1, 0], M[1, 1], M[1, 2]
    d0, d1, d2 = Dl[0], Dl[1], Dl[2]
    e0, e1, e2 = Dnl[0], Dnl[1], Dnl[2]
    for r in range(N):
        k = kh[r]
        g[0, 0, r] = -c[r] * k
        g[0, 1, r] = -s[r] * k
        g[0, 2, r] = -s[r] * fa[0, r] + c[r] * fa[1, r]
        g[1, 0, r] = s[r] * k
        g[1, 1, r] = -c[r] * k
        g[1, 2, r] = -c[r] * fa[0, r] - s[r] * fa[1, r]
    for r in range(N):
        u, v, w = x[3, r], x[4, r], x[5, r]
        ax, ay = fa[2, r], fa[3, r]
        g[0, 3, r] = M10 * w - (d0 + 2.0 * e0 * abs(u))
        g[0, 4, r] = M11 * w
        g[0, 5, r] = ay + M12 * w
        g[1, 3, r] = -M00 * w
        g[1, 4, r] = -M01 * w - (d1 + 2.0 * e1 * abs(v))
        g[1, 5, r] = -ax - M02 * w
        g[2, 3, r] = -(M10 * u + ay - M00 * v)
        g[2, 4, r] = -(M11 * u - ax - M01 * v)
        g[2, 5, r] = -(M12 * u - M02 * v) - (d2 + 2.0 * e2 * abs(w))
    for r in range(N):
        g[0, 6, r] = c[r]
        g[0, 7, r] = s[r]
        g[1, 6, r] = -s[r]
        g[1, 7, r] = c[r]
    for i in range(3):
        m0, m1, m2 = Minv[i, 0], Minv[i, 1], Minv[i, 2]
        for j in range(9):
            for r in range(N):
                phi[3 + i, j, r] = (m0 * g[0, j, r] + m1 * g[1, j, r] + m2 * g[2, j, r]) * dt
    for r in range(N):
        phi[0, 2, r] *= dt
        phi[0, 3, r] *= dt
        phi[0, 4, r] *= dt
        phi[1, 2, r] *= dt
        phi[1, 3, r] *= dt
        phi[1, 4, r] *= dt
        phi[2, 5, r] = 1.0 * dt
        phi[3, 3, r] += 1.0
        phi[4, 4, r] += 1.0
        phi[5, 5, r] += 1.0
    for i in range(3):
        d = -dt / Tb[i] + 1.0
        for r in range(N):
            phi[6 + i, 6 + i, r] = d


@njit(**_ROWS)
def _phi_column_into(out, phi, j, r, a0, a1, a2, a3, a4, a5, a6, a7, a8):
    """Column j of Phi A for run r, A's column being (a0 ... a8): ``ekf.phi_times_into``'s
    sums, without Phi's known zeros."""
    out[0, j, r] = a0 + phi[0, 2, r] * a2 + phi[0, 3, r] * a3 + phi[0, 4, r] * a4
    out[1, j, r] = a1 + phi[1, 2, r] * a2 + phi[1, 3, r] * a3 + phi[1, 4, r] * a4
    out[2, j, r] = a2 + phi[2, 5, r] * a5
    for i in range(3, 6):
        out[i, j, r] = (
            phi[i, 0, r] * a0 + phi[i, 1, r] * a1 + phi[i, 2, r] * a2
            + phi[i, 3, r] * a3 + phi[i, 4, r] * a4 + phi[i, 5, r] * a5
            + phi[i, 6, r] * a6 + phi[i, 7, r] * a7 + phi[i, 8, r] * a8
        )  # fmt: skip
    out[6, j, r] = phi[6, 6, r] * a6
    out[7, j, r] = phi[7, 7, r] * a7
    out[8, j, r] = phi[8, 8, r] * a8


@njit(**_ROWS)
def _phi_times_rows(out, phi, A):
    """``ekf.phi_times_into(out, phi, A, False)`` per run (out must not alias A or phi)."""
    for j in range(9):
        for r in range(out.shape[2]):
            _phi_column_into(
                out, phi, j, r, A[0, j, r], A[1, j, r], A[2, j, r], A[3, j, r], A[4, j, r],
                A[5, j, r], A[6, j, r], A[7, j, r], A[8, j, r],
            )  # fmt: skip


@njit(**_ROWS)
def _phi_times_t_rows(out, phi, A):
    """``ekf.phi_times_into(out, phi, A, True)`` per run (out must not alias A or phi)."""
    for j in range(9):
        for r in range(out.shape[2]):
            _phi_column_into(
                out, phi, j, r, A[j, 0, r], A[j, 1, r], A[j, 2, r], A[j, 3, r], A[j, 4, r],
                A[j, 5, r], A[j, 6, r], A[j, 7, r], A[j, 8, r],
            )  # fmt: skip


@njit(**_ROWS)
def _add_and_symmetrise_rows(P, GQG):
    """P += GQG, then P = (P + P^T) / 2 element by element, per run (``predict_into``'s end)."""
    N = P.shape[2]
    for i in range(9):
        for j in range(9):
            q = GQG[i, j]
            for r in range(N):
                P[i, j, r] += q
    for i in range(9):
        for j in range(i):
            for r in range(N):
                v = 0.5 * (P[i, j, r] + P[j, i, r])
                P[i, j, r] = v
                P[j, i, r] = v


@njit(**_ROWS)
def _heading_trig_rows(c, s, x):
    """The heading's cosine and sine per run, libm's as the scalar code's (not vectorised)."""
    for r in range(x.shape[1]):
        c[r] = np.cos(x[2, r])
        s[r] = np.sin(x[2, r])


@njit(**_ROWS)
def _predict_rows(x, P, tau, dt, kh, peq, M, Minv, Dl, Dnl, Tb, GQG, w):
    c, s, f0, fa, phi, g, tmp = w
    _heading_trig_rows(c, s, x)
    _rhs_rows(f0, fa, x, c, s, tau, kh, peq, M, Minv, Dl, Dnl, Tb)
    _phi_rows(phi, g, x, c, s, fa, kh, dt, M, Minv, Dl, Dnl, Tb)
    for i in range(9):
        for r in range(x.shape[1]):
            x[i, r] = x[i, r] + dt * f0[i, r]
    _phi_times_rows(tmp, phi, P)
    _phi_times_t_rows(P, phi, tmp)
    _add_and_symmetrise_rows(P, GQG)


def _work(n: int) -> tuple:
    g = np.zeros((3, 9, n))
    g[2, 8, :] = 1.0  # d(g_2)/d(b_psi)
    phi = np.zeros((9, 9, n))
    return (np.empty(n), np.empty(n), np.empty((9, n)), np.empty((7, n)), phi, g, phi.copy())


@njit(**JIT_NOALLOC)
def _scalar(reps, x, P, tau, dt, kh, peq, M, Minv, Dl, Dnl, Tb, GQG, f0, phi, tmp):
    for _ in range(reps):
        for r in range(x.shape[0]):
            ekf.predict_into(
                x[r], P[r], tau[r], dt, Minv, M, Dl, Dnl, kh[r], peq[r], Tb, GQG, f0, phi, tmp
            )


@njit(**JIT_NOALLOC)
def _rows(reps, x, P, tau, dt, kh, peq, M, Minv, Dl, Dnl, Tb, GQG, xs, Ps, ts, khs, peqs, w, copy):
    """``reps`` predictions of every run in rows; ``copy``: the runs' states copied into the
    rows and back around each (else once, before and after)."""
    n = x.shape[0]
    for r in range(n):
        khs[r] = kh[r]
        peqs[0, r] = peq[r, 0]
        peqs[1, r] = peq[r, 1]
        for i in range(3):
            ts[i, r] = tau[r, i]
    for k in range(reps):
        if copy or k == 0:
            for r in range(n):
                for i in range(9):
                    xs[i, r] = x[r, i]
                    for j in range(9):
                        Ps[i, j, r] = P[r, i, j]
        _predict_rows(xs, Ps, ts, dt, khs, peqs, M, Minv, Dl, Dnl, Tb, GQG, w)
        if copy or k == reps - 1:
            for r in range(n):
                for i in range(9):
                    x[r, i] = xs[i, r]
                    for j in range(9):
                        P[r, i, j] = Ps[i, j, r]


@njit(**JIT_NOALLOC)
def _part(which, reps, x, P, tau, dt, kh, peq, M, Minv, Dl, Dnl, Tb, GQG, w):
    c, s, f0, fa, phi, g, tmp = w
    for _ in range(reps):
        if which == 0:
            _phi_times_rows(tmp, phi, P)
        elif which == 1:
            _phi_times_t_rows(P, phi, tmp)
        elif which == 2:
            _add_and_symmetrise_rows(P, GQG)
        elif which == 3:
            _rhs_rows(f0, fa, x, c, s, tau, kh, peq, M, Minv, Dl, Dnl, Tb)
            _phi_rows(phi, g, x, c, s, fa, kh, dt, M, Minv, Dl, Dnl, Tb)
        else:
            _heading_trig_rows(c, s, x)


PARTS = (
    "Phi P",
    "Phi (Phi P)^T",
    "+ GQG, symmetrise",
    "model and Jacobian",
    "heading cos, sin",
)


def _problem(n: int) -> dict[str, Any]:
    """N runs' filters in a plausible state: a tree's model-scale-like mass matrix, random
    poses, velocities (some exactly zero, as at rest) and covariances."""
    rng = np.random.default_rng(7)
    x = rng.normal(size=(n, 9))
    x[:, 2] *= 3.0
    x[: n // 4, 3:6] = 0.0
    A = rng.normal(size=(n, 9, 9))
    M = np.array([[4.0e4, 10.0, -20.0], [-5.0, 5.0e4, 1.0e3], [3.0, 1.0e3, 2.0e5]])
    GQG = np.eye(9) * 1e-4
    GQG[6, 7] = GQG[7, 6] = 3e-5
    return {
        "x": x,
        "P": np.einsum("rij,rkj->rik", A, A) * 0.01,
        "tau": rng.normal(size=(n, 3)) * 1e4,
        "dt": 0.01,
        "kh": rng.uniform(1e3, 5e3, n),
        "peq": rng.normal(size=(n, 2)),
        "M": M,
        "Minv": np.linalg.inv(M),
        "Dl": np.array([1e3, 2e3, 3e3]),
        "Dnl": np.array([2e3, 4e3, 6e3]),
        "Tb": np.array([100.0, 100.0, 200.0]),
        "GQG": GQG,
    }


def _run(kind: str, p: dict[str, Any], reps: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(x, P, seconds) after ``reps`` predictions of every run, ``kind`` one of scalar, rows,
    rows + copies."""
    n = p["x"].shape[0]
    x, P = p["x"].copy(), p["P"].copy()
    cfg = (p["dt"], p["kh"], p["peq"], p["M"], p["Minv"], p["Dl"], p["Dnl"], p["Tb"], p["GQG"])
    t0 = time.perf_counter()
    if kind == "scalar":
        _scalar(reps, x, P, p["tau"], *cfg, np.empty(9), np.empty((9, 9)), np.empty((9, 9)))
    else:
        rows = (np.empty((9, n)), np.empty((9, 9, n)), np.empty((3, n)))
        _rows(
            reps, x, P, p["tau"], *cfg, *rows, np.empty(n), np.empty((2, n)), _work(n),
            kind == "rows + copies",
        )  # fmt: skip
    return x, P, time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=32)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    n = args.runs
    p = _problem(n)
    xs, Ps, _ = _run("scalar", p, 7)
    xr, Pr, _ = _run("rows + copies", p, 7)
    same = bool(np.array_equal(xs, xr) and np.array_equal(Ps, Pr))
    same = same and bool(np.array_equal(np.signbit(Ps), np.signbit(Pr)))
    if not same:
        raise SystemExit("the rows form does not give the scalar prediction's bits")
    reps = max(1, 200_000 // n)
    best: dict[str, float] = {}
    for _ in range(args.rounds):
        for kind in ("scalar", "rows", "rows + copies"):
            seconds = _run(kind, p, reps)[2]
            best[kind] = min(best.get(kind, np.inf), seconds / reps / n * 1e9)
    w = _work(n)
    c, s = w[0], w[1]
    c[:], s[:] = np.cos(p["x"][:, 2]), np.sin(p["x"][:, 2])
    x_rows = np.ascontiguousarray(p["x"].T)
    P_rows = np.ascontiguousarray(p["P"].transpose(1, 2, 0))
    tau_rows = np.ascontiguousarray(p["tau"].T)
    peq_rows = np.ascontiguousarray(p["peq"].T)
    args_rows = (p["dt"], p["kh"], peq_rows, p["M"], p["Minv"], p["Dl"], p["Dnl"], p["Tb"])
    parts: dict[str, float] = {}
    for k, name in enumerate(PARTS):
        for _ in range(args.rounds):
            t0 = time.perf_counter()
            _part(k, reps, x_rows, P_rows, tau_rows, *args_rows, p["GQG"], w)
            ns = (time.perf_counter() - t0) / reps / n * 1e9
            parts[name] = min(parts.get(name, np.inf), ns)
    out = {
        "runs": n,
        "same_bits": same,
        "ns_per_run_step": best,
        "rows_parts_ns_per_run_step": parts,
        "load": load_text(),
    }
    if args.json:
        print(json.dumps(out, indent=1))
        return
    print(f"EKF prediction of {n} runs, best of {args.rounds} (ns per run-step; {out['load']}):")
    print("  the rows form gives the scalar code's bits: yes (7 steps, x and P, signs of zeros)")
    for kind, ns in best.items():
        print(f"  {kind:16s} {ns:7.1f}")
    print("  parts of the rows form:")
    for name, ns in parts.items():
        print(f"    {name:20s} {ns:7.1f}")


if __name__ == "__main__":
    main()
