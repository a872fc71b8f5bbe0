"""The "Control" tab: the control system's mode, allocation and grip, the controller's gains
(each within its band, ``commands.gain_band``), the current, and the vessel's crane tip (with a
dock leg's advice to move it, ``web.tabs.advice``)."""

from __future__ import annotations

from typing import Any

from app.console import MODES, Console, Gains, Snapshot, compass_heading_deg
from app.console import commands as cmd
from web.tabs.advice import AdvicePanel, advised_tip
from web.widgets import Operator

TERMS = ("kp", "ki", "kd")


def gain_row_text(values: tuple[float, ...]) -> str:
    return ", ".join(f"{v:g}" for v in values)


def gain_band_text(preset: Gains) -> str:
    """The band each gain may be set in (commands.gain_band), as a small table."""
    lines = ["| band | surge | sway | yaw |", "|---|---|---|---|"]
    for term in TERMS:
        cells = " | ".join(f"0 - {cmd.gain_band(v):g}" for v in getattr(preset, term))
        lines.append(f"| {term} | {cells} |")
    return "\n".join(lines)


def parse_gain_row(term: str, text: str) -> tuple[float, float, float]:
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


class ControlTab:
    def __init__(self, operator: Operator, console: Console) -> None:
        self.operator = operator
        self.console = console
        gui, op = operator.gui, operator
        snap = console.loop.snapshot
        self.mode = op.guard(gui.add_dropdown("Mode", MODES, initial_value=snap.mode))
        self.mode.on_update(op.when_client(lambda: cmd.SetMode(self.mode.value)))
        self.allocation = op.guard(
            gui.add_dropdown(
                "Allocation",
                ("pinv", "priority", "qp"),
                initial_value=snap.allocation or "priority",
            )
        )
        self.allocation.on_update(op.when_client(lambda: cmd.SetAllocation(self.allocation.value)))
        self.grip = op.guard(gui.add_checkbox("Grip", bool(snap.grip)))
        self.grip.on_update(op.when_client(lambda: cmd.SetGrip(bool(self.grip.value))))
        with gui.add_form("Gains") as gains_form:
            self._build_gains(snap, gains_form)
        with gui.add_form("Current") as current_form:
            self.current_speed = op.live_input(
                "current",
                op.bounded(
                    gui.add_number("Speed m/s", round(snap.current_speed_mps, 3), step=0.01),
                    0.0,
                    cmd.CURRENT_MAX_MPS,
                    "m/s",
                ),
            )
            self.current_dir = op.live_input(
                "current",
                op.angle(
                    gui.add_number(
                        "Towards deg",
                        compass_heading_deg(snap.current_direction_rad),
                        step=1.0,
                    )
                ),
            )
            op.action(
                op.guard(gui.add_button("Set current")),
                lambda: cmd.SetCurrent(op.number(self.current_speed), op.degrees(self.current_dir)),
                done="current",
                form=current_form,
            )
        with gui.add_form("Vessel (crane tip)") as vessel_form:
            self.advice = AdvicePanel(op)
            ct = advised_tip(snap)
            lim = cmd.VESSEL_RANGE_M
            self.vessel_n, self.vessel_e = (
                op.live_input("vessel", op.bounded(number, -lim, lim, "m"))
                for number in (
                    gui.add_number("North m", round(ct[0], 2), step=0.1),
                    gui.add_number("East m", round(ct[1], 2), step=0.1),
                )
            )
            for tip_input in (self.vessel_n, self.vessel_e):
                # to the centimetre they follow the crane tip: viser takes the digits it shows
                # from the first value, and a crane tip at 1.0 m showed a later 5.68 as 5.7
                tip_input.precision = 2
            op.action(
                op.guard(gui.add_button("Move vessel")),
                lambda: cmd.MoveVessel(op.number(self.vessel_n), op.number(self.vessel_e), 0.5),
                done="vessel",
                form=vessel_form,
            )

    def _build_gains(self, snap: Snapshot, form: Any) -> None:
        """The gain rows; Enter in a row applies them (``form``), as "Apply gains" does."""
        gui, op = self.operator.gui, self.operator
        preset = snap.scene.preset_gains
        live = snap.gains or preset
        self.gain_md = gui.add_markdown(gain_band_text(preset))
        self.gain_rows = {
            term: op.live_input(
                "gains",
                gui.add_text(
                    f"{term} [surge, sway, yaw]",
                    gain_row_text(getattr(live, term)),
                    hint=f"three numbers, each within its band (see above); {term} of "
                    "the parameter set: " + gain_row_text(getattr(preset, term)),
                ),
            )
            for term in TERMS
        }
        op.action(op.guard(gui.add_button("Apply gains")), self.typed_gains, "gains", form)
        op.action(
            op.guard(gui.add_button("Preset gains")),
            lambda: cmd.SetGains(self.console.loop.snapshot.scene.preset_gains),
            done="gains",
        )

    def typed_gains(self) -> cmd.SetGains:
        """The gains typed in the three rows; ValueError naming the row and entry."""
        rows = {
            term: parse_gain_row(term, str(handle.value)) for term, handle in self.gain_rows.items()
        }
        cmd.check_gain_band(rows, self.console.loop.snapshot.scene.preset_gains)
        return cmd.SetGains(Gains.of(rows["kp"], rows["ki"], rows["kd"]))

    def update(self, live: Snapshot) -> None:
        """Keep the inputs in step with changes made elsewhere (the API, missions, other
        browsers), but not over what the operator is editing."""
        op = self.operator
        if live.gains is not None:
            op.follow(
                "gains",
                [
                    (handle, gain_row_text(getattr(live.gains, term)))
                    for term, handle in self.gain_rows.items()
                ],
            )
            band = gain_band_text(live.scene.preset_gains)
            if self.gain_md.content != band:
                self.gain_md.content = band
        if live.mode != self.mode.value:
            self.mode.value = live.mode
        if live.allocation and live.allocation != self.allocation.value:
            self.allocation.value = live.allocation
        if live.grip is not None and live.grip != self.grip.value:
            self.grip.value = live.grip
        op.follow(
            "current",
            (
                (self.current_speed, round(live.current_speed_mps, 3)),
                (self.current_dir, compass_heading_deg(live.current_direction_rad)),
            ),
        )
        self.advice.update(live)
        tip = advised_tip(live)
        op.follow("vessel", ((self.vessel_n, round(tip[0], 2)), (self.vessel_e, round(tip[1], 2))))
