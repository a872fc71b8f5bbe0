"""``rov-console shadow``: a recorded trial through our observer and controller.

The sources (``ShadowSource``): our own MCAP session logs (``from_recording``) and a CSV
whose columns a small TOML file maps (``from_csv``, docs/formats.md). Each becomes a
``control.shadow.ShadowInput`` on the control step's grid, a start (the control system's
configuration and state, rebuilt from the recording's set-up or, for a CSV, the mapping's
mission with the estimate started from the first measurements), and the recorded rows to
compare with. ``shadow`` runs it (``control.shadow.run_shadow``) and sums it up
(``ShadowReport``); ``write_recording`` writes an MCAP the console replays, its estimates and
commands the shadow's; ``shadow_figure`` draws estimates against the recording and the NIS.
"""

from __future__ import annotations

import csv
import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from control import loop
from control.columns import LAYOUT, LOG_COLUMNS, N_LOG, LogRows
from control.shadow import (
    ShadowInput,
    ShadowResult,
    ShadowStart,
    fresh_from_changes,
    hold_on_grid,
    nis_consistency,
    nis_values,
    reference_acceleration_from_feedforward,
    run_shadow,
)
from sim import sensors
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]

SHADOW_COLUMNS = (
    "eta_hat_n",
    "nu_hat_tree",
    "bias_tree",
    "nis",
    "accepted",
    "eta_ref_n",
    "eta_ref_rate_n",
    "tau_tree_cmd",
    "tau_rov_cmd_b",
    "control_terms",
    "mode",
)
"""The log blocks a shadow recording takes from the shadow; the others are the recording's."""


class ShadowError(ValueError):
    """A source that cannot be shadowed, with one line saying why."""


@dataclass(frozen=True)
class ShadowSource:
    """A recording made ready for the shadow."""

    name: str
    inputs: ShadowInput
    start: ShadowStart
    row_steps: NDArray[np.intp]
    """The grid step of each recorded row."""
    recorded: LogRows
    """The recorded rows (in ``control.columns`` layout; blocks a source lacks are zero)."""
    has_estimates: bool
    has_commands: bool
    metadata: dict
    ps: ParameterSet
    """The parameter set the start was built with."""
    notes: list[str] = field(default_factory=list)


def _build(mission_toml_or_name: str, settings: dict | None, seed: int | None):
    """The Simulation (not stepped) a mission's set-up and the recorded settings make."""
    from missions import schema
    from missions.setup import build_simulation

    if "\n" in mission_toml_or_name:
        spec = schema.parse_mission(tomllib.loads(mission_toml_or_name), "<recording>")
    else:
        spec = schema.load_mission(mission_toml_or_name)
    s = settings or {}
    sim = build_simulation(
        spec,
        seed=seed,
        allocation=s.get("allocation"),
        feedback=s.get("feedback"),
        feedforward=s.get("feedforward"),
    )
    return spec, sim


def _whole_rows(data) -> LogRows:
    """The file's rows in ``control.columns``' layout (blocks it lacks stay zero)."""
    own = data.log.layout
    out = np.zeros((len(data.t_s), N_LOG))
    for name, sl in ((n, LAYOUT.slice(n)) for n in LAYOUT.starts):
        if own.has(name):
            block = own.take(data.rows, name).reshape(len(out), -1)
            out[:, sl.start : sl.start + block.shape[1]] = block[:, : sl.stop - sl.start]
    return LogRows(out, data.n_thrusters)


