"""Session logs (app.recording, app.log_cli): written with mcap, read back by the mcap Python
reader, by our loader and by Foxglove's JavaScript reader (@mcap/core), complete, cut off,
damaged and after a SIGKILL of a real writing process."""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import tomllib
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from app import cli, headless, recording
from app.console.replay import Replay
from app.console.snapshot import scene_info
from app.log_cli import log_app
from app.recording import channels, messages
from app.recording.reader import read_scan
from control.columns import COLUMN_NAMES, LAYOUT, N_LOG, Layout, LogRows
from control.config import ControlSettings
from control.simulation import Simulation
from missions import schema
from sim import params
from sim.docking import DockingFrame
from sim.drawing import attachment_point_n, rov_drawing_box_m
from sim.gnc import Rzyx

ROOT = Path(__file__).resolve().parents[1]
JS_DIR = ROOT / "tests" / "js"
RUN_S = 20.0
NUMERIC_HZ, SCENE_HZ = 20.0, 5.0
PLOT_TOPICS = (
    "/tree/state",
    "/rov/state",
    "/tree/estimate",
    "/reference",
    "/measurements",
    "/control/forces",
    "/thrusters",
    "/control/terms",
    "/wire",
)
FOXGLOVE = {
    "/tf": "foxglove.FrameTransforms",
    "/scene": "foxglove.SceneUpdate",
    "/log": "foxglove.Log",
}
EVENTS = [
    (2.0, "leg", "leg 1: hold", {"leg": 1}),
    (7.5, "alarm", "compass frozen", {}),
    (12.0, "gains", "kp x2", {"kp": [100.0, 100.0, 600.0]}),
]
MISSION = "model-square-ekf-400"
STARTED = datetime(2024, 5, 1, 12, 0, tzinfo=UTC)
SESSION_KEYS = {
    "mission_name",
    "mission_toml",
    "seed",
    "settings",
    "gains",
    "params_name",
    "label",
    "started_utc",
    "start_t_s",
    "dt_s",
    "crane_tip_n",
    "wire_length_m",
    "docking_frame",
    "legs_run",
    "current",
    "time_offset_s",
}


def first_in_each_slot(t_s: np.ndarray, rate_hz: float) -> np.ndarray:
    """Indices of the first row in each 1/rate slot of time (written independently of the
    recorder's Decimator)."""
    return np.unique(np.floor(t_s * rate_hz + 1e-9), return_index=True)[1]


def record_run(
    path: Path,
    *,
    seed: int = 0,
    feedback: str = "perfect",
    seconds: float = RUN_S,
    flush_interval_s: float = 0.5,
    with_events: bool = True,
) -> np.ndarray:
    """Record a real closed-loop run in 1 s calls; returns the full source log."""
    ps = params.load("model-scale")
    sim = Simulation(ps, tree_depth_m=100.0, seed=seed, settings=ControlSettings(feedback=feedback))  # type: ignore[arg-type]
    dock = DockingFrame(np.array([1.5, 1.0]), math.radians(20.0), 101.0)
    meta = recording.session_metadata(
        sim,
        schema.load_mission(MISSION),
        seed=seed,
        label="test",
        docking=dock,
        started_utc=STARTED,
    )
    pieces = []
    with recording.SessionRecorder(
        path,
        metadata=meta,
        params=ps,
        n_thrusters=sim.n_thrusters,
        flush_interval_s=flush_interval_s,
    ) as rec:
        pending = list(EVENTS) if with_events else []
        for k in range(int(seconds)):
            if k == 5:
                sim.set_target(1.5, 1.2, math.radians(30.0))
            rows = sim.run_for(1.0)
            pieces.append(rows.data)
            rec.write_log(
                rows, crane_tip_n=sim.crane_tip_n, wire_length_m=sim.wire_length_m, docking=dock
            )
            while pending and pending[0][0] <= sim.t_s:
                rec.event(*pending.pop(0))
    return np.vstack(pieces)


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, np.ndarray]:
    path = tmp_path_factory.mktemp("rec") / "session.mcap"
    return path, record_run(path)


def mcap_messages(path: Path) -> tuple[dict, dict[str, list], dict[str, dict[str, str]]]:
    """(channels by topic, decoded messages by topic, metadata records) via the mcap reader."""
    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None, "a closed file has a summary section"
        channels = {c.topic: (c, summary.schemas[c.schema_id]) for c in summary.channels.values()}
        msgs: dict[str, list] = {t: [] for t in channels}
        for _, channel, message in reader.iter_messages():
            msgs[channel.topic].append((message.log_time, json.loads(message.data)))
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    return channels, msgs, meta


