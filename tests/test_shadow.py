"""Shadow mode (``rov-console shadow``, ``app.shadow``, ``control.shadow``): our observer and
controller on a recording's measurements, without the plant."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from app import headless
from app.cli import app
from app.shadow import from_csv, from_recording, shadow, shadow_figure, write_recording
from missions import schema
from missions.driver import MissionDriver
from missions.setup import build_simulation

ESTIMATE_TOL_M = 1e-12
"""The shadow runs the observer's compiled operations in the run's order on the run's held
measurements and achieved wrench: its estimates are the same bits (0.0 measured)."""
COMMAND_TOL_NEWTON = 1e-8
"""The commands too, but for the reference's acceleration, which a log does not keep and the
shadow solves back from the recorded feedforward term (``M a = ff - rest``): rounding of some
1e-16 of forces up to 1e4 N (6e-14 N measured on model-rotation-wrong-r)."""


def _short_rotation(wrong_mount: bool) -> schema.Mission:
    """model-rotation-wrong-r cut short: 10 s hold, the rotation for at most 60 s (the
    rotation is what shows the mount: the wrong r turns the fix's offset round)."""
    data = schema.load_mission("model-rotation-wrong-r").model_dump()
    data["legs"][0]["duration_s"] = 10.0
    data["legs"][1].update(settle_s=5.0, timeout_s=60.0)
    if not wrong_mount:
        data["setup"]["r_mount_config_m"] = None
    return schema.Mission.model_validate(data)


def _record(spec: schema.Mission, path: Path, rate_hz: float) -> Path:
    sim = build_simulation(spec)
    recorder = headless.open_recorder(str(path), spec, sim, None, numeric_rate_hz=rate_hz)
    try:
        headless.drive(MissionDriver(spec, sim), recorder)
    finally:
        recorder.close()
    return path


@pytest.fixture(scope="module")
def wrong_mount_log(tmp_path_factory) -> Path:
    return _record(_short_rotation(True), tmp_path_factory.mktemp("shadow") / "wrong.mcap", 100)


@pytest.fixture(scope="module")
def wrong_mount(wrong_mount_log):
    return from_recording(wrong_mount_log)


def _step_run(path: Path) -> Path:
    """model-step-priority with the EKF's feedback: a step with the feedforward law."""
    spec = schema.load_mission("model-step-priority")
    sim = build_simulation(spec, feedback="ekf")
    with headless.open_recorder(str(path), spec, sim, None, numeric_rate_hz=100.0) as recorder:
        recorder.write_log(sim.run_for(3.0).data, crane_tip_n=sim.crane_tip_n)
        sim.set_target(2.0, 1.0, math.radians(30.0))
        recorder.write_log(sim.run_for(7.0).data)
    return path


def _winch_run(path: Path) -> Path:
    """The same, the winch paying out 0.5 m at 0.1 m/s: the control model's wire spring
    changes on whole seconds."""
    spec = schema.load_mission("model-step-priority")
    sim = build_simulation(spec, feedback="ekf")
    with headless.open_recorder(str(path), spec, sim, None, numeric_rate_hz=100.0) as recorder:
        recorder.write_log(sim.run_for(2.0).data, crane_tip_n=sim.crane_tip_n)
        sim.winch_to(sim.wire_length_m + 0.5, 0.1)
        sim.set_target(1.0, 0.0, 0.0)
        recorder.write_log(sim.run_for(8.0).data, wire_length_m=sim.wire_length_m)
    return path


def _hookup_run(path: Path) -> Path:
    """The appendix C trial's first legs: the ROV flies in free and grips the tree (the
    observer starts again), a heave force is set, the observer converges."""
    data = schema.load_mission("sea-trial-appendix-c").model_dump()
    data["legs"] = data["legs"][:3]
    data["legs"][2]["duration_s"] = 10.0
    return _record(schema.Mission.model_validate(data), path, 100)


@pytest.mark.parametrize("run", [_step_run, _winch_run, _hookup_run])
def test_a_100hz_recording_is_reproduced_step_for_step(run, tmp_path):
    """Fed a 100 Hz recording of our own run (model scale, EKF feedback), the shadow's
    estimates and commands are the run's: with the feedforward law's step, with the winch
    paying out, and across a hook-up and a heave force. The free ROV's commands (on a set
    point a log does not keep) are left out of the comparison."""
    report = shadow(from_recording(run(tmp_path / "run.mcap")))
    s = report.summary
    assert s["step_exact"] and s["samples"] == s["steps"]
    assert s["command_samples"] >= 1000  # at least 10 s of the tree controller
    assert s["max_estimate_difference_m"] <= ESTIMATE_TOL_M
    assert s["max_heading_difference_deg"] <= ESTIMATE_TOL_M
    assert s["max_command_difference_newton"] <= COMMAND_TOL_NEWTON
    assert s["max_command_difference_newton_m"] <= COMMAND_TOL_NEWTON
    assert s["nis"]["position"]["verdict"] == "consistent"


def test_the_wrong_mount_shows_in_the_nis(wrong_mount, tmp_path):
    """The trial's error (thesis 6.2.1, appendix E): the mount vector with the wrong sign. The
    position fix's NIS is far above its chi-square band; the same run with the right r
    configured keeps it in."""
    report = shadow(wrong_mount)
    nis = report.summary["nis"]["position"]
    assert nis["verdict"] == "above band"
    assert nis["mean"] > 3.0 * nis["band"][1]
    assert report.summary["max_estimate_difference_m"] <= ESTIMATE_TOL_M
    right = shadow(from_recording(_record(_short_rotation(False), tmp_path / "right.mcap", 100)))
    assert right.summary["nis"]["position"]["verdict"] == "consistent"
    # the reviewer's question: with the right r, our observer's innovations shrink
    fixed = shadow(wrong_mount, np.array([-2.0, 0.0, 0.0]))
    assert fixed.summary["nis"]["position"]["mean"] < nis["mean"] / 4.0


def test_the_shadow_writes_a_recording_and_a_figure(tmp_path):
    from app.recording import load_session

    spec = schema.load_mission("model-step-priority")
    sim = build_simulation(spec, feedback="ekf")
    path = tmp_path / "step.mcap"
    with headless.open_recorder(str(path), spec, sim, None, numeric_rate_hz=100.0) as rec:
        rec.write_log(sim.run_for(5.0).data, crane_tip_n=sim.crane_tip_n)
    report = shadow(from_recording(path))
    out = write_recording(report, tmp_path / "shadow.mcap")
    data = load_session(out)
    assert data.complete and len(data.t_s) == report.summary["steps"]
    np.testing.assert_array_equal(data.log["eta_hat_n"], report.result.rows["eta_hat_n"])
    assert any(e["kind"] == "shadow" for e in data.events)
    png = shadow_figure(report, tmp_path / "shadow.png")
    assert png.stat().st_size > 10_000


def test_a_20hz_recording_is_held_between_rows_and_said_not_exact(tmp_path):
    spec = schema.load_mission("model-step-priority")
    sim = build_simulation(spec, feedback="ekf")
    path = tmp_path / "slow.mcap"
    with headless.open_recorder(str(path), spec, sim, None) as recorder:
        recorder.write_log(sim.run_for(5.0).data, crane_tip_n=sim.crane_tip_n)
    report = shadow(from_recording(path))
    s = report.summary
    assert not s["step_exact"] and s["samples"] == 101 and s["steps"] == 500
    assert any("not exact" in note for note in s["notes"])
    assert s["max_estimate_difference_m"] < 0.5


LABVIEW_MAPPING = """
mission = "model-rotation-wrong-r"   # the configuration the trial's controller had
delimiter = "\\t"
decimal = ","
skip_rows = 1

[columns]
time_s = "Time"
pos_north_m = "North"
pos_east_m = "East"
heading_rad = { column = "Heading", unit = "deg" }
gyro_r_rad_s = { column = "Yaw rate", unit = "deg/s" }
dvl_u_mps = "DVL u"
dvl_v_mps = "DVL v"
tau_surge_newton = { column = "Surge", unit = "kN" }
tau_sway_newton = { column = "Sway", unit = "kN" }
tau_yaw_newton_m = { column = "Yaw", unit = "kN" }
est_north_m = "Est north"
est_east_m = "Est east"
"""


def _labview_csv(log: Path, path: Path) -> Path:
    """The recording's measurements at 10 Hz as a LabVIEW-style export: a title line, tabs,
    decimal commas, degrees and kN."""
    from app.recording import load_session

    rows = load_session(log).log
    keep = slice(9, None, 10)
    y, ach, est = rows["y"][keep], rows["tau_rov_ach_b"][keep], rows["eta_hat_n"][keep]
    cols = {
        "Time": rows.t_s[keep],
        "North": y[:, 0],
        "East": y[:, 1],
        "Heading": np.degrees(y[:, 4]),
        "Yaw rate": np.degrees(y[:, 10]),
        "DVL u": y[:, 5],
        "DVL v": y[:, 6],
        "Surge": ach[:, 0] / 1e3,
        "Sway": ach[:, 1] / 1e3,
        "Yaw": ach[:, 5] / 1e3,
        "Est north": est[:, 0],
        "Est east": est[:, 1],
    }
    lines = ["Sea trial log, exported", "\t".join(cols)]
    for k in range(len(cols["Time"])):
        lines.append("\t".join(f"{v[k]:.6f}".replace(".", ",") for v in cols.values()))
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_trials_csv_through_its_mapping(wrong_mount_log, tmp_path):
    csv_path = _labview_csv(wrong_mount_log, tmp_path / "trial.txt")
    mapping = tmp_path / "trial.toml"
    mapping.write_text(LABVIEW_MAPPING)
    report = shadow(from_csv(csv_path, mapping))
    s = report.summary
    assert s["samples"] == 700 and not s["step_exact"]
    assert s["nis"]["position"]["verdict"] == "above band"
    assert s["max_estimate_difference_m"] is not None
    assert s["max_command_difference_newton"] is None  # no commands mapped


def test_the_command_line_prints_one_json_object(wrong_mount_log, tmp_path):
    result = CliRunner().invoke(app, ["shadow", str(wrong_mount_log), "--json"])
    assert result.exit_code == 1, result.output  # the NIS left its band
    s = json.loads(result.stdout)
    assert {"samples", "max_estimate_difference_m", "max_command_difference_newton", "nis"} <= set(
        s
    )


def _cut(src: Path, dst: Path, n: int) -> Path:
    dst.write_bytes(src.read_bytes()[:n])
    return dst


@pytest.mark.parametrize("kind", ["text", "empty", "cut", "foreign", "csv-no-mapping"])
def test_a_bad_file_gets_one_line(kind, wrong_mount_log, tmp_path):
    from mcap.writer import Writer

    path = tmp_path / f"{kind}.mcap"
    if kind == "text":
        path.write_text("time,north\n0,1\n")
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "cut":
        _cut(wrong_mount_log, path, 5000)
    elif kind == "foreign":  # a valid MCAP of someone else's, with no session in it
        with open(path, "wb") as f:
            w = Writer(f)
            w.start()
            sid = w.register_schema("x", "jsonschema", b"{}")
            ch = w.register_channel("/other", "json", sid)
            w.add_message(ch, 0, b"{}", 0)
            w.finish()
    else:
        path = tmp_path / "trial.csv"
        path.write_text("t,n\n0,1\n")
    result = CliRunner().invoke(app, ["shadow", str(path)])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("shadow: "), result.output


BAG_MAPPING = """
mission = "model-rotation-wrong-r"

[columns]                               # log times of the messages are the rows' times
pos_north_m = { topic = "/rov/fix", field = "point.x" }
pos_east_m = { topic = "/rov/fix", field = "point.y" }
heading_rad = { topic = "/rov/heading", field = "data", unit = "deg" }
gyro_r_rad_s = { topic = "/rov/gyro", field = "vector.z" }
dvl_u_mps = { topic = "/rov/dvl", field = "twist.linear.x" }
dvl_v_mps = { topic = "/rov/dvl", field = "twist.linear.y" }
tau_surge_newton = { topic = "/rov/wrench", field = "wrench.force.x" }
tau_sway_newton = { topic = "/rov/wrench", field = "wrench.force.y" }
tau_yaw_newton_m = { topic = "/rov/wrench", field = "wrench.torque.z" }
"""


def _bag(log: Path, path: Path, storage: str) -> Path:
    """The recording's measurements as a ROS 2 bag, each sensor on its own topic at its own
    rate (fix 1 Hz, compass and DVL 10 Hz, gyro and the wrench 20 Hz)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    from app.recording import load_session

    ts = get_typestore(Stores.ROS2_HUMBLE)
    m = ts.types
    rows = load_session(log).log
    t_ns = np.round(rows.t_s * 1e9).astype(np.int64)
    y, ach = rows["y"], rows["tau_rov_ach_b"]

    def vec(x: float, y: float, z: float):
        return m["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z))

    def header(k: int):
        sec, nanosec = divmod(int(t_ns[k]), 10**9)
        stamp = m["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
        return m["std_msgs/msg/Header"](stamp=stamp, frame_id="ned")

    def fix(k: int):
        point = m["geometry_msgs/msg/Point"](x=y[k, 0], y=y[k, 1], z=y[k, 2])
        return m["geometry_msgs/msg/PointStamped"](header=header(k), point=point)

    def heading(k: int):
        return m["std_msgs/msg/Float64"](data=float(np.degrees(y[k, 4])))

    def gyro(k: int):
        v = vec(*y[k, 8:11])
        return m["geometry_msgs/msg/Vector3Stamped"](header=header(k), vector=v)

    def dvl(k: int):
        twist = m["geometry_msgs/msg/Twist"](linear=vec(*y[k, 5:8]), angular=vec(0, 0, y[k, 10]))
        return m["geometry_msgs/msg/TwistStamped"](header=header(k), twist=twist)

    def wrench(k: int):
        w = m["geometry_msgs/msg/Wrench"](force=vec(*ach[k, 0:3]), torque=vec(*ach[k, 3:6]))
        return m["geometry_msgs/msg/WrenchStamped"](header=header(k), wrench=w)

    topics = {  # topic: (type, every how many 100 Hz rows, message of row k)
        "/rov/fix": ("geometry_msgs/msg/PointStamped", 100, fix),
        "/rov/heading": ("std_msgs/msg/Float64", 10, heading),
        "/rov/gyro": ("geometry_msgs/msg/Vector3Stamped", 5, gyro),
        "/rov/dvl": ("geometry_msgs/msg/TwistStamped", 10, dvl),
        "/rov/wrench": ("geometry_msgs/msg/WrenchStamped", 5, wrench),
    }
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conns = {
            t: writer.add_connection(t, kind, typestore=ts) for t, (kind, _, _) in topics.items()
        }
        for k in range(len(t_ns)):
            for topic, (kind, every, make) in topics.items():
                if k % every == every - 1:
                    writer.write(conns[topic], int(t_ns[k]), ts.serialize_cdr(make(k), kind))
    return path


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_ros2_bag_through_its_mapping(storage, wrong_mount_log, tmp_path):
    bag = _bag(wrong_mount_log, tmp_path / f"trial-{storage}", storage)
    mapping = tmp_path / "bag.toml"
    mapping.write_text(BAG_MAPPING)
    result = CliRunner().invoke(app, ["shadow", str(bag), "--mapping", str(mapping), "--json"])
    assert result.exit_code == 1, result.output  # the wrong mount: NIS above band
    s = json.loads(result.stdout)
    assert s["nis"]["position"]["verdict"] == "above band"
    assert s["nis"]["position"]["samples"] >= 60


def test_run_records_every_step_for_the_shadow(tmp_path):
    """``run --log-rate 100`` keeps every plant step, and ``shadow`` then reproduces the run."""
    mission = tmp_path / "hold.toml"
    data = schema.load_mission("model-step-priority").model_dump()
    data["setup"]["feedback"] = "ekf"
    data["legs"] = [{"type": "hold", "name": "hold", "duration_s": 3.0}]
    mission.write_text(schema.dump_mission(schema.Mission.model_validate(data)))
    log = tmp_path / "hold.mcap"
    runner = CliRunner()
    ran = runner.invoke(
        app, ["run", str(mission), "--log", str(log), "--log-rate", "100", "--json"]
    )
    assert ran.exit_code == 0, ran.output
    result = runner.invoke(app, ["shadow", str(log), "--json"])
    assert result.exit_code == 0, result.output
    s = json.loads(result.stdout)
    assert s["step_exact"] and s["samples"] == 300
    assert s["max_estimate_difference_m"] <= ESTIMATE_TOL_M
    assert s["max_command_difference_newton"] <= COMMAND_TOL_NEWTON