def from_recording(path: Path) -> ShadowSource:
    """A session log of ours: its set-up rebuilt (``mission_toml``, seed, settings), its rows
    on the control step's grid. ShadowError when the file is not one or holds no rows."""
    from app.recording import load_session, recorded_mission_toml
    from app.recording.reader import MCAP_MAGIC

    with open(path, "rb") as f:
        if f.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
            raise ShadowError(f"{path}: not an MCAP file")
    try:
        data = load_session(path)
    except (ValueError, KeyError, OSError) as err:
        raise ShadowError(f"{path}: not a readable session log ({err})") from err
    if len(data.t_s) < 2:
        raise ShadowError(f"{path}: holds no log rows to shadow ({data.problem or 'empty'})")
    toml = recorded_mission_toml(data.metadata)
    if toml is None:
        raise ShadowError(f"{path}: not a session log of ours (no mission set-up recorded)")
    notes = [] if data.complete else [f"file cut off ({data.problem}): shadowed its intact part"]
    try:
        _, sim = _build(toml, data.metadata.get("settings"), data.metadata.get("seed"))
    except ValueError as err:
        raise ShadowError(f"{path}: its recorded set-up does not build: {err}") from err
    start = ShadowStart.of(sim)
    rec = _whole_rows(data)
    t = rec.t_s
    first_t = float(data.metadata.get("start_t_s", 0.0)) + start.dt_s
    if len(data.runs) > 1 or abs(t[0] - first_t) > 0.5 * start.dt_s:
        notes.append("the recording does not start at its run's start: the observer starts "
                     "from the first measurements")  # fmt: skip
        start = _started_from(start, rec["y"][0], sim.ps)
    index = hold_on_grid(t, start.dt_s)
    row_steps = np.flatnonzero(np.diff(np.concatenate(([-1], index))) > 0)
    if len(row_steps) != len(index):
        notes.append(f"rows every {np.median(np.diff(t)):.3g} s, the controller's step "
                     f"{start.dt_s:g} s: each row held to the next, so the shadow is not exact "
                     "(record with run --log-rate for a step-exact shadow)")  # fmt: skip
    spring = _recorded_spring(rec, sim, start.dt_s)
    if start.C.use_ff:
        acc = reference_acceleration_from_feedforward(
            rec["control_terms"][:, 9:12], rec["eta_hat_n"][:, 2], rec["eta_ref_n"],
            rec["eta_ref_rate_n"], start.C, spring,
        )  # fmt: skip
    else:  # the law without feedforward does not read the acceleration
        acc = np.zeros((len(t), 3))
    reference = np.hstack([rec["eta_ref_n"], rec["eta_ref_rate_n"], acc])
    y = rec["y"][index]
    t_steps = np.arange(len(index)) * start.dt_s + (t[0] - start.dt_s)
    restart = np.zeros(len(index), dtype=np.bool_)
    for event in data.events:  # the observer starts again at a grip (missions.legs' hookup)
        k = int(round((float(event["t_s"]) - t_steps[0]) / start.dt_s))
        if event.get("kind") == "hookup" and 0 < k < len(index):
            restart[k] = True
    inputs = ShadowInput(
        t_s=t_steps,
        y=y,
        fresh=fresh_from_changes(y, start.held_y),
        tau_ach_b=rec["tau_rov_ach_b"][index],
        mode=rec["mode"][index].astype(np.int64),
        reference=reference[index],
        has_reference=np.ones(len(index), dtype=np.bool_),
        handover_command_b=_handover_commands(rec, index),
        spring=spring[index],
        heave_newton=_recorded_heave(rec, start)[index],
        restart=restart,
    )
    return ShadowSource(
        name=str(path), inputs=inputs, start=start, row_steps=row_steps, recorded=rec,
        has_estimates=True, has_commands=True, metadata=data.metadata, ps=sim.ps, notes=notes,
    )  # fmt: skip


def _payout_m(rest_length_m: float, w: float, axial_stiffness: float) -> float:
    """The wire's payout L whose stretched length L + w L^2 / (2 EA) is the row's rest length
    (``sim.site.wire_entries_into``), to the last bit where one gives it back."""
    a = 0.5 * w / axial_stiffness
    payout = 2.0 * rest_length_m / (1.0 + math.sqrt(1.0 + 4.0 * a * rest_length_m))
    best = payout
    for candidate in (payout, np.nextafter(payout, 0.0), np.nextafter(payout, np.inf)):
        if candidate + 0.5 * w * (candidate * candidate) / axial_stiffness == rest_length_m:
            best = float(candidate)
    return best