def node_read(path: Path) -> dict:
    node = shutil.which("node")
    if node is None or not (JS_DIR / "node_modules" / "@mcap" / "core").is_dir():
        pytest.fail(
            "the JavaScript reader needs node and `npm ci` in tests/js (scripts/test.sh does it)"
        )
    proc = subprocess.run(
        [node, str(JS_DIR / "read_mcap.mjs"), str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


# ------------------------------------------------------------------------------------ layout


def block(rows: np.ndarray, name: str) -> np.ndarray:
    """A block of rows in this software's layout (control.columns)."""
    return LAYOUT.take(rows, name)


def test_column_names_are_the_declared_log_row():
    names = recording.column_names()
    assert names == list(COLUMN_NAMES) == recording.COLUMNS
    assert len(names) == N_LOG == len(set(names))
    assert names[LAYOUT.slice("t_s")] == ["t_s"]
    assert names[LAYOUT.slice("tree_eta_n")][5] == "tree_yaw_rad"
    assert names[LAYOUT.slice("y")][4] == "y_heading_rad"
    assert names[LAYOUT.slice("accepted")][4] == "accepted_gyro"


def test_plot_fields_read_their_block_by_name():
    """Every block of a row gets its own values; each field must find its element and convert
    its unit (degrees, rpm), whatever offset the block has in the row."""
    row = 0.001 * np.arange(1.0, N_LOG + 1.0)  # distinct: a field reading another column shows
    value = {name: row[k] for k, name in enumerate(LAYOUT.names)}
    plots = {ch.topic: messages.plot_message(ch, row) for ch in recording.plot_channels(5)}
    assert plots["/tree/state"]["yaw_deg"] == math.degrees(value["tree_yaw_rad"])
    assert plots["/rov/state"]["down_m"] == value["rov_down_m"]
    assert plots["/tree/estimate"]["bias_yaw_newton_m"] == value["bias_yaw_newton_m"]
    assert plots["/reference"]["error_yaw_deg"] == pytest.approx(
        math.degrees(value["tree_yaw_rad"] - value["ref_yaw_rad"]), rel=1e-12
    )
    assert plots["/measurements"]["heading_deg"] == math.degrees(value["y_heading_rad"])
    assert plots["/measurements"]["accepted_gyro"] == value["accepted_gyro"]
    assert plots["/control/forces"]["rov_ach_pitch_newton_m"] == value["tau_rov_ach_pitch_newton_m"]
    assert plots["/control/forces"]["mode"] == value["mode"]
    assert plots["/thrusters"]["thruster2_speed_rpm"] == 60.0 * value["thruster2_speed_rps"]
    assert plots["/control/terms"]["ff_sway_newton"] == value["term_ff_sway_newton"]
    assert all(p["t_s"] == value["t_s"] for p in plots.values())
    with pytest.raises(ValueError, match="tree_eta_n"):
        channels.PlotField("beyond", "tree_eta_n", 6)
    with pytest.raises(ValueError, match="no_such_block"):
        channels.PlotField("nothing", "no_such_block")


def test_attachment_point_is_above_the_centre_in_body_axes():
    eta = np.array([3.0, -2.0, 100.0, 0.0, 0.0, 1.0])
    np.testing.assert_allclose(attachment_point_n(eta, 2.5), [3.0, -2.0, 97.5])
    tilted = np.array([0.0, 0.0, 100.0, 0.0, math.radians(10.0), 0.0])
    p = attachment_point_n(tilted, 2.0)  # nose up: the top leans aft (south)
    np.testing.assert_allclose(
        p,
        [-2.0 * math.sin(math.radians(10.0)), 0.0, 100.0 - 2.0 * math.cos(math.radians(10.0))],
        atol=1e-12,
    )


def test_rov_is_drawn_about_minervas_size():
    """Minerva (appendix B.4, 460 kg) is 1.44 x 0.82 x 0.8 m; the drawn box is an open frame
    of twice its displaced water, 1.6 : 1 : 0.9, so 1.37 x 0.85 x 0.77 m (to the centimetre)."""
    box = rov_drawing_box_m(params.load("model-scale"))
    np.testing.assert_allclose(box, [1.37, 0.85, 0.77], atol=0.005)
    assert np.prod(box) == pytest.approx(2.0 * 460.0 / 1025.0, rel=1e-12)


# ------------------------------------------------------------------------- complete file


def test_mcap_reader_sees_every_channel_at_its_rate(session):
    path, source = session
    channels, msgs, _ = mcap_messages(path)
    n_numeric = len(first_in_each_slot(block(source, "t_s"), NUMERIC_HZ))
    n_scene = len(first_in_each_slot(block(source, "t_s"), SCENE_HZ))
    # rows at 0.01 .. 20.00 s: slot 0 (t < 0.05 s) and slots 1 .. 400
    assert n_numeric == RUN_S * NUMERIC_HZ + 1 and n_scene == RUN_S * SCENE_HZ + 1
    expected = {
        "/session/log": n_numeric,
        "/tf": n_numeric,
        "/scene": n_scene,
        "/events": len(EVENTS),
        "/log": len(EVENTS),
    }
    expected |= dict.fromkeys(PLOT_TOPICS, n_numeric)
    assert {t: len(m) for t, m in msgs.items()} == expected
    for topic, name in FOXGLOVE.items():
        channel, sch = channels[topic]
        assert (sch.name, sch.encoding, channel.message_encoding) == (name, "jsonschema", "json")
        assert json.loads(sch.data)["title"] == name
    tf_schema = json.loads(channels["/tf"][1].data)
    item = tf_schema["properties"]["transforms"]["items"]["properties"]
    assert set(item) == {
        "timestamp",
        "parent_frame_id",
        "child_frame_id",
        "translation",
        "rotation",
    }
    thr = msgs["/thrusters"][0][1]
    assert "thruster5_utilisation" in thr and "thruster6_force_newton" not in thr  # Minerva: 5


def test_messages_carry_the_rows_in_foxglove_frames(session):
    path, source = session
    _, msgs, _ = mcap_messages(path)
    rows = source[first_in_each_slot(block(source, "t_s"), NUMERIC_HZ)]
    k = 150
    tree_eta, ref = block(rows, "tree_eta_n")[k], block(rows, "eta_ref_n")[k]
    t_ns, tf = msgs["/tf"][k]
    # log times are the session's real start (STARTED, at simulation time 0) plus the
    # simulation time, so Foxglove shows the date the session ran, not 1970
    origin = round(STARTED.timestamp() * 1e9)
    assert t_ns == origin + round(block(rows, "t_s")[k] * 1e9)
    assert (
        tf["transforms"][0]["timestamp"]["sec"]
        == (origin + round(block(rows, "t_s")[k] * 1e9)) // 10**9
    )
    # end time in simulation seconds again; 0.06 s > one 20 Hz row interval (decimation)
    assert recording.load_session(path).end_time_s == pytest.approx(
        block(source, "t_s")[-1], abs=0.06
    )
    frames = {x["child_frame_id"]: x for x in tf["transforms"]}
    assert frames["ned"]["parent_frame_id"] == "world"
    assert frames["ned"]["rotation"] == {"x": 1.0, "y": 0.0, "z": 0.0, "w": 0.0}
    tree = frames["tree"]["translation"]
    assert [tree["x"], tree["y"], tree["z"]] == tree_eta[0:3].tolist()
    last_eta = block(rows, "tree_eta_n")[-1]
    assert last_eta[5] > 0.1 and last_eta[4] < -0.005  # turned and pitched: a rotation to check
    last = {x["child_frame_id"]: x["rotation"] for x in msgs["/tf"][-1][1]["transforms"]}
    q = last["tree"]  # Foxglove's {x, y, z, w}, as scipy reads it
    np.testing.assert_allclose(
        Rotation.from_quat([q["x"], q["y"], q["z"], q["w"]]).as_matrix(),
        Rzyx(*last_eta[3:6]),
        atol=1e-12,
    )
    state = msgs["/tree/state"][k][1]
    assert state["yaw_deg"] == pytest.approx(math.degrees(tree_eta[5]), rel=1e-12)
    reference = msgs["/reference"][k][1]
    assert reference["error_north_m"] == pytest.approx(tree_eta[0] - ref[0])
    scene = msgs["/scene"][30][1]
    ents = {e["id"]: e for e in scene["entities"]}
    assert set(ents) == {"tree", "rov", "reference", "wire", "docking_frame"}
    assert ents["tree"]["frame_locked"] and ents["tree"]["frame_id"] == "tree"
    assert [ents["tree"]["cubes"][0]["size"][a] for a in "xyz"] == [1.0, 1.5, 1.2]
    rov_box = rov_drawing_box_m(params.load("model-scale")).tolist()
    assert [ents["rov"]["cubes"][0]["size"][a] for a in "xyz"] == rov_box
    assert len(ents["docking_frame"]["cylinders"]) == 2  # the model's two guideposts
    wire = ents["wire"]["lines"][0]["points"]
    assert [wire[0][a] for a in "xyz"] == [1.0, 1.0, 0.0]  # crane tip
    assert wire[1]["z"] < block(rows, "tree_eta_n")[0, 2] - 0.5  # attachment above the centre


SCALARS = {"boolean": bool, "string": str, "number": (int, float), "integer": int}


def foxglove_can_parse(schema: dict, where: str) -> None:
    """The rules of Foxglove's JSON-schema reader (@mcap/support parseJsonSchema): objects list
    their properties, a field has one plain type or numeric oneOf constants, array items are
    scalars or objects, strings carry no encoding but base64."""
    assert schema.get("type") == "object" and isinstance(schema.get("properties"), dict), where
    for name, field in schema["properties"].items():
        at = f"{where}.{name}"
        if "oneOf" in field:
            assert all(isinstance(alt["const"], int) for alt in field["oneOf"]), at
            continue
        kind = field.get("type")
        assert kind in (*SCALARS, "object", "array"), f"{at}: type {kind!r}"
        if kind == "string":
            assert field.get("contentEncoding") in (None, "base64"), at
        if kind == "object":
            foxglove_can_parse(field, at)
        if kind == "array":
            item = field["items"]
            assert item.get("type") in (*SCALARS, "object") and "contentEncoding" not in item, at
            if item["type"] == "object":
                foxglove_can_parse(item, at + "[]")


def conforms(value: object, schema: dict, where: str) -> None:
    """A message has exactly the schema's fields, each of the schema's type."""
    if "oneOf" in schema:
        assert value in [alt["const"] for alt in schema["oneOf"]], where
    elif schema["type"] == "object":
        assert isinstance(value, dict), where
        if schema["properties"]:
            assert set(value) == set(schema["properties"]), where
            for k, v in value.items():
                conforms(v, schema["properties"][k], f"{where}.{k}")
    elif schema["type"] == "array":
        assert isinstance(value, list), where
        for i, v in enumerate(value):
            conforms(v, schema["items"], f"{where}[{i}]")
    else:
        assert isinstance(value, SCALARS[schema["type"]]), f"{where}: {value!r}"


def test_every_channel_has_a_schema_foxglove_can_parse(session):
    path, _ = session
    channels, msgs, _ = mcap_messages(path)
    for topic, (_, sch) in channels.items():
        parsed = json.loads(sch.data)
        foxglove_can_parse(parsed, sch.name)
        for _, message in msgs[topic][:: max(1, len(msgs[topic]) // 7)]:
            conforms(message, parsed, topic)


def test_metadata_holds_the_setup(session):
    path, _ = session
    _, _, meta = mcap_messages(path)
    setup = {k: json.loads(v) for k, v in meta["setup"].items()}
    assert set(setup) == SESSION_KEYS | set(channels.RESERVED_SETUP_KEYS)
    assert setup["params"] == params.load("model-scale").spec.model_dump(mode="json")
    assert setup["columns"] == recording.COLUMNS
    assert setup["seed"] == 0 and setup["label"] == "test"
    assert setup["mission_name"] == MISSION
    mission = schema.parse_mission(tomllib.loads(setup["mission_toml"]))
    assert mission == schema.load_mission(MISSION)
    assert setup["gains"]["kp"] == list(params.load("model-scale").gains.kp)
    assert setup["settings"]["feedback"] == "perfect"
    assert setup["started_utc"] == STARTED.isoformat() and setup["start_t_s"] == 0.0
    assert setup["crane_tip_n"] == [1.0, 1.0, 0.0]
    assert setup["docking_frame"] == {
        "center_n": [1.5, 1.0],
        "heading_rad": math.radians(20.0),
        "landing_depth_m": 101.0,
    }
    assert setup["recorder"]["software_version"] == recording.software_version()
    assert setup["recorder"]["numeric_rate_hz"] == NUMERIC_HZ
    assert setup["recorder"]["format_version"] == recording.FORMAT_VERSION == 3


def test_load_session_returns_the_decimated_rows_exactly(session):
    path, source = session
    data = recording.load_session(path)
    expected = source[first_in_each_slot(block(source, "t_s"), NUMERIC_HZ)]
    assert data.complete and data.problem == ""
    assert data.rows.shape == expected.shape == (RUN_S * NUMERIC_HZ + 1, N_LOG)
    assert np.array_equal(data.rows, expected)
    assert np.array_equal(data.t_s, block(expected, "t_s"))
    assert np.array_equal(data.log["tree_eta_n"], block(expected, "tree_eta_n"))
    assert data.log["thruster_force"].shape == (len(expected), 5)  # Minerva's five
    assert [(e["t_s"], e["kind"], e["text"], e["data"]) for e in data.events] == EVENTS
    assert data.end_time_s == pytest.approx(block(source, "t_s")[-1])
    assert data.metadata["seed"] == 0
    assert recording.recorded_mission_name(data.metadata) == MISSION
    frame = recording.recorded_docking_frame(data.metadata)
    assert frame is not None and frame.center_n.tolist() == [1.5, 1.0]
    assert frame.heading_rad == math.radians(20.0) and frame.landing_depth_m == 101.0


def test_session_log_holds_each_number_once_and_replay_rebuilds_the_rows(session):
    """/session/log leaves out what the plot channels carry exactly; the reader and the
    console's replay put every row back together, bit for bit."""
    path, source = session
    expected = source[first_in_each_slot(block(source, "t_s"), NUMERIC_HZ)]
    scan, data = read_scan(path)
    meta = next(c.metadata for c in scan.channels.values() if c.topic == "/session/log")
    written, carried = json.loads(meta["columns"]), json.loads(meta["carried"])
    assert written == channels.session_columns(5)
    assert not set(written) & set(carried)
    assert sorted([*written, *carried]) == sorted(recording.COLUMNS)
    # each carried column is its plot channel's field, exactly (same value, same log time)
    first = json.loads(scan.messages[carried["tree_north_m"][0]][0].data)
    assert first[carried["tree_north_m"][1]] == expected[0, COLUMN_NAMES.index("tree_north_m")]
    # the numbers stored once: whole rows were a quarter of this file's message bytes (27 % of
    # a full-scale square run's); the columns no channel carries are 13 % of them
    size = {t: sum(len(m.data) for m in msgs) for t, msgs in scan.messages.items()}
    whole_rows = sum(len(messages.json_bytes(messages.session_row_message(r))) for r in expected)
    share = size["/session/log"] / sum(size.values())
    share_whole = whole_rows / (sum(size.values()) - size["/session/log"] + whole_rows)
    assert share_whole > 0.24 and share < 0.15, (share, share_whole)
    assert np.array_equal(data.rows, expected)
    # replay shows the recorded rows in the live layout
    ps = params.load("model-scale")
    frame = DockingFrame(np.array([1.5, 1.0]), 0.0, 101.0)
    replay = Replay("session.mcap", data, scene_info(ps, frame, 1), 0.01)
    for k in (0, len(expected) // 2, len(expected) - 1):
        replay.seek(float(expected[k, 0]))
        assert np.array_equal(replay.row(), expected[k])


def columns_before_control_columns() -> list[str]:
    """Flat names as the recorder wrote them before the log row was declared in
    control.columns: no velocity blocks, newtons spelt _n and _nm, the site block last."""
    pose = ("north_m", "east_m", "down_m", "roll_rad", "pitch_rad", "yaw_rad")
    axes3 = ("surge_n", "sway_n", "yaw_nm")
    axes6 = ("surge_n", "sway_n", "heave_n", "roll_nm", "pitch_nm", "yaw_nm")
    held = (
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
    thr = range(1, 9)
    return [
        "t_s",
        *(f"tree_{n}" for n in pose),
        *(f"rov_{n}" for n in pose),
        "est_tree_north_m",
        "est_tree_east_m",
        "est_tree_yaw_rad",
        "est_tree_u_mps",
        "est_tree_v_mps",
        "est_tree_r_rad_s",
        *(f"bias_{n}" for n in axes3),
        "ref_north_m",
        "ref_east_m",
        "ref_yaw_rad",
        "ref_north_rate_mps",
        "ref_east_rate_mps",
        "ref_yaw_rate_rad_s",
        *(f"tau_tree_{n}" for n in axes3),
        *(f"tau_rov_cmd_{n}" for n in axes6),
        *(f"tau_rov_ach_{n}" for n in axes6),
        *(f"thruster{i}_force_n" for i in thr),
        *(f"thruster{i}_speed_rps" for i in thr),
        *(f"thruster{i}_utilisation" for i in thr),
        *(f"term_{p}_{a}" for p in ("p", "i", "d", "ff") for a in axes3),
        *(f"y_{n}" for n in held),
        "mode",
        "nis_north",
        "nis_east",
        "nis_heading",
        *(f"accepted_{s}" for s in ("position", "depth", "compass", "dvl", "gyro")),
        "crane_tip_north_m",
        "crane_tip_east_m",
        "wire_rest_length_m",
        "wire_tension_n",
    ]


def write_session_by_hand(path: Path, columns: list[str], rows: np.ndarray, setup: dict) -> None:
    """A session file as an earlier recorder wrote it (plain mcap writer, no SessionRecorder)."""
    with path.open("wb") as f:
        w = Writer(f)
        w.start(profile="", library="rov-console 0.1")
        sid = w.register_schema("rov_console.SessionLogRow", "jsonschema", b"{}")
        cid = w.register_channel(
            "/session/log", "json", sid, {"kind": "table", "columns": json.dumps(columns)}
        )
        w.add_metadata("setup", {k: json.dumps(v) for k, v in setup.items()})
        for i, row in enumerate(rows):
            t_ns = round(row[0] * 1e9)
            w.add_message(
                cid,
                log_time=t_ns,
                publish_time=t_ns,
                sequence=i,
                data=json.dumps({"t_s": row[0], "row": row.tolist()}).encode(),
            )
        w.finish()


def test_recordings_of_an_older_layout_are_read_by_block_name(tmp_path):
    """A file written before control.columns (other column order, old unit spelling): its rows
    are read by block name from where that file put them."""
    columns = columns_before_control_columns()
    assert columns != recording.COLUMNS and len(columns) != N_LOG
    rows = np.arange(3.0 * len(columns)).reshape(3, len(columns)) + 0.5
    rows[:, 0] = [0.05, 0.10, 0.15]
    path = tmp_path / "old.mcap"
    write_session_by_hand(
        path,
        columns,
        rows,
        {"columns": columns, "mission": "harbour test", "recorder": {"n_thrusters": 5}},
    )
    data = recording.load_session(path)
    assert data.complete and data.columns == columns
    assert np.array_equal(data.t_s, [0.05, 0.10, 0.15])
    assert np.array_equal(data.log["tree_eta_n"], rows[:, 1:7])
    bias = columns.index("bias_surge_n")
    assert np.array_equal(data.log["bias_tree"], rows[:, bias : bias + 3])
    assert np.array_equal(data.log["wire_tension"], rows[:, -1])
    assert np.array_equal(
        data.log["thruster_force"], rows[:, columns.index("thruster1_force_n") :][:, :5]
    )
    with pytest.raises(KeyError, match="rov_nu_b"):
        data.log["rov_nu_b"]  # that file has no velocities
    assert recording.recorded_mission_name(data.metadata) == "harbour test"


def test_run_and_console_recordings_share_one_metadata_layout(tmp_path):
    """`rov-console run --log` writes session_metadata; files of the two older layouts (run:
    mission = the TOML; console: mission = the name) still give the mission's name and file."""
    spec = schema.load_mission(MISSION)
    sim = Simulation(params.load("model-scale"), tree_depth_m=100.0)
    with headless.open_recorder(str(tmp_path / "run.mcap"), spec, sim, None) as rec:
        rec.write_log(sim.run_for(0.1))
    meta = recording.load_session(tmp_path / "run.mcap").metadata
    assert set(meta) == SESSION_KEYS | set(channels.RESERVED_SETUP_KEYS)
    assert meta["seed"] == spec.setup.seed and meta["mission_name"] == spec.name
    assert meta["params_name"] == "model-scale" and meta["docking_frame"] is None
    assert recording.recorded_docking_frame(meta) is None
    assert (
        recording.session_metadata(sim, spec, seed=spec.setup.seed + 7)["seed"]
        == spec.setup.seed + 7
    )
    toml = schema.dump_mission(spec)
    older = [
        {"mission": toml, "mission_name": spec.name},
        {"mission": spec.name, "mission_toml": toml},
    ]
    for m in (meta, *older):
        assert recording.recorded_mission_name(m, "?") == spec.name
        text = recording.recorded_mission_toml(m)
        assert text is not None and schema.parse_mission(tomllib.loads(text)) == spec
    assert recording.recorded_mission_name({}, "?") == "?"
    assert recording.recorded_mission_toml({}) is None


def test_javascript_reader_agrees_on_a_complete_file(session):
    path, _ = session
    js = node_read(path)
    _, msgs, _ = mcap_messages(path)
    assert js["reader"] == "indexed" and js["complete"] is True and js["error"] is None
    assert js["counts"] == {t: len(m) for t, m in msgs.items()}
    assert js["schemas"]["/scene"] == "foxglove.SceneUpdate"
    assert json.loads(js["metadata"]["setup"]["columns"]) == recording.COLUMNS


# --------------------------------------------------------------------- cut off and damaged


def test_truncated_file_is_read_up_to_the_cut_by_both_readers(session, tmp_path):
    path, _ = session
    whole = path.read_bytes()
    full = recording.load_session(path)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[: int(0.6 * len(whole))])
    data = recording.load_session(cut)
    assert not data.complete and "cut off" in data.problem
    assert 0 < len(data.rows) < len(full.rows)
    assert np.array_equal(data.rows, full.rows[: len(data.rows)])
    assert data.metadata == full.metadata
    report = recording.check_session(cut)
    assert report["status"] == "truncated"
    assert report["intact_bytes"] < report["file_bytes"] == len(whole) * 6 // 10
    js = node_read(cut)
    assert js["reader"] == "stream" and js["complete"] is False
    assert js["counts"] == data.message_counts | {
        "/events": data.message_counts.get("/events", 0),
        "/log": data.message_counts.get("/log", 0),
    }
    assert path.read_bytes() == whole  # reading changed nothing
    assert recording.load_session(path).complete


def test_damaged_chunk_stops_the_read_before_it(session, tmp_path):
    path, _ = session
    whole = bytearray(path.read_bytes())
    full = recording.load_session(path)
    middle = len(whole) // 2
    whole[middle : middle + 64] = bytes(64)
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(whole))
    data = recording.load_session(bad)
    assert not data.complete and "damaged" in data.problem
    assert 0 < len(data.rows) < len(full.rows)
    assert np.array_equal(data.rows, full.rows[: len(data.rows)])


@pytest.mark.parametrize(
    "content", [b"", b"this is not a log\n", bytes(100), recording.MCAP_MAGIC + b"\x01\x05"]
)
def test_non_mcap_input_is_a_clear_error(tmp_path, content):
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(content)
    with pytest.raises(ValueError, match="bad.mcap"):
        recording.load_session(bad)
    result = CliRunner().invoke(log_app, ["check", str(bad)])
    assert result.exit_code == 2
    assert "bad.mcap" in result.output
    assert bad.read_bytes() == content


# -------------------------------------------------------------------------- SIGKILL


CHILD = """
import sys, time
from sim import params
from control.simulation import Simulation
from app.recording import SessionRecorder
ps = params.load("model-scale")
sim = Simulation(ps, tree_depth_m=100.0)
sim.run_for(0.1)
with SessionRecorder(sys.argv[1], metadata={"seed": 0}, params=ps, n_thrusters=5,
                     flush_interval_s=0.5) as rec:
    k = 0
    while True:  # as the console at 50x: 0.5 s of simulation every 10 ms
        rows = sim.run_for(0.5)
        rec.write_log(rows, crane_tip_n=sim.crane_tip_n, wire_length_m=sim.wire_length_m)
        k += 1
        if k % 20 == 0:
            rec.event(sim.t_s, "leg", f"batch {k}")
        print(f"{time.monotonic():.6f} {rows.t_s[-1]:.6f}", flush=True)
        time.sleep(0.01)
"""
FLUSH_S = 0.5
"""The child's flush_interval_s."""
SLACK_S = 0.5
"""Wall time the test allows beyond FLUSH_S for the writer thread to encode, write and fsync
a batch on a loaded machine (the promise is FLUSH_S plus what is queued; unmeasured here)."""


def record_and_kill(path: Path) -> tuple[float, list[tuple[float, float]]]:
    """Run CHILD recording to ``path`` for about 3 s, SIGKILL it; (the kill's monotonic
    time, the (wall, simulated time) of each batch it reported handing over)."""
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(path)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    lines: list[tuple[float, float]] = []

    def read() -> None:
        assert child.stdout is not None
        for line in child.stdout:
            wall, sim = line.split()
            lines.append((float(wall), float(sim)))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + 60.0
        while not lines and time.monotonic() < deadline and child.poll() is None:
            time.sleep(0.05)
        assert lines, f"the child wrote nothing: {child.stderr.read() if child.stderr else ''}"
        time.sleep(3.0)
        t_kill = time.monotonic()
        os.kill(child.pid, signal.SIGKILL)
    finally:
        child.kill()
        child.wait(10)
    reader.join(10)
    return t_kill, lines


def test_sigkill_loses_at_most_the_flush_interval_and_recover_makes_it_whole(tmp_path):
    """Kill a real recording process writing as the console does at 50x. The file holds what
    the child had handed over FLUSH_S (+ SLACK_S) before the kill; the stock reader cannot
    read it, and ``rov-console log recover`` rewrites it as a complete file that mcap's
    make_reader reads whole, with every message the product's reader finds in the killed
    one."""
    path = tmp_path / "killed.mcap"
    t_kill, lines = record_and_kill(path)
    data = recording.load_session(path)
    assert not data.complete
    handed_over_before = max(sim for wall, sim in lines if wall <= t_kill - FLUSH_S - SLACK_S)
    assert data.t_s[-1] >= handed_over_before - 1e-9
    assert np.all(np.diff(data.t_s) > 0)
    assert data.message_counts["/events"] > 0
    killed_bytes = path.read_bytes()

    out = tmp_path / "whole.mcap"
    result = CliRunner().invoke(cli.app, ["log", "recover", str(path), str(out)])
    assert result.exit_code == 0, result.output
    assert path.read_bytes() == killed_bytes, "the killed file is not changed"
    with out.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        counts = {
            summary.channels[cid].topic: n
            for cid, n in summary.statistics.channel_message_counts.items()
        }
        read = [(channel.topic, m.log_time) for _, channel, m in reader.iter_messages()]
    assert {t: n for t, n in counts.items() if n} == data.message_counts
    assert len(read) == sum(data.message_counts.values())
    whole = recording.load_session(out)
    assert whole.complete and whole.metadata == data.metadata
    assert np.array_equal(whole.rows, data.rows, equal_nan=True)
    assert whole.events == data.events


def test_recover_keeps_every_whole_record_and_refuses_to_overwrite(session, tmp_path):
    """A cut file (and a complete one) rewritten: the same messages, byte for byte, in the same
    order; the output is new unless --force, and never the source."""
    complete = tmp_path / "complete.mcap"
    shutil.copy(session[0], complete)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(complete.read_bytes()[: complete.stat().st_size * 6 // 10])
    runner = CliRunner()
    for source in (cut, complete):
        out = tmp_path / f"{source.stem}-recovered.mcap"
        result = runner.invoke(log_app, ["recover", str(source)])  # the default output name
        assert result.exit_code == 0, result.output
        assert result.output.strip().endswith(str(out))
        before, _ = read_scan(source)
        after, data = read_scan(out)
        assert data.complete
        assert [(m.channel_id, m.log_time, m.sequence, m.data) for m in after.in_order] == [
            (m.channel_id, m.log_time, m.sequence, m.data) for m in before.in_order
        ]
        assert after.metadata == before.metadata
        assert {c.topic: c.metadata for c in after.channels.values()} == {
            c.topic: c.metadata for c in before.channels.values()
        }
    again = runner.invoke(log_app, ["recover", str(cut)])
    assert again.exit_code == 2 and "exists" in again.output
    assert runner.invoke(log_app, ["recover", str(cut), "--force"]).exit_code == 0
    same = runner.invoke(log_app, ["recover", str(cut), str(cut), "--force"])
    assert same.exit_code == 2 and "must not be the file" in same.output
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not a log")
    assert runner.invoke(log_app, ["recover", str(bad)]).exit_code == 2


# ---------------------------------------------------------------- the writer thread


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def wait_for(condition: Callable[[], bool], timeout_s: float = 10.0) -> bool:
    """Poll ``condition`` until it holds (True) or ``timeout_s`` passes (False): a guard
    against a hang, not a measurement."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_the_callers_thread_encodes_and_writes_nothing(tmp_path, monkeypatch):
    """``write_log`` and ``event`` only queue: every message is encoded and handed to mcap on
    the recorder's own thread (the console's loop is not held by encoding or the disk)."""
    from app.recording import stream as stream_mod
    from app.recording import writer as writer_mod

    writers: set[int] = set()
    encoders: set[int] = set()
    add_message = writer_mod.Writer.add_message
    tf = stream_mod.tf_message

    def noting_add(self, *args, **kwargs):
        writers.add(threading.get_ident())
        return add_message(self, *args, **kwargs)

    def noting_tf(*args, **kwargs):
        encoders.add(threading.get_ident())
        return tf(*args, **kwargs)

    monkeypatch.setattr(writer_mod.Writer, "add_message", noting_add)
    monkeypatch.setattr(stream_mod, "tf_message", noting_tf)
    ps = params.load("model-scale")
    sim = Simulation(ps, tree_depth_m=100.0)
    with recording.SessionRecorder(
        tmp_path / "thread.mcap", metadata={}, params=ps, n_thrusters=5
    ) as rec:
        for _ in range(5):
            rec.write_log(sim.run_for(1.0), crane_tip_n=sim.crane_tip_n, wire_length_m=100.0)
        rec.event(sim.t_s, "leg", "done")
    assert writers and encoders
    assert threading.get_ident() not in writers | encoders
    data = recording.load_session(tmp_path / "thread.mcap")
    assert data.complete and len(data.rows) == 101 and len(data.events) == 1


def test_a_writer_behind_holds_the_caller_at_max_queued(tmp_path, monkeypatch):
    """While the writer thread is stuck (a slow disk), ``write_log`` returns until MAX_QUEUED
    batches wait, then waits for room: memory stays bounded and nothing is dropped."""
    from app.recording import writer as writer_mod

    gate = threading.Event()
    add_message = writer_mod.Writer.add_message

    def slow_disk(self, *args, **kwargs):
        gate.wait()
        return add_message(self, *args, **kwargs)

    monkeypatch.setattr(writer_mod.Writer, "add_message", slow_disk)
    monkeypatch.setattr(writer_mod, "MAX_QUEUED", 4)
    ps = params.load("model-scale")
    sim = Simulation(ps, tree_depth_m=100.0)
    batches = [sim.run_for(0.5) for _ in range(10)]
    rec = recording.SessionRecorder(tmp_path / "slow.mcap", metadata={}, params=ps, n_thrusters=5)
    handed = []

    def caller() -> None:
        for rows in batches:
            rec.write_log(rows)
            handed.append(rows.t_s[-1])

    thread = threading.Thread(target=caller, daemon=True)
    thread.start()
    # one batch taken by the stuck writer, four queued, the sixth call waits
    assert wait_for(lambda: len(handed) == 5 and rec._queue.full())
    assert thread.is_alive() and len(handed) == 5
    gate.set()
    thread.join(10)
    rec.close()
    data = recording.load_session(tmp_path / "slow.mcap")
    assert data.complete and len(handed) == 10 and data.t_s[-1] == pytest.approx(5.0, abs=0.05)


def test_a_failure_in_the_writer_thread_is_raised_to_the_caller(tmp_path, monkeypatch):
    import errno

    from app.recording import writer as writer_mod

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    ps = params.load("model-scale")
    sim = Simulation(ps, tree_depth_m=100.0)
    rec = recording.SessionRecorder(tmp_path / "full.mcap", metadata={}, params=ps, n_thrusters=5)
    monkeypatch.setattr(writer_mod.Writer, "add_message", full)
    rec.write_log(sim.run_for(1.0))
    with pytest.raises(recording.RecordingError, match="No space left"):
        rec.flush()
    with pytest.raises(recording.RecordingError, match="No space left"):
        rec.write_log(sim.run_for(1.0))
    with pytest.raises(recording.RecordingError, match="No space left"):
        rec.close()
    rec.close()  # idempotent once closed


def test_the_writer_syncs_every_flush_interval_of_wall_time(tmp_path):
    """Rows handed over are on disk (a chunk closed, fsync'ed) once flush_interval_s of the
    recorder's clock has passed, with the caller idle; ``flush`` syncs at once."""
    ps = params.load("model-scale")
    sim = Simulation(ps, tree_depth_m=100.0)
    clock = FakeClock()
    path = tmp_path / "idle.mcap"
    rec = recording.SessionRecorder(
        path, metadata={}, params=ps, n_thrusters=5, flush_interval_s=0.5, clock=clock
    )
    try:
        rec.write_log(sim.run_for(1.0).data)
        time.sleep(0.3)
        assert len(recording.load_session(path).rows) == 0  # the clock has not moved
        clock.now = 0.5  # the caller stays idle: the writer thread syncs
        assert wait_for(lambda: len(recording.load_session(path).rows) == 21)
        clock.now = 0.6
        rec.event(1.0, "leg", "flushed at once")
        rec.flush()
        assert recording.load_session(path).message_counts["/events"] == 1
    finally:
        rec.close()
        rec.close()  # idempotent
    assert recording.load_session(path).complete
    with pytest.raises(recording.RecordingError, match="closed"):
        rec.write_log(sim.run_for(0.1).data)


def test_a_row_is_never_split_between_chunks(tmp_path, monkeypatch):
    """Chunks close at CHUNK_BYTES only between batches, so a file cut anywhere holds whole
    rows: every row read from every cut of a file of many small chunks equals the source's."""
    from app.recording import writer as writer_mod

    monkeypatch.setattr(writer_mod, "CHUNK_BYTES", 20_000)
    path = tmp_path / "chunks.mcap"
    source = record_run(path, seconds=4, flush_interval_s=1e6)
    full = recording.load_session(path)
    whole = path.read_bytes()
    assert np.array_equal(full.rows, source[first_in_each_slot(source[:, 0], NUMERIC_HZ)])
    for k in range(1, 20):
        cut = tmp_path / "cut.mcap"
        cut.write_bytes(whole[: len(whole) * k // 20])
        part = recording.load_session(cut)
        assert np.array_equal(part.rows, full.rows[: len(part.rows)])


def test_numeric_messages_from_templates_are_the_dict_builders_bytes():
    """``encoding.RowEncoder`` writes exactly ``json_bytes`` of ``plot_message``,
    ``session_row_message`` and ``wire_message``, non-finite numbers, signed zeros and the
    largest floats included."""
    from app.recording.encoding import RowEncoder

    ps = params.load("model-scale")
    sim = Simulation(ps, tree_depth_m=100.0)
    rows = sim.run_for(0.5).data.copy()
    rng = np.random.default_rng(3)
    specials = [np.nan, np.inf, -np.inf, -0.0, 1e308, -5e-324, 1 / 3, 1e-7, 123456789.0]
    for k in range(len(rows)):
        cols = rng.choice(N_LOG, size=6, replace=False)
        rows[k, cols] = rng.choice(specials, size=6)
    session_at = np.array([COLUMN_NAMES.index(c) for c in channels.session_columns(5)])
    encoder = RowEncoder(channels.plot_channels(5), session_at)
    tip = np.array([1.5, -2.0, 0.0])
    with np.errstate(over="ignore"):  # 1e308 in degrees is inf, both ways
        plots = encoder.plot_messages(rows)
        built = [[messages.plot_message(ch, row) for ch in encoder.plots] for row in rows]
    session = encoder.session_messages(rows)
    wires = encoder.wire_messages(rows, tip, 101.25)
    nan_wire = encoder.wire_messages(rows, tip, math.nan)
    for k, row in enumerate(rows):
        assert [msgs[k] for msgs in plots] == [messages.json_bytes(m) for m in built[k]]
        assert session[k] == messages.json_bytes(messages.session_row_message(row, session_at))
        assert wires[k] == messages.json_bytes(messages.wire_message(row, tip, 101.25))
        assert nan_wire[k] == messages.json_bytes(messages.wire_message(row, tip, math.nan))


def test_recorder_refuses_bad_input_and_existing_files(tmp_path):
    ps = params.load("model-scale")
    old = tmp_path / "old.mcap"
    old.write_bytes(b"an earlier session")
    with pytest.raises(FileExistsError):
        recording.SessionRecorder(old, metadata={}, params=ps, n_thrusters=5)
    assert old.read_bytes() == b"an earlier session"
    with pytest.raises(ValueError, match="written by the recorder"):
        recording.SessionRecorder(
            tmp_path / "a.mcap", metadata={"params": {}}, params=ps, n_thrusters=5
        )
    same = {"params": ps.spec.model_dump(mode="json")}  # the recorder's own value is accepted
    recording.SessionRecorder(
        tmp_path / "same.mcap", metadata=same, params=ps, n_thrusters=5
    ).close()
    dock = DockingFrame(np.array([0.0, 0.0]), 0.0, 101.0)
    with recording.SessionRecorder(
        tmp_path / "b.mcap", metadata={}, params=ps, n_thrusters=5, docking=dock
    ) as rec:
        with pytest.raises(ValueError, match="shape"):
            rec.write_log(np.zeros((3, N_LOG - 1)))
        reordered = Layout.from_names(list(reversed(COLUMN_NAMES)))
        with pytest.raises(ValueError, match="layout"):
            rec.write_log(LogRows(np.zeros((3, N_LOG)), layout=reordered))
        with pytest.raises(ValueError, match="JSON"):
            rec.event(1.0, "leg", "x", {"bad": object()})
        rows = LogRows(np.zeros((2, N_LOG)))
        rows["t_s"][:] = [0.05, 0.10]
        rows["nis"][1, 0] = np.nan
        rec.write_log(rows)
        with pytest.raises(ValueError, match="forward in time"):
            rec.write_log(rows)  # the same rows again: refused, not silently dropped
    data = recording.load_session(tmp_path / "b.mcap")
    assert math.isnan(data.log["nis"][1, 0]) and data.log["nis"][0, 0] == 0.0
    assert not np.isnan(data.log["nis"][1, 1:]).any()
    _, msgs, _ = mcap_messages(tmp_path / "b.mcap")
    ((_, scene),) = msgs["/scene"]
    assert "docking_frame" in {e["id"] for e in scene["entities"]}
    assert msgs["/wire"] == []  # no crane tip given: no wire


# ------------------------------------------------------------------------- determinism


def test_same_seed_gives_the_same_log_contents(tmp_path):
    """Same seeded EKF run, recorded twice with different flush timing: every message is the
    same. Another seed gives other contents (the comparison can fail)."""

    def contents(path: Path) -> list:
        _, msgs, meta = mcap_messages(path)
        setup = {k: json.loads(v) for k, v in meta["setup"].items()}
        del setup["recorder"]["flush_interval_s"]
        return [setup, sorted((t, ts, json.dumps(m)) for t, ms in msgs.items() for ts, m in ms)]

    a, b, c = (tmp_path / f"{n}.mcap" for n in "abc")
    record_run(a, seed=7, feedback="ekf", seconds=8)
    record_run(b, seed=7, feedback="ekf", seconds=8, flush_interval_s=1e-6)
    record_run(c, seed=8, feedback="ekf", seconds=8)
    assert contents(a) == contents(b)
    assert contents(a)[1] != contents(c)[1]
    assert np.array_equal(recording.load_session(a).rows, recording.load_session(b).rows)


# -------------------------------------------------------------------------------- CLI


def test_log_check_exit_codes_and_json(session, tmp_path):
    path, _ = session
    runner = CliRunner()
    ok = runner.invoke(log_app, ["check", str(path)])
    assert ok.exit_code == 0, ok.output
    assert "COMPLETE" in ok.output and "/scene" in ok.output
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size * 6 // 10])
    res = runner.invoke(log_app, ["check", str(cut), "--json"])
    assert res.exit_code == 1
    report = json.loads(res.output)
    assert report["status"] == "truncated" and report["rows"] > 0
    assert {c["topic"] for c in report["channels"]} >= set(PLOT_TOPICS)


def test_log_export_csv_matches_the_rows(session, tmp_path):
    path, _ = session
    out = tmp_path / "csv"
    res = CliRunner().invoke(log_app, ["export", str(path), "--csv", str(out)])
    assert res.exit_code == 0, res.output
    data = recording.load_session(path)
    with (out / "session_log.csv").open() as f:
        table = list(csv.reader(f))
    assert table[0] == data.columns
    assert np.array_equal(np.array(table[1:], dtype=float), data.rows)
    with (out / "tree_state.csv").open() as f:
        tree = list(csv.DictReader(f))
    assert len(tree) == len(data.rows)
    np.testing.assert_allclose(
        [float(r["yaw_deg"]) for r in tree], np.degrees(data.log["tree_eta_n"][:, 5]), rtol=1e-12
    )
    assert [float(r["t_s"]) for r in tree] == data.t_s.tolist()
    with (out / "events.csv").open() as f:
        assert [r["kind"] for r in csv.DictReader(f)] == [e[1] for e in EVENTS]
    assert {p.name for p in out.iterdir()} >= {"thrusters.csv", "wire.csv", "control_terms.csv"}
    again = CliRunner().invoke(log_app, ["export", str(path), "--csv", str(out)])
    assert again.exit_code == 2 and "would replace" in again.output


def test_a_recorder_that_cannot_start_leaves_no_empty_file(tmp_path, monkeypatch):
    """A full disk when the file is started: the error is raised and no 0-byte file stays."""
    import errno

    from app.recording import writer as writer_mod

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(writer_mod.Writer, "start", full)
    path = tmp_path / "full.mcap"
    with pytest.raises(OSError, match="No space left"):
        recording.SessionRecorder(
            path, metadata={}, params=params.load("model-scale"), n_thrusters=5
        )
    assert not path.exists()


def test_a_viewers_replay_runs_on_its_own_clock_beside_the_live_run(session, tmp_path):
    """A browser's replay (``ViewerReplay``): its clock moves by wall time times the console's
    speed only while it plays, seeks, and shows the recording's rows in the recording's scene
    (its docking frame), with the live run's sequence number and operations; the live session
    is not touched."""
    from app.console.session import Session, prepare_run, station_keeping_mission
    from app.console.snapshot import LoopStats
    from app.console.viewer_replay import ViewerReplay

    path, source = session
    data = recording.load_session(path)
    live_session = Session(prepare_run(station_keeping_mission("model-scale", 100.0)), tmp_path)
    live = live_session.snapshot(7, False, 2.0, LoopStats(0.01, 0.0, 0.0, 0, 0, 0.0))
    viewer = ViewerReplay("session.mcap", data, live, 1)
    t0 = viewer.status().t_s
    viewer.advance(2.0, now=100.0)
    assert viewer.status().t_s == t0, "not playing: the clock stands"
    # play and advance on the same clock: the test's own, not the machine's monotonic clock
    # (which is the machine's uptime: played on it, a machine up less than 1 000 s saw the
    # first advance as a stall and the replay 2 s ahead)
    viewer.play(True, now=1000.0)
    viewer.advance(2.0, now=1000.0)  # no wall time yet: the clock stands
    assert viewer.status().t_s == t0
    viewer.advance(2.0, now=1000.5)  # 0.5 s of wall time at 2x: 1 s of the recording
    # rows are 20 Hz: the shown row is the last at or before the clock
    assert viewer.status().t_s == pytest.approx(t0 + 1.0, abs=0.05 + 1e-9)
    viewer.advance(2.0, now=1010.5)  # a 10 s stall is taken as 1 s (MAX_WALL_STEP_S)
    assert viewer.status().t_s == pytest.approx(t0 + 3.0, abs=0.05 + 1e-9)
    viewer.play(False)
    middle = float(source[len(source) // 2, 0])
    viewer.seek(middle)
    snap = viewer.snapshot(live)
    assert snap.source == "replay" and snap.seq == 7 and snap.replay is not None
    assert snap.t_s == pytest.approx(middle, abs=0.05 + 1e-9)
    assert snap.scene.frame.center_n.tolist() == [1.5, 1.0], "the recording's docking frame"
    assert snap.scene.frame.heading_rad == pytest.approx(math.radians(20.0))
    assert live_session.replay is None and live_session.sim.t_s == live.t_s
