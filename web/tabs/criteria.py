"""The assessment's criteria in the Instructor tab: the criteria in force as a table, and an
editor of one criterion at a time (its limit, the value where its score reaches 0 and its
weight, with the ranges a criteria file allows), applied or reset to the defaults.

The criteria are the console's (``app.console.criteria``): the same file the API's
``PUT /api/assessment/criteria`` writes, checked by the same validation. A value out of range
is refused with the error naming the field and its range, and nothing changes. Reading them
needs no token; changing them needs the instructor's, which the tab checks (``unlocked``).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from app.console import criteria as in_force
from app.console import md_text

FROM_SET_TEXT = "the parameter set's"


def _number(v: float) -> float | int:
    """A typed value as the file would hold it (500, not 500.0, in an error)."""
    return int(v) if float(v).is_integer() else float(v)


def ranges_text(c: in_force.Criterion) -> str:
    """A criterion's title, unit and what a criteria file allows, in words for the panel."""
    d = c.definition
    unit = d.unit
    limit = f"limit 0 to {d.limit_max:g} {unit}"
    if d.limit is None:
        limit += f" (default: {FROM_SET_TEXT}, from its docking frame)"
    return (
        f"`{c.name}`: {md_text(d.title)} [{md_text(unit)}]. {limit}; score 0 at: above the "
        f"limit; weight 0 to {in_force.WEIGHT_MAX:g}"
    )


def criteria_markdown(criteria: in_force.Criteria, by_instructor: bool) -> str:
    """The criteria in force as a table."""
    lines = [
        f"**criteria in force** ({'set by the instructor' if by_instructor else 'the defaults'})",
        "",
        "| criterion | unit | limit | score 0 at | weight |",
        "|---|---|---|---|---|",
    ]
    for c in criteria:
        limit = FROM_SET_TEXT if c.limit is None else f"{c.limit:g}"
        zero = "twice the limit" if c.zero_at is None else f"{c.zero_at:g}"
        lines.append(
            f"| {c.name} | {md_text(c.definition.unit)} | {limit} | {zero} | {c.weight:g} |"
        )
    return "\n".join(lines)


class CriteriaEditor:
    """The criteria's part of one browser's Instructor tab. ``guard`` registers a control the
    instructor's token enables; ``unlocked`` says whether it is unlocked now."""

    def __init__(
        self,
        gui: Any,
        recordings_dir: Path,
        guard: Callable[[Any], Any],
        unlocked: Callable[[], bool],
    ) -> None:
        self.recordings_dir = recordings_dir
        self.unlocked = unlocked
        self.last_error = ""
        criteria, _ = self._in_force()
        names = tuple(c.name for c in criteria)
        with gui.add_folder("Assessment criteria"):
            self.name = guard(gui.add_dropdown("Criterion", names, initial_value=names[0]))
            self.name.on_update(lambda _: self.show_criterion())
            self.ranges_md = gui.add_markdown("")
            self.from_set = guard(gui.add_checkbox("Limit from the parameter set", True))
            self.from_set.on_update(lambda _: self._follow_from_set())
            self.limit = guard(gui.add_number("Criterion limit", 0.0, step=0.001))
            self.zero_at = guard(gui.add_number("Score 0 at", 0.0, step=0.001))
            self.weight = guard(gui.add_number("Criterion weight", 1.0, step=0.1))
            self.apply_button = guard(gui.add_button("Apply criteria"))
            self.apply_button.on_click(lambda _: self.apply())
            self.reset_button = guard(gui.add_button("Reset criteria to defaults"))
            self.reset_button.on_click(lambda _: self.reset())
            self.message_md = gui.add_markdown("")
            self.table_md = gui.add_markdown("")
        self.show_criterion()

    def _in_force(self) -> tuple[in_force.Criteria, str]:
        """The criteria in force, and the error when the console's file is broken (the
        defaults are shown then, and Apply writes a good file over it)."""
        try:
            return in_force.criteria_in_force(self.recordings_dir), ""
        except in_force.CriteriaError as err:
            return in_force.default_criteria(), str(err)

    def _criterion(self, criteria: in_force.Criteria) -> in_force.Criterion:
        (c,) = [c for c in criteria if c.name == self.name.value]
        return c

    def show_criterion(self) -> None:
        """Fill the inputs with the chosen criterion as it is in force, and the table."""
        criteria, broken = self._in_force()
        c = self._criterion(criteria)
        self.ranges_md.content = ranges_text(c)
        can_follow = c.definition.limit is None
        self.from_set.visible = can_follow
        self.from_set.value = can_follow and c.limit is None
        self.limit.value = 0.0 if c.limit is None else c.limit  # 0: the set's, not a value
        self.zero_at.value = 0.0 if c.zero_at is None else c.zero_at
        self.weight.value = c.weight
        self._follow_from_set()
        self._show_table(criteria, broken)

    def _follow_from_set(self) -> None:
        follow = bool(self.from_set.visible and self.from_set.value)
        locked = not self.unlocked()
        self.limit.disabled = follow or locked
        self.zero_at.disabled = follow or locked

    def _show_table(self, criteria: in_force.Criteria, broken: str = "") -> None:
        text = criteria_markdown(criteria, in_force.set_by_instructor(self.recordings_dir))
        if broken:
            text = f"**the console's criteria file is broken**: {md_text(broken)}\n\n{text}"
        self.table_md.content = text

    def set_enabled(self, enabled: bool) -> None:
        """After the guarded controls were enabled or disabled: keep the limit's inputs off
        while the limit follows the parameter set."""
        if enabled:
            self._follow_from_set()

    def fields(self) -> dict:
        """The criteria in force with the chosen criterion as typed, as a file's fields."""
        criteria, _ = self._in_force()
        data = in_force.fields_of(criteria)
        typed: dict[str, float | int] = {"weight": _number(self.weight.value)}
        if not (self.from_set.visible and self.from_set.value):
            typed["limit"] = _number(self.limit.value)
            typed["zero_at"] = _number(self.zero_at.value)
        data["criteria"][str(self.name.value)] = typed
        return data

    def _say(self, text: str) -> None:
        self.message_md.content = text

    def apply(self) -> str:
        """Put the typed criterion in force; the refusal's text (naming the field and its
        range) when a value is out of range, and nothing changes. Returns what it said."""
        self.last_error = ""
        if not self.unlocked():
            self.last_error = "locked: enter the instructor token"
        else:
            try:
                criteria = in_force.apply_criteria(self.recordings_dir, self.fields(), "the page")
            except in_force.CriteriaError as err:
                self.last_error = str(err).removeprefix("invalid criteria in the page:\n")
            except OSError as err:
                self.last_error = f"cannot write: {err.strerror or err}"
        if self.last_error:
            lines = self.last_error.splitlines()
            self._say("**not applied**: " + "<br>".join(md_text(line) for line in lines))
            return self.last_error
        c = self._criterion(criteria)
        self._say(
            f"applied `{c.name}`: trends and logbook entries are scored with these criteria "
            "from now on"
        )
        self.show_criterion()
        return ""

    def reset(self) -> None:
        """The default criteria in force again."""
        if not self.unlocked():
            self._say("**not reset**: locked: enter the instructor token")
            return
        in_force.reset_criteria(self.recordings_dir)
        self._say("the default criteria are in force again")
        self.show_criterion()
