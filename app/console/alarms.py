"""Operator alarms computed from the simulation's log rows (read by name, control.columns).

Five alarms, each with a limit taken from the parameter set where the thesis gives one:

- ``saturation``: a thruster has been at or above ``SATURATED`` utilisation for more than
  ``saturation_s`` seconds without a break.
- ``position_error``: the tree is further from the reference than the funnels' capture
  tolerance (``DockingLayout.tolerance_m``), or its heading is off by more than
  ``heading_error_deg``. It is armed once the run has settled: from the first row within
  those limits, or ``position_arm_s`` after the run's first row. A run starts with the current
  already flowing against a controller that has not learnt it (its integral and the
  observer's bias start at zero, the reference at the hook-up estimate), so the tree is
  blown off and brought back: 0.45 m at model scale in the first 16 s of the calm observer
  hold (model-square-ekf-400), back within 0.10 m by 40 s; that is the start, not an error.
- ``position_error`` in free mode and flown by hand (the ROV flying on its own, or the pilot's
  holds): the ROV against its set point (``Simulation.free_setpoint_n``; while the ROV grips
  the tree, where the ROV sits with the tree at its hold), with the same limits.
- ``wire_slack``: the wire tension has dropped below ``slack_fraction`` of the tree's
  submerged weight W0 (the wire only pulls, eq. 2.28: a slack wire no longer carries the tree),
  while the tree hangs; a tree whose bottom is down at the post tops or deeper rests on the
  frame, which carries it, and a slack wire is then the landed state, not an alarm.
- ``wire_snap``: the wire tightened again after going slack while the tree hung (a snap
  load, DNV-RP-H103's other wire criterion, found in the tick's rows by
  ``missions.seaway.WireWatch`` as the seaway study finds it: slack below 10 % of W0, the
  peak tension within ``SNAP_WINDOW_S`` after); it stands for ``snap_show_s`` after the
  peak, saying how many times the static tension it reached. Rows where the tree rests on the
  frame count as taut (a landing is not a slack, nor a lift-off a snap).
- ``innovation``: the mean normalised innovation squared of the last ``nis_window`` accepted
  position or heading fixes is above ``nis_limit`` (its expected value is 1 per axis when the
  EKF's model and noise agree with the measurements).
- ``dropout``: a sensor has delivered no accepted sample for ``dropout_periods`` of its sample
  periods (at least ``dropout_min_s``).
- ``mount_vector``: the live check of the mounting vector r (the sea trial's wrong sign,
  thesis 6.2.1). With r mirrored, the control system holds the wrong point still and the real
  tree swings round it on a circle of radius 2|r| as the heading changes; the wire pulls the
  real tree with an extra ``-2 k_h R(psi) r`` (NED) that the observer's model does not have, so
  its position innovations drive its bias estimate (tree axes) to ``R(psi)^T c - 2 k_h r``:
  a constant offset in tree axes, where a current's force (fixed in NED, ``c``) turns with
  the heading. Over the last ``mount_window_s`` the monitor fits ``bias = R(psi)^T c + d``
  (least squares; needs ``mount_spread_deg`` of heading change to tell c from d) and reads
  ``s = d . m / |m|^2`` with ``m = -2 k_h r``: 0 for the configured r, 1 for a mirrored one.
  Above ``mount_limit`` (0.5, halfway) it says r looks mirrored.

The monitor only reads rows; it never changes the loop. The last two alarms need the EKF (with
perfect feedback the sensors are not read and the columns stay zero); they stay inactive then.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from control.columns import LogRows
from missions.scoring import SATURATED
from missions.seaway import WireWatch
from sim.gnc import ssa
from sim.params import ParameterSet
from sim.sensors import SENSOR_NAMES

FloatArray = NDArray[np.float64]
ALARM_NAMES = (
    "saturation",
    "position_error",
    "wire_slack",
    "innovation",
    "dropout",
    "mount_vector",
    "wire_snap",
)
SETTLE_S = 60.0
"""How long a run may take to settle from its start before the position alarm is armed
regardless [s]: the library missions' first leg holds 60 s for that."""
MOUNT_SAMPLE_S = 0.1
"""The mount check keeps one row in this many seconds."""


