"""The operator's panel, one per browser (viser client): the status at the top, the camera
presets, the Access folder, the thrusters, the plots, then the tabs (``web.tabs``).

Each browser has its own panel (its own camera preset, mission being built, replay and unlock
state) while all share the scene. Watching needs nothing; every control that changes the run
stays disabled until the console token is entered in "Access" (``web.widgets.Operator``).
``update`` is called by the view's publisher thread with each new snapshot.
"""

from __future__ import annotations

import time

import viser

from app.console import Console, Snapshot, ViewerReplay
from web.camera import Camera
from web.scene import SceneView
from web.status import StatusHeader, next_due
from web.tabs.control import ControlTab
from web.tabs.instructor import InstructorTab
from web.tabs.mission import MissionTab
from web.tabs.plots import add_plots, plots_url
from web.tabs.record import RecordTab
from web.tabs.run import RunTab
from web.tabs.scores import ScoresTab
from web.water import WaterPanel
from web.widgets import Operator

STATUS_EVERY_S = 0.2


class ClientPanel:
    """The panel of one browser: composes the header, the tabs and the plots."""

    def __init__(
        self, client: viser.ClientHandle, console: Console, shared_scene: SceneView | None = None
    ) -> None:
        self.client = client
        self.console = console
        self.shared_scene = shared_scene
        """The scene every browser shares (its nodes are hidden here while a replay shows)."""
        self._replay_scene: SceneView | None = None
        self._status_wall = 0.0
        self.updates_sent = {"status": 0}
        """Status-line refreshes made (``benchmarks/page_rates.py`` reads them)."""
        gui = client.gui
        self.status = StatusHeader(gui)
        self.camera = Camera(client, console)
        self.operator = Operator(client, console, self.status.say)
        self.water = WaterPanel(client, console, self.operator)
        self.operator.add_access()
        self.status.add_folders()
        # the plots above the tabs: below them, a long tab (the mission builder) pushed them
        # out of sight
        with gui.add_folder("Plots", expand_by_default=True):
            self.plots_url = plots_url(console.settings, client.client_id)
            self.plots_html = add_plots(gui, self.plots_url)
        tabs = gui.add_tab_group()
        with tabs.add_tab("Run"):
            self.run = RunTab(self.operator, console)
        with tabs.add_tab("Mission"):
            self.mission = MissionTab(client, self.operator, console, self.camera.show_points)
        with tabs.add_tab("Control"):
            self.control = ControlTab(self.operator, console)
        with tabs.add_tab("Record"):
            self.record = RecordTab(self.operator, console, self._on_replay)
        with tabs.add_tab("Scores"):
            self.scores = ScoresTab(self.operator, console, self._any_unlocked)
        with tabs.add_tab("Instructor"):
            self.instructor = InstructorTab(self.operator, console)
        self.record.may_note = self._any_unlocked  # notes: the console token or the instructor's
        self.operator.set_enabled(False)

    @property
    def replay(self) -> ViewerReplay | None:
        """This browser's replay (None: it shows the live run)."""
        return self.record.replay

    def _any_unlocked(self) -> bool:
        """Unlocked with the console token or the instructor's."""
        return self.operator.unlocked or self.instructor.unlocked

    def _on_replay(self) -> None:
        self.camera.pending = True  # a replay opened or closed: frame the scene anew

    # ------------------------------------------------------------------ updates
    def update(self, snap: Snapshot) -> None:
        """Refresh from a snapshot (the publisher thread): the live one, or this browser's
        replay drawn in its own scene (the inputs follow the live run either way)."""
        view = self._shown(snap)
        self.camera.follow(view)
        scene = self._replay_scene or self.shared_scene
        if scene is not None:
            self.water.update(view, self.camera.mode == "ROV camera", scene.silt.state)
        now = time.monotonic()
        if now >= self._status_wall:
            self._status_wall = next_due(self._status_wall, STATUS_EVERY_S, now)
            self.status.update(view, snap)
            self.run.update(snap)
            self.mission.update(snap)
            self.control.update(snap)
            self.record.update(view)
            self.instructor.update(view)
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
