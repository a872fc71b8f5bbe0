"""The "Instructor" tab, one per browser.

It stays locked until the instructor token is entered in its own field (the console token does
not open it, and opening it does not unlock the console's controls). Unlocked, it injects a
fault (kind, with its unit and range shown; value; thruster for the thruster kinds; now or at a
simulation time; duration), lists the faults active and scheduled with the latest starts and
ends and the instructor's own commands, and clears them. Its commands go to the loop like any
other (``app.console.faults``); the trainee's operations log leaves them out. Below, the
assessment's criteria in force, which the unlocked instructor edits (``web.tabs.criteria``).
"""

from __future__ import annotations

from typing import Any

from app.console import (
    FAULT_KINDS,
    INSTRUCTOR_TOKEN_ENV,
    THRUSTER_KINDS,
    ClearFaults,
    Console,
    ConsoleError,
    InjectFault,
    Snapshot,
    md_text,
)
from web.tabs.criteria import CriteriaEditor
from web.widgets import Operator, masked_input_style

STARTS = ("now", "at time")
OFF_TEXT = (
    "*Instructor features are off.* Start the console with `--instructor-token` "
    f"(or `{INSTRUCTOR_TOKEN_ENV}`) to inject faults."
)


def kind_help(kind: str) -> str:
    """The unit and range of a kind's value, in words for the panel."""
    unit, lo, hi = FAULT_KINDS[kind]
    value = "takes no value" if unit == "-" else f"value in [{lo:g}, {hi:g}] {unit}"
    which = "; give the thruster's number" if kind in THRUSTER_KINDS else ""
    return f"`{kind}`: {value}{which}"


def faults_markdown(snap: Snapshot) -> str:
    """Active and scheduled faults, the latest starts and ends, and the instructor's commands."""
    lines = ["**faults** (times are simulation time)"]
    if not snap.faults:
        lines.append("- none active or scheduled")
    for f in snap.faults:
        lines.append(f"- **{f.state}**: {md_text(f.text)}")
    if snap.fault_log:
        lines.append("\n**starts and ends**")
        lines += [f"- t {t:.1f} s: {md_text(text)}" for t, text in reversed(snap.fault_log[-8:])]
    mine = [op for op in snap.operations if op.instructor][-5:]
    if mine:
        lines.append("\n**instructor's commands**")
        lines += [
            f"- t {op.t_s:.1f} s {md_text(op.who)}: {md_text(op.action)} - {md_text(op.outcome)}"
            for op in mine
        ]
    return "\n".join(lines)


