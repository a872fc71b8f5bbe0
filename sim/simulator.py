"""Open-loop simulator: composes environment, wire, plant and sensors, steps them at a fixed
rate, records into preallocated arrays and raises ``SimulationDiverged`` on a non-finite state.

The control layer (``control/``) drives the same plant through ``sim.plant`` directly; this
class is what ``rov-console simulate`` and the plant tests use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sim import environment as envmod
from sim import plant, sensors, site
from sim.docking import DockingFrame
from sim.gnc import Rzyx
from sim.params import ParameterSet

FloatArray = NDArray[np.float64]


class SimulationDiverged(RuntimeError):
    """The plant state stopped being finite."""


@dataclass(frozen=True)
class Trajectory:
    """A recorded run: one row per plant step (state at the end of the step)."""

    t_s: FloatArray
    """(n,) time at the end of each step [s]."""
    x: FloatArray
    """(n, 24) plant state (see sim.plant)."""
    y: FloatArray
    """(n, 11) held sensor outputs (see sim.sensors)."""
    current_n: FloatArray
    """(n, 3) water velocity at the site, NED [m/s]."""

    @property
    def tree_eta_n(self) -> FloatArray:
        return self.x[:, plant.ETA_T]

    @property
    def rov_eta_n(self) -> FloatArray:
        return self.x[:, plant.ETA_R]


def initial_state(ps: ParameterSet, tree_position_n: FloatArray, tree_heading_rad: float = 0.0,
                  has_rov: bool = True) -> FloatArray:
    """Tree at rest at the given position and heading, ROV (if any) exactly on its mount."""
    x = np.zeros(plant.N_STATE)
    x[0:3] = tree_position_n
    x[5] = tree_heading_rad
    R_t = Rzyx(0.0, 0.0, tree_heading_rad)
    x[12:15] = tree_position_n + R_t @ ps.mount.r_rov_from_tree_tree_m
    x[17] = tree_heading_rad + ps.mount.psi_rov_from_tree_rad if has_rov else 0.0
    return x


def check_finite_vector(name: str, value: FloatArray, length: int) -> FloatArray:
    """Validate a command vector: right length and finite, else ValueError naming it."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != (length,):
        raise ValueError(f"{name} must have {length} entries, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return arr


class Simulator:
    """Steps the plant at ``dt_s`` (default 100 Hz) in compiled chunks of ``chunk_steps``."""

    def __init__(self, ps: ParameterSet, *, tree_depth_m: float,
                 crane_tip_n: FloatArray = (1.0, 1.0, 0.0),
                 current: envmod.CurrentParams | None = None,
                 waves: envmod.WaveParams | None = None, has_rov: bool = True,
                 tree_heading_rad: float = 0.0, seed: int = 0, dt_s: float = 0.01,
                 chunk_steps: int = 100) -> None:
        if not (1e-4 <= dt_s <= 0.05):
            raise ValueError(f"dt_s must be in [0.0001, 0.05] s, got {dt_s}")
        self.ps = ps
        self.dt_s = dt_s
        self.chunk_steps = chunk_steps
        self.has_rov = has_rov
        self.arrays = plant.plant_arrays(ps, has_rov=has_rov)
        self.rng = np.random.default_rng(seed)
        self.current_params = current or envmod.CurrentParams(
            speed_mps=0.0, direction_rad=0.0, speed_min_mps=0.0, speed_max_mps=0.0,
            direction_min_rad=0.0, direction_max_rad=0.0)
        self.current_state = envmod.initial_current(self.current_params)
        self.wave_field = envmod.make_wave_field(waves, self.rng) if waves is not None else None
        self.crane_tip_n = check_finite_vector("crane_tip_n", crane_tip_n, 3)
        self.wire_length_m = site.wire_length_for_depth(
            ps, tree_depth_m, self.crane_tip_n[2], self.current_state.speed_mps)
        self.sensor_cfg = sensors.sensor_config(ps.sensors, dt_s)
        self.thruster_speeds_rps = np.zeros(ps.rov.thrusters.T.shape[1])
        self.push_n = np.zeros(3)
        self.gripping = has_rov
        self.crane_target_n = self.crane_tip_n.copy()
        self.crane_speed_mps = 0.0
        self.wire_target_m = self.wire_length_m
        self.wire_rate_mps = 0.0
        self.docking_frame: DockingFrame | None = None
        tree_pos = np.array([self.crane_tip_n[0], self.crane_tip_n[1], tree_depth_m])
        self.x = initial_state(ps, tree_pos, tree_heading_rad, has_rov)
        self.held_y = sensors.true_outputs(self.x)
        self.step_index = 0

    @property
    def t_s(self) -> float:
        return self.step_index * self.dt_s

    # ---- commands (validated; a bad one raises and leaves the state untouched) ----
    def set_thruster_speeds(self, n_rps: FloatArray) -> None:
        self.thruster_speeds_rps = check_finite_vector(
            "thruster speed command [rev/s]", n_rps, self.thruster_speeds_rps.shape[0])

    def set_push(self, force_n: FloatArray) -> None:
        self.push_n = check_finite_vector("push force [N]", force_n, 3)

    def set_crane_tip(self, crane_tip_n: FloatArray) -> None:
        """Put the crane tip somewhere at once (a jump: use ``move_crane_tip`` while running)."""
        self.crane_tip_n = check_finite_vector("crane_tip_n", crane_tip_n, 3)
        self.crane_target_n = self.crane_tip_n.copy()

    def set_wire_length(self, length_m: float) -> None:
        """Set the unstretched wire length at once (a jump: use ``winch_to`` while running)."""
        if not (math.isfinite(length_m) and 1.0 <= length_m <= 5000.0):
            raise ValueError(f"wire length must be in [1, 5000] m, got {length_m}")
        self.wire_length_m = float(length_m)
        self.wire_target_m = float(length_m)

    def winch_to(self, length_m: float, rate_mps: float) -> None:
        """Pay out (or haul in) the wire smoothly to ``length_m`` at ``rate_mps``."""
        if not (math.isfinite(length_m) and 1.0 <= length_m <= 5000.0):
            raise ValueError(f"wire length must be in [1, 5000] m, got {length_m}")
        if not (math.isfinite(rate_mps) and 0.0 < rate_mps <= 2.0):
            raise ValueError(f"winch rate must be in (0, 2] m/s, got {rate_mps}")
        self.wire_target_m = float(length_m)
        self.wire_rate_mps = float(rate_mps)

    def move_crane_tip(self, target_n: FloatArray, speed_mps: float) -> None:
        """Move the vessel (the crane tip) smoothly to ``target_n`` at ``speed_mps``."""
        target = check_finite_vector("crane tip target", target_n, 3)
        if not (math.isfinite(speed_mps) and 0.0 < speed_mps <= 5.0):
            raise ValueError(f"vessel speed must be in (0, 5] m/s, got {speed_mps}")
        self.crane_target_n = target
        self.crane_speed_mps = float(speed_mps)

    def set_docking_frame(self, frame: DockingFrame | None) -> None:
        """Put a docking frame (and the seabed) under the tree, or take it away."""
        self.docking_frame = frame

    def _ramp(self, start: float, target: float, rate: float, n: int) -> FloatArray:
        """Values after each of n steps moving from start towards target at rate."""
        steps = np.arange(1, n + 1) * self.dt_s * rate
        return start + np.sign(target - start) * np.minimum(steps, abs(target - start))

    def _crane_path(self, n: int) -> FloatArray:
        """(n, 3) crane-tip positions over the next n steps."""
        delta = self.crane_target_n - self.crane_tip_n
        dist = float(np.linalg.norm(delta))
        if dist < 1e-12 or self.crane_speed_mps <= 0.0:
            return np.repeat(self.crane_tip_n[None, :], n, axis=0)
        frac = self._ramp(0.0, dist, self.crane_speed_mps, n) / dist
        return self.crane_tip_n[None, :] + frac[:, None] * delta[None, :]

    # ---- stepping ----
    def environment_chunk(self, n: int) -> tuple[FloatArray, FloatArray]:
        self.current_state, speeds, dirs = envmod.advance_current(
            self.current_state, self.current_params, self.dt_s, n, self.rng)
        water_n = envmod.current_velocity_n(speeds, dirs)
        accel_n = np.zeros_like(water_n)
        if self.wave_field is not None:
            t = self.t_s + self.dt_s * np.arange(n)
            v_w, a_w = envmod.wave_kinematics_n(self.wave_field, t, float(self.x[2]),
                                                float(self.x[0]), float(self.x[1]))
            water_n = water_n + v_w
            accel_n = accel_n + a_w
        base = site.wire_environment(self.ps, self.wire_length_m, self.crane_tip_n,
                                     float(np.mean(speeds)), float(np.mean(dirs)))
        base[plant.E_PUSH:plant.E_PUSH + 3] = self.push_n
        base[plant.E_GRIP] = 1.0 if self.gripping else 0.0
        if self.docking_frame is not None:
            base[plant.E_FRAME:plant.E_FRAME + 2] = self.docking_frame.center_n
            base[plant.E_FRAME_PSI] = self.docking_frame.heading_rad
            base[plant.E_LAND] = self.docking_frame.landing_depth_m
        env = np.repeat(base[None, :], n, axis=0)
        env[:, plant.E_VC:plant.E_VC + 3] = water_n
        env[:, plant.E_AC:plant.E_AC + 3] = accel_n
        # winch and vessel move smoothly within the chunk
        lengths = self._ramp(self.wire_length_m, self.wire_target_m, self.wire_rate_mps, n)
        env[:, plant.E_LREST] = lengths + site.self_weight_stretch(self.ps, self.wire_length_m)
        crane = self._crane_path(n)
        env[:, plant.E_CT:plant.E_CT + 3] = crane
        self.wire_length_m = float(lengths[-1])
        self.crane_tip_n = crane[-1].copy()
        return env, water_n

    def run(self, duration_s: float) -> Trajectory:
        """Advance by ``duration_s`` (rounded to whole steps) and return the recorded run."""
        if not (math.isfinite(duration_s) and duration_s >= 0.0):
            raise ValueError(f"duration must be a finite number of seconds >= 0, got {duration_s}")
        total = int(round(duration_s / self.dt_s))
        t_out = np.empty(total)
        x_out = np.empty((total, plant.N_STATE))
        y_out = np.empty((total, sensors.N_Y))
        c_out = np.empty((total, 3))
        done = 0
        while done < total:
            n = min(self.chunk_steps, total - done)
            env, water_n = self.environment_chunk(n)
            noise = sensors.draw_noise(self.sensor_cfg, self.rng, self.step_index, n)
            states, ok = plant.advance(self.x, self.thruster_speeds_rps, env, self.arrays,
                                       self.dt_s)
            if ok < n:
                raise SimulationDiverged(
                    f"plant state not finite at t = {self.t_s + (ok + 1) * self.dt_s:.2f} s")
            ys, self.held_y = sensors.sample_series(states, noise, self.held_y)
            sl = slice(done, done + n)
            t_out[sl] = self.t_s + self.dt_s * np.arange(1, n + 1)
            x_out[sl], y_out[sl], c_out[sl] = states, ys, water_n
            self.x = states[-1].copy()
            self.step_index += n
            done += n
        return Trajectory(t_out, x_out, y_out, c_out)

    def wire_tension_n(self) -> float:
        """Present wire tension at the tree [N]."""
        env = site.wire_environment(self.ps, self.wire_length_m, self.crane_tip_n,
                                    self.current_state.speed_mps, self.current_state.direction_rad)
        R_t = Rzyx(*self.x[3:6])
        p_att = self.x[0:3] + R_t @ self.arrays.tree_r_att
        return float(np.linalg.norm(plant.wire_force_n(p_att, env, self.arrays.tree_W0)))