def _recorded_spring(rec: LogRows, sim, dt_s: float) -> FloatArray:
    """(n, 3) the control model's wire spring each row's step ran with, [k_h, p_eq north,
    east] (``sim.site.chunk_rows_into``): refreshed at the steps on whole seconds from the
    payout and crane tip where that step starts (the row before's end), held in between."""
    from sim import site
    from sim import wire as wm

    wire = site.wire_site(sim.plant_ps)
    w_spring = float(sim.plant_ps.wire.submerged_weight_per_length())
    weight = float(sim.ps.tree.submerged_weight_newton)
    n = len(rec)
    step = np.round((rec.t_s - dt_s) / dt_s).astype(np.int64)
    refresh = np.flatnonzero((step % sim.refresh_steps == 0) & (np.arange(n) > 0))
    spring = np.full((n, 3), np.nan)
    spring[0] = (sim.C.k_h, *sim.C.p_eq)
    rest = rec["wire_rest_length"][refresh - 1]
    payouts = {r: _payout_m(float(r), wire.w, wire.EA) for r in np.unique(rest)}
    spring[refresh, 0] = [wm.horizontal_stiffness_c(w_spring, weight, payouts[r]) for r in rest]
    spring[refresh, 1:3] = rec["crane_tip_ne"][refresh - 1]
    filled = np.flatnonzero(~np.isnan(spring[:, 0]))
    return spring[filled[np.searchsorted(filled, np.arange(n), side="right") - 1]]


def _handover_commands(rec: LogRows, index: NDArray[np.intp]) -> FloatArray:
    """(steps, 6) at each step whose mode is not the step before's, the wrench the row before
    commanded (ROV axes); NaN elsewhere."""
    mode = rec["mode"][index]
    out = np.full((len(index), 6), np.nan)
    change = np.flatnonzero(mode[1:] != mode[:-1]) + 1
    out[change] = rec["tau_rov_cmd_b"][index[change - 1]]
    return out


def _recorded_heave(rec: LogRows, start: ShadowStart) -> FloatArray:
    """(n,) the heave force on the tree the rows command [N] (the tree controller's heave
    command is it), held through the rows in other modes; the start's before the first."""
    heave = np.full(len(rec), np.nan)
    on_tree = rec["mode"] == loop.MODE_TREE
    heave[on_tree] = rec["tau_rov_cmd_b"][on_tree, 2]
    if not on_tree[0]:
        heave[0] = start.C.heave_newton
    filled = np.flatnonzero(~np.isnan(heave))
    return heave[filled[np.searchsorted(filled, np.arange(len(heave)), side="right") - 1]]


def _started_from(start: ShadowStart, y0: FloatArray, ps) -> ShadowStart:
    """``start`` with the observer started from the measurements ``y0`` (at rest, no bias)."""
    from control.startup import initial_estimate

    xhat, p_cov = initial_estimate(np.asarray(y0, dtype=float), start.C, ps)
    return replace(start, xhat=xhat, P_cov=p_cov, held_y=np.array(y0, dtype=float))


# ------------------------------------------------------------------ CSV with a mapping file
MEASUREMENTS = tuple(e.removeprefix("y_") for c in LOG_COLUMNS if c.name == "y" for e in c.elements)
"""The measurement names a mapping may give (``sim.sensors``' order; pos_north_m ...)."""
OPTIONAL = {
    "tau_surge_newton": ("tau_rov_ach_b", 0),
    "tau_sway_newton": ("tau_rov_ach_b", 1),
    "tau_yaw_newton_m": ("tau_rov_ach_b", 5),
    "ref_north_m": ("eta_ref_n", 0),
    "ref_east_m": ("eta_ref_n", 1),
    "ref_heading_rad": ("eta_ref_n", 2),
    "est_north_m": ("eta_hat_n", 0),
    "est_east_m": ("eta_hat_n", 1),
    "est_heading_rad": ("eta_hat_n", 2),
    "cmd_surge_newton": ("tau_rov_cmd_b", 0),
    "cmd_sway_newton": ("tau_rov_cmd_b", 1),
    "cmd_yaw_newton_m": ("tau_rov_cmd_b", 5),
}
"""The other names a mapping may give: the achieved wrench (the observer's input, ROV axes),
the reference the trial's controller followed, its observer's estimate and its commands."""
UNITS = {"": 1.0, "si": 1.0, "deg": math.pi / 180.0, "deg/s": math.pi / 180.0, "kn": 1000.0}


