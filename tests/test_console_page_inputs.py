"""Issue 47 item 24: the page's number inputs refuse an out-of-range value with the field and
its range (viser's inputs clamped 5 m/s to 3, depth -10 to 5 and heading 400 to 360 without a
word), and wrap a typed angle into [0, 360) and say so.

The panel parts are driven without a browser: a viser server's GUI stands in for one
browser's, a value is set as viser sets a typed one (the value, then the callbacks with the
client), and the loop's ``call_blocking`` is replaced by a list of the commands sent.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
import viser
from hypothesis import given
from hypothesis import strategies as st
from viser._gui_handles import GuiEvent

from app.console import Console, ConsoleSettings
from app.console import commands as cmd
from web.builder_panel import BuilderPanel
from web.tabs.control import ControlTab
from web.tabs.run import RunTab
from web.widgets import Bounds, Operator, wrap_deg


@given(st.floats(-1e6, 1e6, allow_nan=False))
def test_wrap_deg_lands_in_0_to_360_on_the_same_direction(angle: float) -> None:
    w = wrap_deg(angle)
    assert 0.0 <= w < 360.0
    assert math.cos(math.radians(w - angle)) == pytest.approx(1.0, abs=1e-9)


def test_bounds_refuse_with_the_field_and_the_range() -> None:
    b = Bounds("Speed m/s", 0.0, 3.0, "m/s")
    assert b.check(3.0) == 3.0
    with pytest.raises(ValueError, match=r"Speed m/s: 5 m/s is out of range; allowed 0 to 3 m/s"):
        b.check(5.0)
    with pytest.raises(ValueError, match="out of range"):
        b.check(math.nan)


def not_clamped(*handles: Any) -> None:
    """viser's browser input clamps to a min or max without a word: the inputs have none."""
    for handle in handles:
        assert handle.min is None and handle.max is None, handle.label


def shown(markdown: Any) -> str:
    """A markdown element's text as the page shows it (escapes removed)."""
    return str(markdown.content).replace("\\", "")


class Page:
    """One browser's panel parts over a viser server's GUI, with the messages it showed and
    the commands it sent."""

    def __init__(self, server: viser.ViserServer, console: Console) -> None:
        self.said: list[str] = []
        self.sent: list[Any] = []
        self.client = SimpleNamespace(gui=server.gui, scene=server.scene, client_id=7)
        self.operator = Operator(self.client, console, self.said.append)  # type: ignore[arg-type]
        self.operator.add_access()
        self.operator.unlocked = True

    @property
    def last_said(self) -> str:
        """The last message as the page shows it (markdown escapes removed)."""
        return shown(SimpleNamespace(content=self.said[-1]))

    def type_in(self, handle: Any, value: Any) -> None:
        """As viser applies a browser's edit: the value first, then the callbacks."""
        handle._impl.value = value
        for callback in list(handle._impl.update_cb):
            callback(GuiEvent(client_id=7, client=self.client, target=handle))  # type: ignore[arg-type]

    def press(self, button: Any) -> None:
        self.type_in(button, True)


@pytest.fixture(scope="module")
def console(tmp_path_factory: pytest.TempPathFactory) -> Console:
    folder = tmp_path_factory.mktemp("recordings")
    return Console.build(ConsoleSettings(view=False, recordings_dir=folder))


@pytest.fixture()
def page(console: Console, monkeypatch: pytest.MonkeyPatch) -> Iterator[Page]:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        pg = Page(server, console)

        def call_blocking(command: Any, **_: Any) -> dict:
            pg.sent.append(command)
            return {}

        monkeypatch.setattr(console.loop, "call_blocking", call_blocking)
        yield pg
    finally:
        server.stop()


def _button(gui: Any, label: str) -> Any:
    """The last input made with this label."""
    handles = gui._gui_input_handle_from_uuid.values()
    return [h for h in handles if h.label == label][-1]


def test_current_speed_out_of_range_is_refused_not_clamped(page: Page, console: Console) -> None:
    control = ControlTab(page.operator, console)
    not_clamped(control.current_speed, control.current_dir, control.vessel_n, control.vessel_e)
    page.type_in(control.current_speed, 5.0)
    assert control.current_speed.value == 5.0, "the typed value stays to be corrected"
    assert "Speed m/s: 5 m/s is out of range; allowed 0 to 3 m/s" in page.last_said
    page.press(_button(page.client.gui, "Set current"))
    assert page.sent == [], "nothing sent"
    assert "allowed 0 to 3 m/s" in page.operator.last_error


