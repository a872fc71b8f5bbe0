"""The operator's panels, one set per browser (viser client).

Each browser has its own panels (its own camera preset, mission being built, and unlock state)
while all share the scene. Watching needs nothing; every control that changes the run stays
disabled until the console token is entered in "Access". Callbacks run on viser's threads:
they only build a command, hand it to the loop (``ConsoleLoop.call_blocking``) and show the
answer. ``update`` is called by the view's publisher thread with each new snapshot.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import viser

from app.console import (
    SATURATED,
    ConsoleError,
    Gains,
    Snapshot,
    list_recordings,
    load_replay,
    prepare_run,
    station_keeping_mission,
)
from app.console import commands as cmd
from missions import schema
from web import geometry as geo
from web.builder_panel import BuilderPanel

if TYPE_CHECKING:
    from app.console import Console

SPEEDS = ("0.25", "0.5", "1", "2", "5", "10", "20", "50")
STATUS_EVERY_S = 0.2
PLOTS_EVERY_S = 0.5
PLOT_WINDOW_S = 120.0
GAIN_RANGE_FACTOR = 4.0
"""Gain sliders run from 0 to this many times the parameter set's gain (a safe band)."""
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

    def __init__(self, client: viser.ClientHandle, console: Console) -> None:
        self.client = client
        self.console = console
        self.gui = client.gui
        self.unlocked = False
        self.camera_mode = "Overview"
        self._camera_pending = True
        self._guarded: list[Any] = []
        self._status_wall = 0.0
        self._plots_wall = 0.0
        self._gain_touch = 0.0
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
        with tabs.add_tab("Plots"):
            self._build_plots()
        with tabs.add_tab("Record"):
            self._build_record()
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
        self._camera_sent: list[tuple[np.ndarray, np.ndarray]] = []
        self._camera_settle = 0.0
        self.client.camera.on_update(self._on_camera_moved)
        with gui.add_folder("Access", expand_by_default=True):
            self.token_text = gui.add_text("Token", initial_value="")
            self.unlock_button = gui.add_button("Unlock controls")
            self.unlock_button.on_click(self._on_unlock)
        with gui.add_folder("Thrusters"):
            self.thruster_md = gui.add_markdown("")
            n = self.console.loop.snapshot.scene.n_thrusters
            self.bars = [gui.add_progress_bar(0.0, color="blue") for _ in range(n)]

    def _guard(self, handle: Any) -> Any:
        """A control that needs the token."""
        self._guarded.append(handle)
        return handle

    def _build_run(self) -> None:
        gui = self.gui
        self._action(self._guard(gui.add_button("Pause")), cmd.Pause)
        self._action(self._guard(gui.add_button("Resume")), cmd.Resume)
        self._action(self._guard(gui.add_button("Step 0.1 s")), lambda: cmd.Step(10))
        self.speed = self._guard(gui.add_dropdown("Speed (x real time)", SPEEDS, initial_value="1"))
        self.speed.on_update(self._on_speed)
        self.reset_button = self._guard(gui.add_button("Reset to station keeping"))
        self.reset_button.on_click(self._on_reset)
        with gui.add_folder("Target (no mission)"):
            self.target_n = self._guard(gui.add_number("Target north m", 0.0, step=0.1))
            self.target_e = self._guard(gui.add_number("Target east m", 0.0, step=0.1))
            self.target_psi = self._guard(gui.add_number("Target heading deg", 0.0, step=1.0))
            self._action(
                self._guard(gui.add_button("Go to target")),
                lambda: cmd.SetTarget(
                    float(self.target_n.value),
                    float(self.target_e.value),
                    float(self.target_psi.value),
                ),
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
        with gui.add_folder("Mission builder"):
            self.builder = BuilderPanel(gui, self.console, self._guard, self._start)

    def _build_control(self, snap: Snapshot) -> None:
        gui = self.gui
        self.mode = self._guard(gui.add_dropdown("Mode", ("tree", "free"), initial_value=snap.mode))
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
            self.gain_sliders: dict[str, list[Any]] = {}
            preset = snap.scene.preset_gains
            live = snap.gains or preset
            for term in ("kp", "ki", "kd"):
                row = []
                for i, axis in enumerate(AXES):
                    hi = _slider_max(getattr(preset, term)[i], getattr(live, term)[i])
                    slider = self._guard(
                        gui.add_slider(
                            f"{term} {axis}",
                            min=0.0,
                            max=hi,
                            step=hi / 200.0,
                            initial_value=float(getattr(live, term)[i]),
                        )
                    )
                    slider.on_update(self._on_gain)
                    row.append(slider)
                self.gain_sliders[term] = row
            self._action(
                self._guard(gui.add_button("Preset gains")),
                lambda: cmd.SetGains(self.console.loop.snapshot.scene.preset_gains),
            )
        with gui.add_folder("Current"):
            self.current_speed = self._guard(
                gui.add_number("Speed m/s", 0.0, min=0.0, max=3.0, step=0.01)
            )
            self.current_dir = self._guard(
                gui.add_number("Towards deg", 0.0, min=-360.0, max=360.0, step=1.0)
            )
            self._action(
                self._guard(gui.add_button("Set current")),
                lambda: cmd.SetCurrent(
                    float(self.current_speed.value), float(self.current_dir.value)
                ),
            )
        with gui.add_folder("Vessel (crane tip)"):
            ct = snap.crane_tip_n
            self.vessel_n = self._guard(
                gui.add_number("North m", round(ct[0], 2), min=-1000.0, max=1000.0, step=0.1)
            )
            self.vessel_e = self._guard(
                gui.add_number("East m", round(ct[1], 2), min=-1000.0, max=1000.0, step=0.1)
            )
            self._action(
                self._guard(gui.add_button("Move vessel")),
                lambda: cmd.MoveVessel(float(self.vessel_n.value), float(self.vessel_e.value), 0.5),
            )

    def _build_plots(self) -> None:
        gui = self.gui
        self.plots = []
        for title, unit in (("North", "m"), ("East", "m"), ("Heading", "deg")):
            empty = np.zeros(2)
            series = (
                {"label": "t [s]"},
                {"label": f"tree {unit}", "stroke": "#1f5fd0", "width": 2},
                {"label": f"reference {unit}", "stroke": "#d03030", "width": 1.5, "dash": (6, 4)},
            )
            self.plots.append(
                gui.add_uplot(
                    (empty, empty, empty),
                    series,  # type: ignore[arg-type]
                    title=f"{title} [{unit}]",
                    aspect=2.0,
                    scales={"x": {"time": False}},
                )
            )

    def _build_record(self) -> None:
        gui = self.gui
        self.record_label = self._guard(gui.add_text("Label", initial_value=""))
        start = self._guard(gui.add_button("Start recording"))
        start.on_click(lambda event: self._on_record(True))
        stop = self._guard(gui.add_button("Stop recording"))
        stop.on_click(lambda event: self._on_record(False))
        self.record_md = gui.add_markdown("")
        with gui.add_folder("Replay"):
            self.recordings = gui.add_dropdown("Recording", self._recording_names())
            refresh = gui.add_button("Refresh list")
            refresh.on_click(lambda _: self._refresh_recordings())
            self.replay_open = self._guard(gui.add_button("Open replay"))
            self.replay_open.on_click(self._on_open_replay)
            self._action(self._guard(gui.add_button("Play replay")), lambda: cmd.PlayReplay(True))
            self._action(self._guard(gui.add_button("Pause replay")), lambda: cmd.PlayReplay(False))
            self._action(self._guard(gui.add_button("Close replay")), cmd.CloseReplay)
            self.replay_time = self._guard(
                gui.add_slider("Replay time s", min=0.0, max=1.0, step=0.1, initial_value=0.0)
            )
            self.replay_time.on_update(
                self._when_client(lambda: cmd.SeekReplay(float(self.replay_time.value)))
            )

    # ================================================================== callbacks
    def _set_enabled(self, enabled: bool) -> None:
        for handle in self._guarded:
            handle.disabled = not enabled

    def _say(self, text: str) -> None:
        self.message_md.content = text

    def _run(self, make: Callable[[], Any]) -> Any:
        """Build a command and have the loop apply it; show the outcome."""
        if not self.unlocked:
            self._say("**locked**: enter the console token under Access")
            return None
        try:
            result = self.console.loop.call_blocking(make(), timeout_s=15.0)
        except (ConsoleError, ValueError, FileNotFoundError, KeyError) as err:
            self._say(f"**error**: {err}")
            return None
        except Exception as err:
            self._say(f"**error**: {type(err).__name__}: {err}")
            return None
        self._say("")
        return result

    def _action(self, button: Any, make: Callable[[], Any]) -> None:
        button.on_click(lambda event: self._run(make) if event.client is not None else None)

    def _when_client(self, make: Callable[[], Any]) -> Callable[[Any], None]:
        """An input callback that acts on what the operator did, not on our own updates."""

        def callback(event: Any) -> None:
            if event.client is not None:
                self._run(make)

        return callback

    def _on_unlock(self, event: Any) -> None:
        # counted for the view as a whole: a new connection does not buy new guesses
        ok, wait = self.console.check_token(str(self.token_text.value).strip(), "view")
        if ok:
            self.unlocked = True
            self._set_enabled(True)
            self._say("controls unlocked")
        elif wait > 0.0:
            self._say(f"**too many wrong tokens**: try again in {wait:.0f} s")
        else:
            self._say("**wrong token**")

    def _on_camera(self, event: Any) -> None:
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
        pos, look = np.asarray(camera.position), np.asarray(camera.look_at)
        scale = 1e-3 * (1.0 + float(np.linalg.norm(self._camera_sent[-1][0])))
        ours_pos = any(np.linalg.norm(pos - p) < scale for p, _ in self._camera_sent)
        ours_look = any(np.linalg.norm(look - q) < scale for _, q in self._camera_sent)
        if not (ours_pos and ours_look):
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
        self._say(f"building {mission.name}...")
        try:
            run = prepare_run(mission, run_legs)
        except ValueError as err:
            self._say(f"**error**: {err}")
            return
        self._run(lambda: cmd.StartRun(run))

    def _on_start_library(self, event: Any) -> None:
        try:
            mission = self.console.find_mission(str(self.mission_pick.value))
        except (KeyError, ValueError) as err:
            self._say(f"**error**: {err}")
            return
        self._start(mission)

    def _on_gain(self, event: Any) -> None:
        if event.client is None:
            return
        self._gain_touch = time.monotonic()
        values = {t: tuple(float(s.value) for s in row) for t, row in self.gain_sliders.items()}
        self._run(lambda: cmd.SetGains(Gains.of(values["kp"], values["ki"], values["kd"])))

    def _on_record(self, start: bool) -> None:
        if start:
            result = self._run(lambda: cmd.StartRecording(str(self.record_label.value).strip()))
        else:
            result = self._run(cmd.StopRecording)
            self._refresh_recordings()
        if result:
            self.record_md.content = f"`{result['name']}`"

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
        try:
            data = load_replay(self.console.settings.recordings_dir, name)
        except (ConsoleError, FileNotFoundError, ValueError) as err:
            self._say(f"**error**: {err}")
            return
        self._run(lambda: cmd.OpenReplay(name, data))

    # ================================================================== updates
    def _apply_camera(self, snap: Snapshot) -> None:
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
        # the last 100 distinct poses sent (5 s of a moving scene at 20 frames a second), to
        # tell the browser's echoes of them from a camera the user moved
        sent = self._camera_sent
        if not sent:
            self._camera_settle = time.monotonic() + CAMERA_SETTLE_S
        if not sent or np.any(sent[-1][0] != pose.position_n) or np.any(sent[-1][1] != between):
            self._camera_sent = [
                *sent[-98:],
                (pose.position_n, between),
                (pose.position_n, pose.look_at_n),
            ]
        self._camera_pending = self.camera_mode in FOLLOWING

    def update(self, snap: Snapshot) -> None:
        """Refresh from a snapshot (the publisher thread)."""
        if self._camera_pending:
            self._apply_camera(snap)
        now = time.monotonic()
        if now - self._status_wall >= STATUS_EVERY_S:
            self._status_wall = now
            self._update_status(snap)
        if now - self._plots_wall >= PLOTS_EVERY_S:
            self._plots_wall = now
            self._update_plots(snap)

    def _update_status(self, snap: Snapshot) -> None:
        tree = snap.tree_eta_n
        m = snap.mission
        leg = f"leg {m.leg_index}/{m.legs_total} {m.leg_type}" if m.leg_index else ""
        state = "paused" if snap.paused else f"running x{snap.speed:g}"
        source = f"REPLAY `{snap.replay.name}`" if snap.replay else "live"
        text = (
            f"**{source}** t = {snap.t_s:8.1f} s, {state}  \n"
            f"tree N {tree[0]:.2f} m, E {tree[1]:.2f} m, heading "
            f"{math.degrees(tree[5]):.1f} deg, mode {snap.mode}  \n"
            f"mission: {m.name or '-'} ({m.state}) {leg}"
            + (f"  \n**{snap.error}**" if snap.error else "")
            + (f"  \nrecording `{snap.recording}`" if snap.recording else "")
        )
        if self.status_md.content != text:
            self.status_md.content = text
        self._update_readout(snap)
        badges = "".join(
            f"<span style='display:inline-block;margin:1px;padding:1px 5px;border-radius:4px;"
            f"color:white;background:{'#c0392b' if a.active else '#27ae60'}' "
            f"title='{a.message}'>{a.name}</span>"
            for a in snap.alarms
        )
        active = "; ".join(f"{a.name}: {a.message}" for a in snap.active_alarms)
        html = f"<div>{badges}</div>" + (
            f"<div style='color:#c0392b'>{active}</div>" if active else ""
        )
        if self.alarms_html.content != html:
            self.alarms_html.content = html
        self._update_thrusters(snap)
        self._update_controls(snap)

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
        for bar, u in zip(self.bars, util, strict=False):
            value = round(100.0 * min(max(u, 0.0), 1.0), 1)
            if bar.value != value:
                bar.value = value  # type: ignore[misc]  # settable at run time
            color = _bar_color(u)
            if bar.color != color:
                bar.color = color
        text = " | ".join(f"T{i + 1} {100 * u:.0f}%" for i, u in enumerate(util))
        if self.thruster_md.content != text:
            self.thruster_md.content = text

    def _update_controls(self, snap: Snapshot) -> None:
        """Keep inputs in step with changes made elsewhere (API, missions, other browsers)."""
        if snap.gains is not None and time.monotonic() - self._gain_touch > 1.0:
            for term, row in self.gain_sliders.items():
                for slider, value in zip(row, getattr(snap.gains, term), strict=True):
                    if value > slider.max:
                        slider.max = value
                    if abs(slider.value - value) > 1e-9 * max(1.0, value):
                        slider.value = value
        if snap.mode != self.mode.value:
            self.mode.value = snap.mode
        if snap.allocation and snap.allocation != self.allocation.value:
            self.allocation.value = snap.allocation
        if snap.grip is not None and snap.grip != self.grip.value:
            self.grip.value = snap.grip
        speed = f"{snap.speed:g}"
        if speed in SPEEDS and speed != self.speed.value:
            self.speed.value = speed
        self.mission_md.content = _mission_text(snap)
        self._update_replay(snap)

    def _update_replay(self, snap: Snapshot) -> None:
        rp = snap.replay
        if rp is None:
            self._replay_name = None
            return
        if rp.name != self._replay_name:
            self._replay_name = rp.name
            self.replay_time.min = rp.start_s
            self.replay_time.max = max(rp.end_s, rp.start_s + 0.1)
        if abs(self.replay_time.value - rp.t_s) > 0.05:
            self.replay_time.value = round(rp.t_s, 1)

    def _update_plots(self, snap: Snapshot) -> None:
        trend = snap.trend
        if len(trend) < 2:
            return
        recent = trend[trend[:, 0] >= trend[-1, 0] - PLOT_WINDOW_S]
        t = recent[:, 0]
        data = (
            (t, recent[:, 1], recent[:, 4]),
            (t, recent[:, 2], recent[:, 5]),
            (t, np.degrees(recent[:, 3]), np.degrees(recent[:, 6])),
        )
        for plot, series in zip(self.plots, data, strict=True):
            plot.data = tuple(np.ascontiguousarray(a) for a in series)


def _mission_text(snap: Snapshot) -> str:
    m = snap.mission
    if m.result:
        r = m.result
        return (
            f"**{m.name}** {m.state}: RMS N {r.get('rms_north_m', float('nan')):.3f} m, "
            f"E {r.get('rms_east_m', float('nan')):.3f} m, heading "
            f"{r.get('rms_heading_deg', float('nan')):.2f} deg"
        )
    if m.leg_index:
        return f"**{m.name}**: leg {m.leg_index}/{m.legs_total} `{m.leg_type}` {m.leg_name or ''}"
    return f"{m.name or 'no mission'} ({m.state})"


def _slider_max(preset: float, live: float) -> float:
    return max(GAIN_RANGE_FACTOR * preset, live, 1.0)