@dataclass(frozen=True)
class AlarmLimits:
    """Where each alarm trips."""

    position_error_m: float
    """Horizontal distance tree - reference [m]: the funnels' capture tolerance."""
    sample_period_s: tuple[float, ...]
    """Sample period of each sensor (position, depth, compass, dvl, gyro) [s]."""
    saturation_s: float = 2.0
    """Continuous saturation of one thruster before the alarm [s] (the issue: 2 s)."""
    heading_error_deg: float = 10.0
    """Heading error against the reference [deg]."""
    position_arm_s: float = 0.0
    """Longest the position alarm waits, from the run's first row, for the run to settle
    before it is armed [s]; the console's (``for_params``) is ``SETTLE_S``."""
    slack_fraction: float = 0.1
    """Tension below this fraction of W0 counts as slack [-]."""
    snap_show_s: float = 10.0
    """How long the snap alarm stands after a snap load's peak [s] (our choice: long enough
    for the winch operator to read it; the load itself lasts about a wire period)."""
    nis_limit: float = 4.0
    """Mean NIS per axis over the window above which the observer disagrees with the sensors."""
    nis_window: int = 10
    """Accepted fixes averaged for the innovation alarm."""
    dropout_periods: float = 3.0
    """Missing sample periods before a dropout alarm [-]."""
    dropout_min_s: float = 1.0
    """Shortest gap reported as a dropout [s]."""
    mount_window_s: float = 30.0
    """Rows the mount check fits over [s] (the issue: flagged within 30 s of a turn)."""
    mount_spread_deg: float = 20.0
    """Heading change within the window the mount check needs before it judges [deg]: the
    fit cannot tell a current's force from the mount's offset with less (measured: at 1 deg
    of change a correct r read 0.96, at 10 deg and more -0.15 to -0.09)."""
    mount_limit: float = 0.5
    """Share of the mirrored-r signature above which r is called mirrored: halfway between 0
    (the configured r) and 1 (mirrored); measured -0.15 to -0.09 with the right r and 1.37 to
    1.53 with it mirrored (model-rotation mission, 3 seeds, 10 to 74 deg of turn)."""

    @staticmethod
    def for_params(ps: ParameterSet) -> AlarmLimits:
        """Limits for a parameter set: capture tolerance and the sensors' rates."""
        layout = ps.spec.docking.to_numeric()
        spec = ps.spec.sensors
        periods = tuple(1.0 / getattr(spec, name).rate_hz for name in SENSOR_NAMES)
        return AlarmLimits(
            position_error_m=float(layout.tolerance_m),
            sample_period_s=periods,
            position_arm_s=SETTLE_S,
        )


@dataclass(frozen=True)
class Alarm:
    """One alarm's present state."""

    name: str
    active: bool
    message: str


