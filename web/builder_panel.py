"""The mission builder's panel (one per browser): pick a set-up and edit it (parameter set,
depth, current, docking frame), add legs from the leg models' fields, validate, preview the
mission in this browser's scene, start it, and download, save or upload mission files.

The field specs, the set-up editing, file reading, error wording and the preview's geometry
come from ``web.mission_builder`` (pure); this module turns them into viser inputs and scene
nodes and hands a built mission to the panel's ``start``.

Layout: every input lives in a container made while the builder's folder is open (the
constructor runs inside it). The leg's inputs are re-made when the leg type changes, from a
callback on another thread where no container is open; they go into a fixed, label-less
folder (``_leg_box``) that the callback re-enters, so they stay in place in the builder and on
the Mission tab.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from app.console import md_code, md_text
from missions import schema
from web import geometry as geo
from web import mission_builder as mb
from web.widgets import Bounds, wrap_deg, wrapped_text

if TYPE_CHECKING:
    import viser

    from app.console import Console, Snapshot

PATH_COLOR = (200, 40, 200)
FRAME_COLOR = (200, 40, 200)
MAX_PREVIEW_LABELS = 40
"""Targets labelled in the preview at most (a long waypoint list stays readable)."""


class BuilderPanel:
    """Builder inputs inside the folder that is open when it is made."""

    def __init__(
        self,
        client: viser.ClientHandle,
        console: Console,
        guard: Callable[[Any], Any],
        start: Callable[[schema.Mission], None],
        is_unlocked: Callable[[], bool],
        pickers: Sequence[Any] = (),
        show: Callable[[np.ndarray, str], None] | None = None,
    ) -> None:
        """``show``: turns this browser's camera to points (k, 3) named in words; the
        preview is shown with it when it lies out of the live run's sight."""
        self.client = client
        self._show = show
        self._shown_extent: tuple[float, ...] | None = None
        """The preview's extent the camera was last turned to (not again for the same)."""
        self.gui = gui = client.gui
        self.console = console
        self._start = start
        self._is_unlocked = is_unlocked
        self._pickers = tuple(pickers)
        """Other mission dropdowns of the page, refreshed when a mission is saved here."""
        self.legs: list[dict[str, Any]] = []
        self._leg_inputs: dict[str, tuple[mb.FieldSpec, Any]] = {}
        self._leg_folder: Any = None
        self._rebuild_lock = threading.Lock()
        self._preview: list[Any] = []
        self._preview_lock = threading.Lock()
        self._preview_scene = -1
        """Scene version the preview was drawn over: a new run (any mission) removes it."""

        names = self._mission_names()
        self.setup_pick = gui.add_dropdown(
            "Set-up from",
            names,
            initial_value=names[0],
            hint="the mission whose set-up the built mission starts from; edit it below",
        )
        self.setup_pick.on_update(self._on_setup_pick)
        with gui.add_folder("Set-up"):
            self._build_setup_inputs()
        types = tuple(schema.leg_models())
        self.leg_type = gui.add_dropdown("Leg type", types, initial_value=types[0])
        self.leg_type.on_update(lambda _: self._rebuild_leg_inputs())
        self._leg_box = gui.add_folder(None)
        self._rebuild_leg_inputs()
        self.add_leg = gui.add_button("Add leg")
        self.add_leg.on_click(self._on_add_leg)
        self.leg_edit = gui.add_button_group("Legs", ("Remove last", "Clear"))
        self.leg_edit.on_click(self._on_leg_edit)
        self.legs_md = gui.add_markdown("*no legs yet*")
        self.validate_button = gui.add_button("Validate")
        self.validate_button.on_click(self._on_validate)
        self.build_start = guard(gui.add_button("Start built mission"))
        self.build_start.on_click(self._on_start_built)
        self.builder_md = gui.add_markdown("")
        with gui.add_folder("Mission file"):
            self.download_button = gui.add_button(
                "Download TOML", hint="the built mission as a mission file"
            )
            self.download_button.on_click(self._on_download)
            self.save_button = guard(
                gui.add_button(
                    "Save to console",
                    hint="keep the built mission in the console under its name (startable "
                    "from 'Mission' and the HTTP API)",
                )
            )
            self.save_button.on_click(self._on_save)
            self.upload_button = guard(
                gui.add_upload_button(
                    "Upload mission file",
                    hint=f"a mission TOML file (at most {schema.MAX_FILE_BYTES // 1024} kB): "
                    "kept in the console and loaded into the builder",
                )
            )
            self.upload_button.on_upload(self._on_upload)
        self._load_setup()

    # ------------------------------------------------------------------ set-up
    def _build_setup_inputs(self) -> None:
        gui, labels = self.gui, mb.SETUP_LABELS
        self.name_text = gui.add_text(labels["name"], "built mission", hint="1 to 80 characters")
        sets = mb.parameter_sets()
        self.params = gui.add_dropdown(labels["setup.params"], sets, initial_value=sets[0])
        # no min or max on the inputs: viser clamps to them silently; the ranges are checked
        # here, with the field and the range on the builder's message line
        self.depth = gui.add_number(labels["setup.depth_m"], 100.0, step=0.1, hint="tree centre")
        self.current_speed = gui.add_number(labels["setup.current.speed_mps"], 0.0, step=0.01)
        self.current_dir = gui.add_number(
            labels["setup.current.direction_deg"],
            0.0,
            step=1.0,
            hint="direction the current flows towards, 0 to 360",
        )
        self.frame_on = gui.add_checkbox(
            labels["setup.docking_frame"], False, hint="a frame to land on (dock and lift legs)"
        )
        self.frame_n = gui.add_number("Frame north [m]", 0.0, step=0.1)
        self.frame_e = gui.add_number("Frame east [m]", 0.0, step=0.1)
        self.frame_psi = gui.add_number(
            labels["setup.docking_frame.heading_deg"], 0.0, step=1.0, hint="0 to 360"
        )
        self.landing = gui.add_number(
            labels["setup.docking_frame.landing_depth_m"],
            110.0,
            step=0.1,
            hint="depth of the seabed the frame stands on; deeper than the tree",
        )
        self._bounds = {
            id(handle): Bounds(str(handle.label), lo, hi, unit)
            for handle, lo, hi, unit in (
                (self.depth, 5.0, 4000.0, "m"),
                (self.current_speed, 0.0, 3.0, "m/s"),
                (self.frame_n, -1000.0, 1000.0, "m"),
                (self.frame_e, -1000.0, 1000.0, "m"),
                (self.landing, 5.0, 4000.0, "m"),
            )
        }
        self._angles = {id(self.current_dir), id(self.frame_psi)}
        for handle in (
            self.depth,
            self.current_speed,
            self.current_dir,
            self.frame_on,
            self.frame_n,
            self.frame_e,
            self.frame_psi,
            self.landing,
        ):
            handle.on_update(self._on_setup_edit)

    def _number(self, handle: Any) -> float:
        """A set-up input's value: checked against its range (ValueError naming the field and
        the range) or, for an angle, wrapped into [0, 360)."""
        value = float(handle.value)
        if id(handle) in self._angles:
            if not np.isfinite(value):
                raise ValueError(f"{handle.label}: {value:g} is not a finite number")
            return wrap_deg(value)
        return self._bounds[id(handle)].check(value)

    def _setup_values(self) -> mb.SetupValues:
        return mb.SetupValues(
            params=str(self.params.value),
            depth_m=self._number(self.depth),
            current_speed_mps=self._number(self.current_speed),
            current_direction_deg=self._number(self.current_dir),
            frame=bool(self.frame_on.value),
            frame_north_m=self._number(self.frame_n),
            frame_east_m=self._number(self.frame_e),
            frame_heading_deg=self._number(self.frame_psi),
            landing_depth_m=self._number(self.landing),
        )

    def _load_setup(self) -> None:
        """Fill the set-up inputs from the mission picked in "Set-up from"."""
        try:
            base = self.console.find_mission(str(self.setup_pick.value))
        except (KeyError, ValueError):
            return
        v = mb.SetupValues.of(base.setup)
        if v.params not in self.params.options:
            self.params.options = (*self.params.options, v.params)
        _set(self.params, v.params)
        _set(self.depth, v.depth_m)
        _set(self.current_speed, v.current_speed_mps)
        _set(self.current_dir, wrap_deg(v.current_direction_deg))
        _set(self.frame_on, v.frame)
        _set(self.frame_n, v.frame_north_m)
        _set(self.frame_e, v.frame_east_m)
        _set(self.frame_psi, wrap_deg(v.frame_heading_deg))
        _set(self.landing, v.landing_depth_m)

    def _on_setup_pick(self, event: Any) -> None:
        if event.client is None:
            return
        self._load_setup()
        self.builder_md.content = f"set-up from {md_code(self.setup_pick.value)}"
        self._draw_preview()

    def _on_setup_edit(self, event: Any) -> None:
        """A typed set-up value: an angle outside [0, 360) is wrapped (and the message line
        says so), a value out of its range is refused on the message line."""
        if event.client is None:
            return
        handle = event.target
        if id(handle) in self._angles:
            value = float(handle.value)
            if np.isfinite(value) and wrap_deg(value) != value:
                _set(handle, wrap_deg(value))
                self.builder_md.content = md_text(wrapped_text(str(handle.label), value))
        elif id(handle) in self._bounds:
            try:
                self._number(handle)
            except ValueError as err:
                self._error(str(err))
                return
        self._draw_preview()

    def _setup(self) -> schema.Setup:
        """The edited set-up; KeyError or MissionError (one line) when it cannot be made."""
        base = self.console.find_mission(str(self.setup_pick.value))
        return mb.edited_setup(base.setup, self._setup_values())

    # ------------------------------------------------------------------ legs
    def _rebuild_leg_inputs(self) -> None:
        """Inputs for the chosen leg type, from its pydantic model's fields, in the fixed box
        (entered here: this runs on a callback thread with no container open)."""
        with self._rebuild_lock:
            if self._leg_folder is not None:
                self._leg_folder.remove()
            leg_type = str(self.leg_type.value)
            model = schema.leg_models()[leg_type]
            self._leg_inputs = {}
            with self._leg_box, self.gui.add_folder(f"{leg_type} leg") as folder:
                for spec in mb.field_specs(model):
                    self._leg_inputs[spec.name] = (spec, self._leg_input(spec))
                    if spec.kind == "json":
                        example = mb.PAIRS_EXAMPLE if spec.pairs else mb.VECTOR_EXAMPLE
                        what = "north, east pairs" if spec.pairs else "surge, sway, yaw"
                        self.gui.add_markdown(f"<small>{what}, e.g. `{example}`</small>")
            self._leg_folder = folder

    def _leg_input(self, spec: mb.FieldSpec) -> Any:
        gui, value = self.gui, mb.initial_value(spec)
        hint = spec.hint
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
            # no min or max: viser would clamp to them silently; parse_input refuses a value
            # out of range with the field and its range
            handle = gui.add_number(spec.label, value, step=step, hint=hint)
            handle.on_update(lambda event: self._on_leg_number(spec, event))
            return handle
        if spec.kind == "json" and value is None and spec.name in ("kp", "ki", "kd"):
            snap = self.console.loop.snapshot
            value = list(getattr(snap.gains or snap.scene.preset_gains, spec.name))
        return gui.add_text(spec.label, mb.text_of(spec, value), hint=hint)

    def _on_leg_number(self, spec: mb.FieldSpec, event: Any) -> None:
        """A typed leg number out of its range is refused on the message line at once."""
        if event.client is None:
            return
        try:
            mb.parse_input(spec, event.target.value)
        except ValueError as err:
            self._error(str(err))

    def _on_add_leg(self, event: Any) -> None:
        try:
            values = {
                name: mb.parse_input(spec, handle.value)
                for name, (spec, handle) in self._leg_inputs.items()
            }
            leg = mb.build_leg(str(self.leg_type.value), values)
            mb.build_mission("check", self._setup(), [*self.legs, leg])
        except KeyError:
            self._error(f"'Set-up from': no mission named {self.setup_pick.value!r}")
            return
        except ValueError as err:
            self._error(f"invalid leg: {mb.one_line(err)}")
            return
        self.legs.append(leg)
        self._show_legs()
        self.builder_md.content = f"added {leg['type']} leg"
        self._draw_preview()

    def _on_leg_edit(self, event: Any) -> None:
        if self.leg_edit.value == "Clear":
            self.legs.clear()
            self._clear_preview()
        elif self.legs:
            self.legs.pop()
            self._draw_preview()
        self._show_legs()

    def _show_legs(self) -> None:
        lines = [f"{i + 1}. {md_code(mb.describe_leg(leg))}" for i, leg in enumerate(self.legs)]
        self.legs_md.content = "\n".join(lines) if lines else "*no legs yet*"

    def _error(self, text: str) -> None:
        self.builder_md.content = f"**error**: {md_text(text)}"

    def say(self, text: str) -> None:
        """Show an error from outside the panel (the view's upload limits)."""
        self._error(text)

    def _built_mission(self) -> schema.Mission | None:
        """The built mission, or None with the reason shown on one line."""
        if not self.legs:
            self._error("add at least one leg")
            return None
        try:
            return mb.build_mission(str(self.name_text.value).strip(), self._setup(), self.legs)
        except KeyError:
            self._error(f"'Set-up from': no mission named {self.setup_pick.value!r}")
        except ValueError as err:
            self._error(f"invalid mission: {mb.one_line(err)}")
        return None

    def _on_validate(self, event: Any) -> None:
        mission = self._built_mission()
        if mission is not None:
            self.builder_md.content = f"valid: {len(mission.legs)} legs"
            self._draw_preview()

    def _on_start_built(self, event: Any) -> None:
        mission = self._built_mission()
        if mission is not None:
            self._clear_preview()
            self._start(mission)

    # ------------------------------------------------------------------ files
    def _mission_names(self) -> tuple[str, ...]:
        library, uploaded = self.console.mission_names()
        return tuple(library + uploaded) or ("(none)",)

    def _refresh_names(self) -> None:
        names = self._mission_names()
        for dropdown in (self.setup_pick, *self._pickers):
            dropdown.options = names

    def _on_download(self, event: Any) -> None:
        mission = self._built_mission()
        if mission is None:
            return
        text = schema.dump_mission(mission)
        name = mb.file_name(mission)
        self.client.send_file_download(name, text.encode(), save_immediately=True)
        self.builder_md.content = f"downloaded {md_code(name)} ({len(mission.legs)} legs)"

    def _keep(self, mission: schema.Mission) -> bool:
        """Keep a mission in the console (as the HTTP upload does); False with the reason."""
        if not self._is_unlocked():
            self._error("locked: enter the console token under Access")
            return False
        try:
            self.console.add_upload(mission)
        except ValueError as err:
            self._error(mb.one_line(err))
            return False
        self._refresh_names()
        return True

    def _on_save(self, event: Any) -> None:
        mission = self._built_mission()
        if mission is not None and self._keep(mission):
            self.builder_md.content = (
                f"saved {md_code(mission.name)} in the console: start it from 'Mission' above"
            )

    def _on_upload(self, event: Any) -> None:
        if not self._is_unlocked():
            self._error("locked: enter the console token under Access")
            return
        upload = self.upload_button.value
        try:
            mission = mb.parse_upload(upload.name, upload.content)
        except schema.MissionError as err:
            self._error(f"upload refused: {err}")
            return
        if not self._keep(mission):
            return
        _set(self.setup_pick, mission.name)
        self._load_setup()
        _set(self.name_text, mission.name)
        self.legs = [leg.model_dump(mode="json", exclude_defaults=True) for leg in mission.legs]
        self._show_legs()
        self.builder_md.content = (
            f"uploaded {md_code(mission.name)} ({len(mission.legs)} legs): loaded into the builder"
        )
        self._draw_preview()

    # ------------------------------------------------------------------ preview
    def _draw_preview(self) -> None:
        """Draw the built mission's path, targets and docking frame in this browser's scene
        (replacing the last preview); nothing when the set-up is not valid."""
        try:
            setup = self._setup()
            pv = mb.preview(setup, self.legs)
        except (KeyError, ValueError):
            return
        snap = self.console.loop.snapshot
        size = max(snap.scene.tree_dimensions_m)
        scene = self.client.scene
        with self._preview_lock:
            self._remove_preview_nodes()
            self._preview_scene = snap.scene.version
            nodes = self._preview
            depth = pv.depth_m
            if len(pv.path_ne) >= 2:
                pts = np.array([[n, e, depth] for n, e in pv.path_ne])
                nodes.append(
                    scene.add_line_segments(
                        "/builder_preview/path",
                        geo.polyline_segments(pts),
                        PATH_COLOR,
                        thickness=3.0,
                        thickness_units="screen",
                    )
                )
            nodes.append(
                scene.add_label(
                    "/builder_preview/start",
                    "start",
                    position=(pv.path_ne[0][0], pv.path_ne[0][1], depth),
                    anchor="bottom-left",  # targets' labels hang below: both readable
                )
            )
            for k, (n, e, tag) in enumerate(pv.targets[:MAX_PREVIEW_LABELS]):
                nodes.append(
                    scene.add_icosphere(
                        f"/builder_preview/target_{k}",
                        radius=0.08 * size,
                        color=PATH_COLOR,
                        position=(n, e, depth),
                    )
                )
                nodes.append(
                    scene.add_label(f"/builder_preview/label_{k}", tag, position=(n, e, depth))
                )
            if pv.frame is not None:
                nodes.extend(self._draw_frame(pv.frame, snap.scene.layout.frame_size_m, size))
        self._show_if_out_of_sight(pv, snap, size)

    def _show_if_out_of_sight(self, pv: mb.Preview, snap: Snapshot, size: float) -> None:
        """Turn the camera to the preview when it lies more than two tree sizes above or below
        the live tree, or ten away across (drawn there, it was out of the picture: 150 m above
        the camera), once for each new extent of it."""
        points = [(n, e, pv.depth_m) for n, e in pv.path_ne]
        if pv.frame is not None:
            points.append((pv.frame[0], pv.frame[1], pv.frame[3]))
        pts = np.array(points, float)
        tree = np.array(snap.tree_eta_n[0:3])
        far = (
            np.abs(pts[:, 2] - tree[2]).max() > 2.0 * size
            or np.hypot(*(pts[:, 0:2] - tree[0:2]).T).min() > 10.0 * size
        )
        extent = tuple(np.round(np.concatenate([pts.min(axis=0), pts.max(axis=0)]), 1))
        if self._show is None or not far or extent == self._shown_extent:
            return
        self._shown_extent = extent
        self._show(pts, f"the built mission's preview ({pv.depth_m:g} m deep)")

    def _draw_frame(
        self, frame: tuple[float, float, float, float], frame_size_m: Any, size: float
    ) -> list[Any]:
        """The charted frame's outline at the landing depth, a line along its heading and a
        label (the outline's size is the running parameter set's frame)."""
        n, e, psi, depth = frame
        half = 0.5 * np.asarray(frame_size_m, float)[:2]
        c, s = np.cos(psi), np.sin(psi)
        corners = [(half[0], half[1]), (half[0], -half[1]), (-half[0], -half[1])]
        corners += [(-half[0], half[1]), (half[0], half[1])]
        ring = np.array([[n + c * x - s * y, e + s * x + c * y, depth] for x, y in corners])
        bow = np.array([[n, e, depth], [n + c * size, e + s * size, depth]])
        scene = self.client.scene
        return [
            scene.add_line_segments(
                "/builder_preview/frame",
                geo.polyline_segments(ring),
                FRAME_COLOR,
                thickness=3.0,
                thickness_units="screen",
            ),
            scene.add_line_segments(
                "/builder_preview/frame_heading",
                geo.polyline_segments(bow),
                FRAME_COLOR,
                thickness=3.0,
                thickness_units="screen",
            ),
            scene.add_label(
                "/builder_preview/frame_label", "docking frame (built)", position=(n, e, depth)
            ),
        ]

    def update(self, snap: Snapshot) -> None:
        """From the panel's updates: a new run (a mission started here, from the Mission
        list, the API or another browser; a reset or a replay) removes the preview."""
        if self._preview and snap.scene.version != self._preview_scene:
            self._clear_preview()

    def _remove_preview_nodes(self) -> None:
        for node in self._preview:
            node.remove()
        self._preview.clear()

    def _clear_preview(self) -> None:
        with self._preview_lock:
            self._remove_preview_nodes()

    @property
    def preview_nodes(self) -> int:
        """Scene nodes of the preview drawn now (for tests)."""
        with self._preview_lock:
            return len(self._preview)


def _set(handle: Any, value: Any) -> None:
    """Set an input's value from the server (viser allows it at run time)."""
    handle.value = value


def _step_for(spec: mb.FieldSpec) -> float:
    span = (spec.hi or 1.0) - (spec.lo or 0.0)
    return 0.01 if span <= 10.0 else 0.1
