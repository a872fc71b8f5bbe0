"""What the page's tabs share, one per browser: the operator (who they are, whether the console
token unlocked their controls, the inputs they are editing) and the way a control sends its
command to the loop.

Callbacks run on viser's threads: they only build a command, hand it to the loop
(``PacedLoop.call_blocking``) and show the answer on the page's message line.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import viser

from app.console import Console, ConsoleError, md_text

EDIT_HOLD_S = 30.0
"""An input the operator has edited keeps the edit this long before it follows the live value
again (unless its command is sent first)."""
LOCKED_TEXT = "locked: enter the console token under Access"


@dataclass(frozen=True)
class Bounds:
    """The range a number input of the page allows.

    viser's number inputs clamp what is typed to their min and max without a word (5 m/s
    became 3), so the page's inputs are made without min and max: the typed value reaches the
    server and is refused here, naming the field and the range."""

    label: str
    lo: float
    hi: float
    unit: str = ""

    @property
    def allowed(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        return f"{self.lo:g} to {self.hi:g}{unit}"

    def check(self, value: float) -> float:
        """``value`` when it is finite and within [lo, hi]; ValueError naming the field, the
        value and the allowed range otherwise."""
        if not (math.isfinite(value) and self.lo <= value <= self.hi):
            unit = f" {self.unit}" if self.unit else ""
            raise ValueError(
                f"{self.label}: {value:g}{unit} is out of range; allowed {self.allowed}"
            )
        return value


def wrap_deg(angle_deg: float) -> float:
    """``angle_deg`` wrapped into [0, 360): 400 -> 40, -90 -> 270, 360 -> 0."""
    wrapped = angle_deg % 360.0
    return 0.0 if wrapped >= 360.0 else wrapped  # -1e-15 % 360 rounds to 360.0


def wrapped_text(label: str, typed_deg: float) -> str:
    """What the page says when it wraps a typed angle."""
    return (
        f"{label}: {typed_deg:g} deg taken as {wrap_deg(typed_deg):g} deg "
        "(angles are wrapped into 0 to 360)"
    )


def masked_input_style(handle: Any) -> str:
    """CSS that draws a text input's characters as dots (Chromium, Firefox, Safari): viser has
    no password input. The field is found by its label's 'for', which is the input's uuid."""
    uuid = handle._impl.uuid  # viser labels an input with for="<uuid>"
    return (
        "<style>"
        f'div:has(> div > p > label[for="{uuid}"]) input '
        "{ -webkit-text-security: disc; }"
        "</style>"
    )


class Operator:
    """One browser's operator: the Access folder (name, token, unlock and lock), the controls
    the console token unlocks, the inputs that follow the live values until edited, and the
    commands those controls send."""

    def __init__(
        self,
        client: viser.ClientHandle,
        console: Console,
        say: Callable[[str], None],
    ) -> None:
        """``say``: shows a line on the page's message line."""
        self.client = client
        self.gui = client.gui
        self.console = console
        self.say = say
        self.unlocked = False
        self.last_error = ""
        """What went wrong with the last command this browser sent ('' when it was done)."""
        self._guarded: list[Any] = []
        self._edited: dict[str, float] = {}
        self._inputs: dict[str, list[Any]] = {}  # the live inputs of each group
        self._put_in: dict[int, Any] = {}  # what this browser last put in each live input
        self._bounds: dict[int, Bounds] = {}  # the range of each bounded number input

    def add_access(self) -> None:
        """The Access folder: the operator's name and the console token."""
        gui = self.gui
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

    # ------------------------------------------------------------------ who
    @property
    def guess_client(self) -> str:
        """Whom this browser's wrong tokens count against: itself."""
        return f"view:{self.client.client_id}"

    @property
    def who(self) -> str:
        """This browser in the operations log: 'viewer 3 (Anna)'."""
        name = " ".join(str(self.name_text.value).split())[:40]
        return f"viewer {self.client.client_id}" + (f" ({name})" if name else "")

    # ------------------------------------------------------------------ controls
    def guard(self, handle: Any) -> Any:
        """A control that needs the token."""
        self._guarded.append(handle)
        return handle

    def unguard(self, handle: Any) -> None:
        """A guarded control that is being removed."""
        self._guarded = [h for h in self._guarded if h is not handle]

    def set_enabled(self, enabled: bool) -> None:
        for handle in self._guarded:
            handle.disabled = not enabled

    def live_input(self, group: str, handle: Any) -> Any:
        """An input (guarded) that shows the live value of ``group`` until the operator edits
        it; it follows the live value again ``EDIT_HOLD_S`` after the last edit or once the
        group's command has been sent."""

        def edited(event: Any) -> None:
            if event.client is not None:
                self._edited[group] = time.monotonic()

        handle.on_update(edited)
        self._inputs.setdefault(group, []).append(handle)
        self._put_in[id(handle)] = handle.value
        return self.guard(handle)

    def editing(self, group: str) -> bool:
        return time.monotonic() - self._edited.get(group, -math.inf) < EDIT_HOLD_S

    def follow(self, group: str, live: Sequence[tuple[Any, Any]]) -> None:
        """Show the live values (input, value) in a group's inputs unless the operator is
        editing them. An input that holds neither what this browser last showed in it was typed
        in by a viewer whose edit callback has not run yet (viser sets the value, then queues
        the callbacks on its thread pool, which under load lags by seconds): an edit as well,
        not something to write over."""
        if self.editing(group):
            return
        if any(h.value != self._put_in[id(h)] for h, _ in live):
            self._edited[group] = time.monotonic()
            return
        for handle, value in live:
            if handle.value != value:
                handle.value = value
            self._put_in[id(handle)] = handle.value

    def _sent(self, group: str) -> None:
        """A group's command was sent: its inputs follow the live values again."""
        self._edited.pop(group, None)
        for handle in self._inputs.get(group, ()):
            self._put_in[id(handle)] = handle.value

    # ------------------------------------------------------------------ numbers
    def bounded(self, handle: Any, lo: float, hi: float, unit: str = "") -> Any:
        """A number input (made without min and max, which viser clamps to silently) whose
        typed value must lie in [lo, hi]: a value outside is refused on the message line at
        once, and again by ``number`` when a command reads it."""
        bounds = Bounds(str(handle.label), lo, hi, unit)
        self._bounds[id(handle)] = bounds

        def typed(event: Any) -> None:
            if event.client is None:
                return
            try:
                bounds.check(float(handle.value))
            except ValueError as err:
                self.say(f"**refused**: {md_text(str(err))}")

        handle.on_update(typed)
        return handle

    def angle(self, handle: Any) -> Any:
        """A number input of an angle in degrees: a typed value outside [0, 360) is wrapped
        into it in the input, and the message line says so."""

        def typed(event: Any) -> None:
            if event.client is None:
                return
            value = float(handle.value)
            if math.isfinite(value) and wrap_deg(value) != value:
                handle.value = wrap_deg(value)
                self.say(md_text(wrapped_text(str(handle.label), value)))

        handle.on_update(typed)
        return handle

    def number(self, handle: Any) -> float:
        """The value of a number input for a command: checked against its ``bounded`` range
        (ValueError naming the field and the range), or wrapped into [0, 360) for an
        ``angle``."""
        value = float(handle.value)
        bounds = self._bounds.get(id(handle))
        if bounds is not None:
            return bounds.check(value)
        if not math.isfinite(value):
            raise ValueError(f"{handle.label}: {value:g} is not a finite number")
        return value

    def degrees(self, handle: Any) -> float:
        """The value of an ``angle`` input, wrapped into [0, 360)."""
        return wrap_deg(self.number(handle))

    # ------------------------------------------------------------------ commands
    def run(self, make: Callable[[], Any]) -> Any:
        """Build a command and have the loop apply it; show the outcome."""
        self.last_error = ""
        if not self.unlocked:
            self.last_error = LOCKED_TEXT
            self.say(f"**{md_text(self.last_error)}**")
            return None
        try:
            result = self.console.loop.call_blocking(make(), timeout_s=15.0, who=self.who)
        except (ConsoleError, ValueError, FileNotFoundError, KeyError) as err:
            self.last_error = str(err)
        except Exception as err:
            self.last_error = f"{type(err).__name__}: {err}"
        if self.last_error:
            self.say(f"**error**: {md_text(self.last_error)}")
            return None
        self.say("")
        return result

    def action(
        self,
        button: Any,
        make: Callable[[], Any],
        done: str | None = None,
        form: Any = None,
    ) -> None:
        """A button that runs a command; ``done``: the input group it sends, which follows
        the live value again once sent; ``form``: the form (``gui.add_form``) holding the
        button's inputs, where Enter in an input runs the command too, as a click does."""

        feedback = self.gui.add_markdown("") if done is not None else None

        def clicked(event: Any) -> None:
            if event.client is None:
                return
            self.run(make)
            if done is None or feedback is None:
                return
            if self.last_error:  # the typed values stay, to be corrected
                feedback.content = f"**not applied**: {md_text(self.last_error)}"
            else:
                feedback.content = ""
                self._sent(done)

        button.on_click(clicked)
        if form is not None:
            form.on_submit(clicked)

    def when_client(self, make: Callable[[], Any]) -> Callable[[Any], None]:
        """An input callback that acts on what the operator did, not on our own updates."""

        def callback(event: Any) -> None:
            if event.client is not None:
                self.run(make)

        return callback

    # ------------------------------------------------------------------ access
    def _on_unlock(self, event: Any) -> None:
        # counted per browser: one viewer's wrong tokens lock that viewer out, not the others
        ok, wait = self.console.check_token(str(self.token_text.value).strip(), self.guess_client)
        self.token_text.value = ""  # type: ignore[misc]  # the token does not stay on the page
        if ok:
            self.unlocked = True
            self.set_enabled(True)
            self.unlock_button.visible = False
            self.lock_button.visible = True
            self.say("controls unlocked")
        elif wait > 0.0:
            self.say(f"**too many wrong tokens**: try again in {wait:.0f} s")
        else:
            self.say("**wrong token**")

    def _on_lock(self, event: Any) -> None:
        self.unlocked = False
        self.set_enabled(False)
        self.lock_button.visible = False
        self.unlock_button.visible = True
        self.say("controls locked")
