"""Building a simulation: from a parameter set and the run's options to the parts of its start.

``build`` checks the options, spawns the run's random streams from its seed, builds the plant's
arrays and start state, the environment (``control.site_motion.SiteMotion``), the sensors'
noise, and, with control, the control system's configuration, state and first estimate, and
hands them back as a ``Start`` that ``control.simulation.Simulation`` takes over. Nothing here
steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from control import allocation as alloc
from control import loop, model, quality
from control.config import (
    ControlSettings,
    Gains,
    control_arrays,
    pilot_capacity,
    system_thruster_config,
)
from control.controller_state import ControllerState
from control.site_motion import REFRESH_S, WIRE_MODELS, SiteMotion, steady_current
from control.startup import StartupReport, check_mount_vector, initial_estimate
from sim import environment as envmod
from sim import plant, sensors
from sim import vessel as vesselmod
from sim.gnc import Rzyx
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]
DT_RANGE_S = (1e-4, 0.05)
"""Plant step sizes accepted [s] (RK4 on the 2.5 Hz gripper mode is stable below 0.18 s)."""
LONG_CHUNK_S = 5.0
"""The longest chunk while nothing but the quasi-static wire's entries needs a refresh
(``Simulation._still``: winch and crane at rest, no sea, no faults) [s]. Each chunk costs some
Python besides its steps; longer chunks share it over more steps, and much longer ones gain
little while their rows outgrow the processor's cache (docs/performance.md)."""


def initial_state(
    ps: ParameterSet,
    tree_position_n: FloatArray,
    tree_heading_rad: float = 0.0,
    has_rov: bool = True,
) -> FloatArray:
    """Tree at rest at the given position and heading, ROV (if any) exactly on its mount."""
    x = np.zeros(plant.N_STATE)
    x[0:3] = tree_position_n
    x[5] = tree_heading_rad
    R_t = Rzyx(0.0, 0.0, tree_heading_rad)
    x[12:15] = tree_position_n + R_t @ ps.mount.r_rov_from_tree_tree_m
    x[17] = tree_heading_rad + ps.mount.psi_rov_from_tree_rad if has_rov else 0.0
    return x