@dataclass
class AlarmMonitor:
    """Keeps the little history the alarms need; ``update`` with each new block of rows."""

    limits: AlarmLimits
    n_thrusters: int
    weight_newton: float
    """Tree submerged weight W0 [N]."""
    uses_sensors: bool
    """True with EKF feedback: innovation and dropout alarms are armed."""
    support_depth_m: float | None = None
    """Depth of the docking frame's post tops [m] (None: no frame): a tree whose bottom is
    there or deeper rests on the frame."""
    tree_half_height_m: float = 0.0
    """Half the tree's height: from its pose (centre) to its bottom [m]."""
    _sat_since: FloatArray = field(init=False)
    _last_accept: FloatArray = field(init=False)
    _nis: tuple[deque[float], deque[float]] = field(init=False)
    _mount_rows: deque[tuple[float, float, float]] = field(init=False)
    _mount_last_k: float = field(init=False, default=-1.0)
    _mount_alarm: Alarm = field(init=False)
    _t_s: float = field(init=False, default=0.0)
    _t_first_s: float = field(init=False, default=math.nan)
    _position_armed: bool = field(init=False, default=False)
    _wire_watch: WireWatch = field(init=False)
    _snap_alarm: Alarm = field(init=False)
    _snap_until_s: float = field(init=False, default=-math.inf)
    state: tuple[Alarm, ...] = field(init=False)

    def __post_init__(self) -> None:
        self._sat_since = np.full(self.n_thrusters, np.nan)
        self._last_accept = np.full(len(SENSOR_NAMES), np.nan)
        self._nis = (deque(maxlen=self.limits.nis_window), deque(maxlen=self.limits.nis_window))
        self.state = tuple(Alarm(name, False, "") for name in ALARM_NAMES)
        self._mount_rows = deque(maxlen=int(round(self.limits.mount_window_s / MOUNT_SAMPLE_S)))
        self._mount_alarm = Alarm("mount_vector", False, "")
        self._wire_watch = WireWatch(self.weight_newton)
        self._snap_alarm = Alarm("wire_snap", False, "")

    def update(
        self,
        rows: LogRows,
        tension_newton: float | None,
        free_setpoint_n: FloatArray | None = None,
        mount: tuple[float, FloatArray] | None = None,
    ) -> tuple[Alarm, ...]:
        """Advance with log rows, the present wire tension (None: unknown), the free-flying
        ROV's set point [north, east, down, psi] (None: unknown, as in a replay) and what the
        control system takes for the wire's horizontal stiffness k_h [N/m] and the mounting
        vector r [m, tree axes] (None: the mount check stays as it was)."""
        if len(rows) == 0:
            return self.state
        self._t_s = float(rows.t_s[-1])
        if math.isnan(self._t_first_s):
            self._t_first_s = float(rows.t_s[0])
        self.state = (
            self._saturation(rows),
            self._position(rows, free_setpoint_n),
            self._slack(rows, tension_newton),
            self._innovation(rows),
            self._dropout(rows),
            self._mount_check(rows, mount),
            self._snap(rows),
        )
        return self.state

    def _mount_check(self, rows: LogRows, mount: tuple[float, FloatArray] | None) -> Alarm:
        """The live mounting-vector check (see the module's notes)."""
        if not self.uses_sensors or mount is None:
            return self._mount_alarm
        k_h, r = mount
        signature = -2.0 * float(k_h) * np.asarray(r, float)[0:2]
        size = float(signature @ signature)
        if size <= 0.0:
            return self._mount_alarm
        t, mode = rows.t_s, np.asarray(rows["mode"]).reshape(len(rows), -1)[:, 0]
        bias, psi = rows["bias_tree"], rows["eta_hat_n"][:, 2]
        k = np.floor(t / MOUNT_SAMPLE_S + 1e-9)
        new = np.flatnonzero(k != np.concatenate(([self._mount_last_k], k[:-1])))
        if new.size == 0:
            return self._mount_alarm
        for i in new:
            if mode[i] > 0.5:  # the ROV is free: the tree's observer is not the one to judge
                self._mount_rows.clear()
                continue
            self._mount_rows.append((float(psi[i]), float(bias[i, 0]), float(bias[i, 1])))
        self._mount_last_k = float(k[-1])
        if len(self._mount_rows) < 10:
            return self._mount_alarm
        data = np.array(self._mount_rows)
        heading = np.unwrap(data[:, 0])
        if math.degrees(float(np.ptp(heading))) < self.limits.mount_spread_deg:
            return self._mount_alarm  # not turned enough to judge: the last verdict stands
        c, s = np.cos(heading), np.sin(heading)
        n = len(heading)
        a = np.zeros((2 * n, 4))
        a[0::2, 0], a[0::2, 1], a[0::2, 2] = c, s, 1.0
        a[1::2, 0], a[1::2, 1], a[1::2, 3] = -s, c, 1.0
        y = np.empty(2 * n)
        y[0::2], y[1::2] = data[:, 1], data[:, 2]
        d = np.linalg.lstsq(a, y, rcond=None)[0][2:4]
        share = float(d @ signature) / size
        if share > self.limits.mount_limit:
            self._mount_alarm = Alarm(
                "mount_vector",
                True,
                f"the mounting vector r looks mirrored (wrong sign): while turning, the "
                f"observer's force estimate shows {share:.0%} of the mirrored-r signature; "
                f"check r's sign in the set-up",
            )
        else:
            self._mount_alarm = Alarm("mount_vector", False, "")
        return self._mount_alarm

    def _saturation(self, rows: LogRows) -> Alarm:
        util = rows["thruster_utilisation"][:, : self.n_thrusters]
        t = rows.t_s
        for i in range(self.n_thrusters):
            below = np.flatnonzero(util[:, i] < SATURATED)
            if below.size == len(t):
                self._sat_since[i] = np.nan
            elif below.size == 0:
                if math.isnan(self._sat_since[i]):
                    self._sat_since[i] = t[0]
            else:
                last_below = below[-1]
                self._sat_since[i] = np.nan if last_below == len(t) - 1 else t[last_below + 1]
        held = self._t_s - self._sat_since
        worst = int(np.nanargmax(held)) if np.any(np.isfinite(held)) else -1
        if worst >= 0 and held[worst] > self.limits.saturation_s:
            return Alarm(
                "saturation", True, f"thruster {worst + 1} saturated for {held[worst]:.1f} s"
            )
        return Alarm("saturation", False, "")

    def _position(self, rows: LogRows, free_setpoint_n: FloatArray | None) -> Alarm:
        if float(rows["mode"][-1]) > 0.5:  # free mode: the ROV flies on its own
            if free_setpoint_n is None:
                return Alarm("position_error", False, "")
            who, pose = "ROV", rows["rov_eta_n"][-1]
            ref = np.array([free_setpoint_n[0], free_setpoint_n[1], free_setpoint_n[3]])
            what = "its set point"
        else:
            who, pose, ref = "tree", rows["tree_eta_n"][-1], rows["eta_ref_n"][-1]
            what = "the reference"
        err_m = math.hypot(pose[0] - ref[0], pose[1] - ref[1])
        err_deg = abs(math.degrees(ssa(float(pose[5] - ref[2]))))
        off = err_m > self.limits.position_error_m or err_deg > self.limits.heading_error_deg
        if not self._position_armed:
            # armed once settled (see the module's notes)
            waited_s = self._t_s - self._t_first_s
            self._position_armed = not off or waited_s >= self.limits.position_arm_s
        if off and self._position_armed:
            return Alarm(
                "position_error", True, f"{who} {err_m:.2f} m / {err_deg:.1f} deg off {what}"
            )
        return Alarm("position_error", False, "")

    def resting(self, rows: LogRows) -> bool:
        """The tree's bottom is down at the post tops or deeper: the frame carries it."""
        if self.support_depth_m is None:
            return False
        bottom_m = float(rows["tree_eta_n"][-1][2]) + self.tree_half_height_m
        return bottom_m >= self.support_depth_m

    def _slack(self, rows: LogRows, tension_newton: float | None) -> Alarm:
        slack = self.limits.slack_fraction * self.weight_newton
        if tension_newton is not None and tension_newton < slack and not self.resting(rows):
            return Alarm("wire_slack", True, f"wire tension {tension_newton / 1e3:.1f} kN")
        return Alarm("wire_slack", False, "")

    def _snap(self, rows: LogRows) -> Alarm:
        """The snap alarm (see the module's notes); rows without the tension leave it be."""
        if not rows.layout.has("wire_tension"):
            return self._snap_alarm
        tension = np.array(rows["wire_tension"], dtype=float).reshape(len(rows))
        if self.support_depth_m is not None:
            bottom_m = rows["tree_eta_n"][:, 2] + self.tree_half_height_m
            tension[bottom_m >= self.support_depth_m] = self.weight_newton
        for event in self._wire_watch.feed(rows.t_s, tension):
            if event.kind == "snap":
                self._snap_until_s = event.t_s + self.limits.snap_show_s
                ratio = event.tension_newton / self.weight_newton
                self._snap_alarm = Alarm(
                    "wire_snap",
                    True,
                    f"{event.tension_newton / 1e3:.1f} kN, {ratio:.2f} x the static tension, "
                    f"at {event.t_s:.1f} s",
                )
        self._wire_watch.events.clear()  # only the newest matter here; bounded memory
        if self._snap_alarm.active and self._t_s >= self._snap_until_s:
            self._snap_alarm = Alarm("wire_snap", False, "")
        return self._snap_alarm

    def _innovation(self, rows: LogRows) -> Alarm:
        if not self.uses_sensors:
            return Alarm("innovation", False, "")
        accepted, nis = rows["accepted"], rows["nis"]
        pos = accepted[:, 0] > 0.5
        psi = accepted[:, 2] > 0.5
        self._nis[0].extend(0.5 * (nis[pos, 0] + nis[pos, 1]))
        self._nis[1].extend(nis[psi, 2])
        for label, window in zip(("position", "heading"), self._nis, strict=True):
            if len(window) == window.maxlen and np.mean(window) > self.limits.nis_limit:
                return Alarm(
                    "innovation",
                    True,
                    f"{label} fixes off the observer's prediction: mean normalised "
                    f"innovation {np.mean(window):.1f}, about 1 expected",
                )
        return Alarm("innovation", False, "")

    def _dropout(self, rows: LogRows) -> Alarm:
        if not self.uses_sensors:
            return Alarm("dropout", False, "")
        t = rows.t_s
        accepted = rows["accepted"] > 0.5
        for k in range(len(SENSOR_NAMES)):
            hits = np.flatnonzero(accepted[:, k])
            if hits.size:
                self._last_accept[k] = t[hits[-1]]
            elif math.isnan(self._last_accept[k]):
                self._last_accept[k] = t[0]
        for k, name in enumerate(SENSOR_NAMES):
            limit = max(
                self.limits.dropout_periods * self.limits.sample_period_s[k],
                self.limits.dropout_min_s,
            )
            gap = self._t_s - self._last_accept[k]
            if gap > limit:
                return Alarm("dropout", True, f"no {name} sample for {gap:.1f} s")
        return Alarm("dropout", False, "")
