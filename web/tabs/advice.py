"""A dock leg's advice to move the vessel (``vessel = "advise"``), as the Mission tab and the
Control tab's vessel form show it: the leg's words, and an "Apply advice" button that moves
the vessel there (``commands.ApplyVesselAdvice``); once applied, how far the vessel still has
to go."""

from __future__ import annotations

from app.console import Snapshot, VesselAdvice, advice_words, md_text
from app.console import commands as cmd
from web.widgets import LOCKED_TEXT, Operator


def advice_markdown(advice: VesselAdvice | None, unlocked: bool) -> str:
    """The advice in words (``advice_words``), and on a locked page that the token applies it."""
    if advice is None:
        return ""
    heading, words = advice_words(advice)
    lock = "" if advice.applied or unlocked else f" ({md_text(LOCKED_TEXT)} to apply it)"
    return f"**{heading}** {md_text(words)}{lock}"


class AdvicePanel:
    """The advice's line and its "Apply advice" button (shown while there is advice to
    apply), in one tab of one browser."""

    def __init__(self, operator: Operator) -> None:
        self.operator = operator
        gui = operator.gui
        self.text = gui.add_markdown("", visible=False)
        self.apply = operator.guard(gui.add_button("Apply advice", visible=False))
        operator.action(self.apply, cmd.ApplyVesselAdvice)

    def update(self, live: Snapshot) -> None:
        advice = live.mission.vessel_advice
        text = advice_markdown(advice, self.operator.unlocked)
        if self.text.content != text:
            self.text.content = text
        if self.text.visible != bool(text):
            self.text.visible = bool(text)
        pending = advice is not None and not advice.applied
        if self.apply.visible != pending:
            self.apply.visible = pending


def advised_tip(live: Snapshot) -> tuple[float, float]:
    """Where the vessel form's north and east show the crane tip: at the advised place
    while there is advice to apply, else where it is."""
    advice = live.mission.vessel_advice
    if advice is not None and not advice.applied:
        return advice.crane_tip_ne_m
    return live.crane_tip_n[0], live.crane_tip_n[1]
