"""What the console view computes without a browser: poses and the loaded wire's shape, the
mission builder's inputs read from the leg models, and the alarms."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from app.console.alarms import AlarmLimits, AlarmMonitor
from control.columns import N_LOG, LogRows
from missions import schema
from sim import gnc
from sim import wire as wire_mod
from web import geometry as geo
from web import mission_builder as mb

angles = st.floats(-math.pi, math.pi, allow_nan=False)


def rotation_of(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


@given(angles, st.floats(-1.5, 1.5), angles)
def test_quaternion_is_the_zyx_rotation_of_the_core(phi: float, theta: float, psi: float) -> None:
    q = geo.quaternion_wxyz_from_rpy_radians(phi, theta, psi)
    assert np.linalg.norm(q) == pytest.approx(1.0)
    np.testing.assert_allclose(rotation_of(q), gnc.Rzyx(phi, theta, psi), atol=1e-12)
    np.testing.assert_allclose(geo.Rzyx(phi, theta, psi), gnc.Rzyx(phi, theta, psi), atol=1e-12)


def test_attachment_point_is_above_the_cg_and_tilts_with_the_tree() -> None:
    upright = geo.attachment_point_n(np.array([1.0, 2.0, 400.0, 0.0, 0.0, 0.7]), 2.584)
    np.testing.assert_allclose(upright, [1.0, 2.0, 400.0 - 2.584])
    pitched = geo.attachment_point_n(np.array([0.0, 0.0, 0.0, 0.0, 0.1, 0.0]), 1.0)
    assert pitched[0] < 0.0, "pitching nose-up moves the top of the tree aft"


W, W0, L = 199.6, 307_046.75, 397.0


def test_wire_without_drag_is_the_straight_line_between_its_ends() -> None:
    top, bottom = np.array([1.0, 1.0, 0.0]), np.array([3.0, -1.0, 397.0])
    pts = geo.loaded_wire_points_n(top, bottom, L, W, W0, np.zeros(2), n_points=21)
    np.testing.assert_allclose(pts[0], bottom)
    np.testing.assert_allclose(pts[-1], top)
    s = np.linspace(0.0, 1.0, 21)
    # no drag: x(s) = x_load - H0 I1(s); I1 is concave, so the line hangs steeper at the top
    # (heavier there): between the ends and on the same side of the chord everywhere
    chord = bottom[None, :2] + s[:, None] * (top - bottom)[None, :2]
    off = pts[:, :2] - chord
    assert np.all(np.abs(off) < 0.05 * np.linalg.norm(top[:2] - bottom[:2]))


def test_wire_in_current_bows_downstream_and_matches_the_closed_form() -> None:
    q = 0.5 * 1025.0 * 0.076 * 1.2 * 0.1**2  # eq. 2.26 at 0.1 m/s
    offset = wire_mod.horizontal_offset(q, W, W0, L)  # load's equilibrium offset (eq. 2.29)
    top = np.array([0.0, 0.0, 0.0])
    bottom = np.array([offset, 0.0, L])
    pts = geo.loaded_wire_points_n(top, bottom, L, W, W0, np.array([q, 0.0]), n_points=81)
    np.testing.assert_allclose(pts[-1], top, atol=1e-9)
    # at equilibrium no extra horizontal force acts at the load: H0 = 0, so the shape is
    # the offset formula evaluated along the line (the closed form, measured from the top)
    for k in (20, 40, 60):
        s_from_load = L * k / 80
        expected = offset - wire_mod.horizontal_offset(q, W, W0, s_from_load)
        assert pts[k, 0] == pytest.approx(expected, rel=1e-6, abs=1e-9)
    assert np.all(pts[1:-1, 0] > -1e-9), "the wire bows downstream of the crane tip"


def test_camera_presets_look_at_the_job() -> None:
    tree = np.array([1.0, 1.0, 400.0, 0.0, 0.0, 0.3])
    over = geo.overview_camera(tree, 3.6)
    assert over.position_n[2] < tree[2], "the overview looks down from above the tree"
    top = geo.top_down_camera(np.array([1.0, 1.0]), 405.0, tree, 3.6)
    np.testing.assert_allclose(top.position_n[:2], [1.0, 1.0])
    assert top.position_n[2] < tree[2] - 3.6


def _off_axis_deg(cam: geo.CameraPose, point: np.ndarray) -> float:
    axis = (cam.look_at_n - cam.position_n) / np.linalg.norm(cam.look_at_n - cam.position_n)
    ray = (point - cam.position_n) / np.linalg.norm(point - cam.position_n)
    return math.degrees(math.acos(float(np.clip(ray @ axis, -1.0, 1.0))))


def test_top_down_keeps_the_tree_and_the_rov_clear_of_the_panel() -> None:
    """Defect (issue 47 item 27): Top-down cut the tree off. It looked straight down at the
    frame from three tree sizes over it: the tree's corners and the ROV beside it lay up to
    18 deg off its axis over the frame (more with the tree off it), where the panel covers
    the right part of a 25 deg half-angle view.
    Now the tree, the ROV beside it (a tree size from its centre) and the frame stay within
    0.35 of the field of view (17.5 deg), the tree over the frame or 8 m off it."""
    frame = np.array([1.0, 1.0, 404.3])
    size = 3.6
    for north in (1.0, 9.0):
        tree = np.array([north, 1.0, 400.0, 0.0, 0.0, 0.0])
        cam = geo.top_down_camera(frame[:2], frame[2], tree, size)
        np.testing.assert_allclose(cam.up_n, [1.0, 0.0, 0.0]), "north up on the screen"
        points = [frame, tree[:3]]
        for d in ((1, 1), (1, -1), (-1, 1), (-1, -1)):  # the tree's top corners
            points.append(tree[:3] + np.array([0.5 * size * d[0], 0.5 * size * d[1], -0.5 * size]))
        for d in ((1, 0), (-1, 0), (0, 1), (0, -1)):  # the ROV, on any side of the tree
            points.append(tree[:3] + np.array([size * d[0], size * d[1], 0.0]))
        worst = max(_off_axis_deg(cam, p) for p in points)
        assert worst <= 0.35 * 50.0 + 1e-9, (north, worst)


def test_framing_camera_holds_a_preview_far_from_the_live_run() -> None:
    """The builder's preview, 150 m above the live run (issue 47 item 23), framed whole."""
    pts = np.array([[0.0, 0.0, 250.0], [20.0, 5.0, 250.0], [4.0, 2.5, 254.3]])
    cam = geo.framing_camera(pts, 3.6)
    assert cam.position_n[2] < 250.0, "from above"
    assert max(_off_axis_deg(cam, p) for p in pts) < 25.0


