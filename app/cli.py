"""``rov-console``: the product's command line."""

from __future__ import annotations

import json
import math
import sys
import time
from typing import Annotated

import numpy as np
import typer

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Simulator, control system and console for ROV-assisted tree-on-wire "
                       "installation.")


@app.callback()
def _root() -> None:
    """Simulator, control system and console for ROV-assisted tree-on-wire installation."""


def parse_polar(text: str, what: str, unit: str) -> tuple[float, float]:
    """Parse 'VALUE@DIR_DEG' (direction the thing points towards, from north, clockwise)."""
    try:
        value_s, dir_s = text.split("@")
        value, direction = float(value_s), float(dir_s)
    except ValueError:
        raise typer.BadParameter(f"{what} must look like VALUE@DIR_DEG, e.g. 0.1@225 "
                                 f"({unit} towards 225 deg), got {text!r}") from None
    if not (math.isfinite(value) and math.isfinite(direction)):
        raise typer.BadParameter(f"{what} must be finite, got {text!r}")
    return value, math.radians(direction)


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


@app.command()
def simulate(
    params: Annotated[str, typer.Option(help="parameter set name (full-scale, model-scale) "
                                             "or a .toml/.json file")] = "full-scale",
    depth: Annotated[float, typer.Option(help="tree depth [m]; the wire length follows")] = 400.0,
    duration: Annotated[float, typer.Option(help="simulated time [s]", min=0.0,
                                            max=1.0e6)] = 600.0,
    current: Annotated[str, typer.Option(help="SPEED@DIR_DEG, m/s towards DIR")] = "0.1@225",
    no_rov: Annotated[bool, typer.Option("--no-rov", help="the tree alone")] = False,
    push: Annotated[str | None, typer.Option(help="NEWTONS@DIR_DEG steady horizontal force on "
                                                  "the tree's centre")] = None,
    waves: Annotated[str | None, typer.Option(help="HS_M@TP_S@DIR_DEG ITTC sea")] = None,
    crane_tip: Annotated[str, typer.Option(help="N,E of the wire's surface point [m]")] = "1,1",
    seed: Annotated[int, typer.Option(help="random seed")] = 0,
) -> None:
    """Run the plant without control and print one JSON object describing where it ends."""
    from sim import environment as envmod
    from sim import params as params_mod
    from sim.simulator import SimulationDiverged, Simulator

    speed, direction = parse_polar(current, "--current", "m/s")
    if not 0.0 <= speed <= 3.0:
        raise typer.BadParameter(f"--current speed must be in [0, 3] m/s, got {speed}")
    try:
        ct = [float(v) for v in crane_tip.split(",")]
        assert len(ct) == 2
    except (ValueError, AssertionError):
        raise typer.BadParameter(f"--crane-tip must be N,E in metres, got {crane_tip!r}") from None
    wave_params = None
    if waves is not None:
        try:
            hs, tp, wdir = (float(v) for v in waves.split("@"))
            wave_params = envmod.WaveParams(significant_height_m=hs, peak_period_s=tp,
                                            direction_rad=math.radians(wdir))
        except ValueError as err:
            raise typer.BadParameter(f"--waves must be HS_M@TP_S@DIR_DEG: {err}") from None
    try:
        ps = params_mod.load(params)
        cur = envmod.CurrentParams(speed_mps=speed, direction_rad=direction,
                                   speed_min_mps=speed, speed_max_mps=speed,
                                   direction_min_rad=direction, direction_max_rad=direction)
        sim = Simulator(ps, tree_depth_m=depth, crane_tip_n=np.array([ct[0], ct[1], 0.0]),
                        current=cur, waves=wave_params, has_rov=not no_rov, seed=seed)
        if push is not None:
            force, pdir = parse_polar(push, "--push", "N")
            sim.set_push(np.array([force * math.cos(pdir), force * math.sin(pdir), 0.0]))
        t0 = time.perf_counter()
        traj = sim.run(duration)
        wall = time.perf_counter() - t0
    except (ValueError, SimulationDiverged) as err:
        _fail(str(err))
        return
    typer.echo(json.dumps(simulation_summary(sim, traj, wall), indent=2))


def simulation_summary(sim, traj, wall_s: float) -> dict:  # type: ignore[no-untyped-def]
    """The JSON answer of ``simulate``: final poses (angles in degrees) and settling."""
    from sim.gnc import ssa

    def eta_deg(eta: np.ndarray) -> list[float]:
        out = [float(v) for v in eta[:3]] + [math.degrees(ssa(float(a))) for a in eta[3:]]
        return [round(v, 6) for v in out]

    x = sim.x
    speeds = np.linalg.norm(traj.x[:, 6:9], axis=1)
    last = traj.t_s >= traj.t_s[-1] - 60.0 if len(traj.t_s) else np.array([], dtype=bool)
    settled = bool(len(traj.t_s) and traj.t_s[-1] >= 60.0 and np.all(speeds[last] < 1e-3))
    duration = float(traj.t_s[-1]) if len(traj.t_s) else 0.0
    return {
        "params": sim.ps.name,
        "time_s": round(sim.t_s, 6),
        "tree_eta_n": eta_deg(x[0:6]),
        "rov_eta_n": eta_deg(x[12:18]) if sim.has_rov else None,
        "crane_tip_n": [float(v) for v in sim.crane_tip_n],
        "wire_length_m": round(sim.wire_length_m, 4),
        "horizontal_offset_m": round(float(np.hypot(x[0] - sim.crane_tip_n[0],
                                                    x[1] - sim.crane_tip_n[1])), 6),
        "heading_deg": round(math.degrees(ssa(float(x[5]))), 4),
        "wire_tension_n": round(sim.wire_tension_n(), 2),
        "tree_speed_mps": float(speeds[-1]) if len(speeds) else 0.0,
        "settled": settled,
        "steps": len(traj.t_s),
        "steps_per_second": round(len(traj.t_s) / wall_s, 1) if wall_s > 0 else None,
        "real_time_factor": round(duration / wall_s, 1) if wall_s > 0 else None,
    }


def main() -> None:
    """Entry point of the ``rov-console`` script."""
    try:
        app()
    except KeyboardInterrupt:
        sys.exit(130)


if __name__ == "__main__":
    main()
