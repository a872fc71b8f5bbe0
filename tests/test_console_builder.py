"""The mission builder in a real headless Chromium (issue 10, "the builder cannot build a
landing" and "builder layout"): leg inputs stay in the builder when the leg type changes,
labels carry units, a bad value gets a one-line error naming the field, a landing is built on
a docking set-up and flown, and mission files go out (download) and come in (upload).

One server and one browser for the module; the fixtures and helpers are the browser tests'.
Screenshots go to docs/screenshots/.
"""

from __future__ import annotations

import re
import time
from pathlib import Path

import pytest

from app.server import RunningServer
from missions import schema
from tests.browser import (
    button,
    choose,
    click,
    field,
    save,
    tab,
    unlock,
    wait_for,
)

# the fixtures server, page and api: tests/browser.py (one server and one Chromium a module)


def builder_message(server: RunningServer) -> str:
    """The builder's message line (the markdown just under "Start built mission"), as it
    reads: names and messages are written escaped (``app.console.md_text``)."""
    return re.sub(r"\\(.)", r"\1", str(panel_of(server).builder_md.content))


def panel_of(server: RunningServer):
    """The builder of the (only) browser."""
    panels = list(server.app.state.view._panels.values())
    assert len(panels) == 1
    return panels[0].mission.builder


@pytest.fixture
def still(api):
    """The run paused while the test works the panel (a still scene costs the software-
    rendering browser nothing, so the page answers faster), resumed after."""
    api.post("/api/run/pause").raise_for_status()
    yield
    api.post("/api/run/resume").raise_for_status()


def set_number(pg, label: str, value: float, handle) -> None:
    """Type a number and wait until the server holds it (the browser sends typed values a
    moment later; a click right after could go out first)."""
    box = field(pg, label)
    box.fill(f"{value:g}")
    box.press("Tab")
    wait_for(lambda: float(handle.value) == value, 10.0, f"{label} = {value:g} on the server")


def pick_leg_type(pg, builder, leg_type: str, first_label: str) -> None:
    """Choose a leg type and wait until its own inputs are made on the server and shown (an
    input of the same name from the previous type may still be on the page a moment)."""
    choose(pg, "Leg type", leg_type)
    wait_for(
        lambda: builder._leg_folder is not None and builder._leg_folder.label == f"{leg_type} leg",
        10.0,
        f"the {leg_type} leg's inputs",
    )
    field(pg, first_label).wait_for(timeout=10_000)


def clear_legs(pg) -> None:
    click(pg, "Clear")
    pg.get_by_text("no legs yet").first.wait_for(timeout=5000)


# ---------------------------------------------------------------------- layout
def test_leg_inputs_stay_in_the_builder_on_the_mission_tab(page, still) -> None:
    tab(page, "Mission")
    choose(page, "Leg type", "waypoints")
    points = field(page, "Waypoints north, east [m]")
    points.wait_for(timeout=10_000)
    assert points.input_value() == "0, 5; 5, 5", "the waypoints input starts with an example"
    page.get_by_text("north, east pairs, e.g.").first.wait_for(timeout=5000)
    top = lambda locator: locator.bounding_box()["y"]  # noqa: E731
    assert top(field(page, "Leg type")) < top(points) < top(button(page, "Add leg")), (
        "the leg's inputs must sit between 'Leg type' and 'Add leg'"
    )
    assert field(page, "Settle [s]").is_visible()
    assert page.locator("xpath=//label[normalize-space(.)='settle_s']").count() == 0
    save(page.screenshot(), "console-builder.png")
    tab(page, "Control")
    time.sleep(0.5)
    assert not points.is_visible(), "leg inputs leaked onto the Control tab"
    assert not button(page, "Add leg").is_visible()
    tab(page, "Mission")


def test_a_bad_value_gets_a_one_line_error_naming_the_field(page, server, still) -> None:
    tab(page, "Mission")
    choose(page, "Leg type", "waypoints")
    field(page, "Waypoints north, east [m]").fill("0, 5; 3")
    click(page, "Add leg")
    page.get_by_text("point 2 ('3') is not a north, east pair").wait_for(timeout=5000)
    text = builder_message(server)
    assert text.startswith("**error**: invalid leg: Waypoints north, east [m] (points_ne_m)")
    assert "\n" not in text and "{" not in text, text
    assert panel_of(server).legs == []