def test_the_reference_ghost_is_hidden_when_flown_by_hand(tmp_path) -> None:
    """Defect (issue 47 item 27): in manual mode the reference ghost stayed at the autopilot's
    old target, where the ROV was not going. It is hidden while flown by hand."""
    import dataclasses

    import viser

    from app.console.session import Session, prepare_run, station_keeping_mission
    from app.console.snapshot import LoopStats
    from web.scene import SceneView

    session = Session(prepare_run(station_keeping_mission("model-scale", 100.0), False), tmp_path)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        snap = session.snapshot(1, False, 1.0, LoopStats(0.01, 0.0, 0.0, 0, 0, 0.0))
        scene = SceneView(server)
        scene.update(snap)
        assert scene._ghost.visible
        scene.update(dataclasses.replace(snap, mode="manual"))
        assert not scene._ghost.visible
        scene.update(dataclasses.replace(snap, mode="free"))
        assert scene._ghost.visible
    finally:
        server.stop()
        session.close()


def test_overview_keeps_tree_and_frame_in_its_field_of_view() -> None:
    """Both the tree and the frame's centre lie inside the overview's cone (half angle 25 deg)
    with a margin, whether they are together or 18 m (five tree lengths) apart."""
    frame = np.array([1.0, 1.0, 404.3])
    for north in (1.0, 19.0, -30.0):
        tree = np.array([north, 1.0, 400.0, 0.0, 0.0, 0.0])
        cam = geo.overview_camera(tree, 3.6, frame)
        axis = (cam.look_at_n - cam.position_n) / np.linalg.norm(cam.look_at_n - cam.position_n)
        for point in (tree[:3], frame):
            ray = (point - cam.position_n) / np.linalg.norm(point - cam.position_n)
            angle = math.degrees(math.acos(float(np.clip(ray @ axis, -1.0, 1.0))))
            assert angle < 0.8 * 25.0, (north, angle)
        # the distance grows with the separation: half of it plus two tree sizes over sin 25
        radius = 0.5 * np.linalg.norm(frame - tree[:3]) + 2.0 * 3.6
        expected = max(radius / math.sin(math.radians(25.0)), 4.0 * 3.6)
        assert np.linalg.norm(cam.look_at_n - cam.position_n) == pytest.approx(expected)
    # it moves with the tree: a small move of the tree is a small move of the camera
    a = geo.overview_camera(np.array([5.0, 1.0, 400.0, 0, 0, 0]), 3.6, frame)
    b = geo.overview_camera(np.array([5.01, 1.0, 400.0, 0, 0, 0]), 3.6, frame)
    assert np.linalg.norm(a.position_n - b.position_n) < 0.05


