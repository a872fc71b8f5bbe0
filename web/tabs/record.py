"""The "Record" tab: start and stop the console's recording, and replay a recording in this
browser alone (on its own clock, in its own scope of the scene: the live run and the other
browsers go on), with a scrub bar marked with the recording's events."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from app.console import (
    Console,
    ConsoleError,
    ReplayStatus,
    Snapshot,
    ViewerReplay,
    list_recordings,
    load_replay,
    md_code,
    md_text,
)
from app.console import commands as cmd
from web.widgets import Operator

REPLAY_SPEEDS = ("0.25", "1", "5", "20", "50")
"""A replay's own speeds (the live run keeps its own)."""
NO_JUMP = "(choose an event)"
REPLAY_HELP = (
    "Watch a recording in this browser alone (no token needed): the live run and the other "
    "browsers go on. On the scrub bar the dots are the recording's events (legs, runs, "
    "landings, commands, alarms coming on): *Jump to event* names them."
)


def jump_label(t_s: float, text: str) -> str:
    """An entry of the jump list: '412.3 s: leg 2 (move) started'."""
    return f"{t_s:.1f} s: {text}"


def replay_text(rp: ReplayStatus, speed: float) -> str:
    """Where the replay is on the recording's time axis (the scrub bar's, and *Go to*'s), at
    what speed."""
    state = "playing" if rp.playing else "paused"
    return (
        f"replay {state} at x{speed:g}: {rp.t_s:.1f} s into the recording, which runs "
        f"{rp.start_s:.1f} to {rp.end_s:.1f} s"
        + ("" if rp.complete else " (a recording cut short: its tail read)")
    )