def finite_vector(name: str, value: object, length: int) -> FloatArray:
    """A command vector of the right length with finite entries, else ValueError naming it."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != (length,):
        raise ValueError(f"{name} must have {length} entries, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return arr


@dataclass(frozen=True, eq=False)
class Start:
    """A simulation's parts as it starts (see ``Simulation`` for each one's meaning)."""

    plant_ps: ParameterSet
    dt_s: float
    chunk_steps: int
    refresh_steps: int
    long_chunk_steps: int
    has_rov: bool
    control_on: bool
    arrays: plant.PlantArrays
    site: SiteMotion
    sensor_cfg: sensors.SensorConfig
    noise_stream: sensors.NoiseStream
    x: FloatArray
    held_y: FloatArray
    gripping: bool
    settings: ControlSettings
    sysm: model.SystemModel
    gains: Gains
    thruster_config: alloc.ThrusterConfig
    C: loop.ControlArrays
    controller_state: ControllerState
    pilot_capacity: FloatArray
    xhat: FloatArray
    P_cov: FloatArray
    Q: loop.QualityState
    target: FloatArray
    startup: StartupReport


def _check(
    dt_s: float,
    chunk_steps: int,
    control: bool,
    has_rov: bool,
    wire: str,
    wire_damping_ratio: float,
) -> None:
    if wire not in WIRE_MODELS:
        raise ValueError(f"wire must be one of {', '.join(WIRE_MODELS)}, got {wire!r}")
    if not (math.isfinite(wire_damping_ratio) and 0.0 <= wire_damping_ratio <= 1.0):
        raise ValueError(f"wire_damping_ratio must lie in [0, 1], got {wire_damping_ratio!r}")
    if not (DT_RANGE_S[0] <= dt_s <= DT_RANGE_S[1]):
        raise ValueError(f"dt_s must be in [{DT_RANGE_S[0]:g}, {DT_RANGE_S[1]:g}] s, got {dt_s}")
    if control and not has_rov:
        raise ValueError("control needs the ROV (has_rov=True)")
    if not (isinstance(chunk_steps, int) and chunk_steps >= 1):
        raise ValueError(f"chunk_steps must be a whole number >= 1, got {chunk_steps}")


def chunk_lengths(dt_s: float, chunk_steps: int) -> tuple[int, int]:
    """(steps between refreshes of the slow parts (``REFRESH_S``), the longest chunk while
    they stand still (``LONG_CHUNK_S``; a ``chunk_steps`` under a second keeps every chunk
    that short))."""
    refresh_steps = max(1, round(REFRESH_S / dt_s))
    if chunk_steps < refresh_steps:
        return refresh_steps, chunk_steps
    return refresh_steps, refresh_steps * round(LONG_CHUNK_S / REFRESH_S)


def build(
    ps: ParameterSet,
    *,
    tree_depth_m: float,
    settings: ControlSettings | None,
    control: bool,
    has_rov: bool,
    crane_tip_n: FloatArray | tuple[float, ...],
    current: envmod.CurrentParams | None,
    waves: envmod.WaveParams | None,
    seed: int,
    dt_s: float,
    tree_heading_rad: float,
    chunk_steps: int,
    plant_ps: ParameterSet | None,
    start_gripping: bool,
    vessel: vesselmod.VesselMotion | None,
    wire: str,
    wire_damping_ratio: float,
) -> Start:
    """The parts of a simulation at its start (the options as ``Simulation`` takes them)."""
    _check(dt_s, chunk_steps, control, has_rov, wire, wire_damping_ratio)
    truth = plant_ps or ps
    refresh_steps, long_chunk_steps = chunk_lengths(dt_s, chunk_steps)
    arrays = plant.plant_arrays(truth, has_rov=has_rov)
    # One stream per purpose, each spawned from the seed and read in step order, so the
    # numbers a step gets do not depend on how the run is cut into chunks, nor on what
    # else draws (a current that walks leaves the sensors' noise as it is).
    streams = np.random.SeedSequence(seed).spawn(4)
    rng_current, rng_dropouts, rng_noise, rng_waves = (np.random.default_rng(s) for s in streams)
    site = SiteMotion(
        truth,
        tree_depth_m=tree_depth_m,
        crane_tip_n=finite_vector("crane_tip_n", crane_tip_n, 3),
        current=current or steady_current(0.0, 0.0),
        waves=waves,
        vessel=vessel,
        wire=wire,
        wire_damping_ratio=wire_damping_ratio,
        dt_s=dt_s,
        refresh_steps=refresh_steps,
        rng_current=rng_current,
        rng_waves=rng_waves,
        model_spring=control,
        model_tree_weight_newton=ps.tree.submerged_weight_newton,
    )
    tip = site.crane_tip_n
    x = initial_state(truth, np.array([tip[0], tip[1], tree_depth_m]), tree_heading_rad, has_rov)
    if wire == "moordyn":
        site.start_moordyn_wire(x, arrays.tree_r_att)
    settings = settings or ControlSettings()
    r_cfg = settings.r_mount_config_m
    sysm = model.system_model(
        ps, site.wire_length_m, None if r_cfg is None else np.asarray(r_cfg, float)
    )
    gains = settings.gains or Gains.of(ps.gains.kp, ps.gains.ki, ps.gains.kd)
    C = control_arrays(ps, sysm, settings, gains, tip[0:2], dt_s)
    if has_rov and not start_gripping:
        # the ROV waits free, 3 m further back and 1 m above its mount (a hook-up to come)
        c, s = math.cos(x[5]), math.sin(x[5])
        x[12:15] += np.array([-3.0 * c, -3.0 * s, -1.0])
    held_y = sensors.true_outputs(x)
    xhat, P_cov = initial_estimate(held_y, C, ps)
    eta0 = xhat[0:3] if settings.feedback == "ekf" else x[[0, 1, 5]]
    startup = (
        check_mount_vector(
            held_y,
            sysm.r_rov_from_tree_tree_m,
            tip,
            site.wire_length_m,
            ps,
            site.current_state.speed_mps,
        )
        if control and start_gripping
        else StartupReport(False, 0.0, 0.0)
    )
    return Start(
        plant_ps=truth,
        dt_s=dt_s,
        chunk_steps=chunk_steps,
        refresh_steps=refresh_steps,
        long_chunk_steps=long_chunk_steps,
        has_rov=has_rov,
        control_on=control,
        arrays=arrays,
        site=site,
        sensor_cfg=sensors.sensor_config(truth.sensors, dt_s),
        noise_stream=sensors.NoiseStream(rng_dropouts, rng_noise),
        x=x,
        held_y=held_y,
        gripping=has_rov and start_gripping,
        settings=settings,
        sysm=sysm,
        gains=gains,
        thruster_config=system_thruster_config(ps, sysm),
        C=C,
        controller_state=ControllerState.start(
            loop.MODE_TREE if start_gripping else loop.MODE_FREE
        ),
        pilot_capacity=pilot_capacity(ps),
        xhat=xhat,
        P_cov=P_cov,
        Q=_quality_state(),
        target=np.array(eta0, float),
        startup=startup,
    )


def _quality_state() -> loop.QualityState:
    """The signal checks before their first sample."""
    w = quality.WINDOW
    return loop.QualityState(
        np.zeros(sensors.N_Y),
        -np.ones(5),
        np.zeros(5, np.int64),
        np.zeros((sensors.N_Y, w)),
        np.zeros((5, 4), np.int64),
    )