def _column_spec(name: str, spec: object) -> tuple[str, float, float]:
    """(column, scale, offset) of one mapping entry: a column name, or a table with
    ``column`` and optional ``unit`` (deg, deg/s, kN), ``scale`` and ``offset``."""
    if isinstance(spec, str):
        return spec, 1.0, 0.0
    if not isinstance(spec, dict) or not isinstance(spec.get("column"), str):
        raise ShadowError(f"mapping: {name} must be a column name or {{column = ...}}")
    unit = str(spec.get("unit", "")).lower()
    if unit not in UNITS:
        raise ShadowError(f"mapping: {name}: unit {unit!r} is not one of deg, deg/s, kN")
    scale = float(spec.get("scale", 1.0)) * UNITS[unit]
    return spec["column"], scale, float(spec.get("offset", 0.0))


def _read_table(path: Path, mapping: dict) -> dict[str, FloatArray]:
    """The CSV's columns as floats by header name (``delimiter``, ``decimal``, ``skip_rows``
    of the mapping)."""
    delimiter = str(mapping.get("delimiter", ","))
    decimal = str(mapping.get("decimal", "."))
    try:
        lines = path.read_text(encoding=str(mapping.get("encoding", "utf-8"))).splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise ShadowError(f"{path}: cannot read: {err}") from err
    reader = csv.reader(lines[int(mapping.get("skip_rows", 0)) :], delimiter=delimiter)
    rows = [r for r in reader if r and any(c.strip() for c in r)]
    if len(rows) < 3:
        raise ShadowError(f"{path}: fewer than two data rows")
    header = [h.strip() for h in rows[0]]
    table: dict[str, FloatArray] = {}
    for k, name in enumerate(header):
        try:
            table[name] = np.array([float(r[k].strip().replace(decimal, ".")) for r in rows[1:]])
        except (ValueError, IndexError):
            continue  # a text column, or a short row: only an error if the mapping uses it
    return table


def _read_mapping(mapping_path: Path) -> dict:
    """A mapping file's table: ``mission`` (a name or file) and ``[columns]``."""
    try:
        mapping = tomllib.loads(mapping_path.read_text())
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise ShadowError(f"{mapping_path}: not a readable mapping file: {err}") from err
    if not isinstance(mapping.get("mission"), str) or not isinstance(mapping.get("columns"), dict):
        raise ShadowError(f"{mapping_path}: needs mission = NAME and a [columns] table")
    for name in mapping["columns"]:
        if name not in MEASUREMENTS and name not in OPTIONAL and name != "time_s":
            raise ShadowError(f"{mapping_path}: unknown name {name!r} in [columns]")
    return mapping


def _mapped_source(
    name: str, columns: dict[str, FloatArray], mapping: dict, mapping_path: Path
) -> ShadowSource:
    """The source of mapped columns, on the control system the mapping's mission builds."""
    for need in ("time_s", "pos_north_m", "pos_east_m", "heading_rad"):
        if need not in columns:
            raise ShadowError(f"{mapping_path}: [columns] must map {need}")
    try:
        _, sim = _build(mapping["mission"], None, None)
    except (ValueError, OSError) as err:
        raise ShadowError(f"{mapping_path}: mission {mapping['mission']!r}: {err}") from err
    return _source_of_columns(name, columns, sim)


