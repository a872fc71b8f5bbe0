"""The "Record" tab: start and stop the console's recording, and replay a recording in this
browser alone (on its own clock, in its own scope of the scene: the live run and the other
browsers go on), with a scrub bar marked with the recording's events and notes; add a note
(live, or at the scrub bar's time of the replay); compare the replay with a second recording
(its run drawn as a ghost, the table of differences)."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from app.console import (
    CompareError,
    Console,
    ConsoleError,
    Note,
    ReplayStatus,
    SceneInfo,
    Snapshot,
    ViewerReplay,
    add_review_note,
    compare,
    comparison_image,
    list_recordings,
    load_replay,
    md_code,
    md_text,
    notes_of,
    recording_path,
)
from app.console import commands as cmd
from web.ghost import Ghost
from web.review import comparison_markdown, notes_markdown, with_notes
from web.widgets import Operator

ALIGN_AT = {"mission start": "mission", "first contact": "contact", "recordings' start": "start"}
"""Where the page aligns two runs (``app.compare``'s choices, in words)."""

REPLAY_SPEEDS = ("0.25", "1", "5", "20", "50")
"""A replay's own speeds (the live run keeps its own)."""
NO_JUMP = "(choose an event)"
REPLAY_HELP = (
    "Watch a recording in this browser alone (no token needed): the live run and the other "
    "browsers go on. On the scrub bar the dots are the recording's events (legs, runs, "
    "landings, commands, alarms coming on, notes): *Jump to event* names them."
)
NOTES_HELP = (
    "A note marks a moment: what happened ('silt cloud, lost the view'). Live, it is at the "
    "present time, an event of the recording being made; while this browser replays a "
    "recording, it is at the scrub bar's time, kept in a side file beside the recording "
    "(`NAME.mcap.notes.jsonl`: the recording itself is never rewritten). Needs the console "
    "token or the instructor's."
)
NOTE_LOCKED = "locked: enter the console token under Access (or the instructor's token)"
COMPARE_HELP = (
    "Compare the replay (A) with a second recording (B): B's tree and ROV move with the "
    "replay as a translucent purple ghost, the two aligned at the mission's start; the table has "
    "each figure of both runs and the better one."
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
        self.may_note: Callable[[], bool] = lambda: operator.unlocked
        """Whether this browser may add notes: unlocked with the console token (the panel
        adds the instructor's)."""
        self._notes: list[Note] = []
        """The notes of the open replay (its events' and its side file's)."""
        self._notes_changed = False
        self._lock = threading.Lock()
        """Guards the ghost and the notes: callbacks and the publisher thread touch both."""
        self.ghost: Ghost | None = None
        """The compared run's ghost in this browser's scene (None: no comparison)."""
        self._scene_info: SceneInfo | None = None
        gui, op = operator.gui, operator
        self.record_label = op.guard(gui.add_text("Label", initial_value=""))
        start = op.guard(gui.add_button("Start recording"))
        start.on_click(lambda event: self._on_record(True))
        stop = op.guard(gui.add_button("Stop recording"))
        stop.on_click(lambda event: self._on_record(False))
        self.record_md = gui.add_markdown("")
        with gui.add_folder("Notes"):
            gui.add_markdown(NOTES_HELP)
            with gui.add_form(None) as note_form:
                self.note_text = gui.add_text("Note", initial_value="")
                add = gui.add_button("Add note")
            add.on_click(self._on_add_note)
            note_form.on_submit(self._on_add_note)
            self.note_md = gui.add_markdown("")
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
            self.notes_md = gui.add_markdown("")
            with gui.add_folder("Compare"):
                gui.add_markdown(COMPARE_HELP)
                self.compare_with = gui.add_dropdown("Compare with", self._recording_names())
                self.align = gui.add_dropdown(
                    "Align at", tuple(ALIGN_AT), initial_value=next(iter(ALIGN_AT))
                )
                gui.add_button("Compare runs").on_click(self._replay_action(self._compare))
                gui.add_button("Clear comparison").on_click(self._replay_action(self._uncompare))
                self.compare_md = gui.add_markdown("")
                self.compare_plot = gui.add_image(
                    np.full((2, 2, 3), 255, dtype=np.uint8), format="png", visible=False
                )
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
        for dropdown in (self.recordings, self.compare_with):
            dropdown.options = names
            if dropdown.value not in names:
                dropdown.value = names[0]  # type: ignore[misc]  # settable at run time

    # ------------------------------------------------------------------ notes
    def _on_add_note(self, event: Any) -> None:
        """A note: live at the present time (the ``AddNote`` command, through the loop, this
        browser its sender), or at the scrub bar's time of this browser's replay (into the
        recording's side file). A refused note keeps its text, to be corrected."""
        if event.client is None:
            return
        if not self.may_note():
            self._note_said(f"**{md_text(NOTE_LOCKED)}**")
            return
        text = str(self.note_text.value)
        replay = self.replay
        try:
            if replay is None:
                said = self._live_note(text)
            else:
                said = self._review_note(replay, text)
        except (ConsoleError, ValueError, OSError) as err:
            self._note_said(f"**note refused**: {md_text(err)}")
            return
        self.note_text.value = ""  # type: ignore[misc]  # settable at run time
        self._note_said(said)

    def _note_said(self, text: str) -> None:
        self.note_md.content = text
        self.operator.say(text)

    def _live_note(self, text: str) -> str:
        command = cmd.AddNote(text)  # ValueError: empty, too long, control characters
        result = self.console.loop.call_blocking(command, timeout_s=15.0, who=self.operator.who)
        assert isinstance(result, dict)
        where = (
            f"in the recording {md_code(result['recording'])}"
            if result.get("recording")
            else "on the live feed and in the operations log (no recording is being made)"
        )
        return f"note at t = {result['t_s']:.1f} s by {md_text(result['author'])}, {where}"

    def _review_note(self, replay: ViewerReplay, text: str) -> str:
        status = replay.status()
        path = recording_path(self.console.settings.recordings_dir, replay.name)
        note = add_review_note(path, status.t_s, self.operator.who, text, status.end_s)
        with self._lock:
            self._notes = sorted([*self._notes, note], key=lambda n: n.t_s)
            self._notes_changed = True
        return (
            f"note at {replay.run_time_s(note.t_s):.1f} s of {md_code(replay.name)} by "
            f"{md_text(note.author)}, in its side file {md_code(path.name + '.notes.jsonl')}"
        )

    # ------------------------------------------------------------------ compare
    def _compare(self) -> None:
        """Compare this browser's replay (A) with the recording picked (B), aligned where the
        page says: the table, both runs' errors on one time axis, and B drawn as a ghost."""
        replay = self.replay
        if replay is None:
            return
        other = str(self.compare_with.value)
        directory = self.console.settings.recordings_dir
        self.compare_md.content = f"comparing with {md_code(other)}..."
        try:
            c = compare(
                recording_path(directory, replay.name),
                recording_path(directory, other),
                ALIGN_AT.get(str(self.align.value), "mission"),
            )
            plot = comparison_image(c)
        except (CompareError, ConsoleError, ValueError, FileNotFoundError) as err:
            self.compare_md.content = f"**cannot compare**: {md_text(err)}"
            return
        log = c.b.log
        info = self._scene_info
        if log is None or info is None:
            self.compare_md.content = "**cannot compare**: no rows of B, or no scene yet"
            return
        ghost = Ghost(
            self.operator.client.scene,
            info,
            log.t_s,
            log["tree_eta_n"],
            log["rov_eta_n"],
            c.aligned.b_s - c.aligned.a_s,
        )
        with self._lock:
            old, self.ghost = self.ghost, ghost
        if old is not None:
            old.remove()
        self.compare_md.content = comparison_markdown(c)
        self.compare_plot.image = plot
        self.compare_plot.visible = True
        self.operator.say(f"compared with {md_code(other)}: its run is the purple ghost")

    def _uncompare(self) -> None:
        with self._lock:
            old, self.ghost = self.ghost, None
        if old is not None:
            old.remove()
        self.compare_md.content = ""
        self.compare_plot.visible = False

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
            notes = notes_of(
                recording_path(self.console.settings.recordings_dir, name), data.events
            )
        except (ConsoleError, FileNotFoundError, ValueError) as err:
            say(f"**error**: {md_text(err)}")
            return
        with self._lock:
            self._notes = notes
            self._notes_changed = True
        self._uncompare()
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
        self._uncompare()
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
            if self.notes_md.content:
                self.notes_md.content = ""
            if self.ghost is not None:
                self._uncompare()
            return
        self._scene_info = snap.scene
        with self._lock:
            changed, self._notes_changed = self._notes_changed, False
            notes, ghost = list(self._notes), self.ghost
        if rp.name != self._replay_name or changed:
            self._replay_name = rp.name
            marks, jumps = with_notes(rp.marks, rp.jumps, notes, rp.start_s, rp.end_s)
            self._make_replay_slider(rp.start_s, rp.end_s, marks)
            self._replay_jumps = jumps
            options = (NO_JUMP, *(self._jump_label(t, text) for t, text in jumps))
            self.jump.options = options
            self.jump.value = NO_JUMP  # type: ignore[misc]  # settable at run time
            replay = self.replay
            self.notes_md.content = notes_markdown(
                notes, replay.run_time_s if replay is not None else None
            )
        if ghost is not None:
            ghost.show(snap.t_s)  # the replayed run's own clock, as the comparison's
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