def test_rov_camera_sits_ahead_of_the_bow_and_keeps_the_rov_out_of_view() -> None:
    """Lens ahead of the ROV's bow, under the tree's bottom; every corner ray of the frustum
    (60 deg vertical, up to 2.1:1 wide) points forward, so the ROV (all behind the lens)
    cannot be seen, whatever the posts' places."""
    size = np.array([2.18, 1.36, 1.23])
    tree = np.array([1.0, 1.0, 400.0, 0.0, 0.0, 0.0])
    rng = np.random.default_rng(3)
    tan_v = math.tan(math.radians(30.0))
    for psi in (0.0, 0.7, -2.5, 3.1):
        rov = np.array([1.0 - 2.0 * math.cos(psi), 1.0 - 2.0 * math.sin(psi), 400.0, 0, 0, psi])
        forward = np.array([math.cos(psi), math.sin(psi), 0.0])
        for _ in range(20):
            tops = np.column_stack([rng.uniform(-6, 8, (2, 2)), rng.uniform(400.5, 420.0, 2)])
            cam = geo.rov_camera(rov, size, tree, 2.808, tops)
            assert (cam.position_n - rov[:3]) @ forward == pytest.approx(0.5 * size[0] + 0.05)
            assert cam.position_n[2] > tree[2] + 0.5 * 2.808, "below the tree's bottom"
            axis = cam.look_at_n - cam.position_n
            look = axis / np.linalg.norm(axis)
            right = np.cross(np.array([0.0, 0.0, -1.0]), look)
            right /= np.linalg.norm(right)
            down = np.cross(look, right)
            down *= np.sign(down[2])
            for sv in (-1.0, 1.0):
                for sh in (-1.0, 1.0):
                    corner = look + sv * tan_v * down + sh * 2.1 * tan_v * right
                    assert corner @ forward > 0.0
    # a post ahead within the turn and tilt limits: the camera looks straight at its top
    rov = np.array([-1.0, 1.5, 400.0, 0.0, 0.0, 0.0])  # that top 20 deg down, 10 deg to starboard
    tops = np.array([[2.4, 1.9, 402.8], [-0.4, 0.1, 402.8]])
    cam = geo.rov_camera(rov, size, tree, 2.808, tops)
    look = cam.look_at_n - cam.position_n
    to_top = tops[0] - cam.position_n
    np.testing.assert_allclose(look / np.linalg.norm(look), to_top / np.linalg.norm(to_top))


def test_follow_rov_camera_is_behind_and_above_along_the_heading() -> None:
    rov = np.array([3.0, -2.0, 400.0, 0.0, 0.0, math.radians(90.0)])
    cam = geo.follow_rov_camera(rov, np.array([2.0, 1.2, 1.2]), 3.6)
    assert cam.position_n[1] < rov[1] - 2.0 and abs(cam.position_n[0] - rov[0]) < 1e-9
    assert cam.position_n[2] < rov[2] - 1.0
    assert cam.look_at_n[1] > rov[1]


