"""The operator's panels, one set per browser (viser client).

Each browser has its own panels (its own camera preset, mission being built, and unlock state)
while all share the scene. Watching needs nothing; every control that changes the run stays
disabled until the console token is entered in "Access". Callbacks run on viser's threads:
they only build a command, hand it to the loop (``ConsoleLoop.call_blocking``) and show the
answer. ``update`` is called by the view's publisher thread with each new snapshot.
"""

from __future__ import annotations

import html
import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import viser

from app.console import (
    MODES,
    SATURATED,
    ConsoleError,
    Gains,
    Snapshot,
    ViewerReplay,
    counters_markdown,
    list_recordings,
    load_replay,
    md_code,
    md_text,
    prepare_run,
    result_markdown,
    station_keeping_mission,
    trainee_view,
)
from app.console import commands as cmd
from missions import schema
from web import geometry as geo
from web.builder_panel import BuilderPanel
from web.instructor_panel import InstructorPanel
from web.scene import SceneView
from web.scores_panel import ScoresPanel
from web.widgets import masked_input_style

if TYPE_CHECKING:
    from app.console import Console

SPEEDS = ("0.25", "0.5", "1", "2", "5", "10", "20", "50")
STATUS_EVERY_S = 0.2
EDIT_HOLD_S = 30.0
"""An input the operator has edited keeps the edit this long before it follows the live value
again (unless its command is sent first)."""
AXES = ("surge", "sway", "yaw")
CAMERAS = ("Overview", "Top-down", "ROV camera", "Follow ROV")
FOLLOWING = ("Overview", "ROV camera", "Follow ROV")
"""Presets that follow the scene each frame (the overview only until the user moves it)."""
CAMERA_SETTLE_S = 1.5
"""After a preset is pressed (or the first pose is sent), camera reports are not taken for
the user's: the browser may still report the camera it had."""


BarColor = Literal["red", "orange", "blue"]


def _bar_color(utilisation: float) -> BarColor:
    if utilisation >= SATURATED:
        return "red"
    return "orange" if utilisation >= 0.8 else "blue"


