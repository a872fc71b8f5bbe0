"""A mission run headless from the command line (``rov-console run``, ``rov-console campaign
rerun``): the run with its progress bar, and its recording (``--log``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from app.recording import SessionRecorder
    from control.simulation import Simulation
    from missions.driver import MissionDriver
    from missions.schema import Mission


def drive(driver: MissionDriver, recorder: SessionRecorder | None, show: bool) -> None:
    """Run the mission to its end, with a progress bar over its legs."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    sim = driver.sim
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("leg {task.completed:.0f}/{task.total:.0f}"),
        TextColumn("sim {task.fields[sim]:7.0f} s"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, disable=not show, transient=True) as bar:
        task = bar.add_task(driver.mission.name, total=len(driver.mission.legs), sim=0.0)
        while not driver.done:
            rows = driver.advance()
            if recorder is not None:
                write_new_events(driver, recorder)
                if len(rows):
                    recorder.write_log(
                        rows.data, crane_tip_n=sim.crane_tip_n, wire_length_m=sim.wire_length_m
                    )
            leg = driver.current_leg
            bar.update(
                task,
                completed=max(driver.leg_index, 0),
                sim=sim.t_s,
                description=f"{driver.mission.name}: {leg.type if leg else 'done'}",
            )


def write_new_events(driver: MissionDriver, recorder: SessionRecorder) -> None:
    """Events (leg changes, landings, alarms) go into the log as they happen."""
    done = getattr(recorder, "_events_written", 0)
    for event in driver.events[done:]:
        recorder.event(event["t_s"], event["kind"], event["text"], event["data"])
    recorder._events_written = len(driver.events)  # type: ignore[attr-defined]


def open_recorder(path: str, spec: Mission, sim: Simulation, seed: int | None) -> SessionRecorder:
    """A recorder for ``run --log``, with the setup metadata every recording has."""
    from app.recording import SessionRecorder, session_metadata

    metadata = session_metadata(sim, spec, seed=seed)  # seed None: the mission's
    return SessionRecorder(
        path,
        metadata=metadata,
        params=sim.ps,
        n_thrusters=sim.n_thrusters,
        docking=sim.docking_frame,
    )
