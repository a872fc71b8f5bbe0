"""Shadow mode: our observer and controller on recorded measurements, without the plant.

A closed-loop step (``control.loop._closed_steps``) is sensors -> control step (signal checks,
EKF corrections, reference, controller) -> allocation -> thrusters -> plant -> the observer's
prediction from the step's achieved wrench. A shadow step puts the recording in place of the
plant and the sensors: the held measurements ``y`` and which of them are fresh come from the
recorded rows, the observer's prediction is driven by the recorded achieved wrench
(``tau_rov_ach_b``), and the mode and the grip by the recorded mode. The controller follows the
recorded reference (``eta_ref_n``, ``eta_ref_rate_n`` and an acceleration, ``ShadowInput``):
a trial's log has the reference its controller followed, not the commands that made it.

    start = ShadowStart.of(sim)          # configuration and initial state, from a Simulation
    result = run_shadow(inputs, start)   # ShadowResult: estimates, commands, NIS, innovations
    nis_consistency(result, inputs)      # NIS against its chi-square band

``run_shadow`` runs on the control step's grid (``start.dt_s``); ``ShadowInput`` is on that grid
(``hold_on_grid`` puts slower rows on it, each held until the next).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy import stats

from control import loop, pid
from control.columns import LAYOUT, N_LOG, LogRows
from control.startup import hookup_estimate
from sim import plant, sensors
from sim.gnc import JIT_NOALLOC, ssa_scalar
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_ETA_HAT = LAYOUT.starts["eta_hat_n"]
_NU_HAT = LAYOUT.starts["nu_hat_tree"]
_BIAS = LAYOUT.starts["bias_tree"]
_ETA_D = LAYOUT.starts["eta_ref_n"]
_DETA_D = LAYOUT.starts["eta_ref_rate_n"]
_TAU_ROV = LAYOUT.starts["tau_rov_cmd_b"]
_TAU_ACH = LAYOUT.starts["tau_rov_ach_b"]
_MODE = LAYOUT.starts["mode"]

NIS_DIMENSIONS = {"position": 2, "compass": 1}
"""Measurement dimension of each NIS the observer logs (a fix's north and east, a heading)."""
NIS_BAND = 0.95
"""Probability inside the chi-square band the NIS statistics are judged against."""


@dataclass(frozen=True)
class ShadowInput:
    """A recording on the control step's grid, by name (n steps)."""

    t_s: FloatArray
    """(n,) time of each control step [s] (the step's start; a log row's t_s is one dt later)."""
    y: FloatArray
    """(n, 11) held measurements, as ``sim.sensors`` orders them (SI, rad)."""
    fresh: BoolArray
    """(n, 5) the sensors with a new sample at this step."""
    tau_ach_b: FloatArray
    """(n, 6) the ROV's achieved wrench over the step (ROV axes) [N, N m]."""
    mode: NDArray[np.int64]
    """(n,) the supervisor's mode (``control.loop.MODE_*``)."""
    reference: FloatArray
    """(n, 9) the reference the controller follows: pose, rate, acceleration, NED [m, rad]."""
    has_reference: BoolArray
    """(n,) False where no reference is known (the controller's own model runs there)."""
    handover_command_b: FloatArray | None = None
    """(n, 6) where not NaN: the ROV wrench the recording commanded before this step, which a
    change of mode hands over from (the bumpless starts read the last command); the
    shadow's own where NaN or None (ROV axes) [N, N m]."""
    spring: FloatArray | None = None
    """(n, 3) the control model's wire spring at each step, [k_h [N/m], p_eq north, east [m]]
    (``control.jobs.ClosedChunk.spring``); None: the start's throughout."""
    heave_newton: FloatArray | None = None
    """(n,) the ROV's heave force while on the tree [N] (``Simulation.set_heave_force``);
    None: the start's throughout."""
    restart: BoolArray | None = None
    """(n,) True where the observer starts again before the step, from the held measurements
    (a hook-up: ``control.startup.hookup_estimate``, as ``Simulation.reset_observer``)."""


def fresh_from_changes(y: FloatArray, held_before: FloatArray | None = None) -> BoolArray:
    """(n, 5): a sensor is fresh where any of its entries differs from the step before (the
    first step against ``held_before``; all fresh without it). A fresh sample equal to the
    held one (a frozen sensor) is not seen, nor is a sample that never changed."""
    before = np.vstack([held_before if held_before is not None else np.full(y.shape[1], np.nan),
                        y[:-1]])  # fmt: skip
    changed = ~((y == before) | (np.isnan(y) & np.isnan(before)))
    fresh = np.zeros((y.shape[0], sensors.N_SENSORS), dtype=np.bool_)
    for k in range(sensors.N_SENSORS):
        fresh[:, k] = changed[:, sensors.Y_SENSOR == k].any(axis=1)
    return fresh


def hold_on_grid(row_t_s: FloatArray, dt_s: float) -> NDArray[np.intp]:
    """For rows at times ``row_t_s`` (a log row's time: the end of its step), the row each
    control step of ``dt_s`` from the first row's step takes: the latest at or before it
    (a zero-order hold). ``len`` is the number of steps to the last row."""
    start = row_t_s[0] - dt_s
    steps = np.round((row_t_s - dt_s - start) / dt_s).astype(np.intp)
    if np.any(np.diff(steps) <= 0):
        raise ValueError("rows must be in time order, at most one per control step")
    n = int(steps[-1]) + 1
    index = np.zeros(n, dtype=np.intp)
    index[steps] = np.arange(len(steps))
    return np.maximum.accumulate(index)


def reference_acceleration_from_feedforward(
    ff_tree: FloatArray,
    psi_hat: FloatArray,
    eta_d: FloatArray,
    deta_d: FloatArray,
    C: loop.ControlArrays,
    spring: FloatArray | None = None,
) -> FloatArray:
    """(n, 3) the reference's acceleration (NED) that the recorded feedforward term
    ``ff_tree`` (n, 3, tree axes) was made of: ``control.pid.feedforward_into`` solved for
    ``ddeta_d`` given the estimate's heading and the reference's pose and rate. A run's log
    keeps the reference's pose and rate but not its acceleration; this gives it back to
    rounding (some 1e-12 of the term). ``spring`` (n, 3): the control model's wire spring of
    each row, [k_h, p_eq north, east] (None: C's)."""
    cd, sd = np.cos(eta_d[:, 2]), np.sin(eta_d[:, 2])
    nu0 = cd * deta_d[:, 0] + sd * deta_d[:, 1]
    nu1 = -sd * deta_d[:, 0] + cd * deta_d[:, 1]
    nu2 = deta_d[:, 2]
    M = C.M
    ax = M[0, 0] * nu0 + M[0, 1] * nu1 + M[0, 2] * nu2
    ay = M[1, 0] * nu0 + M[1, 1] * nu1 + M[1, 2] * nu2
    rest = np.column_stack([-ay * nu2, ax * nu2, ay * nu0 - ax * nu1])
    rest[:, 0] += (C.D_l[0] + C.D_nl[0] * np.abs(nu0)) * nu0
    rest[:, 1] += (C.D_l[1] + C.D_nl[1] * np.abs(nu1)) * nu1
    rest[:, 2] += (C.D_l[2] + C.D_nl[2] * np.abs(nu2)) * nu2
    c, s = np.cos(psi_hat), np.sin(psi_hat)
    if spring is None:
        spring = np.tile([C.k_h, C.p_eq[0], C.p_eq[1]], (len(eta_d), 1))
    sp0 = spring[:, 0] * (eta_d[:, 0] - spring[:, 1])
    sp1 = spring[:, 0] * (eta_d[:, 1] - spring[:, 2])
    rest[:, 0] += c * sp0 + s * sp1
    rest[:, 1] += -s * sp0 + c * sp1
    acc = np.linalg.solve(M, (ff_tree - rest).T).T  # tree-axis acceleration of the reference
    sv0, sv1 = -deta_d[:, 1], deta_d[:, 0]
    b0 = acc[:, 0] + nu2 * (cd * sv0 + sd * sv1)
    b1 = acc[:, 1] + nu2 * (-sd * sv0 + cd * sv1)
    return np.column_stack([cd * b0 - sd * b1, sd * b0 + cd * b1, acc[:, 2]])


@dataclass(frozen=True)
class ShadowStart:
    """The control system's configuration and its state before the first step."""

    C: loop.ControlArrays
    P: plant.PlantArrays
    """The plant's arrays (the observer's unit writes the site columns of a row with them)."""
    dt_s: float
    xhat: FloatArray
    P_cov: FloatArray
    cs: FloatArray
    Q: loop.QualityState
    held_y: FloatArray
    """The held measurements before the first step."""
    ps: ParameterSet | None = None
    """The parameter set the configuration comes from (needed for ``ShadowInput.restart``)."""

    @staticmethod
    def of(sim) -> ShadowStart:
        """The start of a built, not yet stepped, ``Simulation`` (with the EKF's feedback)."""
        return ShadowStart(
            C=sim.C._replace(feedback_ekf=True),
            P=sim.arrays,
            dt_s=float(sim.dt_s),
            xhat=np.array(sim.xhat, dtype=float),
            P_cov=np.ascontiguousarray(sim.P_cov, dtype=float).copy(),
            cs=np.array(sim.controller_state.vector, dtype=float),
            Q=loop.QualityState(*(np.array(a) for a in sim.Q)),
            held_y=np.array(sim.held_y, dtype=float),
            ps=sim.ps,
        )

    def with_mount(self, r_rov_from_tree_tree_m: FloatArray) -> ShadowStart:
        """The same start with another mounting vector (tree axes) [m]: what the observer
        would have done with it."""
        r = np.asarray(r_rov_from_tree_tree_m, dtype=float)
        return replace(self, C=self.C._replace(r_mount=r.copy()))


@dataclass(frozen=True)
class ShadowResult:
    """What the shadow's observer estimated and its controller commanded, per step."""

    rows: LogRows
    """(n, N_LOG) log rows with the shadow's control columns (estimates, NIS, accepted,
    commands, terms, mode); the plant's columns are left to the caller."""
    innovation: FloatArray
    """(n, 3) the fix's north and east and the compass's heading less what the estimate before
    the step's corrections predicted [m, m, rad]; NaN where the sensor was not accepted."""


@njit(inline="always", **JIT_NOALLOC)
def _tree_law_on_reference_into(
    tau6: np.ndarray, xhat: np.ndarray, cs: np.ndarray, ref_in: np.ndarray,
    C: loop.ControlArrays, dt: float, row: np.ndarray, W: loop.ControlWork,
) -> None:  # fmt: skip
    """``control.loop.control_law_into``'s tree controller with the reference ``ref_in`` (9,)
    taken as it is instead of stepped by the reference model (the EKF's feedback)."""
    eta = W.vec[loop.W_ETA, 0:3]
    deta = W.vec[loop.W_DETA, 0:3]
    eta[0], eta[1], eta[2] = xhat[0], xhat[1], xhat[2]
    c, s = np.cos(eta[2]), np.sin(eta[2])
    deta[0] = c * xhat[3] - s * xhat[4]
    deta[1] = s * xhat[3] + c * xhat[4]
    deta[2] = xhat[5]
    last = int(cs[loop.CS_LAST_MODE])
    from_hold = last == loop.MODE_MANUAL and cs[loop.CS_LAST_GRIP] > 0.5
    if last != loop.MODE_TREE:
        if not from_hold:
            loop._bumpless_tree_start(cs, eta, deta, C.use_ff, C, W)
        elif not C.use_ff:
            loop._spring_into_integral(cs, cs[loop.CS_REF : loop.CS_REF + 3], 1.0, C)
    for i in range(9):
        cs[loop.CS_REF + i] = ref_in[i]
    ref = cs[loop.CS_REF : loop.CS_REF + 9]
    for i in range(6):
        tau6[i] = 0.0
    tau_tree = W.vec[loop.W_TAU_TREE, 0:3]
    i_next = W.vec[loop.W_I_NEXT, 0:3]
    e = W.vec[loop.W_E, 0:3]
    de = W.vec[loop.W_DE, 0:3]
    pid.tree_pid_into(
        tau_tree, i_next, W.terms, e, de, eta, deta, ref[0:3], ref[3:6], ref[6:9],
        cs[loop.CS_I : loop.CS_I + 3], C.Kp, C.Ki, C.Kd, C.use_ff, C.M, C.D_l, C.D_nl, C.k_h,
        C.p_eq, loop.EYE3, loop.EYE3, C.i_limit, dt, W.pid,
    )  # fmt: skip
    for k in range(3):
        cs[loop.CS_I + k] = i_next[k]
        cs[loop.CS_E + k] = e[k]
        cs[loop.CS_DE + k] = de[k]
    loop._hand_over_into(tau_tree, W.terms, cs, C, from_hold, dt, W)
    loop._tree_wrench_out(tau6, tau_tree, C.heave_newton, C, row, W)
    cs[loop.CS_LAST_MODE] = loop.MODE_TREE
    cs[loop.CS_LAST_GRIP] = cs[loop.CS_GRIP]
    for k in range(6):
        cs[loop.CS_TAU + k] = row[_TAU_ROV + k]
    for k in range(3):
        row[_ETA_HAT + k] = eta[k]
        row[_NU_HAT + k] = xhat[3 + k]
        row[_BIAS + k] = xhat[6 + k]
        row[_ETA_D + k] = ref[k]
        row[_DETA_D + k] = ref[3 + k]
    row[_MODE] = loop.MODE_TREE


@njit(inline="always", **JIT_NOALLOC)
def _prior_innovation_into(
    out: np.ndarray, y: np.ndarray, xhat: np.ndarray, accepted_fresh: np.ndarray,
    C: loop.ControlArrays, W: loop.ControlWork,
) -> None:  # fmt: skip
    """The fix (moved to the tree) and the heading less the estimate before the corrections,
    into ``out`` (3,); NaN for a sensor without a fresh sample."""
    ne = W.vec[loop.W_NE, 0:2]
    uv = W.vec[loop.W_UV, 0:2]
    psi_m, _ = loop.tree_measurements_into(ne, uv, y, xhat[2], C)
    pos, psi = accepted_fresh[sensors.POSITION], accepted_fresh[sensors.COMPASS]
    out[0] = ne[0] - xhat[0] if pos else np.nan
    out[1] = ne[1] - xhat[1] if pos else np.nan
    out[2] = ssa_scalar(psi_m - xhat[2]) if psi else np.nan


@njit(**JIT_NOALLOC)
def shadow_steps(
    t_s: np.ndarray, y: np.ndarray, fresh: np.ndarray, tau_ach: np.ndarray, mode: np.ndarray,
    reference: np.ndarray, has_reference: np.ndarray, handover: np.ndarray, xhat: np.ndarray,
    Pc: np.ndarray,
    cs: np.ndarray, C: loop.ControlArrays, P: plant.PlantArrays, Q: loop.QualityState,
    dt: float, rows: np.ndarray, innovation: np.ndarray, x: np.ndarray, env: np.ndarray,
    saved_cs: np.ndarray, work: plant.PlantWork, W: loop.ControlWork,
) -> None:  # fmt: skip
    """The shadow's steps (see the module docstring), advancing ``xhat``, ``Pc``, ``cs`` and
    ``Q`` in place and writing ``rows`` and ``innovation``; allocates nothing. ``x`` (24,) is
    a plant state the control step does not read with the EKF's feedback (zeros), ``env``
    (N_ENV,) an environment row whose grip is set per step, ``saved_cs`` (len(cs),) space."""
    tau6 = W.vec[loop.W_TAU6, 0:6]
    for j in range(t_s.shape[0]):
        row = rows[j]
        held = y[j]
        grip = 1.0 if mode[j] == loop.MODE_TREE else 0.0
        env[plant.E_GRIP] = grip
        cs[loop.CS_GRIP] = grip
        cs[loop.CS_MODE] = mode[j]
        if not np.isnan(handover[j, 0]):
            for k in range(6):
                cs[loop.CS_TAU + k] = handover[j, k]
        _prior_innovation_into(innovation[j], held, xhat, fresh[j], C, W)
        for i in range(cs.shape[0]):
            saved_cs[i] = cs[i]
        target = reference[j, 0:3]
        loop.control_step_into(
            tau6, t_s[j], x, held, fresh[j], xhat, Pc, cs, target, C, Q, dt, row, W
        )
        if mode[j] == loop.MODE_TREE and has_reference[j]:
            for i in range(cs.shape[0]):
                cs[i] = saved_cs[i]
            _tree_law_on_reference_into(tau6, xhat, cs, reference[j], C, dt, row, W)
        for k in range(6):
            row[_TAU_ACH + k] = tau_ach[j, k]
        loop.observe_into(x, env, xhat, Pc, C, P, dt, t_s[j] + dt, held, row, work, W)


def run_shadow(inputs: ShadowInput, start: ShadowStart) -> ShadowResult:
    """Our observer and controller over ``inputs`` from ``start`` (see the module
    docstring). The innovations are NaN where the sensor's sample was not accepted."""
    n = len(inputs.t_s)
    rows = np.zeros((n, N_LOG))
    innovation = np.full((n, 3), np.nan)
    xhat, Pc, cs = start.xhat.copy(), start.P_cov.copy(), start.cs.copy()
    Q = loop.QualityState(*(np.array(a) for a in start.Q))
    t_s = np.ascontiguousarray(inputs.t_s, dtype=float)
    y = np.ascontiguousarray(inputs.y, dtype=float)
    fresh = np.ascontiguousarray(inputs.fresh, dtype=np.bool_)
    tau_ach = np.ascontiguousarray(inputs.tau_ach_b, dtype=float)
    mode = np.ascontiguousarray(inputs.mode, dtype=np.int64)
    reference = np.ascontiguousarray(inputs.reference, dtype=float)
    has_reference = np.ascontiguousarray(inputs.has_reference, dtype=np.bool_)
    handover = np.full((n, 6), np.nan)
    if inputs.handover_command_b is not None:
        handover[:] = inputs.handover_command_b
    x, env, saved = np.zeros(24), np.zeros(plant.N_ENV), np.zeros(cs.shape[0])
    work, W = plant.make_work(start.P.thr_T.shape[1]), loop.make_control_work()
    restarts = [] if inputs.restart is None else np.flatnonzero(inputs.restart).tolist()
    heave, spring = inputs.heave_newton, inputs.spring
    changes = [] if heave is None else (np.flatnonzero(np.diff(heave) != 0.0) + 1).tolist()
    if spring is not None:
        changes += (np.flatnonzero(np.any(np.diff(spring, axis=0) != 0.0, axis=1)) + 1).tolist()
    edges = sorted({0, n, *restarts, *changes})
    for a, b in itertools.pairwise(edges):
        if a in restarts:
            xhat, Pc = _restarted(y[a - 1] if a else start.held_y, start, t_s[a], Q)
        C = start.C if heave is None else start.C._replace(heave_newton=float(heave[a]))
        if spring is not None:
            C = C._replace(k_h=float(spring[a, 0]), p_eq=spring[a, 1:3].copy())
        shadow_steps(
            t_s[a:b], y[a:b], fresh[a:b], tau_ach[a:b], mode[a:b], reference[a:b],
            has_reference[a:b], handover[a:b], xhat, Pc, cs, C, start.P, Q, start.dt_s, rows[a:b],
            innovation[a:b], x, env, saved, work, W,
        )  # fmt: skip
    result = LogRows(rows)
    accepted = result["accepted"] > 0.5
    innovation[~accepted[:, sensors.POSITION], 0:2] = np.nan
    innovation[~accepted[:, sensors.COMPASS], 2] = np.nan
    return ShadowResult(rows=result, innovation=innovation)


def _restarted(
    held_y: FloatArray, start: ShadowStart, t_s: float, Q: loop.QualityState
) -> tuple[FloatArray, FloatArray]:
    """The observer started again at ``t_s`` from ``held_y`` (``Simulation.reset_observer``)."""
    if start.ps is None:
        raise ValueError("an observer restart needs the start's parameter set")
    last_fix_s = float(Q.last_t[sensors.POSITION])
    xhat, P_cov = hookup_estimate(held_y, start.C, start.ps, t_s, last_fix_s)
    return xhat, np.ascontiguousarray(P_cov)


@dataclass(frozen=True)
class NisStatistics:
    """One sensor's normalised innovation squared against its chi-square band."""

    sensor: str
    dimension: int
    samples: int
    mean: float
    band: tuple[float, float]
    """The band the mean of ``samples`` independent NIS values falls in with ``NIS_BAND``."""
    sample_band: tuple[float, float]
    """The band one NIS value falls in with ``NIS_BAND``."""
    fraction_above: float
    """Share of the samples above ``sample_band`` (1 - NIS_BAND)/2 expected."""
    verdict: str
    """``consistent``, ``above band`` (innovations larger than the observer expects: a model
    or a configuration is wrong, or the noise is larger than configured), ``below band``,
    or ``no samples``."""

    def as_dict(self) -> dict:
        return {
            "sensor": self.sensor,
            "dimension": self.dimension,
            "samples": self.samples,
            "mean": self.mean,
            "band": list(self.band),
            "sample_band": list(self.sample_band),
            "fraction_above": self.fraction_above,
            "verdict": self.verdict,
        }


def nis_values(rows: LogRows, on_tree: BoolArray | None = None) -> dict[str, FloatArray]:
    """Each sensor's NIS at the steps its sample was accepted (position: north + east), of the
    steps ``on_tree`` only when given (the ROV's measurements tell of the tree only while it
    grips it)."""
    nis = rows["nis"]
    accepted = rows["accepted"] > 0.5
    if on_tree is not None:
        accepted = accepted & on_tree[:, None]
    return {
        "position": (nis[:, 0] + nis[:, 1])[accepted[:, sensors.POSITION]],
        "compass": nis[:, 2][accepted[:, sensors.COMPASS]],
    }


def nis_consistency(values: FloatArray, sensor: str) -> NisStatistics:
    """The mean NIS of ``values`` against the chi-square band of its dimension: the mean of N
    independent NIS of dimension d is chi2(N d) / N (Bar-Shalom, Li and Kirubarajan, section
    5.4). Samples close in time are correlated, so the band is narrower than it should be:
    read a mean just outside it with care, one several times above it as a fault."""
    d = NIS_DIMENSIONS[sensor]
    n = int(len(values))
    tail = (1.0 - NIS_BAND) / 2.0
    lo1, hi1 = (float(v) for v in stats.chi2.ppf([tail, 1.0 - tail], d))
    if n == 0:
        return NisStatistics(sensor, d, 0, math.nan, (math.nan, math.nan), (lo1, hi1), 0.0,
                             "no samples")  # fmt: skip
    lo, hi = (float(v) / n for v in stats.chi2.ppf([tail, 1.0 - tail], n * d))
    mean = float(np.mean(values))
    verdict = "above band" if mean > hi else "below band" if mean < lo else "consistent"
    above = float(np.mean(values > hi1))
    return NisStatistics(sensor, d, n, mean, (lo, hi), (lo1, hi1), above, verdict)