@pytest.mark.parametrize(
    ("tree_psi_deg", "frame_psi_deg", "error_deg"),
    [
        (10.0, 0.0, 10.0),
        (179.0, -179.0, -2.0),
        (-179.0, 179.0, 2.0),
        (90.0, 270.0, -180.0),
        (0.0, 360.0, 0.0),
        (-170.0, 30.0, 160.0),
    ],
)
def test_readout_heading_error_wraps_to_plus_minus_180(
    tree_psi_deg: float, frame_psi_deg: float, error_deg: float
) -> None:
    tree = np.array([0.0, 0.0, 100.0, 0.0, 0.0, math.radians(tree_psi_deg)])
    r = geo.pilot_readout(tree, 2.8, np.zeros(2), math.radians(frame_psi_deg), 102.0, None)
    assert math.degrees(r.heading_error_rad) == pytest.approx(error_deg, abs=1e-9)


def test_readout_height_distance_and_text() -> None:
    """Tree centre at 99.8 m, 2.8 m tall: bottom at 101.2 m; post tops at 102.5 m: 1.3 m above.
    Centre 3 m north and 4 m east of the frame's centre: 5 m away (3-4-5)."""
    tree = np.array([4.0, 5.0, 99.8, 0.0, 0.0, math.radians(3.0)])
    r = geo.pilot_readout(tree, 2.8, np.array([1.0, 1.0]), 0.0, 102.5, 306_800.0)
    assert r.height_above_posts_m == pytest.approx(1.3)
    assert r.distance_to_frame_m == pytest.approx(5.0)
    assert geo.readout_markdown(r) == (
        "above posts 1.30 m | to frame 5.00 m | heading error +3.0 deg | wire 306.8 kN"
    )
    assert geo.readout_markdown(
        geo.pilot_readout(tree, 2.8, np.array([1.0, 1.0]), 0.0, 100.0, None)
    ).startswith("above posts -1.20 m")
    no_tension = geo.pilot_readout(tree, 2.8, np.array([1.0, 1.0]), 0.0, 102.5, None)
    assert geo.readout_markdown(no_tension).endswith("wire -")


def test_current_arrow_has_a_readable_minimum_and_a_label() -> None:
    still = geo.current_arrow(0.0, 1.0, 3.6)
    assert (still.length_m, still.label) == (0.0, "no current")
    slow = geo.current_arrow(0.1, math.radians(225.0), 3.6)
    assert slow.label == "current 0.10 m/s towards 225 deg"
    assert slow.length_m == pytest.approx(3.6 * (1.0 + 4.0 * 0.1))
    assert slow.length_m >= 3.6, "at least a tree size long"
    west = geo.current_arrow(0.33, math.radians(-90.0), 3.6)
    assert west.label == "current 0.33 m/s towards 270 deg" and west.length_m > slow.length_m
    center = np.array([1.0, 1.0, 404.0])
    tail, head = geo.current_arrow_ends_n(center, 5.0, math.radians(225.0), slow.length_m)
    along = (head - tail) / np.linalg.norm(head - tail)
    np.testing.assert_allclose(along, [-math.sqrt(0.5), -math.sqrt(0.5), 0.0], atol=1e-12)
    middle = 0.5 * (tail + head)
    assert np.linalg.norm(middle - center) == pytest.approx(5.0)
    assert (middle - center) @ along == pytest.approx(0.0, abs=1e-12), "beside, not in line"


@pytest.mark.parametrize(("size", "bar"), [(3.6, 2.0), (0.9, 0.5), (12.0, 10.0), (5.0, 5.0)])
def test_scale_bar_is_a_round_length_within_the_tree_size(size: float, bar: float) -> None:
    assert geo.scale_bar_length_m(size) == pytest.approx(bar)


# ---------------------------------------------------------------------- mission builder
def test_builder_offers_every_leg_type_of_the_schema() -> None:
    models = schema.leg_models()
    assert set(models) == set(schema.LEG_TYPES)
    for name, model in models.items():
        specs = mb.field_specs(model)
        assert "type" not in [s.name for s in specs]
        assert [s.name for s in specs][-3:] == ["name", "score", "timeout_s"], name


