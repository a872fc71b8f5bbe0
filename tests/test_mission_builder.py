"""The mission builder's pure model (web/mission_builder.py) for issue 10: labels with units,
waypoints typed as "n, e; n, e", range errors naming the field and the allowed range, one-line
errors, the set-up edited in the page (a docking frame makes dock legs valid), uploaded files
and the preview's geometry. The browser side is tests/test_console_builder.py.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from missions import schema
from web import mission_builder as mb


def specs(leg_type: str) -> dict[str, mb.FieldSpec]:
    return {s.name: s for s in mb.field_specs(schema.leg_models()[leg_type])}


def test_labels_carry_units_and_the_hint_the_allowed_range() -> None:
    hold, dock = specs("hold"), specs("dock")
    assert hold["duration_s"].label == "Duration [s]"
    assert dock["lower_rate_mps"].label == "Lower rate [m/s]"
    assert specs("heave")["force_newton"].label == "Force [N]"
    assert specs("move")["heading_deg"].label == "Heading [deg] (optional)"
    assert specs("waypoints")["points_ne_m"].label == "Waypoints north, east [m]"
    # Field(gt=0, le=86400): the lower bound is excluded, the upper one allowed
    assert hold["duration_s"].allowed == "> 0 and <= 86400"
    assert "allowed > 0 and <= 86400 s" in hold["duration_s"].hint
    assert "file key: duration_s" in hold["duration_s"].hint
    every = [s for m in schema.leg_models().values() for s in mb.field_specs(m)]
    assert all("_" not in s.label for s in every), [s.label for s in every if "_" in s.label]


def test_waypoints_are_typed_as_pairs_with_an_example_to_start_from() -> None:
    points = specs("waypoints")["points_ne_m"]
    assert points.pairs and not specs("gains")["kp"].pairs
    shown = mb.text_of(points, mb.initial_value(points))
    assert shown == mb.PAIRS_EXAMPLE == "0, 5; 5, 5"
    assert mb.parse_input(points, shown) == [[0.0, 5.0], [5.0, 5.0]]
    assert mb.parse_input(points, "1 2\n-3,4.5") == [[1.0, 2.0], [-3.0, 4.5]]
    assert mb.parse_input(points, "[[1, 2]]") == [[1, 2]]  # JSON still accepted
    with pytest.raises(ValueError, match=r"\(points_ne_m\): point 2 \('3'\) is not a north"):
        mb.parse_input(points, "0, 5; 3")
    with pytest.raises(ValueError, match="give at least one point"):
        mb.parse_input(points, " ; ")
    kp = specs("gains")["kp"]
    assert mb.parse_input(kp, "1e5, 2e5, 3e6") == [1e5, 2e5, 3e6]
    assert mb.text_of(kp, [1e5, 2e5, 3e6]) == "100000, 200000, 3e+06"


@pytest.mark.parametrize(
    ("raw", "message"),
    [
        (-1.0, "Duration [s] (duration_s): -1 s is out of range; allowed > 0 and <= 86400"),
        (0.0, "Duration [s] (duration_s): 0 s is out of range; allowed > 0 and <= 86400"),
        (1e9, "Duration [s] (duration_s): 1e+09 s is out of range; allowed > 0 and <= 86400"),
        ("abc", "Duration [s] (duration_s): 'abc' is not a number"),
        (math.inf, "Duration [s] (duration_s): must be a finite number"),
    ],
)
def test_a_number_out_of_range_names_the_field_and_the_range(raw: object, message: str) -> None:
    with pytest.raises(ValueError) as err:
        mb.parse_input(specs("hold")["duration_s"], raw)
    assert str(err.value) == message
    assert mb.parse_input(specs("hold")["duration_s"], 86400.0) == 86400.0


def test_schema_errors_become_one_readable_line() -> None:
    data = {
        "format_version": 1,
        "name": "m",
        "setup": {"params": "full-scale", "depth_m": 100.0},
        "legs": [
            {"type": "waypoints", "points_ne_m": [[1.0]]},
            {"type": "gains", "kp": [1, 2], "ki": [1, 1, 1], "kd": [1, 1, -1]},
        ],
    }
    with pytest.raises(schema.MissionError) as err:
        schema.parse_mission(data)
    line = mb.one_line(err.value)
    assert "\n" not in line and "{" not in line
    assert line.startswith("leg 1 (waypoints) Waypoints north, east [m] (points_ne_m[1]): ")
    assert "leg 2 (gains) Kp surge, sway, yaw (kp): " in line and line.endswith("(and 1 more)")


def test_a_dock_leg_needs_a_frame_and_the_edited_set_up_gives_one() -> None:
    """The defect: dock legs were checked against a set-up without a frame. With the page's
    "Docking frame" ticked the same leg builds; without it the error says what to tick."""
    base = schema.load_mission("full-square-400").setup
    assert base.docking_frame is None
    values = mb.SetupValues.of(base)
    dock = [mb.build_leg("dock", {"settle_s": 5.0})]
    with pytest.raises(schema.MissionError) as err:
        mb.build_mission("m", mb.edited_setup(base, values), dock)
    assert mb.one_line(err.value).startswith(
        "leg 1 (dock) needs a docking frame: tick 'Docking frame' in the set-up"
    )
    framed = dataclasses.replace(
        values,
        frame=True,
        frame_north_m=3.0,
        frame_east_m=-2.0,
        frame_heading_deg=45.0,
        landing_depth_m=values.depth_m + 8.0,
        current_speed_mps=0.2,
    )
    setup = mb.edited_setup(base, framed)
    mission = mb.build_mission("m", setup, dock)
    assert mission.setup.docking_frame is not None
    assert mission.setup.docking_frame.center_ne_m == [3.0, -2.0]
    assert mission.setup.current.speed_mps == 0.2
    assert mission.setup.feedback == base.feedback and mission.setup.seed == base.seed
    assert mb.SetupValues.of(setup) == framed
    with pytest.raises(schema.MissionError, match=r"^Tree depth \[m\]: .*greater than 5"):
        mb.edited_setup(base, dataclasses.replace(values, depth_m=1.0))
    shallow = dataclasses.replace(framed, landing_depth_m=values.depth_m - 1.0)
    with pytest.raises(schema.MissionError) as err:
        mb.build_mission("m", mb.edited_setup(base, shallow), dock)
    assert "'Landing depth [m]' must be deeper than 'Tree depth [m]'" in mb.one_line(err.value)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"a = [[[[\n", "cannot parse bad.toml: "),
        (b"\xff\xfe\x00", "bad.toml: not a text file (UTF-8)"),
        (b"x = " + b"[" * 5000 + b"]" * 5000, "bad.toml"),
        (b"# " + b"x" * (schema.MAX_FILE_BYTES + 1), "a mission file has at most 262144 bytes"),
        (b'format_version = 1\nname = "x"\n', "bad.toml: "),
    ],
)
def test_a_malformed_upload_is_one_line(content: bytes, message: str) -> None:
    with pytest.raises(schema.MissionError) as err:
        mb.parse_upload("bad.toml", content)
    text = str(err.value)
    assert message in text and "\n" not in text, text
    assert len(text) < 400, text


def test_a_downloaded_mission_reads_back_and_its_file_name_is_safe() -> None:
    mission = schema.load_mission("full-docking-current-0.3")
    again = mb.parse_upload("x.toml", schema.dump_mission(mission).encode())
    assert again == mission
    renamed = mission.model_copy(update={"name": "../a b:c"})
    assert mb.file_name(renamed) == "a-b-c.toml"


def test_the_preview_follows_the_legs_targets() -> None:
    """Targets as missions.legs sets them: relative moves add up, a square's corners go north
    first then east (clockwise), waypoints are relative to the leg's start, dock goes to the
    frame's centre."""
    setup = schema.load_mission("full-docking-current-0.3").setup
    start = tuple(setup.crane_tip_n)
    legs = [
        {"type": "move", "north_m": 2.0, "east_m": 0.0},
        {"type": "square", "side_m": 1.0},
        {"type": "waypoints", "points_ne_m": [[0.0, 3.0]]},
        {"type": "hold", "duration_s": 1.0},
        {"type": "dock"},
    ]
    pv = mb.preview(setup, legs)
    n0, e0 = start
    assert pv.path_ne == [
        (n0, e0),
        (n0 + 2, e0),
        (n0 + 3, e0),
        (n0 + 3, e0 + 1),
        (n0 + 2, e0 + 1),
        (n0 + 2, e0),
        (n0 + 2, e0 + 3),
        (4.0, 2.5),
    ]
    assert [t[2] for t in pv.targets][:2] == ["1 move", "2 square 1"]
    assert pv.frame == (4.0, 2.5, math.radians(30.0), 400.0) and pv.depth_m == 390.0
