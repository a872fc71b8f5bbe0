"""The mission builder's panel (one per browser): pick a set-up, add legs from the leg models'
fields, validate and start the built mission.

The field specs come from ``web.mission_builder`` (pure); this module turns them into viser
inputs and hands a built mission to the panel's ``start``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from missions import schema
from web import mission_builder as mb

if TYPE_CHECKING:
    import viser

    from app.console import Console


class BuilderPanel:
    """Builder inputs inside the folder that is open when it is made."""

    def __init__(
        self,
        gui: viser.GuiApi,
        console: Console,
        guard: Callable[[Any], Any],
        start: Callable[[schema.Mission], None],
    ) -> None:
        self.gui = gui
        self.console = console
        self._start = start
        self.legs: list[dict[str, Any]] = []
        self._leg_inputs: dict[str, tuple[mb.FieldSpec, Any]] = {}
        self._leg_folder: Any = None
        library, uploaded = console.mission_names()
        names = tuple(library + uploaded) or ("(none)",)
        self.setup_pick = gui.add_dropdown("Set-up from", names, initial_value=names[0])
        types = tuple(schema.leg_models())
        self.leg_type = gui.add_dropdown("Leg type", types, initial_value=types[0])
        self.leg_type.on_update(lambda _: self._rebuild_leg_inputs())
        self._leg_anchor = gui.add_markdown("**Leg values**")
        self._rebuild_leg_inputs()
        self.add_leg = gui.add_button("Add leg", order=self._leg_anchor.order + 0.2)
        self.add_leg.on_click(self._on_add_leg)
        self.leg_edit = gui.add_button_group(
            "Legs", ("Remove last", "Clear"), order=self._leg_anchor.order + 0.3
        )
        self.leg_edit.on_click(self._on_leg_edit)
        self.legs_md = gui.add_markdown("*no legs yet*", order=self._leg_anchor.order + 0.4)
        self.validate_button = gui.add_button("Validate", order=self._leg_anchor.order + 0.5)
        self.validate_button.on_click(self._on_validate)
        self.build_start = guard(
            gui.add_button("Start built mission", order=self._leg_anchor.order + 0.6)
        )
        self.build_start.on_click(self._on_start_built)
        self.builder_md = gui.add_markdown("", order=self._leg_anchor.order + 0.7)

    def _rebuild_leg_inputs(self) -> None:
        """Inputs for the chosen leg type, from its pydantic model's fields."""
        if self._leg_folder is not None:
            self._leg_folder.remove()
        model = schema.leg_models()[self.leg_type.value]
        self._leg_inputs = {}
        with self.gui.add_folder(
            f"{self.leg_type.value} leg", order=self._leg_anchor.order + 0.1
        ) as folder:
            for spec in mb.field_specs(model):
                self._leg_inputs[spec.name] = (spec, self._leg_input(spec))
        self._leg_folder = folder

    def _leg_input(self, spec: mb.FieldSpec) -> Any:
        gui, value = self.gui, mb.initial_value(spec)
        hint = spec.description or None
        if spec.kind == "bool":
            return gui.add_checkbox(spec.label, bool(value), hint=hint)
        if spec.kind in ("choice", "tristate"):
            return gui.add_dropdown(
                spec.label,
                spec.choices,
                initial_value=str(value if value is not None else spec.choices[0]),
                hint=hint,
            )
        if spec.kind in ("number", "integer") and not spec.optional:
            step = 1.0 if spec.kind == "integer" else _step_for(spec)
            return gui.add_number(spec.label, value, min=spec.lo, max=spec.hi, step=step, hint=hint)
        return gui.add_text(spec.label, mb.text_of(spec, value), hint=hint)

    def _on_add_leg(self, event: Any) -> None:
        try:
            values = {
                name: mb.parse_input(spec, handle.value)
                for name, (spec, handle) in self._leg_inputs.items()
            }
            leg = mb.build_leg(str(self.leg_type.value), values)
            schema.parse_mission(
                {
                    "format_version": 1,
                    "name": "check",
                    "setup": {"params": "full-scale", "depth_m": 100.0},
                    "legs": [leg],
                },
                "<leg>",
            )
        except ValueError as err:
            self.builder_md.content = f"**invalid leg**: {err}"
            return
        self.legs.append(leg)
        self._show_legs()
        self.builder_md.content = f"added {leg['type']} leg"

    def _on_leg_edit(self, event: Any) -> None:
        if self.leg_edit.value == "Clear":
            self.legs.clear()
        elif self.legs:
            self.legs.pop()
        self._show_legs()

    def _show_legs(self) -> None:
        lines = [f"{i + 1}. `{mb.describe_leg(leg)}`" for i, leg in enumerate(self.legs)]
        self.legs_md.content = "\n".join(lines) if lines else "*no legs yet*"

    def _built_mission(self) -> schema.Mission | None:
        try:
            base = self.console.find_mission(str(self.setup_pick.value))
            return mb.build_mission("built mission", base.setup, self.legs)
        except (KeyError, ValueError) as err:
            self.builder_md.content = f"**invalid**: {err}"
            return None

    def _on_validate(self, event: Any) -> None:
        mission = self._built_mission()
        if mission is not None:
            self.builder_md.content = f"valid: {len(mission.legs)} legs"

    def _on_start_built(self, event: Any) -> None:
        mission = self._built_mission()
        if mission is not None:
            self._start(mission)


def _step_for(spec: mb.FieldSpec) -> float:
    span = (spec.hi or 1.0) - (spec.lo or 0.0)
    return 0.01 if span <= 10.0 else 0.1