def test_builder_reads_bounds_and_kinds_from_the_models() -> None:
    rotate = {s.name: s for s in mb.field_specs(schema.leg_models()["rotate"])}
    assert (rotate["angle_deg"].lo, rotate["angle_deg"].hi) == (-1080.0, 1080.0)
    assert rotate["angle_deg"].kind == "number" and rotate["angle_deg"].required
    move = {s.name: s for s in mb.field_specs(schema.leg_models()["move"])}
    assert move["heading_deg"].optional and move["relative"].kind == "bool"
    mode = {s.name: s for s in mb.field_specs(schema.leg_models()["mode"])}
    assert mode["mode"].choices == ("tree", "free", "manual") and mode["grip"].kind == "tristate"
    waypoints = {s.name: s for s in mb.field_specs(schema.leg_models()["waypoints"])}
    assert waypoints["points_ne_m"].kind == "json"


def test_every_leg_type_builds_with_its_initial_values_or_names_the_missing_field() -> None:
    setups = [schema.load_mission(n).setup for n in schema.library_names()]
    with_frame = [s for s in setups if getattr(s, "docking_frame", None) is not None]
    setup = with_frame[0] if with_frame else schema.Setup(params="full-scale", depth_m=100.0)
    for leg_type, model in schema.leg_models().items():
        values = {s.name: mb.parse_input(s, mb.initial_value(s)) for s in mb.field_specs(model)}
        leg = mb.build_leg(leg_type, values)
        try:
            mission = mb.build_mission("m", setup, [leg])
        except schema.MissionError as err:
            missing = [
                s.name for s in mb.field_specs(model) if s.required and values[s.name] is None
            ]
            named = any(name in str(err) for name in missing) or f"({leg_type})" in str(err)
            assert named, str(err)
        else:
            assert mission.legs[0].type == leg_type


def test_builder_inputs_parse_and_bad_values_name_the_field() -> None:
    specs = {s.name: s for s in mb.field_specs(schema.leg_models()["waypoints"])}
    assert mb.parse_input(specs["points_ne_m"], "[[1, 2], [3, 4]]") == [[1, 2], [3, 4]]
    with pytest.raises(ValueError, match="points_ne_m"):
        mb.parse_input(specs["points_ne_m"], "[[1, 2")
    move = {s.name: s for s in mb.field_specs(schema.leg_models()["move"])}
    assert mb.parse_input(move["heading_deg"], "") is None
    assert mb.parse_input(move["heading_deg"], "45") == 45.0
    with pytest.raises(ValueError, match="heading_deg"):
        mb.parse_input(move["heading_deg"], "north")
    setup = schema.Setup(params="full-scale", depth_m=100.0)
    with pytest.raises(schema.MissionError, match=r"legs\[1\].*angle_deg"):
        mb.build_mission("m", setup, [mb.build_leg("rotate", {"angle_deg": 5000.0})])
    with pytest.raises(ValueError, match="type"):
        mb.build_leg("teleport", {})


# ---------------------------------------------------------------------- alarms
def rows(t: np.ndarray, util: float = 0.0, err_m: float = 0.0) -> LogRows:
    out = LogRows(np.zeros((len(t), N_LOG)), n_thrusters=4)
    out["t_s"][:] = t
    out["thruster_utilisation"][:, 0] = util
    out["tree_eta_n"][:, 0] = err_m
    return out


def monitor(uses_sensors: bool = False) -> AlarmMonitor:
    limits = AlarmLimits(position_error_m=0.25, sample_period_s=(1.0, 0.1, 0.1, 0.2, 0.02))
    return AlarmMonitor(limits, n_thrusters=4, weight_newton=300e3, uses_sensors=uses_sensors)


def active(m: AlarmMonitor) -> set[str]:
    return {a.name for a in m.state if a.active}


def test_saturation_alarm_needs_more_than_two_seconds_without_a_break() -> None:
    m = monitor()
    t = np.arange(1, 151) * 0.01
    m.update(rows(t, util=1.0), 300e3)
    assert "saturation" not in active(m), "1.5 s is not yet an alarm"
    m.update(rows(t + 1.5, util=1.0), 300e3)
    assert "saturation" in active(m)
    broken = rows(t + 3.0, util=1.0)
    broken["thruster_utilisation"][-1, 0] = 0.5
    m.update(broken, 300e3)
    assert "saturation" not in active(m)