def test_current_direction_is_wrapped_and_the_page_says_so(page: Page, console: Console) -> None:
    control = ControlTab(page.operator, console)
    page.type_in(control.current_speed, 0.2)
    page.type_in(control.current_dir, 400.0)
    assert control.current_dir.value == pytest.approx(40.0)
    assert "400 deg taken as 40 deg" in page.last_said
    page.press(_button(page.client.gui, "Set current"))
    assert page.sent == [cmd.SetCurrent(0.2, 40.0)]


def test_target_heading_is_wrapped_and_far_target_refused(page: Page, console: Console) -> None:
    run = RunTab(page.operator, console)
    not_clamped(run.target_n, run.target_e, run.target_psi)
    page.type_in(run.target_psi, -90.0)
    assert run.target_psi.value == pytest.approx(270.0)
    assert "-90 deg taken as 270 deg" in page.last_said
    page.type_in(run.target_n, 2e4)
    assert "Target north m: 20000 m is out of range; allowed -10000 to 10000 m" in page.last_said
    page.press(_button(page.client.gui, "Go to target"))
    assert page.sent == []


def test_builder_refuses_a_negative_depth_and_wraps_a_frame_heading(
    page: Page, console: Console
) -> None:
    builder = BuilderPanel(
        page.client,  # type: ignore[arg-type]
        console,
        page.operator.guard,
        lambda mission: None,
        lambda: True,
    )
    not_clamped(builder.depth, builder.current_speed, builder.current_dir, builder.frame_psi)
    not_clamped(*(handle for _, handle in builder._leg_inputs.values() if hasattr(handle, "min")))
    page.type_in(builder.depth, -10.0)
    assert builder.depth.value == -10.0
    assert "Tree depth [m]: -10 m is out of range; allowed 5 to 4000 m" in shown(builder.builder_md)
    builder.legs = [{"type": "hold", "duration_s": 10.0}]
    page.press(builder.validate_button)
    assert "allowed 5 to 4000 m" in shown(builder.builder_md)
    page.type_in(builder.depth, 100.0)
    page.type_in(builder.frame_psi, 400.0)
    assert builder.frame_psi.value == pytest.approx(40.0)
    assert "400 deg taken as 40 deg" in shown(builder.builder_md)


def test_live_current_direction_is_shown_within_0_to_360(page: Page, console: Console) -> None:
    control = ControlTab(page.operator, console)
    snap = console.loop.snapshot
    for rad, shown_deg in ((math.radians(-90.0), 270.0), (math.radians(-0.02), 0.0)):
        control.update(dataclasses.replace(snap, current_direction_rad=rad))
        assert control.current_dir.value == pytest.approx(shown_deg)


def _form(gui: Any, holding: Any) -> Any:
    """The form that holds ``holding`` (viser's forms are containers)."""
    from viser._gui_handles import GuiFormHandle

    forms = [h for h in gui._container_handle_from_uuid.values() if isinstance(h, GuiFormHandle)]
    parent = holding._impl.parent_container_id
    (form,) = (f for f in forms if f._impl.uuid == parent)
    return form


def submit(page: Page, form: Any) -> None:
    """As viser applies a browser's Enter in a form's input: the form's submit callbacks."""
    for callback in list(form._submit_cb):
        callback(GuiEvent(client_id=7, client=page.client, target=form))  # type: ignore[arg-type]


def test_a_typed_speed_is_applied_by_enter(page: Page, console: Console) -> None:
    """Defect (issue 47 item 26): typing a speed and pressing Enter did nothing (the speed was
    a dropdown of eight values; a typed '3' matched none). The speed is a number in a form:
    Enter applies it, as "Set speed" does, and a preset is a click."""
    run = RunTab(page.operator, console)
    page.type_in(run.speed, 3.0)
    submit(page, _form(page.client.gui, run.speed))
    assert page.sent == [cmd.SetSpeed(3.0)]
    page.type_in(run.speed, 80.0)
    submit(page, _form(page.client.gui, run.speed))
    assert page.sent == [cmd.SetSpeed(3.0)], "out of range: refused in words, not sent"
    assert "allowed 0.25 to 50 x" in page.operator.last_error
    page.type_in(run.speed_presets, "20")
    assert page.sent[-1] == cmd.SetSpeed(20.0)