def from_csv(path: Path, mapping_path: Path) -> ShadowSource:
    """A trial's CSV export, its columns mapped by ``mapping_path`` (docs/formats.md)."""
    mapping = _read_mapping(mapping_path)
    table = _read_table(path, mapping)
    columns: dict[str, FloatArray] = {}
    for name, spec in mapping["columns"].items():
        column, scale, offset = _column_spec(name, spec)
        if column not in table:
            raise ShadowError(f"{path}: no numeric column {column!r} (mapped to {name})")
        columns[name] = table[column] * scale + offset
    return _mapped_source(str(path), columns, mapping, mapping_path)


def _field(message: object, path: str) -> float:
    """The number at ``path`` (``pose.position.x``; ``data``) of a deserialised message."""
    value = message
    for part in path.split("."):
        value = getattr(value, part)
    return float(value)  # type: ignore[arg-type]


def from_rosbag(path: Path, mapping_path: Path) -> ShadowSource:
    """A ROS 2 bag (rosbag2, MCAP or SQLite storage; read with ``rosbags``), each of our
    names mapped to a topic's field (docs/formats.md). Every message's log time is a row; each
    name holds its topic's latest value there."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    mapping = _read_mapping(mapping_path)
    specs: dict[str, tuple[str, str, float, float]] = {}
    for name, spec in mapping["columns"].items():
        if name == "time_s":
            continue
        if not isinstance(spec, dict) or not isinstance(spec.get("topic"), str):
            raise ShadowError(f"{mapping_path}: {name} needs {{topic = ..., field = ...}}")
        _, scale, offset = _column_spec(name, {**spec, "column": spec["topic"]})
        specs[name] = (spec["topic"], str(spec.get("field", "data")), scale, offset)
    series: dict[str, tuple[list[int], list[float]]] = {n: ([], []) for n in specs}
    try:
        typestore = get_typestore(Stores.ROS2_HUMBLE)
        with AnyReader([path], default_typestore=typestore) as reader:
            topics = {topic for topic, _, _, _ in specs.values()}
            missing = topics - {c.topic for c in reader.connections}
            if missing:
                raise ShadowError(f"{path}: no topic {', '.join(sorted(missing))} in the bag")
            wanted = [c for c in reader.connections if c.topic in topics]
            for conn, t_ns, raw in reader.messages(connections=wanted):
                msg = reader.deserialize(raw, conn.msgtype)
                for name, (topic, field_path, scale, offset) in specs.items():
                    if topic == conn.topic:
                        series[name][0].append(t_ns)
                        series[name][1].append(_field(msg, field_path) * scale + offset)
    except ShadowError:
        raise
    except AttributeError as err:
        raise ShadowError(f"{path}: a mapped field is not in its message: {err}") from err
    except Exception as err:  # rosbags' reader errors have no common base beyond this
        raise ShadowError(f"{path}: not a readable ROS 2 bag: {err}") from err
    return _mapped_source(str(path), _held_columns(series), {**mapping}, mapping_path)


def _held_columns(series: dict[str, tuple[list[int], list[float]]]) -> dict[str, FloatArray]:
    """Series of their own times as columns on their times' union [s], each held from its last
    message (its first value before it)."""
    stamps = [np.asarray(t, dtype=np.int64) for t, _ in series.values() if t]
    if not stamps:
        return {}
    t_all = np.unique(np.concatenate(stamps))
    columns = {"time_s": (t_all - t_all[0]) * 1e-9}
    for name, (t, v) in series.items():
        if t:
            at = np.searchsorted(np.asarray(t, dtype=np.int64), t_all, side="right") - 1
            columns[name] = np.asarray(v)[np.maximum(at, 0)]
    return columns


def _source_of_columns(name: str, columns: dict[str, FloatArray], sim) -> ShadowSource:
    """A CSV's mapped columns as a source: rows in ``control.columns``' layout, the observer
    started from the first measurements, the reference held at that start unless mapped."""
    t = columns["time_s"]
    if len(t) < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0.0):
        raise ShadowError(f"{name}: time_s must increase from row to row")
    dt = float(sim.dt_s)
    step = np.round((t - t[0]) / dt).astype(np.int64)
    last = np.append(step[1:] != step[:-1], True)  # the last row of each control step
    columns = {k: v[last] for k, v in columns.items()}
    t = step[last] * dt
    columns["time_s"] = t
    n = len(t)
    rec = np.zeros((n, N_LOG))
    rec[:, LAYOUT.starts["t_s"]] = t - t[0]
    y0 = LAYOUT.starts["y"]
    for k, m in enumerate(MEASUREMENTS):
        if m in columns:
            rec[:, y0 + k] = columns[m]
    for m, (block, k) in OPTIONAL.items():
        if m in columns:
            rec[:, LAYOUT.starts[block] + k] = columns[m]
    rec[:, LAYOUT.starts["mode"]] = loop.MODE_TREE
    rows = LogRows(rec, sim.n_thrusters)
    start = ShadowStart.of(sim)
    start = _started_from(start, rows["y"][0], sim.ps)
    notes = ["a trial: the observer starts from the first measurements; the controller is in "
             "the tree mode throughout"]  # fmt: skip
    if any(m in columns for m in ("ref_north_m", "ref_east_m", "ref_heading_rad")):
        ref = rows["eta_ref_n"].copy()
        for k, m in enumerate(("ref_north_m", "ref_east_m", "ref_heading_rad")):
            if m not in columns:
                ref[:, k] = start.xhat[k]
    else:
        ref = np.tile(start.xhat[0:3], (n, 1))
        notes.append("no reference mapped: the controller holds the first estimate")
    if not any(m in columns for m in ("tau_surge_newton", "tau_sway_newton", "tau_yaw_newton_m")):
        notes.append("no achieved wrench mapped: the observer predicts without the ROV's thrust")
    index = hold_on_grid(rec[:, LAYOUT.starts["t_s"]] + start.dt_s, start.dt_s)
    row_steps = np.flatnonzero(np.diff(np.concatenate(([-1], index))) > 0)
    rate = np.vstack([np.zeros(3), np.diff(ref, axis=0) / np.diff(t)[:, None]])
    acc = np.vstack([np.zeros(3), np.diff(rate, axis=0) / np.diff(t)[:, None]])
    reference = np.hstack([ref, rate, acc])
    y = rows["y"][index]
    inputs = ShadowInput(
        t_s=np.arange(len(index), dtype=np.float64) * start.dt_s,
        y=y,
        fresh=fresh_from_changes(y),
        tau_ach_b=rows["tau_rov_ach_b"][index],
        mode=np.full(len(index), loop.MODE_TREE, dtype=np.int64),
        reference=reference[index],
        has_reference=np.ones(len(index), dtype=np.bool_),
    )
    has_est = any(m.startswith("est_") for m in columns)
    has_cmd = any(m.startswith("cmd_") for m in columns)
    metadata = {"mission_name": sim.ps.name, "label": f"shadow of {Path(name).name}"}
    return ShadowSource(name, inputs, start, row_steps, rows, has_est, has_cmd, metadata,
                        sim.ps, notes)  # fmt: skip


# ------------------------------------------------------------------ running and summing up
@dataclass(frozen=True)
class ShadowReport:
    """A shadow run and its figures against the recording."""

    source: ShadowSource
    result: ShadowResult
    summary: dict


def _max_abs(a: FloatArray) -> float | None:
    return float(np.max(np.abs(a))) if a.size else None


def shadow(source: ShadowSource, mount_m: FloatArray | None = None) -> ShadowReport:
    """Run the shadow over ``source`` (with the mounting vector ``mount_m``, tree axes [m],
    instead of the configured one when given) and sum it up (the JSON ``--json`` prints)."""
    start = source.start
    if mount_m is not None:  # the observer starts again from the first fix, moved through it
        start = _started_from(start.with_mount(mount_m), source.inputs.y[0], source.ps)
    result = run_shadow(source.inputs, start)
    at = source.row_steps
    mine, rec = result.rows, source.recorded
    est = mine["eta_hat_n"][at] - rec["eta_hat_n"]
    # the free ROV's and the pilot's set points are commands a log does not keep: the
    # commands are compared where the tree controller ran
    on_tree = rec["mode"] == loop.MODE_TREE
    cmd = (mine["tau_rov_cmd_b"][at] - rec["tau_rov_cmd_b"])[on_tree]
    notes = list(source.notes)
    if source.has_commands and not on_tree.all():
        notes.append(f"{int((~on_tree).sum())} rows with the ROV free or flown by hand: their "
                     "commands (on set points a log does not keep) are not compared")  # fmt: skip
    summary: dict = {
        "source": source.name,
        "samples": int(len(at)),
        "steps": int(len(source.inputs.t_s)),
        "dt_s": start.dt_s,
        "step_exact": bool(len(at) == len(source.inputs.t_s)),
        "mount_m": [float(v) for v in start.C.r_mount],
        "max_estimate_difference_m": (
            _max_abs(np.hypot(est[:, 0], est[:, 1])) if source.has_estimates else None
        ),
        "max_heading_difference_deg": (
            _max_abs(np.degrees(np.angle(np.exp(1j * est[:, 2])))) if source.has_estimates else None
        ),
        "max_command_difference_newton": (_max_abs(cmd[:, 0:3]) if source.has_commands else None),
        "max_command_difference_newton_m": (_max_abs(cmd[:, 5]) if source.has_commands else None),
        "nis": {
            name: nis_consistency(v, name).as_dict()
            for name, v in nis_values(mine, source.inputs.mode == loop.MODE_TREE).items()
        },
        "innovation_rms": _innovation_rms(result.innovation),
        "command_samples": int(on_tree.sum()) if source.has_commands else 0,
        "notes": notes,
    }
    return ShadowReport(source, result, summary)


def _innovation_rms(innovation: FloatArray) -> dict[str, float | None]:
    def rms(v: FloatArray) -> float | None:
        v = v[np.isfinite(v)]
        return float(np.sqrt(np.mean(v * v))) if v.size else None

    heading = rms(innovation[:, 2])
    return {
        "north_m": rms(innovation[:, 0]),
        "east_m": rms(innovation[:, 1]),
        "heading_deg": None if heading is None else math.degrees(heading),
    }


def shadow_rows(report: ShadowReport) -> FloatArray:
    """(steps, N_LOG): the recorded rows held on the grid with the shadow's control columns
    (``SHADOW_COLUMNS``) in place of the recorded ones; a CSV's tree pose is the shadow's
    estimate and its ROV pose the fix and compass (a trial has no truth)."""
    src = report.source
    index = np.maximum.accumulate(
        np.searchsorted(src.row_steps, np.arange(len(src.inputs.t_s)), side="right") - 1
    )
    out = src.recorded.data[index].copy()
    mine = report.result.rows.data
    for name in SHADOW_COLUMNS:
        out[:, LAYOUT.slice(name)] = mine[:, LAYOUT.slice(name)]
    out[:, LAYOUT.starts["t_s"]] = src.inputs.t_s + src.start.dt_s
    if not src.has_estimates or "mission_toml" not in src.metadata:
        tree, rov = LAYOUT.starts["tree_eta_n"], LAYOUT.starts["rov_eta_n"]
        y = src.inputs.y
        est = mine[:, LAYOUT.slice("eta_hat_n")]
        out[:, tree], out[:, tree + 1], out[:, tree + 5] = est[:, 0], est[:, 1], est[:, 2]
        out[:, rov], out[:, rov + 1], out[:, rov + 2] = y[:, 0], y[:, 1], y[:, 3]
        out[:, rov + 5] = y[:, sensors.Y_PSI]
    return out


def write_recording(report: ShadowReport, path: Path, overwrite: bool = False) -> Path:
    """An MCAP of the shadow (``shadow_rows``), at the step's rate, which the console
    replays; the recording's events are copied, and one ``shadow`` event says what it is."""
    from app.recording import SessionRecorder, load_session

    src = report.source
    metadata = dict(src.metadata)
    metadata["label"] = f"shadow of {Path(src.name).name}"
    metadata.pop("columns", None)
    metadata.pop("recorder", None)
    metadata.pop("params", None)
    rows = shadow_rows(report)
    recorder = SessionRecorder(
        path, metadata=metadata, params=src.ps, n_thrusters=src.recorded.n_thrusters,
        numeric_rate_hz=1.0 / src.start.dt_s, overwrite=overwrite,
    )  # fmt: skip
    try:
        recorder.event(float(rows[0, 0]), "shadow", metadata["label"], report.summary["nis"])
        if Path(src.name).suffix == ".mcap":
            for e in load_session(src.name).events:
                recorder.event(e["t_s"], e["kind"], e["text"], e.get("data"))
        tip = metadata.get("crane_tip_n")
        recorder.write_log(rows, crane_tip_n=tip, wire_length_m=metadata.get("wire_length_m"))
    finally:
        recorder.close()
    return path