class ClientPanel:
    """Panels of one browser."""

    def __init__(
        self, client: viser.ClientHandle, console: Console, shared_scene: SceneView | None = None
    ) -> None:
        self.client = client
        self.shared_scene = shared_scene
        """The scene every browser shares (its nodes are hidden here while a replay shows)."""
        self.replay: ViewerReplay | None = None
        """This browser's replay (None: it shows the live run)."""
        self._replay_scene: SceneView | None = None
        self._replay_count = 0
        self.console = console
        self.gui = client.gui
        self.unlocked = False
        self.camera_mode = "Overview"
        self._camera_pending = True
        self._camera_lock = threading.Lock()
        """Held while a pose is chosen and sent to this browser's camera: a preset pressed (a
        viser callback thread) and the publisher thread's following of the scene each send
        whole poses, one after the other. Interleaved, one's position went out with the
        other's look-at point and up direction (viser carries the look-at along with each
        position it sets), and a page pressed to "Top-down" while its overview was
        following showed the seabed edge-on (CI on a slower machine,
        tests/test_console_replay.py)."""
        self._guarded: list[Any] = []
        self._edited: dict[str, float] = {}
        self._inputs: dict[str, list[Any]] = {}  # the live inputs of each group
        self._put_in: dict[int, Any] = {}  # what this panel last put in each live input
        self.last_error = ""
        """What went wrong with the last command this browser sent ('' when it was done)."""
        self._status_wall = 0.0
        self.updates_sent = {"status": 0}
        """Status-line refreshes made (``benchmarks/page_rates.py`` reads them)."""
        self._scene_version = -1
        self._replay_name: str | None = None
        snap = console.loop.snapshot
        self._build_header()
        tabs = self.gui.add_tab_group()
        with tabs.add_tab("Run"):
            self._build_run()
        with tabs.add_tab("Mission"):
            self._build_missions()
        with tabs.add_tab("Control"):
            self._build_control(snap)
        with tabs.add_tab("Record"):
            self._build_record()
        with tabs.add_tab("Scores"):
            self.scores = ScoresPanel(
                self.gui, console, lambda: str(self.name_text.value), self._any_unlocked
            )
        with tabs.add_tab("Instructor"):
            self.instructor = InstructorPanel(
                self.gui, console, lambda: self.who, self.guess_client
            )
        # not a tab: the plots page redraws whenever it is shown again (its own ResizeObserver)
        with self.gui.add_folder("Plots", expand_by_default=True):
            self._build_plots()
        self._set_enabled(False)

    # ================================================================== building
    def _build_header(self) -> None:
        gui = self.gui
        self.status_md = gui.add_markdown("starting...")
        self.readout_md = gui.add_markdown("")
        self.alarms_html = gui.add_html("")
        self.message_md = gui.add_markdown("")
        with gui.add_folder("View"):
            self.camera_buttons = gui.add_button_group("Camera", CAMERAS)
            self.camera_buttons.on_click(self._on_camera)
            self.camera_md = gui.add_markdown("")
        self._camera_sent = geo.CameraEchoes()
        self._camera_settle = 0.0
        self.client.camera.on_update(self._on_camera_moved)
        with gui.add_folder("Access", expand_by_default=True):
            self.name_text = gui.add_text(
                "Your name", initial_value="", hint="shown in the operations log beside what you do"
            )
            self.token_text = gui.add_text("Token", initial_value="")
            gui.add_html(masked_input_style(self.token_text))
            self.unlock_button = gui.add_button("Unlock controls")
            self.unlock_button.on_click(self._on_unlock)
            self.lock_button = gui.add_button("Lock controls", visible=False)
            self.lock_button.on_click(self._on_lock)
        with gui.add_folder("Operations log", expand_by_default=False):
            self.operations_md = gui.add_markdown("*nothing done yet*")
        with gui.add_folder("Thrusters") as self.thruster_folder:
            self.thruster_md = gui.add_markdown("")
        self.bars: list[Any] = []
        self._make_bars(self.console.loop.snapshot.scene.n_thrusters)

    def _make_bars(self, n: int) -> None:
        """One bar a thruster (the ROV of a new set-up may have another number of them)."""
        for bar in self.bars:
            bar.remove()
        with self.thruster_folder:
            self.bars = [self.gui.add_progress_bar(0.0, color="blue") for _ in range(n)]

    def _guard(self, handle: Any) -> Any:
        """A control that needs the token."""
        self._guarded.append(handle)
        return handle

    def _live_input(self, group: str, handle: Any) -> Any:
        """An input (guarded) that shows the live value of ``group`` until the operator edits
        it; it follows the live value again ``EDIT_HOLD_S`` after the last edit or once the
        group's command has been sent."""

        def edited(event: Any) -> None:
            if event.client is not None:
                self._edited[group] = time.monotonic()

        handle.on_update(edited)
        self._inputs.setdefault(group, []).append(handle)
        self._put_in[id(handle)] = handle.value
        return self._guard(handle)

    def _editing(self, group: str) -> bool:
        return time.monotonic() - self._edited.get(group, -math.inf) < EDIT_HOLD_S

    def _follow(self, group: str, live: Sequence[tuple[Any, Any]]) -> None:
        """Show the live values (input, value) in a group's inputs unless the operator is
        editing them. An input that holds neither what this panel last showed in it was typed
        in by a viewer whose edit callback has not run yet (viser sets the value, then queues
        the callbacks on its thread pool, which under load lags by seconds): an edit as well,
        not something to write over."""
        if self._editing(group):
            return
        if any(h.value != self._put_in[id(h)] for h, _ in live):
            self._edited[group] = time.monotonic()
            return
        for handle, value in live:
            if handle.value != value:
                handle.value = value
            self._put_in[id(handle)] = handle.value

    def _build_run(self) -> None:
        gui = self.gui
        self._action(self._guard(gui.add_button("Pause")), cmd.Pause)
        self._action(self._guard(gui.add_button("Resume")), cmd.Resume)
        self._action(self._guard(gui.add_button("Step 0.1 s")), lambda: cmd.Step(10))
        self.speed = self._guard(gui.add_dropdown("Speed (x real time)", SPEEDS, initial_value="1"))
        self.speed.on_update(self._on_speed)
        self.reset_button = self._guard(gui.add_button("Reset to station keeping"))
        self.reset_button.on_click(self._on_reset)
        snap = self.console.loop.snapshot
        goal = snap.target or snap.eta_ref
        with gui.add_folder("Target (no mission)"):
            self.target_n = self._live_input(
                "target", gui.add_number("Target north m", round(goal[0], 2), step=0.1)
            )
            self.target_e = self._live_input(
                "target", gui.add_number("Target east m", round(goal[1], 2), step=0.1)
            )
            self.target_psi = self._live_input(
                "target",
                gui.add_number("Target heading deg", round(math.degrees(goal[2]), 1), step=1.0),
            )
            self._action(
                self._guard(gui.add_button("Go to target")),
                lambda: cmd.SetTarget(
                    float(self.target_n.value),
                    float(self.target_e.value),
                    float(self.target_psi.value),
                ),
                done="target",
            )

    def _build_missions(self) -> None:
        gui = self.gui
        library, uploaded = self.console.mission_names()
        names = tuple(library + uploaded) or ("(none)",)
        self.mission_pick = gui.add_dropdown("Mission", names, initial_value=names[0])
        self.mission_start = self._guard(gui.add_button("Start mission"))
        self.mission_start.on_click(self._on_start_library)
        self._action(self._guard(gui.add_button("Abort mission", color="red")), cmd.AbortMission)
        self.mission_md = gui.add_markdown("")
        self.counters_md = gui.add_markdown("")
        with gui.add_folder("Mission builder"):
            self.builder = BuilderPanel(
                self.client,
                self.console,
                self._guard,
                self._start,
                lambda: self.unlocked,
                (self.mission_pick,),
            )

    def _build_control(self, snap: Snapshot) -> None:
        gui = self.gui
        self.mode = self._guard(gui.add_dropdown("Mode", MODES, initial_value=snap.mode))
        self.mode.on_update(self._when_client(lambda: cmd.SetMode(self.mode.value)))
        self.allocation = self._guard(
            gui.add_dropdown(
                "Allocation",
                ("pinv", "priority", "qp"),
                initial_value=snap.allocation or "priority",
            )
        )
        self.allocation.on_update(
            self._when_client(lambda: cmd.SetAllocation(self.allocation.value))
        )
        self.grip = self._guard(gui.add_checkbox("Grip", bool(snap.grip)))
        self.grip.on_update(self._when_client(lambda: cmd.SetGrip(bool(self.grip.value))))
        with gui.add_folder("Gains"):
            preset = snap.scene.preset_gains
            live = snap.gains or preset
            self.gain_md = gui.add_markdown(_gain_band_text(preset))
            self.gain_rows = {
                term: self._live_input(
                    "gains",
                    gui.add_text(
                        f"{term} [surge, sway, yaw]",
                        _gain_row_text(getattr(live, term)),
                        hint=f"three numbers, each within its band (see above); {term} of "
                        "the parameter set: " + _gain_row_text(getattr(preset, term)),
                    ),
                )
                for term in ("kp", "ki", "kd")
            }
            self._action(self._guard(gui.add_button("Apply gains")), self._typed_gains, "gains")
            self._action(
                self._guard(gui.add_button("Preset gains")),
                lambda: cmd.SetGains(self.console.loop.snapshot.scene.preset_gains),
                done="gains",
            )
        with gui.add_folder("Current"):
            self.current_speed = self._live_input(
                "current",
                gui.add_number(
                    "Speed m/s", round(snap.current_speed_mps, 3), min=0.0, max=3.0, step=0.01
                ),
            )
            self.current_dir = self._live_input(
                "current",
                gui.add_number(
                    "Towards deg",
                    round(math.degrees(snap.current_direction_rad), 1),
                    min=-360.0,
                    max=360.0,
                    step=1.0,
                ),
            )
            self._action(
                self._guard(gui.add_button("Set current")),
                lambda: cmd.SetCurrent(
                    float(self.current_speed.value), float(self.current_dir.value)
                ),
                done="current",
            )
        with gui.add_folder("Vessel (crane tip)"):
            ct = snap.crane_tip_n
            self.vessel_n = self._live_input(
                "vessel",
                gui.add_number("North m", round(ct[0], 2), min=-1000.0, max=1000.0, step=0.1),
            )
            self.vessel_e = self._live_input(
                "vessel",
                gui.add_number("East m", round(ct[1], 2), min=-1000.0, max=1000.0, step=0.1),
            )
            self._action(
                self._guard(gui.add_button("Move vessel")),
                lambda: cmd.MoveVessel(float(self.vessel_n.value), float(self.vessel_e.value), 0.5),
                done="vessel",
            )

    def _build_plots(self) -> None:
        """The plots page of the console's HTTP API (``app.api.plots``) in an iframe: viser's
        uPlot handle re-sends its whole data at each assignment (no append), 48 kB/s for two
        updates a second; the page gets the window once, then only the new rows."""
        settings = self.console.settings
        host = settings.host
        if host in ("0.0.0.0", "::"):  # a wildcard bind: the loopback name on this machine
            host = "127.0.0.1"
        host = f"[{host}]" if ":" in host else host
        self.plots_url = f"http://{host}:{settings.port}/plots?viewer={self.client.client_id}"
        self.plots_html = self.gui.add_html(
            f'<iframe src="{self.plots_url}" title="plots" '
            'style="width:100%;height:530px;border:0;display:block"></iframe>'
            f'<a href="{self.plots_url}" target="_blank" rel="noopener" '
            'style="font-size:12px">open the plots in their own tab</a>'
        )

    def _build_record(self) -> None:
        gui = self.gui
        self.record_label = self._guard(gui.add_text("Label", initial_value=""))
        start = self._guard(gui.add_button("Start recording"))
        start.on_click(lambda event: self._on_record(True))
        stop = self._guard(gui.add_button("Stop recording"))
        stop.on_click(lambda event: self._on_record(False))
        self.record_md = gui.add_markdown("")
        with gui.add_folder("Replay") as self.replay_folder:
            self.recordings = gui.add_dropdown("Recording", self._recording_names())
            refresh = gui.add_button("Refresh list")
            refresh.on_click(lambda _: self._refresh_recordings())
            self.replay_open = self._guard(gui.add_button("Open replay"))
            self.replay_open.on_click(self._on_open_replay)
            for label, act in (
                ("Play replay", lambda: self._play_replay(True)),
                ("Pause replay", lambda: self._play_replay(False)),
                ("Close replay", self._close_replay),
            ):
                self._guard(gui.add_button(label)).on_click(self._replay_action(act))
        self._make_replay_slider(0.0, 1.0, ())  # enters the folder itself

    def _make_replay_slider(
        self, start_s: float, end_s: float, marks: tuple[tuple[float, str], ...]
    ) -> None:
        """The scrub bar, with the recording's events as marks (legs, runs, landings named;
        commands and alarms as ticks); made anew for each replay opened."""
        old = getattr(self, "replay_time", None)
        if old is not None:
            self._guarded = [h for h in self._guarded if h is not old]
            old.remove()
        with self.replay_folder:
            self.replay_time = self._guard(
                self.gui.add_slider(
                    "Replay time s",
                    min=start_s,
                    max=max(end_s, start_s + 0.1),
                    step=0.1,
                    initial_value=start_s,
                    marks=tuple((t, label) if label else t for t, label in marks) or None,
                )
            )
        self.replay_time.disabled = not self.unlocked
        self.replay_time.on_update(self._on_seek_replay)
        self._replay_shown = float(self.replay_time.value)
        """The scrub bar's value as this panel last set it: another value there is a viewer's
        seek on its way to ``_on_seek_replay``, which the frame updates leave alone."""

    # ================================================================== callbacks
    def _set_enabled(self, enabled: bool) -> None:
        for handle in self._guarded:
            handle.disabled = not enabled

    def _say(self, text: str) -> None:
        self.message_md.content = text

    def _run(self, make: Callable[[], Any]) -> Any:
        """Build a command and have the loop apply it; show the outcome."""
        self.last_error = ""
        if not self.unlocked:
            self.last_error = "locked: enter the console token under Access"
            self._say(f"**{md_text(self.last_error)}**")
            return None
        try:
            result = self.console.loop.call_blocking(make(), timeout_s=15.0, who=self.who)
        except (ConsoleError, ValueError, FileNotFoundError, KeyError) as err:
            self.last_error = str(err)
        except Exception as err:
            self.last_error = f"{type(err).__name__}: {err}"
        if self.last_error:
            self._say(f"**error**: {md_text(self.last_error)}")
            return None
        self._say("")
        return result

    def _action(self, button: Any, make: Callable[[], Any], done: str | None = None) -> None:
        """A button that runs a command; ``done``: the input group it sends, which follows
        the live value again once sent."""

        feedback = self.gui.add_markdown("") if done is not None else None

        def clicked(event: Any) -> None:
            if event.client is None:
                return
            self._run(make)
            if done is None or feedback is None:
                return
            if self.last_error:  # the typed values stay, to be corrected
                feedback.content = f"**not applied**: {md_text(self.last_error)}"
            else:
                feedback.content = ""
                self._edited.pop(done, None)
                for handle in self._inputs.get(done, ()):  # sent: live values again
                    self._put_in[id(handle)] = handle.value

        button.on_click(clicked)

    def _when_client(self, make: Callable[[], Any]) -> Callable[[Any], None]:
        """An input callback that acts on what the operator did, not on our own updates."""

        def callback(event: Any) -> None:
            if event.client is not None:
                self._run(make)

        return callback

    def _on_unlock(self, event: Any) -> None:
        # counted per browser: one viewer's wrong tokens lock that viewer out, not the others
        ok, wait = self.console.check_token(str(self.token_text.value).strip(), self.guess_client)
        self.token_text.value = ""  # type: ignore[misc]  # the token does not stay on the page
        if ok:
            self.unlocked = True
            self._set_enabled(True)
            self.unlock_button.visible = False
            self.lock_button.visible = True
            self._say("controls unlocked")
        elif wait > 0.0:
            self._say(f"**too many wrong tokens**: try again in {wait:.0f} s")
        else:
            self._say("**wrong token**")

    def _on_lock(self, event: Any) -> None:
        self.unlocked = False
        self._set_enabled(False)
        self.lock_button.visible = False
        self.unlock_button.visible = True
        self._say("controls locked")

    def _any_unlocked(self) -> bool:
        """Unlocked with the console token or the instructor's."""
        return self.unlocked or self.instructor.unlocked

    @property
    def guess_client(self) -> str:
        """Whom this browser's wrong tokens count against: itself."""
        return f"view:{self.client.client_id}"

    @property
    def who(self) -> str:
        """This browser in the operations log: 'viewer 3 (Anna)'."""
        name = " ".join(str(self.name_text.value).split())[:40]
        return f"viewer {self.client.client_id}" + (f" ({name})" if name else "")

    def _on_camera(self, event: Any) -> None:
        with self._camera_lock:
            self.camera_mode = str(self.camera_buttons.value)
            self._camera_pending = True
            self._camera_settle = time.monotonic() + CAMERA_SETTLE_S
            self.camera_md.content = ""
            self._apply_camera(self.console.loop.snapshot)

    def _on_camera_moved(self, camera: viser.CameraHandle) -> None:
        """The browser reports its camera: one that matches none of the poses sent lately
        was moved by the user, and the overview stops following until a preset is pressed."""
        if self.camera_mode != "Overview" or not self._camera_pending or not self._camera_sent:
            return
        if time.monotonic() < self._camera_settle:
            return  # reports of the camera the browser had before
        if not self._camera_sent.is_echo(np.asarray(camera.position), np.asarray(camera.look_at)):
            self._camera_pending = False
            self.camera_md.content = "camera moved by hand: press Overview to follow again"

    def _on_speed(self, event: Any) -> None:
        if event.client is not None:
            self._run(lambda: cmd.SetSpeed(float(self.speed.value)))

    def _on_reset(self, event: Any) -> None:
        snap = self.console.loop.snapshot

        mission = station_keeping_mission(snap.scene.params_name, self.console.settings.depth_m)
        self._start(mission, run_legs=False)

    def _start(self, mission: schema.Mission, run_legs: bool = True) -> None:
        if not self.unlocked:
            self._say("**locked**: enter the console token under Access")
            return
        self._say(f"building {md_text(mission.name)}...")
        try:
            run = prepare_run(mission, run_legs)
        except ValueError as err:
            self._say(f"**error**: {md_text(err)}")
            return
        self._run(lambda: cmd.StartRun(run))

    def _on_start_library(self, event: Any) -> None:
        try:
            mission = self.console.find_mission(str(self.mission_pick.value))
        except (KeyError, ValueError) as err:
            self._say(f"**error**: {md_text(err)}")
            return
        self._start(mission)

    def _typed_gains(self) -> cmd.SetGains:
        """The gains typed in the three rows; ValueError naming the row and entry."""
        rows = {
            term: _parse_gain_row(term, str(handle.value))
            for term, handle in self.gain_rows.items()
        }
        cmd.check_gain_band(rows, self.console.loop.snapshot.scene.preset_gains)
        return cmd.SetGains(Gains.of(rows["kp"], rows["ki"], rows["kd"]))

    def _on_record(self, start: bool) -> None:
        if start:
            result = self._run(lambda: cmd.StartRecording(str(self.record_label.value).strip()))
        else:
            result = self._run(cmd.StopRecording)
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

    def _on_open_replay(self, event: Any) -> None:
        name = str(self.recordings.value)
        if not self.unlocked:
            self._say("**locked**: enter the console token under Access")
            return
        self._say(f"opening {md_text(name)}...")
        try:
            data = load_replay(self.console.settings.recordings_dir, name)
            self._replay_count += 1
            replay = ViewerReplay(name, data, self.console.loop.snapshot, self._replay_count)
        except (ConsoleError, FileNotFoundError, ValueError) as err:
            self._say(f"**error**: {md_text(err)}")
            return
        self.replay = replay  # the publisher thread draws it from its next frame
        self._camera_pending = True
        self._say(f"replay of {md_code(name)} in this browser; the live run goes on")

    def _replay_action(self, act: Callable[[], None]) -> Callable[[Any], None]:
        """A replay button: acts on this browser's replay only (the live run and the other
        browsers are not touched, so nothing goes to the loop)."""

        def clicked(event: Any) -> None:
            if event.client is None:
                return
            if not self.unlocked:
                self._say("**locked**: enter the console token under Access")
                return
            if self.replay is None:
                self._say("**error**: no replay is open")
                return
            act()

        return clicked

    def _play_replay(self, playing: bool) -> None:
        if self.replay is not None:
            self.replay.play(playing)
            self._say("")

    def _close_replay(self) -> None:
        self.replay = None  # the publisher thread removes its scene
        self._camera_pending = True
        self._say("replay closed: live")

    def _on_seek_replay(self, event: Any) -> None:
        replay = self.replay
        value = float(self.replay_time.value)
        try:
            if event.client is None or replay is None or not self.unlocked:
                return
            replay.seek(value)
        except ConsoleError as err:
            self._say(f"**error**: {md_text(err)}")
        finally:
            self._replay_shown = value  # the bar follows the replay again

    # ================================================================== updates
    def _apply_camera(self, snap: Snapshot) -> None:
        """Send the pose of the present camera preset (call with ``_camera_lock`` held)."""
        info = snap.scene
        size = max(info.tree_dimensions_m)
        tree = np.array(snap.tree_eta_n)
        frame = info.frame
        if self.camera_mode == "Top-down":
            pose = geo.top_down_camera(frame.center_n, frame.landing_depth_m, tree, size)
        elif self.camera_mode == "ROV camera":
            posts = frame.post_positions_n(info.layout)
            tops = np.column_stack(
                [posts, np.full(len(posts), frame.post_top_depth_m(info.layout))]
            )
            pose = geo.rov_camera(
                np.array(snap.rov_eta_n),
                np.array(info.rov_dimensions_m),
                tree,
                info.tree_dimensions_m[2],
                tops,
            )
        elif self.camera_mode == "Follow ROV":
            pose = geo.follow_rov_camera(
                np.array(snap.rov_eta_n), np.array(info.rov_dimensions_m), size
            )
        else:
            pose = geo.overview_camera(
                tree, size, np.array([*frame.center_n, frame.landing_depth_m])
            )
        cam = self.client.camera
        fov = geo.ROV_CAMERA_FOV_RAD if self.camera_mode == "ROV camera" else geo.OVERVIEW_FOV_RAD
        try:
            # setting the position carries the look-at point along before it is set: the
            # browser may report that in-between pose too
            between = cam.look_at + (pose.position_n - cam.position)
            with self.client.atomic():
                cam.up_direction = pose.up_n
                cam.position = pose.position_n
                cam.look_at = pose.look_at_n
                cam.fov = float(fov)
        except AssertionError:
            return  # the browser has not reported its camera yet: try again next frame
        # the poses sent lately, to tell the browser's echoes of them from a camera the user
        # moved (the in-between pose and the pose itself)
        now = time.monotonic()
        if not self._camera_sent:
            self._camera_settle = now + CAMERA_SETTLE_S
        self._camera_sent.sent(pose.position_n, between, now)
        self._camera_sent.sent(pose.position_n, pose.look_at_n, now)
        self._camera_pending = self.camera_mode in FOLLOWING

    def update(self, snap: Snapshot) -> None:
        """Refresh from a snapshot (the publisher thread): the live one, or this browser's
        replay drawn in its own scene (the inputs follow the live run either way)."""
        view = self._shown(snap)
        with self._camera_lock:
            if self._camera_pending:
                self._apply_camera(view)
        now = time.monotonic()
        if now >= self._status_wall:
            self._status_wall = _next_due(self._status_wall, STATUS_EVERY_S, now)
            self._update_status(view, snap)
            self.updates_sent["status"] += 1

    def _shown(self, live: Snapshot) -> Snapshot:
        """What this browser shows: its replay (drawn in its own scope of the scene, which
        hides the shared nodes for it alone) or the live run (its own scope cleared)."""
        replay = self.replay
        if replay is None:
            if self._replay_scene is not None:
                self._replay_scene.clear()
                self._replay_scene = None
            return live
        view = replay.snapshot(live)
        if self._replay_scene is None and self.shared_scene is not None:
            self._replay_scene = SceneView(self.shared_scene.server, self.client)
        if self._replay_scene is not None:
            self._replay_scene.update(view)
            if self.shared_scene is not None:
                self._replay_scene.hide(self.shared_scene.names())
        return view

    def _update_status(self, snap: Snapshot, live: Snapshot | None = None) -> None:
        live = snap if live is None else live
        tree = snap.tree_eta_n
        m = snap.mission
        leg = f"leg {m.leg_index}/{m.legs_total} {m.leg_type}" if m.leg_index else ""
        state = "paused" if snap.paused else f"running x{snap.speed:g}"
        replaying = snap.source == "replay" and snap.replay is not None
        source = f"REPLAY {md_code(snap.replay.name)}" if replaying and snap.replay else "live"
        text = (
            f"**{source}** t = {snap.t_s:8.1f} s, {state}  \n"
            + (f"live run goes on: t = {live.t_s:.1f} s  \n" if replaying else "")
            + f"tree N {tree[0]:.2f} m, E {tree[1]:.2f} m, heading "
            f"{math.degrees(tree[5]):.1f} deg, mode {snap.mode}  \n"
            f"mission: {md_text(m.name or '-')} ({m.state}) {md_text(leg)}"
            + (f"  \n**{md_text(snap.error)}**" if snap.error else "")
            + (f"  \nrecording {md_code(snap.recording)}" if snap.recording else "")
        )
        if self.status_md.content != text:
            self.status_md.content = text
        self._update_readout(snap)
        badges = "".join(
            f"<span style='display:inline-block;margin:1px;padding:1px 5px;border-radius:4px;"
            f"color:white;background:{'#c0392b' if a.active else '#27ae60'}' "
            f"title='{html.escape(a.message)}'>{html.escape(a.name)}</span>"
            for a in snap.alarms
        )
        active = html.escape("; ".join(f"{a.name}: {a.message}" for a in snap.active_alarms))
        badges_html = f"<div>{badges}</div>" + (
            f"<div style='color:#c0392b'>{active}</div>" if active else ""
        )
        if self.alarms_html.content != badges_html:
            self.alarms_html.content = badges_html
        self._update_thrusters(snap)
        self._update_controls(live)
        self._update_replay(snap)
        ops = _operations_text(snap)
        if self.operations_md.content != ops:
            self.operations_md.content = ops
        self.instructor.update(snap)

    def _update_readout(self, snap: Snapshot) -> None:
        """Height over the post tops, distance and heading error to the frame, wire tension."""
        info = snap.scene
        readout = geo.pilot_readout(
            np.array(snap.tree_eta_n),
            info.tree_dimensions_m[2],
            info.frame.center_n,
            info.frame.heading_rad,
            info.frame.post_top_depth_m(info.layout),
            snap.wire_tension_newton,
        )
        text = geo.readout_markdown(readout)
        if self.readout_md.content != text:
            self.readout_md.content = text

    def _update_thrusters(self, snap: Snapshot) -> None:
        util = snap.thruster_utilisation
        if len(self.bars) != len(util):
            self._make_bars(len(util))
        for bar, u in zip(self.bars, util, strict=False):
            value = round(100.0 * min(max(u, 0.0), 1.0), 1)
            if bar.value != value:
                bar.value = value
            color = _bar_color(u)
            if bar.color != color:
                bar.color = color
        text = " | ".join(f"T{i + 1} {100 * u:.0f}%" for i, u in enumerate(util))
        if self.thruster_md.content != text:
            self.thruster_md.content = text

    def _update_controls(self, snap: Snapshot) -> None:
        """Keep inputs in step with changes made elsewhere (API, missions, other browsers)."""
        if snap.gains is not None:
            self._follow(
                "gains",
                [
                    (handle, _gain_row_text(getattr(snap.gains, term)))
                    for term, handle in self.gain_rows.items()
                ],
            )
            band = _gain_band_text(snap.scene.preset_gains)
            if self.gain_md.content != band:
                self.gain_md.content = band
        if snap.mode != self.mode.value:
            self.mode.value = snap.mode
        if snap.allocation and snap.allocation != self.allocation.value:
            self.allocation.value = snap.allocation
        if snap.grip is not None and snap.grip != self.grip.value:
            self.grip.value = snap.grip
        self._follow_live_inputs(snap)
        speed = f"{snap.speed:g}"
        if speed in SPEEDS and speed != self.speed.value:
            self.speed.value = speed
        text = _mission_text(snap)
        if self.mission_md.content != text:
            self.mission_md.content = text
        counters = counters_markdown(snap.quality_counters)
        if self.counters_md.content != counters:
            self.counters_md.content = counters
        self.builder.update(snap)

    def _follow_live_inputs(self, snap: Snapshot) -> None:
        """Inputs the operator is not editing show the live values."""
        goal = snap.target or snap.eta_ref
        live = {
            "target": (
                (self.target_n, round(goal[0], 2)),
                (self.target_e, round(goal[1], 2)),
                (self.target_psi, round(math.degrees(goal[2]), 1)),
            ),
            "current": (
                (self.current_speed, round(snap.current_speed_mps, 3)),
                (self.current_dir, round(math.degrees(snap.current_direction_rad), 1)),
            ),
            "vessel": (
                (self.vessel_n, round(snap.crane_tip_n[0], 2)),
                (self.vessel_e, round(snap.crane_tip_n[1], 2)),
            ),
        }
        for group, pairs in live.items():
            self._follow(group, pairs)

    def _update_replay(self, snap: Snapshot) -> None:
        rp = snap.replay if snap.source == "replay" else None
        if rp is None:
            self._replay_name = None
            return
        if rp.name != self._replay_name:
            self._replay_name = rp.name
            self._make_replay_slider(rp.start_s, rp.end_s, rp.marks)
        value = self.replay_time.value
        if value != self._replay_shown:
            # a viewer moved the bar since this panel last set it and its seek has not run
            # yet: setting the bar now would make that seek go to where the replay already is
            return
        if abs(value - rp.t_s) > 0.05:
            self._replay_shown = round(rp.t_s, 1)
            self.replay_time.value = self._replay_shown