def test_position_slack_innovation_and_dropout_alarms() -> None:
    m = monitor()
    m.update(rows(np.array([0.01]), err_m=0.3), 300e3)
    assert active(m) == {"position_error"}
    m.update(rows(np.array([0.02])), 10e3)
    assert active(m) == {"wire_slack"}
    m.update(rows(np.array([0.03])), 300e3)
    assert active(m) == set()
    e = monitor(uses_sensors=True)
    t = np.arange(1, 401) * 0.01
    r = rows(t)
    r["accepted"][:] = 1.0
    r["nis"][:] = 9.0  # nine times the expected innovation
    e.update(r, 300e3)
    assert "innovation" in active(e)
    r["nis"][:] = 1.0
    r["accepted"][:, 3] = 0.0  # the DVL stops delivering
    e.update(r, 300e3)
    e.update(rows(t + 4.0), 300e3)
    assert {"dropout"} <= active(e) and "innovation" not in active(e)
    assert any("dvl" in a.message or "position" in a.message for a in e.state if a.active)


def test_a_tree_resting_on_the_frame_is_not_a_slack_wire() -> None:
    """Defect: the slack alarm went red after a good landing. The frame's post tops are at
    99 m; a tree 2 m high (bottom 1 m below its centre) resting there has a slack wire."""
    limits = AlarmLimits(position_error_m=0.25, sample_period_s=(1.0,) * 5)
    m = AlarmMonitor(
        limits, 4, 300e3, uses_sensors=False, support_depth_m=99.0, tree_half_height_m=1.0
    )
    hanging = rows(np.array([0.01]))
    hanging["tree_eta_n"][:, 2] = 97.5  # bottom 0.5 m above the post tops
    m.update(hanging, 10e3)
    assert active(m) == {"wire_slack"}, "a slack wire under a hanging tree is an alarm"
    landed = rows(np.array([0.02]))
    landed["tree_eta_n"][:, 2] = 98.02  # bottom 0.02 m into the contact
    m.update(landed, 0.0)
    assert active(m) == set()


def test_free_mode_position_alarm_compares_the_rov_with_its_set_point() -> None:
    """Defect: in free mode the alarm still compared the (released) tree with the tree's
    reference. Now the ROV against its free-flying set point, with the same 0.25 m limit."""
    m = monitor()
    free = rows(np.array([0.01]), err_m=5.0)  # the tree is 5 m off its old reference
    free["mode"][:] = 1.0
    free["rov_eta_n"][:, 0:2] = (10.0, 2.0)
    m.update(free, 300e3, free_setpoint_n=np.array([10.1, 2.0, 50.0, 0.0]))
    assert active(m) == set()
    m.update(free, 300e3, free_setpoint_n=np.array([10.5, 2.0, 50.0, 0.0]))
    assert active(m) == {"position_error"}
    assert "ROV 0.50 m" in m.state[1].message and "set point" in m.state[1].message


def test_replay_marks_name_legs_runs_and_landings_and_tick_commands_and_alarms() -> None:
    from app.console.replay import event_marks

    events = [
        {"t_s": 1.0, "kind": "mission", "text": "leg 1 (move) started", "data": {"leg": 1}},
        {"t_s": 2.0, "kind": "command", "text": "gains", "data": {}},
        {"t_s": 3.0, "kind": "alarm", "text": "saturation on", "data": {"active": True}},
        {"t_s": 4.0, "kind": "alarm", "text": "saturation off", "data": {"active": False}},
        {"t_s": 5.0, "kind": "landing", "text": "landed", "data": {}},
        {"t_s": 6.0, "kind": "mission", "text": "mission m completed", "data": {"state": "done"}},
        {"t_s": 99.0, "kind": "landing", "text": "after the end", "data": {}},
    ]
    assert event_marks(events, 0.0, 10.0) == (
        (1.0, "L1"),
        (2.0, ""),
        (3.0, ""),
        (5.0, "landing"),
        (6.0, "done"),
    )