def test_enter_applies_the_current_and_the_target(page: Page, console: Console) -> None:
    """Enter in the current's or the target's inputs applies them, as their buttons do."""
    control = ControlTab(page.operator, console)
    page.type_in(control.current_speed, 0.4)
    page.type_in(control.current_dir, 90.0)
    submit(page, _form(page.client.gui, control.current_speed))
    assert page.sent == [cmd.SetCurrent(0.4, 90.0)]
    run = RunTab(page.operator, console)
    page.type_in(run.target_n, 3.0)
    submit(page, _form(page.client.gui, run.target_n))
    assert isinstance(page.sent[-1], cmd.SetTarget) and page.sent[-1].north_m == 3.0


def test_a_preview_out_of_the_live_runs_sight_turns_the_camera_to_it(
    page: Page, console: Console
) -> None:
    """Defect (issue 47 item 23): the builder's preview was drawn at the built mission's depth,
    150 m above the camera that looked at the live run: invisible. The browser's camera is now
    turned to it (once per extent), and not when it lies where the live run is."""
    shown_points: list[Any] = []
    builder = BuilderPanel(
        page.client,  # type: ignore[arg-type]
        console,
        page.operator.guard,
        lambda mission: None,
        lambda: True,
        show=lambda pts, what: shown_points.append((pts, what)),
    )
    live_depth = console.loop.snapshot.tree_eta_n[2]
    builder.legs = [{"type": "move", "north_m": 5.0, "east_m": 0.0}]
    page.type_in(builder.depth, round(live_depth, 1))
    builder._draw_preview()
    assert shown_points == [], "where the live run is: the camera stays"
    page.type_in(builder.depth, round(live_depth - 150.0, 1))
    builder._draw_preview()
    assert len(shown_points) == 1
    pts, what = shown_points[0]
    assert np.isclose(pts[:, 2], live_depth - 150.0).sum() >= 2, "the path, at its depth"
    assert "preview" in what
    builder._draw_preview()
    assert len(shown_points) == 1, "the same preview again: the camera is not moved again"


def _record_a_little(folder: Any) -> str:
    """A recording of 5 s of station keeping in ``folder``, with a pause command in it."""
    from app.console.session import Session, prepare_run, station_keeping_mission

    session = Session(prepare_run(station_keeping_mission("model-scale", 100.0), False), folder)
    try:
        name = session.start_recording("page")
        session.advance(200)
        session.note("command", "pause", {})
        session.advance(300)
        session.stop_recording()
    finally:
        session.close()
    return name


def test_a_replay_is_watched_without_a_token_at_its_own_speed(page: Page, console: Console) -> None:
    """Defects (issue 47 item 27): "Open replay" was greyed out with no word of why until the
    console token was entered (watching changes nothing for anyone else); a typed time was
    ignored while playing (the frames wrote the scrub bar's box over); the replay's speed was
    the live run's; the scrub bar's dots had no words."""
    from web.tabs.record import RecordTab, jump_label

    name = _record_a_little(console.settings.recordings_dir)
    page.operator.unlocked = False
    record = RecordTab(page.operator, console, lambda: None)
    assert not record.replay_open.disabled
    record._refresh_recordings()
    page.type_in(record.recordings, name)
    page.press(record.replay_open)
    assert record.replay is not None, page.said[-1]
    assert record.replay.speed == 1.0, "real time until another speed is clicked"
    live = console.loop.snapshot
    assert live.speed == 1.0
    page.type_in(record.replay_speed, "5")
    assert record.replay.speed == 5.0
    snap = record.replay.snapshot(live)
    assert snap.speed == 5.0, "the replay's own speed, not the live run's"
    record.update(snap)
    assert "x5" in shown(record.replay_md)
    page.press(_button(page.client.gui, "Play replay"))
    page.type_in(record.goto, 3.0)
    submit(page, _form(page.client.gui, record.goto))
    record.update(record.replay.snapshot(live))  # a frame comes: the typed time stays
    assert record.goto.value == 3.0
    assert record.replay.status().t_s == pytest.approx(3.0, abs=0.1)
    # the dots in words: the pause command at 2 s
    jumps = record.replay.status().jumps
    assert any(text == "pause" for _, text in jumps), jumps
    t_pause = next(t for t, text in jumps if text == "pause")
    page.type_in(record.jump, jump_label(t_pause, "pause"))
    assert record.replay.status().t_s == pytest.approx(t_pause, abs=0.05)
    marks = record.replay_time._impl.props._marks or ()
    assert marks and all(not m.label for m in marks), "dots on the bar, words in the list"
    assert page.sent == [], "nothing went to the loop"
