"""The "Run" tab: pause, resume, step, speed, reset to station keeping, and the target the
tree holds when no mission runs."""

from __future__ import annotations

from typing import Any

from app.console import Console, Snapshot, compass_heading_deg, station_keeping_mission
from app.console import commands as cmd
from web.tabs.mission import start_mission
from web.widgets import Operator


def bounded_target(op: Operator, handle: Any) -> Any:
    """A target input within the range ``SetTarget`` allows."""
    return op.bounded(handle, -cmd.TARGET_RANGE_M, cmd.TARGET_RANGE_M, "m")


SPEEDS = ("0.25", "1", "5", "20", "50")
"""The speed presets, a click each (any other speed in range is typed)."""


class RunTab:
    def __init__(self, operator: Operator, console: Console) -> None:
        self.operator = operator
        self.console = console
        gui, op = operator.gui, operator
        op.action(op.guard(gui.add_button("Pause")), cmd.Pause)
        op.action(op.guard(gui.add_button("Resume")), cmd.Resume)
        op.action(op.guard(gui.add_button("Step 0.1 s")), lambda: cmd.Step(10))
        self._build_speed(console.loop.snapshot.speed)
        self.reset_button = op.guard(gui.add_button("Reset to station keeping"))
        self.reset_button.on_click(lambda _: self._reset())
        snap = console.loop.snapshot
        goal = snap.target or snap.eta_ref
        with gui.add_form("Target (no mission)") as target_form:
            self.target_n = op.live_input(
                "target",
                bounded_target(op, gui.add_number("Target north m", round(goal[0], 2), step=0.1)),
            )
            self.target_e = op.live_input(
                "target",
                bounded_target(op, gui.add_number("Target east m", round(goal[1], 2), step=0.1)),
            )
            self.target_psi = op.live_input(
                "target",
                op.angle(
                    gui.add_number("Target heading deg", compass_heading_deg(goal[2]), step=1.0)
                ),
            )
            op.action(
                op.guard(gui.add_button("Go to target")),
                lambda: cmd.SetTarget(
                    op.number(self.target_n),
                    op.number(self.target_e),
                    op.degrees(self.target_psi),
                ),
                done="target",
                form=target_form,
            )

    def _build_speed(self, speed: float) -> None:
        """The run's speed: typed (Enter applies it, as "Set speed" does; any speed in the
        loop's range) or one of the presets at a click."""
        gui, op = self.operator.gui, self.operator
        with gui.add_form("Speed (x real time)") as form:
            self.speed = op.live_input(
                "speed",
                op.bounded(
                    gui.add_number("Speed x real time", speed, step=0.25),
                    cmd.SPEED_MIN,
                    cmd.SPEED_MAX,
                    "x",
                ),
            )
            op.action(
                op.guard(gui.add_button("Set speed")),
                lambda: cmd.SetSpeed(op.number(self.speed)),
                done="speed",
                form=form,
            )
            # not guarded: viser cannot disable a button group (a locked page says so)
            self.speed_presets = gui.add_button_group("Presets", SPEEDS)
            self.speed_presets.on_click(
                op.when_client(lambda: cmd.SetSpeed(float(self.speed_presets.value)))
            )

    def _reset(self) -> None:
        snap = self.console.loop.snapshot
        mission = station_keeping_mission(snap.scene.params_name, self.console.settings.depth_m)
        start_mission(self.operator, mission, run_legs=False)

    def update(self, live: Snapshot) -> None:
        """The target and the speed follow the live run (changed elsewhere: the API, other
        browsers, a mission) unless the operator is editing them."""
        goal = live.target or live.eta_ref
        self.operator.follow(
            "target",
            (
                (self.target_n, round(goal[0], 2)),
                (self.target_e, round(goal[1], 2)),
                (self.target_psi, compass_heading_deg(goal[2])),
            ),
        )
        self.operator.follow("speed", ((self.speed, live.speed),))