@pytest.mark.parametrize(("frame_s", "period_s"), [(0.06, 0.2), (0.06, 0.5), (0.13, 0.2)])
def test_panel_updates_keep_their_rate_whatever_the_frame_period(
    frame_s: float, period_s: float
) -> None:
    """Defect: the status line (every 0.2 s) and plots (every 0.5 s) were counted from the
    frame that did the last update, so each period was rounded up to whole publisher frames:
    with 60 ms frames the status line came 4.2 times a second, not 5 (4 frames = 0.24 s) and
    the plots 1.7 (9 frames). Counting from the due time keeps the promised rate on average."""
    from web.status import next_due

    due, sent, now = 0.0, 0, 0.0
    frames = int(round(60.0 / frame_s))
    for k in range(frames):
        now = k * frame_s
        if now >= due:
            due = next_due(due, period_s, now)
            sent += 1
    # over 60 s the count is 60 / period, give or take the first and the last update
    assert abs(sent - 60.0 / period_s) <= 1


def test_panel_updates_do_not_burst_after_a_stall() -> None:
    """After a stall of several periods, one update and then the normal rate (no catch-up
    burst of the missed ones)."""
    from web.status import next_due

    due = next_due(0.0, 0.2, 0.0)
    assert due == pytest.approx(0.2)
    due = next_due(due, 0.2, 3.0)  # 2.8 s late
    assert due == pytest.approx(3.2)


def test_a_seek_is_not_undone_by_a_frame_update_that_comes_before_its_callback():
    """The scrub bar's race (a flaky browser test found it): viser sets the bar to the value
    a viewer typed, then runs the seek callback; a frame update in between used to set the
    bar back to the replay's present time, so the seek went nowhere. The panel's own methods
    on a stand-in tab, in that order."""
    from types import SimpleNamespace

    from app.console.snapshot import ReplayStatus
    from web.tabs.record import RecordTab

    seeks: list[float] = []
    bar = SimpleNamespace(value=20.0)
    tab = SimpleNamespace(
        replay=SimpleNamespace(seek=seeks.append),
        replay_time=bar,
        operator=SimpleNamespace(unlocked=True, say=lambda text: None),
        _replay_name="trial",
        _replay_shown=20.0,
        replay_md=SimpleNamespace(content=""),
        notes_md=SimpleNamespace(content=""),
        _lock=threading.Lock(),
        _notes=[],
        _notes_changed=False,
        _scene_info=None,
        ghost=None,
    )

    def frame(t_s: float) -> None:
        status = ReplayStatus("trial", t_s, 0.0, 60.0, False, True)
        snap = SimpleNamespace(source="replay", replay=status, speed=1.0, scene=None, t_s=t_s)
        RecordTab.update(tab, snap)

    frame(20.0)
    bar.value = 5.0  # the viewer's value, as viser sets it before the callback
    frame(20.0)  # paused at 20 s: this frame's time is the old one
    RecordTab._on_seek_replay(tab, SimpleNamespace(client=object()))
    assert seeks == [5.0]
    frame(5.0)
    assert bar.value == 5.0
    frame(7.3)  # playing again: the bar follows the replay
    assert bar.value == 7.3


def test_a_publisher_error_says_where_it_was_raised() -> None:
    """The console view's ``errors`` name the line that raised (a rare error seen once in a
    full run, "deque mutated during iteration", said nothing of where)."""
    import json

    from web.view import _where

    def ours() -> None:
        raise RuntimeError("ours")

    def through_a_library() -> None:
        json.loads("{")

    try:
        ours()
    except RuntimeError as err:
        text = _where(err)
    assert "test_console_view_model.py" in text and "in ours)" in text and "; from" not in text
    try:
        through_a_library()
    except ValueError as err:
        text = _where(err)
    assert "json/decoder.py:" in text, "the innermost frame, in the library"
    assert "; from " in text and "test_console_view_model.py:" in text.split("; from ")[1]
    assert text.endswith("in through_a_library)"), "and our own innermost frame after it"


