"""The simulation's log row, declared once.

Every plant step writes one row of ``N_LOG`` numbers. This module is the only place that says
what the row holds: each block has a name, a width, a unit, a frame and one name per element
(the flat names used by recordings and CSV files). The compiled kernel (``control.loop``) writes
rows through the ``L_*`` offsets derived here; everything else reads blocks by name through
``LogRows`` (``rows["tree_eta_n"]``) or ``LAYOUT`` (``LAYOUT.take(row, "wire_tension")``).

Units are in the element names (``_m``, ``_rad``, ``_mps``, ``_newton``, ``_newton_m``) and
frames in the block names (``_n`` NED, ``_b`` body, ``_tree`` tree axes).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from sim.sensors import SENSOR_NAMES

FloatArray = NDArray[np.float64]

M_MAX = 8
"""Thruster slots in a row (an ROV has at most this many thrusters)."""

_POSE6 = ("north_m", "east_m", "down_m", "roll_rad", "pitch_rad", "yaw_rad")
_VEL6 = ("u_mps", "v_mps", "w_mps", "p_rad_s", "q_rad_s", "r_rad_s")
AXES3 = ("surge_newton", "sway_newton", "yaw_newton_m")
"""Element names of [surge, sway, yaw] force blocks (tree controller, bias, terms)."""
AXES6 = (
    "surge_newton",
    "sway_newton",
    "heave_newton",
    "roll_newton_m",
    "pitch_newton_m",
    "yaw_newton_m",
)
_Y_NAMES = (
    "pos_north_m",
    "pos_east_m",
    "pos_down_m",
    "depth_m",
    "heading_rad",
    "dvl_u_mps",
    "dvl_v_mps",
    "dvl_w_mps",
    "gyro_p_rad_s",
    "gyro_q_rad_s",
    "gyro_r_rad_s",
)


@dataclass(frozen=True)
class LogColumn:
    """One block of the log row."""

    name: str
    """Block name (frame suffix where it matters)."""
    unit: str
    frame: str
    """NED, body (ROV or tree axes), tree axes, or '-' for scalars without a frame."""
    description: str
    elements: tuple[str, ...]
    """Flat name of each element (unit in the suffix)."""

    @property
    def width(self) -> int:
        return len(self.elements)


def _block(
    name: str, unit: str, frame: str, description: str, elements: Sequence[str]
) -> LogColumn:
    return LogColumn(name, unit, frame, description, tuple(elements))


def _thr(kind: str) -> tuple[str, ...]:
    return tuple(f"thruster{i}_{kind}" for i in range(1, M_MAX + 1))


LOG_COLUMNS: tuple[LogColumn, ...] = (
    _block("t_s", "s", "-", "simulation time at the end of the step", ["t_s"]),
    _block(
        "tree_eta_n",
        "m, rad",
        "NED",
        "true tree pose [north, east, down, roll, pitch, yaw]",
        [f"tree_{n}" for n in _POSE6],
    ),
    _block("rov_eta_n", "m, rad", "NED", "true ROV pose", [f"rov_{n}" for n in _POSE6]),
    _block(
        "tree_nu_b",
        "m/s, rad/s",
        "tree axes",
        "true tree velocity [u, v, w, p, q, r]",
        [f"tree_{n}" for n in _VEL6],
    ),
    _block("rov_nu_b", "m/s, rad/s", "ROV axes", "true ROV velocity", [f"rov_{n}" for n in _VEL6]),
    _block(
        "eta_hat_n",
        "m, rad",
        "NED",
        "estimated tree [north, east, yaw]",
        ["est_tree_north_m", "est_tree_east_m", "est_tree_yaw_rad"],
    ),
    _block(
        "nu_hat_tree",
        "m/s, rad/s",
        "tree axes",
        "estimated tree [u, v, r]",
        ["est_tree_u_mps", "est_tree_v_mps", "est_tree_r_rad_s"],
    ),
    _block(
        "bias_tree", "N, N m", "tree axes", "estimated bias force", [f"bias_{n}" for n in AXES3]
    ),
    _block(
        "eta_ref_n",
        "m, rad",
        "NED",
        "reference pose [north, east, yaw]",
        ["ref_north_m", "ref_east_m", "ref_yaw_rad"],
    ),
    _block(
        "eta_ref_rate_n",
        "m/s, rad/s",
        "NED",
        "reference rate",
        ["ref_north_rate_mps", "ref_east_rate_mps", "ref_yaw_rate_rad_s"],
    ),
    _block(
        "tau_tree_cmd",
        "N, N m",
        "tree axes",
        "commanded force on the tree",
        [f"tau_tree_{n}" for n in AXES3],
    ),
    _block(
        "tau_rov_cmd_b",
        "N, N m",
        "ROV axes",
        "commanded ROV wrench",
        [f"tau_rov_cmd_{n}" for n in AXES6],
    ),
    _block(
        "tau_rov_ach_b",
        "N, N m",
        "ROV axes",
        "achieved ROV wrench",
        [f"tau_rov_ach_{n}" for n in AXES6],
    ),
    _block("thruster_force", "N", "-", "thruster forces (unused slots 0)", _thr("force_newton")),
    _block("thruster_speed", "rev/s", "-", "propeller speeds", _thr("speed_rps")),
    _block(
        "thruster_utilisation",
        "-",
        "-",
        "force over the thruster's limit, 0..1",
        _thr("utilisation"),
    ),
    _block(
        "control_terms",
        "N, N m",
        "tree axes",
        "P, I, D and feedforward parts of the tree force",
        [f"term_{p}_{a}" for p in ("p", "i", "d", "ff") for a in AXES3],
    ),
    _block(
        "y", "mixed", "sensor", "held sensor values (sim.sensors)", [f"y_{n}" for n in _Y_NAMES]
    ),
    _block("mode", "-", "-", "supervisor mode: 0 tree controller, 1 free ROV", ["mode"]),
    _block(
        "nis",
        "-",
        "-",
        "normalised innovation squared of north, east and heading fixes",
        ["nis_north", "nis_east", "nis_heading"],
    ),
    _block(
        "accepted",
        "-",
        "-",
        "1 where a fresh sample was accepted this step",
        [f"accepted_{s}" for s in SENSOR_NAMES],
    ),
    _block(
        "crane_tip_ne",
        "m",
        "NED",
        "crane tip north and east",
        ["crane_tip_north_m", "crane_tip_east_m"],
    ),
    _block(
        "wire_rest_length",
        "m",
        "-",
        "wire payout below the crane tip, unloaded length plus its stretch under its own weight",
        ["wire_rest_length_m"],
    ),
    _block("wire_tension", "N", "-", "wire tension at the tree", ["wire_tension_newton"]),
)


def _current_name(name: str) -> str:
    """A flat name as declared now (recordings before the newton spelling wrote ``_n`` for
    newtons and ``_nm`` for newton metres)."""
    if name.endswith("_nm"):
        return name[:-3] + "_newton_m"
    if name.endswith("_n") and not name.startswith(("tree_", "rov_")):
        return name[:-2] + "_newton"
    return name


@dataclass(frozen=True)
class Layout:
    """Where each block sits in a row: ``start`` per block name, over ``names`` flat names."""

    names: tuple[str, ...]
    starts: dict[str, int] = field(hash=False)
    widths: dict[str, int] = field(hash=False)

    @staticmethod
    def of(columns: Sequence[LogColumn]) -> Layout:
        names: list[str] = []
        starts, widths = {}, {}
        for col in columns:
            starts[col.name] = len(names)
            widths[col.name] = col.width
            names.extend(col.elements)
        return Layout(tuple(names), starts, widths)

    @staticmethod
    def from_names(names: Sequence[str]) -> Layout:
        """The layout of rows recorded with these flat names (a recording's ``columns``):
        every declared block whose elements stand together, in order, is found."""
        names = [_current_name(n) for n in names]
        index = {n: i for i, n in enumerate(names)}
        starts, widths = {}, {}
        for col in LOG_COLUMNS:
            first = index.get(col.elements[0])
            if first is None:
                continue
            if tuple(names[first : first + col.width]) == col.elements:
                starts[col.name] = first
                widths[col.name] = col.width
        return Layout(tuple(names), starts, widths)

    @property
    def width(self) -> int:
        return len(self.names)

    def slice(self, name: str) -> slice:
        try:
            start = self.starts[name]
        except KeyError:
            raise KeyError(
                f"log column block {name!r} is not in this row layout "
                f"(known: {', '.join(self.starts)})"
            ) from None
        return slice(start, start + self.widths[name])

    def take(self, rows: FloatArray, name: str) -> FloatArray:
        """Block ``name`` of one row (shape (w,), or a float for width 1) or of rows (n, w)
        (or (n,) for width 1)."""
        s = self.slice(name)
        if s.stop - s.start == 1:
            return rows[..., s.start]
        return rows[..., s]

    def has(self, name: str) -> bool:
        return name in self.starts

    def columns_in(self, other: Layout) -> NDArray[np.intp]:
        """Where this layout's columns are in rows of ``other``, in this layout's order (a
        KeyError names a block ``other`` lacks)."""
        return np.array(
            [other.slice(name).start + k for name in self.starts for k in range(self.widths[name])],
            dtype=np.intp,
        )


LAYOUT = Layout.of(LOG_COLUMNS)
N_LOG = LAYOUT.width
COLUMN_NAMES: tuple[str, ...] = LAYOUT.names

# Offsets for the compiled kernel (control.loop) only: everyone else reads by name.
L_T = LAYOUT.starts["t_s"]
L_TREE = LAYOUT.starts["tree_eta_n"]
L_ROV = LAYOUT.starts["rov_eta_n"]
L_TREE_NU = LAYOUT.starts["tree_nu_b"]
L_ROV_NU = LAYOUT.starts["rov_nu_b"]
L_ETA_HAT = LAYOUT.starts["eta_hat_n"]
L_NU_HAT = LAYOUT.starts["nu_hat_tree"]
L_BIAS = LAYOUT.starts["bias_tree"]
L_ETA_D = LAYOUT.starts["eta_ref_n"]
L_DETA_D = LAYOUT.starts["eta_ref_rate_n"]
L_TAU_TREE = LAYOUT.starts["tau_tree_cmd"]
L_TAU_ROV = LAYOUT.starts["tau_rov_cmd_b"]
L_TAU_ACH = LAYOUT.starts["tau_rov_ach_b"]
L_F = LAYOUT.starts["thruster_force"]
L_N = LAYOUT.starts["thruster_speed"]
L_UTIL = LAYOUT.starts["thruster_utilisation"]
L_TERMS = LAYOUT.starts["control_terms"]
L_Y = LAYOUT.starts["y"]
L_MODE = LAYOUT.starts["mode"]
L_NIS = LAYOUT.starts["nis"]
L_ACCEPT = LAYOUT.starts["accepted"]
L_CRANE = LAYOUT.starts["crane_tip_ne"]
L_WIRE_LEN = LAYOUT.starts["wire_rest_length"]
L_TENSION = LAYOUT.starts["wire_tension"]


@dataclass(frozen=True)
class LogRows:
    """Rows of the log (one per plant step), read by block name.

    ``rows["tree_eta_n"]`` is (n, 6); a one-wide block gives (n,). Thruster blocks are cut to
    the ROV's ``n_thrusters``. ``quality_counters`` are the signal checks' counters (5 sensors
    x 4 checks) at the end of these rows."""

    data: FloatArray
    n_thrusters: int = M_MAX
    quality_counters: NDArray[np.int64] = field(default_factory=lambda: np.zeros((5, 4), np.int64))
    layout: Layout = LAYOUT

    def __len__(self) -> int:
        return int(self.data.shape[0])

    def __getitem__(self, name: str) -> FloatArray:
        block = self.layout.take(self.data, name)
        if name.startswith("thruster_"):
            return block[:, : self.n_thrusters]
        return block

    @property
    def t_s(self) -> FloatArray:
        return self["t_s"]

    def plant_state(self) -> FloatArray:
        """(n, 24) plant state [tree eta, tree nu, ROV eta, ROV nu] (see sim.plant)."""
        return np.hstack(
            [self["tree_eta_n"], self["tree_nu_b"], self["rov_eta_n"], self["rov_nu_b"]]
        )

    def last(self) -> FloatArray:
        """The last row (a copy)."""
        return self.data[-1].copy()

    def concat(self, other: LogRows) -> LogRows:
        return LogRows(
            np.vstack([self.data, other.data]),
            self.n_thrusters,
            other.quality_counters,
            self.layout,
        )

    @staticmethod
    def empty(n_thrusters: int = M_MAX) -> LogRows:
        return LogRows(np.zeros((0, N_LOG)), n_thrusters)

    @staticmethod
    def join(parts: Sequence[LogRows], n_thrusters: int) -> LogRows:
        """The parts' rows one after the other. A single part's rows are shared, not copied
        (rows are never written once made: a mission's requests are mostly one part, and
        copying 115 columns per step again cost a docking run some 5 % of its time)."""
        if not parts:
            return LogRows.empty(n_thrusters)
        data = parts[0].data if len(parts) == 1 else np.vstack([p.data for p in parts])
        return LogRows(data, n_thrusters, parts[-1].quality_counters.copy(), parts[0].layout)