def _next_due(due: float, period: float, now: float) -> float:
    """The next time an every-``period`` update is due: one period after the last due time
    (not after now: frames come every 50 ms, and counting from the frame that did the update
    rounded each period up to the next frame, 0.2 s to 0.25 s), or one period from now when
    more than a period behind (no burst of catch-up updates)."""
    due += period
    return due if due > now - period else now + period


def _mission_text(snap: Snapshot) -> str:
    m = snap.mission
    if m.result:
        return result_markdown(m.name, m.state, m.result)
    if m.leg_index:
        return (
            f"**{md_text(m.name)}**: leg {m.leg_index}/{m.legs_total} {md_code(m.leg_type)} "
            f"{md_text(m.leg_name or '')}"
        )
    return f"{md_text(m.name or 'no mission')} ({m.state})"


def _operations_text(snap: Snapshot) -> str:
    """The latest operations, newest first: time, who, what, outcome (a trainee's view: the
    instructor's commands are left out, ``trainee_view``)."""
    operations = trainee_view(snap.operations)
    if not operations:
        return "*nothing done yet*"
    lines = [
        f"- {op.utc[11:19]} (t {op.t_s:.1f} s) **{md_text(op.who)}**: {md_text(op.action)} "
        f"- {md_text(op.outcome)}"
        for op in reversed(operations[-10:])
    ]
    return "\n".join(lines)


def _gain_row_text(values: tuple[float, ...]) -> str:
    return ", ".join(f"{v:g}" for v in values)


def _gain_band_text(preset: Gains) -> str:
    """The band each gain may be set in (commands.gain_band), as a small table."""
    lines = ["| band | surge | sway | yaw |", "|---|---|---|---|"]
    for term in ("kp", "ki", "kd"):
        cells = " | ".join(f"0 - {cmd.gain_band(v):g}" for v in getattr(preset, term))
        lines.append(f"| {term} | {cells} |")
    return "\n".join(lines)


def _parse_gain_row(term: str, text: str) -> tuple[float, float, float]:
    """'2000, 2000, 5000' -> three floats; ValueError naming the gain when an entry is not a
    number or the row does not have three."""
    parts = [p.strip() for p in text.replace(";", ",").split(",")]
    if len(parts) != 3:
        raise ValueError(
            f"{term}: give three numbers (surge, sway, yaw) separated by commas, got {text!r}"
        )
    out = []
    for axis, part in zip(cmd.AXIS_NAMES, parts, strict=True):
        try:
            out.append(float(part))
        except ValueError:
            raise ValueError(f"gain {term} {axis}: {part!r} is not a number") from None
    return out[0], out[1], out[2]
