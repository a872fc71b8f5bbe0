"""From a mission's set-up to a ``Simulation``: parameter sets (with the robustness study's
variations), current, waves, control settings and the docking frame (charted and real)."""

from __future__ import annotations

import math

import numpy as np

from control.config import Allocation, ControlSettings, Feedback
from control.simulation import Simulation
from missions import schema
from sim import environment as envmod
from sim import params as params_mod
from sim.docking import DockingFrame
from sim.vessel import VesselMotion


def load_params(name_or_path: str) -> params_mod.ParameterSet:
    """A parameter set by name or file; a file that is not text (a binary, a file in another
    encoding) is a ParameterError naming the file, not a bare UTF-8 decoding error."""
    try:
        return params_mod.load(name_or_path)
    except UnicodeDecodeError as err:
        raise params_mod.ParameterError(
            f"cannot read the parameter file {name_or_path}: it is not UTF-8 text (byte "
            f"{err.start} is 0x{err.object[err.start]:02x}); a parameter set is a TOML or "
            "JSON file"
        ) from None


def build_simulation(
    mission: schema.Mission,
    seed: int | None = None,
    allocation: Allocation | None = None,
    feedback: Feedback | None = None,
    feedforward: bool | None = None,
    params: params_mod.ParameterSet | None = None,
) -> Simulation:
    """The Simulation a mission's set-up describes (options override the file; ``params``
    replaces the parameter set the file names, e.g. a campaign's with scaled sensor noise)."""
    s = mission.setup
    ps = load_params(s.params) if params is None else params
    plant_ps = None
    if s.plant.mass_scale != 1.0 or s.plant.weight_scale != 1.0:
        plant_ps = vary_tree(ps, s.plant.mass_scale, s.plant.weight_scale)
    cur = current_params(s.current)
    waves = None
    if s.waves is not None:
        water_depth = s.waves.water_depth_m
        if water_depth is None and s.docking_frame is not None:
            water_depth = s.docking_frame.landing_depth_m
        waves = envmod.WaveParams(
            significant_height_m=s.waves.significant_height_m,
            peak_period_s=s.waves.peak_period_s,
            direction_rad=math.radians(s.waves.direction_deg),
            load=s.waves.load,
            water_depth_m=math.inf if water_depth is None else water_depth,
        )
    vessel = None
    if s.vessel is not None:
        wave_heading = 0.0 if s.waves is None else s.waves.direction_deg
        heading = wave_heading + 180.0 if s.vessel.heading_deg is None else s.vessel.heading_deg
        vessel = VesselMotion(
            heading_rad=math.radians(heading),
            heave_compensation=s.vessel.heave_compensation,
            heave_compensation_efficiency=s.vessel.heave_compensation_efficiency,
        )
    settings = ControlSettings(
        feedback=feedback or s.feedback,
        allocation=allocation or s.allocation,
        reference=s.reference,
        feedforward=s.feedforward if feedforward is None else feedforward,
        heave_force_newton=s.heave_force_newton,
        r_mount_config_m=None
        if s.r_mount_config_m is None
        else (
            float(s.r_mount_config_m[0]),
            float(s.r_mount_config_m[1]),
            float(s.r_mount_config_m[2]),
        ),
    )
    sim = Simulation(
        ps,
        tree_depth_m=s.depth_m,
        settings=settings,
        crane_tip_n=np.array([*s.crane_tip_n, 0.0]),
        current=cur,
        waves=waves,
        seed=s.seed if seed is None else seed,
        tree_heading_rad=math.radians(s.heading_deg),
        plant_ps=plant_ps,
        start_gripping=s.start_gripping,
        vessel=vessel,
        wire=s.wire,
    )
    chart = charted_frame(mission)
    if s.docking_frame is not None and chart is not None:
        real_center = chart.center_n + np.asarray(s.docking_frame.survey_error_ne_m, float)
        sim.set_docking_frame(DockingFrame(real_center, chart.heading_rad, chart.landing_depth_m))
    for fault in mission.faults:
        sim.inject_fault(fault.fault())
    return sim


def current_params(c: schema.CurrentSetup) -> envmod.CurrentParams:
    """The current (and its bounded random walk) a set-up's ``[setup.current]`` describes."""
    d = math.radians(c.direction_deg)
    db = math.radians(c.direction_band_deg)
    return envmod.CurrentParams(
        speed_mps=c.speed_mps,
        direction_rad=d,
        speed_min_mps=max(c.speed_mps - c.speed_band_mps, 0.0),
        speed_max_mps=c.speed_mps + c.speed_band_mps,
        direction_min_rad=d - db,
        direction_max_rad=d + db,
        speed_walk_mps_per_sqrt_s=c.speed_walk_mps_per_sqrt_s,
        direction_walk_rad_per_sqrt_s=math.radians(c.direction_walk_deg_per_sqrt_s),
    )


def charted_frame(mission: schema.Mission) -> DockingFrame | None:
    """The docking frame where the mission's chart puts it (what the operator aligns to)."""
    f = mission.setup.docking_frame
    if f is None:
        return None
    return DockingFrame(
        np.asarray(f.center_ne_m, float), math.radians(f.heading_deg), f.landing_depth_m
    )


def vary_tree(
    ps: params_mod.ParameterSet, mass_scale: float, weight_scale: float
) -> params_mod.ParameterSet:
    """The same parameter set with the tree's mass (rigid-body mass and inertia) and submerged
    weight scaled: the plant of the robustness study (thesis 4.2.3)."""
    tree = ps.spec.tree
    w0 = tree.submerged_weight_newton or ps.tree.submerged_weight_newton
    new_tree = tree.model_copy(
        update=dict(
            mass_kg=tree.mass_kg * mass_scale,
            rigid_body_inertia=[v * mass_scale for v in tree.rigid_body_inertia],
            submerged_weight_newton=w0 * weight_scale,
        )
    )
    return params_mod.build(ps.spec.model_copy(update=dict(tree=new_tree)))