def shadow_figure(report: ShadowReport, path: Path) -> Path:
    """Estimates (shadow against recorded), the innovations and the NIS over time with its
    per-sample band, to PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    src, mine = report.source, report.result.rows
    t = src.inputs.t_s + src.start.dt_s
    t_rec = src.recorded.t_s
    fig, axes = plt.subplots(4, 1, figsize=(10, 11), sharex=True)
    labels = ("north [m]", "east [m]")
    for k, ax in enumerate(axes[0:2]):
        ax.plot(t, mine["eta_hat_n"][:, k], label="shadow's estimate")
        if src.has_estimates:
            ax.plot(t_rec, src.recorded["eta_hat_n"][:, k], "--", label="recorded estimate")
        if "mission_toml" in src.metadata:
            ax.plot(t_rec, src.recorded["tree_eta_n"][:, k], ":", label="truth (simulation)")
        ax.set_ylabel(labels[k])
        ax.legend(loc="best", fontsize=8)
    ax = axes[2]
    ax.plot(t, np.degrees(mine["eta_hat_n"][:, 2]), label="shadow's estimate")
    if src.has_estimates:
        ax.plot(t_rec, np.degrees(src.recorded["eta_hat_n"][:, 2]), "--", label="recorded")
    ax.set_ylabel("heading [deg]")
    ax.legend(loc="best", fontsize=8)
    ax = axes[3]
    nis = mine["nis"]
    accepted = mine["accepted"] > 0.5
    accepted &= (src.inputs.mode == loop.MODE_TREE)[:, None]  # as the statistics
    pos = accepted[:, sensors.POSITION]
    ax.semilogy(t[pos], np.maximum(nis[pos, 0] + nis[pos, 1], 1e-6), ".", ms=2,
                label="NIS, position (2)")  # fmt: skip
    psi = accepted[:, sensors.COMPASS]
    ax.semilogy(t[psi], np.maximum(nis[psi, 2], 1e-6), ".", ms=1, alpha=0.4,
                label="NIS, compass (1)")  # fmt: skip
    stats = report.summary["nis"]
    for name, colour in (("position", "C0"), ("compass", "C1")):
        _, hi = stats[name]["sample_band"]
        ax.axhline(hi, color=colour, lw=0.8, ls="--")
    ax.set_ylabel("NIS")
    ax.set_xlabel("time [s]")
    p = stats["position"]
    ax.set_title(f"position NIS mean {p['mean']:.3g}, band {p['band'][0]:.3g}-"
                 f"{p['band'][1]:.3g}: {p['verdict']}", fontsize=9)  # fmt: skip
    ax.legend(loc="best", fontsize=8)
    fig.suptitle(f"shadow of {Path(src.name).name}, mount {report.summary['mount_m']} m")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