# ---------------------------------------------------------------------- a landing
def test_a_dock_leg_built_on_a_docking_set_up_lands_the_tree(page, server, api, still) -> None:
    unlock(page, server.token)
    tab(page, "Mission")
    choose(page, "Set-up from", "full-docking-current-0.3")
    wait_for(lambda: field(page, "Landing depth [m]").input_value() == "400", 10.0, "the frame")
    assert field(page, "Docking frame").is_checked()
    # the set-up edited in the page: the tree starts at the hover height (its bottom 1 m over
    # the post tops: 7 m at 390 m, the library's comment) over a frame under the crane tip
    builder = panel_of(server)
    for label, value, handle in (
        ("Tree depth [m]", 396.0, builder.depth),
        ("Frame north [m]", 1.0, builder.frame_n),
        ("Frame east [m]", 1.0, builder.frame_e),
        ("Frame heading [deg]", 0.0, builder.frame_psi),
    ):
        set_number(page, label, value, handle)
    pick_leg_type(page, builder, "dock", "Hover [m]")
    set_number(page, "Settle [s]", 5.0, builder._leg_inputs["settle_s"][1])
    click(page, "Add leg")
    page.get_by_text("added dock leg").wait_for(timeout=5000)
    assert builder.legs[0]["type"] == "dock" and builder.legs[0]["settle_s"] == 5.0
    assert builder.preview_nodes > 0, "the built mission is previewed in the scene"
    setup = builder._setup()
    assert setup.depth_m == 396.0 and setup.docking_frame is not None
    assert setup.docking_frame.center_ne_m == [1.0, 1.0]
    time.sleep(1.0)
    save(page.screenshot(), "console-builder-preview.png")
    click(page, "Start built mission")
    wait_for(
        lambda: api.get("/api/state").json()["mission"]["name"] == "built mission",
        30.0,
        "the built mission to start",
    )
    assert builder.preview_nodes == 0, "the preview must go when the mission starts"
    api.put("/api/run/speed", json={"speed": 50.0}).raise_for_status()
    api.post("/api/run/resume").raise_for_status()
    try:
        wait_for(
            lambda: server.console.loop.snapshot.mission.result is not None,
            240.0,
            "the landing to finish",
        )
    finally:
        api.put("/api/run/speed", json={"speed": 1.0}).raise_for_status()
    result = server.console.loop.snapshot.mission.result
    assert result is not None and not result["error"], result
    [landing] = result["landings"]
    assert landing["success"] and landing["rests_on"] == "frame", landing
    clear_legs(page)


# ---------------------------------------------------------------------- files
def test_download_gives_a_mission_file_and_a_malformed_upload_one_line(
    page, server, api, still, tmp_path: Path
) -> None:
    unlock(page, server.token)
    tab(page, "Mission")
    builder = panel_of(server)
    field(page, "Mission name").fill("download test")
    field(page, "Mission name").press("Tab")
    wait_for(lambda: builder.name_text.value == "download test", 10.0, "the name on the server")
    pick_leg_type(page, builder, "hold", "Duration [s]")
    set_number(page, "Duration [s]", 7.0, builder._leg_inputs["duration_s"][1])
    click(page, "Add leg")
    page.get_by_text("added hold leg").wait_for(timeout=5000)
    with page.expect_download(timeout=15_000) as info:
        click(page, "Download TOML")
    path = tmp_path / "download.toml"
    info.value.save_as(path)
    mission = schema.parse_text(path.read_text(), str(path))
    assert info.value.suggested_filename == "download-test.toml"
    assert mission.name == "download test" and [leg.type for leg in mission.legs] == ["hold"]
    assert mission.legs[0].duration_s == 7.0  # type: ignore[union-attr]
    assert mission.setup == panel_of(server)._setup()
    clear_legs(page)

    upload = page.locator("input[type=file]").first
    t0 = server.console.loop.snapshot.t_s
    api.post("/api/run/resume").raise_for_status()
    upload.set_input_files(
        files=[{"name": "bad.toml", "mimeType": "text/plain", "buffer": b"a = [[[[\n"}]
    )
    page.get_by_text("upload refused: cannot parse bad.toml").wait_for(timeout=10_000)
    assert "\n" not in builder_message(server).strip()
    wait_for(lambda: server.console.loop.snapshot.t_s > t0 + 0.5, 10.0, "the session to run on")
    assert server.app.state.view.errors == []

    good = path.read_text().replace('name = "download test"', 'name = "uploaded test"')
    upload.set_input_files(
        files=[{"name": "good.toml", "mimeType": "text/plain", "buffer": good.encode()}]
    )
    page.get_by_text("(1 legs): loaded into the builder").wait_for(timeout=10_000)
    assert server.console.find_mission("uploaded test").legs[0].type == "hold"
    assert panel_of(server).legs == [{"type": "hold", "duration_s": 7.0}]
    clear_legs(page)