class RecordTab:
    def __init__(self, operator: Operator, console: Console, on_replay: Callable[[], None]) -> None:
        """``on_replay``: called when this browser's replay opens or closes (its camera
        frames the scene anew)."""
        self.operator = operator
        self.console = console
        self.on_replay = on_replay
        self.replay: ViewerReplay | None = None
        """This browser's replay (None: it shows the live run)."""
        self._replay_count = 0
        self._replay_name: str | None = None
        gui, op = operator.gui, operator
        self.record_label = op.guard(gui.add_text("Label", initial_value=""))
        start = op.guard(gui.add_button("Start recording"))
        start.on_click(lambda event: self._on_record(True))
        stop = op.guard(gui.add_button("Stop recording"))
        stop.on_click(lambda event: self._on_record(False))
        self.record_md = gui.add_markdown("")
        with gui.add_folder("Replay") as self.replay_folder:
            gui.add_markdown(REPLAY_HELP)
            self.recordings = gui.add_dropdown("Recording", self._recording_names())
            refresh = gui.add_button("Refresh list")
            refresh.on_click(lambda _: self._refresh_recordings())
            self.replay_open = gui.add_button("Open replay")
            self.replay_open.on_click(self._on_open_replay)
            for label, act in (
                ("Play replay", lambda: self._play_replay(True)),
                ("Pause replay", lambda: self._play_replay(False)),
                ("Close replay", self._close_replay),
            ):
                gui.add_button(label).on_click(self._replay_action(act))
            self.replay_speed = gui.add_button_group("Replay speed", REPLAY_SPEEDS)
            self._speed = 1.0
            """The speed the next replay opened plays at (the last clicked)."""
            self.replay_speed.on_click(self._on_replay_speed)
            self.replay_md = gui.add_markdown("")
            with gui.add_form(None) as goto_form:
                self.goto = gui.add_number("Go to t s", 0.0, step=0.1)
                go = gui.add_button("Go")
            go.on_click(self._replay_action(self._go_to))
            goto_form.on_submit(self._replay_action(self._go_to))
            self.jump = gui.add_dropdown("Jump to event", (NO_JUMP,), initial_value=NO_JUMP)
            self.jump.on_update(self._on_jump)
        self.replay_time: Any = None
        self._replay_jumps: tuple[tuple[float, str], ...] = ()
        self._make_replay_slider(0.0, 1.0, ())  # enters the folder itself

    def _make_replay_slider(
        self, start_s: float, end_s: float, marks: tuple[tuple[float, str], ...]
    ) -> None:
        """The scrub bar, with the recording's events as dots (their words are in "Jump to
        event": labels on a bar this narrow ran into each other); made anew for each replay
        opened."""
        old = self.replay_time
        if old is not None:
            old.remove()
        with self.replay_folder:
            self.replay_time = self.operator.gui.add_slider(
                "Scrub s",
                min=start_s,
                max=max(end_s, start_s + 0.1),
                step=0.1,
                initial_value=start_s,
                marks=tuple(t for t, _ in marks) or None,
            )
        self.replay_time.on_update(self._on_seek_replay)
        self._replay_shown = float(self.replay_time.value)
        """The scrub bar's value as this tab last set it: another value there is a viewer's
        seek on its way to ``_on_seek_replay``, which the frame updates leave alone."""

    # ------------------------------------------------------------------ recording
    def _on_record(self, start: bool) -> None:
        op = self.operator
        if start:
            result = op.run(lambda: cmd.StartRecording(str(self.record_label.value).strip()))
        else:
            result = op.run(cmd.StopRecording)
            self._refresh_recordings()
        if result:
            self.record_md.content = md_code(result["name"])

    def _recording_names(self) -> tuple[str, ...]:
        names = tuple(r["name"] for r in list_recordings(self.console.settings.recordings_dir))
        return names or ("(none)",)

    def _refresh_recordings(self) -> None:
        names = self._recording_names()
        self.recordings.options = names
        if self.recordings.value not in names:
            self.recordings.value = names[0]  # type: ignore[misc]  # settable at run time

    # ------------------------------------------------------------------ replay
    def _on_open_replay(self, event: Any) -> None:
        name = str(self.recordings.value)
        say = self.operator.say
        say(f"opening {md_text(name)}...")
        try:
            data = load_replay(self.console.settings.recordings_dir, name)
            self._replay_count += 1
            replay = ViewerReplay(
                name, data, self.console.loop.snapshot, self._replay_count, self._speed
            )
        except (ConsoleError, FileNotFoundError, ValueError) as err:
            say(f"**error**: {md_text(err)}")
            return
        self.replay = replay  # the publisher thread draws it from its next frame
        self.on_replay()
        say(f"replay of {md_code(name)} in this browser; the live run goes on")

    def _replay_action(self, act: Callable[[], None]) -> Callable[[Any], None]:
        """A replay control: acts on this browser's replay only (the live run and the other
        browsers are not touched, so nothing goes to the loop and no token is needed)."""

        def clicked(event: Any) -> None:
            if event.client is None:
                return
            if self.replay is None:
                self.operator.say("**error**: no replay is open (choose a recording, Open)")
                return
            try:
                act()
            except (ConsoleError, ValueError) as err:
                self.operator.say(f"**error**: {md_text(err)}")

        return clicked

    def _on_replay_speed(self, event: Any) -> None:
        """The speed clicked, for the replay open and the next ones (a button group's value
        is its last click, and the first option before any: the speed is kept here, 1x until
        one is clicked)."""
        if event.client is None:
            return
        self._speed = float(self.replay_speed.value)
        if self.replay is not None:
            self.replay.set_speed(self._speed)
        self.operator.say(f"replays play at x{self._speed:g}")

    def _play_replay(self, playing: bool) -> None:
        if self.replay is not None:
            self.replay.play(playing)
            self.operator.say("")

    def _close_replay(self) -> None:
        self.replay = None  # the publisher thread removes its scene
        self.on_replay()
        self.operator.say("replay closed: live")

    def _go_to(self) -> None:
        """Seek to the typed time (playing or not: the frames never write over this box)."""
        if self.replay is not None:
            self.replay.seek(float(self.goto.value))

    def _jump_label(self, t_s: float, text: str) -> str:
        """A jump list entry on the run's own clock, as the status line shows it."""
        replay = self.replay
        return jump_label(t_s if replay is None else replay.run_time_s(t_s), text)

    def _on_jump(self, event: Any) -> None:
        if event.client is None or self.replay is None:
            return
        picked = str(self.jump.value)
        for t, text in self._replay_jumps:
            if self._jump_label(t, text) == picked:
                self.replay.seek(t)
                return

    def _on_seek_replay(self, event: Any) -> None:
        replay = self.replay
        value = float(self.replay_time.value)
        try:
            if event.client is None or replay is None:
                return
            replay.seek(value)
        except ConsoleError as err:
            self.operator.say(f"**error**: {md_text(err)}")
        finally:
            self._replay_shown = value  # the bar follows the replay again

    def update(self, snap: Snapshot) -> None:
        """The scrub bar follows the replay this browser shows (``snap``)."""
        rp = snap.replay if snap.source == "replay" else None
        if rp is None:
            self._replay_name = None
            if self.replay_md.content:
                self.replay_md.content = ""
            return
        if rp.name != self._replay_name:
            self._replay_name = rp.name
            self._make_replay_slider(rp.start_s, rp.end_s, rp.marks)
            self._replay_jumps = rp.jumps
            options = (NO_JUMP, *(self._jump_label(t, text) for t, text in rp.jumps))
            self.jump.options = options
            self.jump.value = NO_JUMP  # type: ignore[misc]  # settable at run time
        text = replay_text(rp, snap.speed)
        if self.replay_md.content != text:
            self.replay_md.content = text
        value = self.replay_time.value
        if value != self._replay_shown:
            # a viewer moved the bar since this tab last set it and its seek has not run
            # yet: setting the bar now would make that seek go to where the replay already is
            return
        if abs(value - rp.t_s) > 0.05:
            self._replay_shown = round(rp.t_s, 1)
            self.replay_time.value = self._replay_shown
