"""The "Mission" tab: the missions to start (the library and those uploaded), abort, the
running mission's progress and result, a dock leg's advice to move the vessel
(``web.tabs.advice``), the signal checks' counters, and the mission builder
(``web.builder_panel``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import viser

from app.console import (
    Console,
    Snapshot,
    counters_markdown,
    md_code,
    md_text,
    prepare_run,
    result_markdown,
)
from app.console import commands as cmd
from missions import schema
from web.builder_panel import BuilderPanel
from web.tabs.advice import AdvicePanel
from web.widgets import Operator


def start_mission(operator: Operator, mission: schema.Mission, run_legs: bool = True) -> None:
    """Build ``mission``'s run (off the loop) and have the loop start it."""
    if not operator.unlocked:
        operator.say("**locked**: enter the console token under Access")
        return
    operator.say(f"building {md_text(mission.name)}...")
    try:
        run = prepare_run(mission, run_legs)
    except ValueError as err:
        operator.say(f"**error**: {md_text(err)}")
        return
    operator.run(lambda: cmd.StartRun(run))


def mission_markdown(snap: Snapshot) -> str:
    """The mission's result when it has ended, else its present leg."""
    m = snap.mission
    if m.result:
        return result_markdown(m.name, m.state, m.result)
    if m.leg_index:
        return (
            f"**{md_text(m.name)}**: leg {m.leg_index}/{m.legs_total} {md_code(m.leg_type)} "
            f"{md_text(m.leg_name or '')}"
        )
    return f"{md_text(m.name or 'no mission')} ({m.state})"


class MissionTab:
    def __init__(
        self,
        client: viser.ClientHandle,
        operator: Operator,
        console: Console,
        show: Callable[[np.ndarray, str], None] | None = None,
    ) -> None:
        """``show``: turns this browser's camera to points (the builder's preview)."""
        self.operator = operator
        self.console = console
        gui, op = operator.gui, operator
        library, uploaded = console.mission_names()
        names = tuple(library + uploaded) or ("(none)",)
        self.mission_pick = gui.add_dropdown("Mission", names, initial_value=names[0])
        self.mission_start = op.guard(gui.add_button("Start mission"))
        self.mission_start.on_click(self._on_start_library)
        op.action(op.guard(gui.add_button("Abort mission", color="red")), cmd.AbortMission)
        self.mission_md = gui.add_markdown("")
        self.advice = AdvicePanel(op)
        self.counters_md = gui.add_markdown("")
        with gui.add_folder("Mission builder"):
            self.builder = BuilderPanel(
                client,
                console,
                op.guard,
                lambda mission: start_mission(op, mission),
                lambda: op.unlocked,
                (self.mission_pick,),
                show=show,
            )

    def _on_start_library(self, event: Any) -> None:
        try:
            mission = self.console.find_mission(str(self.mission_pick.value))
        except (KeyError, ValueError) as err:
            self.operator.say(f"**error**: {md_text(err)}")
            return
        start_mission(self.operator, mission)

    def update(self, live: Snapshot) -> None:
        text = mission_markdown(live)
        if self.mission_md.content != text:
            self.mission_md.content = text
        self.advice.update(live)
        counters = counters_markdown(live.quality_counters)
        if self.counters_md.content != counters:
            self.counters_md.content = counters
        self.builder.update(live)
