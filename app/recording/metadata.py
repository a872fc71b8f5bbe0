"""The setup metadata of a recording: one layout for ``rov-console run`` and the console.

``session_metadata`` gives these keys (every value JSON):

- ``mission_name`` (str) and ``mission_toml`` (str, the mission file as TOML);
- ``seed`` (int), the seed the simulation was built with;
- ``settings`` (the ``ControlSettings`` as a dict) and ``gains`` ({kp, ki, kd}, 3 each) in
  force when the recording started;
- ``params_name`` (str), ``label`` (str, '' when none), ``started_utc`` (ISO 8601);
- ``start_t_s`` and ``dt_s`` [s]: simulation time at the start and the plant step;
- ``crane_tip_n`` [north, east, down] [m], ``wire_length_m`` [m];
- ``docking_frame``: {center_n [m], heading_rad, landing_depth_m [m]} or null;
- ``legs_run`` (bool): the mission's legs are run (False: its set-up only, holding station);
- ``current``: {speed_mps, direction_deg (towards)} when the run started;
- ``time_offset_s`` [s]: added to the run's simulation time on the recording's time axis (a
  run started while recording goes on after the one before; ``start_t_s`` includes it).

A run started while recording gets the same keys in a metadata record of its own
(``run.2``, ``run.3``, ...: ``SessionRecorder.add_run``); ``SessionData.runs`` reads them all.

The recorder adds ``params``, ``columns`` and ``recorder`` (software version, thrusters,
rates) itself. Recordings made before this layout differ: ``rov-console run`` wrote
``mission`` = the TOML beside ``mission_name``; the console wrote ``mission`` = the name beside
``mission_toml``. ``recorded_mission_name`` and ``recorded_mission_toml`` read all three.
"""

from __future__ import annotations

import dataclasses
import math
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any

import numpy as np

from missions.schema import dump_mission
from sim.docking import DockingFrame

if TYPE_CHECKING:
    from control.simulation import Simulation
    from missions.schema import Mission


def docking_frame_metadata(frame: DockingFrame | None) -> dict[str, Any] | None:
    """A docking frame as metadata (None stays None)."""
    if frame is None:
        return None
    return {
        "center_n": [float(v) for v in frame.center_n],
        "heading_rad": float(frame.heading_rad),
        "landing_depth_m": float(frame.landing_depth_m),
    }


def session_metadata(
    sim: Simulation,
    mission: Mission,
    *,
    seed: int | None = None,
    label: str = "",
    docking: DockingFrame | None = None,
    started_utc: datetime | None = None,
    legs_run: bool = True,
    time_offset_s: float = 0.0,
) -> dict[str, Any]:
    """The setup metadata of a recording of ``sim`` running ``mission`` (see the module
    docstring). ``seed``: the seed ``sim`` was built with (default: the mission's);
    ``docking``: the docking frame drawn (default: the simulation's); ``started_utc``: default
    now; ``legs_run`` and ``time_offset_s``: see the module docstring."""
    frame = docking if docking is not None else sim.docking_frame
    started = started_utc or datetime.now(UTC)
    gains = sim.gains
    return {
        "mission_name": mission.name,
        "mission_toml": dump_mission(mission),
        "seed": int(mission.setup.seed if seed is None else seed),
        "settings": dataclasses.asdict(sim.settings),
        "gains": {"kp": list(gains.kp), "ki": list(gains.ki), "kd": list(gains.kd)},
        "params_name": sim.ps.name,
        "label": label,
        "started_utc": started.isoformat(),
        "start_t_s": float(sim.t_s) + float(time_offset_s),
        "dt_s": float(sim.dt_s),
        "crane_tip_n": [float(v) for v in sim.crane_tip_n],
        "wire_length_m": float(sim.wire_length_m),
        "docking_frame": docking_frame_metadata(frame),
        "legs_run": bool(legs_run),
        "current": {
            "speed_mps": float(sim.current_speed_mps),
            "direction_deg": math.degrees(float(sim.current_direction_rad)),
        },
        "time_offset_s": float(time_offset_s),
    }


def recorded_mission_name(metadata: dict[str, Any], default: str = "") -> str:
    """The mission's name in a recording's metadata, of this layout or an older one."""
    name = metadata.get("mission_name")
    if isinstance(name, str):
        return name
    old = metadata.get("mission")  # the console's first files: the name
    if isinstance(old, str) and "\n" not in old:
        return old
    return default


def recorded_mission_toml(metadata: dict[str, Any]) -> str | None:
    """The mission file (TOML) in a recording's metadata, of this layout or an older one."""
    toml = metadata.get("mission_toml")
    if isinstance(toml, str):
        return toml
    old = metadata.get("mission")  # rov-console run's first files: the TOML
    return old if isinstance(old, str) and "\n" in old else None


def recorded_docking_frame(metadata: dict[str, Any]) -> DockingFrame | None:
    """The docking frame in a recording's metadata (None when absent or unreadable)."""
    frame = metadata.get("docking_frame")
    if not isinstance(frame, dict):
        return None
    try:
        center = np.asarray(frame["center_n"], dtype=float)
        heading, landing = float(frame["heading_rad"]), float(frame["landing_depth_m"])
    except (KeyError, TypeError, ValueError):
        return None
    return DockingFrame(center, heading, landing) if center.shape == (2,) else None