def _raised_through(files: list[str], message: str) -> RuntimeError:
    """A RuntimeError raised through one frame in each of ``files`` (outermost first), the last
    raising it: the traceback viser's event race leaves, without the race."""

    def call(i: int):
        if i == len(files) - 1:
            code = compile(f"def f(_):\n    raise RuntimeError({message!r})\n", files[i], "exec")
        else:
            code = compile("def f(next_call):\n    return next_call()\n", files[i], "exec")
        space: dict = {}
        exec(code, space)
        return space["f"](lambda: call(i + 1))

    try:
        call(0)
    except RuntimeError as err:
        return err
    raise AssertionError("nothing raised")


RACE_FILES = [
    "/repo/web/scene.py",
    "/venv/site-packages/viser/_scene_handles.py",
    "/venv/site-packages/viser/infra/_async_message_buffer.py",
    "/python/lib/python3.11/asyncio/locks.py",
]


def test_viser_event_race_is_told_from_other_errors() -> None:
    """Only viser's own race (its message buffer setting an asyncio.Event from the sending
    thread, raised in asyncio's locks during a scene update) is healed rather than reported."""
    from web.view import _viser_event_race

    race = "deque mutated during iteration"
    assert _viser_event_race(_raised_through(RACE_FILES, race))
    panel = ["/repo/web/panels.py", *RACE_FILES[1:]]
    assert not _viser_event_race(_raised_through(panel, race)), "a panel's: an error"
    assert not _viser_event_race(_raised_through(RACE_FILES, "another error")), "other words"
    ours = [*RACE_FILES[:3], "/repo/web/scene.py"]
    assert not _viser_event_race(_raised_through(ours, race)), "raised in our code"
    assert not _viser_event_race(ValueError(race)), "another type"


def test_the_publisher_heals_a_viser_event_race_and_reports_other_errors(tmp_path) -> None:
    """A scene update cut short by viser's race is not an error: the scene is drawn whole on
    the next frame and the race is counted. Any other error is reported as before."""
    import time

    from app.console import ConsoleSettings
    from app.server import serve_in_thread

    settings = ConsoleSettings(port=0, viser_port=0, recordings_dir=tmp_path, speed=5.0)
    with serve_in_thread(settings) as running:
        view = running.app.state.view
        update, redraw = view.scene.update, view.scene.redraw
        raised: list[str] = []
        redraws: list[int] = []
        updates_after: list[int] = []

        def failing_update(snap) -> None:
            if len(raised) == 0:
                raised.append("race")
                raise _raised_through(RACE_FILES, "deque mutated during iteration")
            if len(raised) == 1 and redraws:
                raised.append("other")
                raise _raised_through(["/repo/web/scene.py"], "something else")
            if len(raised) == 2:
                updates_after.append(snap.seq)
            update(snap)

        def counted_redraw() -> None:
            redraws.append(1)
            redraw()

        view.scene.update, view.scene.redraw = failing_update, counted_redraw
        deadline = time.monotonic() + 20.0
        while len(updates_after) < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert view.viser_event_races == 1 and len(redraws) == 1
        assert len(view.errors) == 1 and view.errors[0].startswith("RuntimeError: something else")
        assert len(updates_after) >= 3, "the publisher goes on after both"


def test_a_browser_that_has_gone_gets_no_more_frames(tmp_path) -> None:
    """Defect: the view's frame thread updated the panel of a browser whose socket had just
    closed (viser drops the client, then calls the console's disconnect), and viser warned
    "Queued a ... on a closed connection" in most full test runs. A panel whose client viser
    no longer lists gets no update."""
    import time
    from types import SimpleNamespace

    from app.console import ConsoleSettings
    from app.server import serve_in_thread

    settings = ConsoleSettings(port=0, viser_port=0, recordings_dir=tmp_path, speed=5.0)
    with serve_in_thread(settings) as running:
        view = running.app.state.view
        gone: list[int] = []
        frames: list[int] = []
        update = view.scene.update

        def counted_update(snap) -> None:
            frames.append(snap.seq)
            update(snap)

        view.scene.update = counted_update
        with view._lock:  # a panel left behind by a browser viser has dropped already
            view._panels[987654] = SimpleNamespace(update=lambda snap: gone.append(snap.seq))
        deadline = time.monotonic() + 20.0
        while len(frames) < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(frames) >= 3, "the view drew its frames"
        assert gone == [], f"the gone browser's panel was updated {len(gone)} times"
        assert view.errors == []