class InstructorTab:
    """The instructor's tab of one browser: ``operator`` names the browser in the operations
    log and counts its wrong tokens; its own token unlocks it."""

    def __init__(self, operator: Operator, console: Console) -> None:
        self.operator = operator
        self.console = console
        self.gui = operator.gui
        self.unlocked = False
        self._guarded: list[Any] = []
        self.last_error = ""
        if not self.console.instructor_on:
            self.gui.add_markdown(OFF_TEXT)
            return
        self._build()

    def _build(self) -> None:
        gui = self.gui
        self.token_text = gui.add_text("Instructor token", initial_value="")
        gui.add_html(masked_input_style(self.token_text))
        self.unlock_button = gui.add_button("Unlock instructor")
        self.unlock_button.on_click(self._on_unlock)
        self.lock_button = gui.add_button("Lock instructor", visible=False)
        self.lock_button.on_click(self._on_lock)
        kinds = tuple(FAULT_KINDS)
        self.kind = self._guard(gui.add_dropdown("Fault kind", kinds, initial_value=kinds[0]))
        self.kind_md = gui.add_markdown(kind_help(kinds[0]))
        self.kind.on_update(lambda _: self._show_kind())
        self.value = self._guard(gui.add_number("Fault value", 0.0, step=0.01))
        self.thruster = self._guard(gui.add_number("Thruster number", 1, step=1))
        self.start = self._guard(gui.add_dropdown("Fault start", STARTS, initial_value="now"))
        self.start_at = self._guard(gui.add_number("Start at t s", 0.0, step=1.0))
        self.duration = self._guard(gui.add_number("Fault duration s", 60.0, step=1.0))
        self.inject_button = self._guard(gui.add_button("Inject fault"))
        self.inject_button.on_click(self._on_inject)
        self.clear_button = self._guard(gui.add_button("Clear faults"))
        self.clear_button.on_click(self._on_clear)
        self.message_md = gui.add_markdown("")
        self.faults_md = gui.add_markdown("")
        self.criteria = CriteriaEditor(
            gui, self.console.settings.recordings_dir, self._guard, lambda: self.unlocked
        )
        self._set_enabled(False)

    def _guard(self, handle: Any) -> Any:
        self._guarded.append(handle)
        return handle

    def _set_enabled(self, enabled: bool) -> None:
        for handle in self._guarded:
            handle.disabled = not enabled
        self.criteria.set_enabled(enabled)

    def _say(self, text: str) -> None:
        self.message_md.content = text

    def _show_kind(self) -> None:
        self.kind_md.content = kind_help(str(self.kind.value))

    # ------------------------------------------------------------------ callbacks
    def _on_unlock(self, event: Any) -> None:
        verdict, wait = self.console.check_instructor(
            str(self.token_text.value).strip(), self.operator.guess_client
        )
        self.token_text.value = ""  # type: ignore[misc]  # the token does not stay on the page
        if verdict == "ok":
            self.unlocked = True
            self._set_enabled(True)
            self.unlock_button.visible = False
            self.lock_button.visible = True
            self._say("instructor unlocked")
            self.faults_md.content = faults_markdown(self.console.loop.snapshot)
        elif wait > 0.0:
            self._say(f"**too many wrong tokens**: try again in {wait:.0f} s")
        elif verdict == "console token":
            self._say("**that is the console token**: the instructor has a token of its own")
        else:
            self._say("**wrong instructor token**")

    def _on_lock(self, event: Any) -> None:
        self.unlocked = False
        self._set_enabled(False)
        self.lock_button.visible = False
        self.unlock_button.visible = True
        self.faults_md.content = ""
        self._say("instructor locked")

    def command(self) -> InjectFault:
        """The fault typed in the panel (ValueError naming the field and its range)."""
        kind = str(self.kind.value)
        unit = FAULT_KINDS[kind][0]
        return InjectFault(
            kind,
            float(self.duration.value),
            0.0 if unit == "-" else float(self.value.value),
            None if self.start.value == "now" else float(self.start_at.value),
            int(self.thruster.value) if kind in THRUSTER_KINDS else 0,
        )

    def _run(self, make: Any) -> object:
        self.last_error = ""
        if not self.unlocked:
            self.last_error = "locked: enter the instructor token"
        else:
            try:
                return self.console.loop.call_blocking(
                    make(), timeout_s=15.0, who=f"instructor, {self.operator.who}"
                )
            except (ConsoleError, ValueError) as err:
                self.last_error = str(err)
            except Exception as err:
                self.last_error = f"{type(err).__name__}: {err}"
        self._say(f"**not done**: {md_text(self.last_error)}")
        return None

    def _on_inject(self, event: Any) -> None:
        result = self._run(self.command)
        if isinstance(result, dict):
            self._say(f"injected: {md_text(result['text'])}")

    def _on_clear(self, event: Any) -> None:
        result = self._run(ClearFaults)
        if isinstance(result, dict):
            self._say(f"cleared {result['cleared']} fault(s)")

    # ------------------------------------------------------------------ updates
    def update(self, snap: Snapshot) -> None:
        """Refresh the list (the publisher thread), while unlocked."""
        if not self.unlocked:
            return
        text = faults_markdown(snap)
        if self.faults_md.content != text:
            self.faults_md.content = text
