"""A mission run headless from the command line (``rov-console run``, ``rov-console campaign
rerun``): the one run loop (``MissionDriver.run_to_end``) with a progress bar over the legs,
and its recording (``--log``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from app.recording import SessionRecorder
    from control.columns import LogRows
    from control.simulation import Simulation
    from missions.driver import MissionDriver
    from missions.schema import Mission
    from missions.scoring import MissionResult


class _Recording:
    """A headless run's rows and events into its recorder, each event once."""

    def __init__(self, recorder: SessionRecorder) -> None:
        self.recorder = recorder
        self.events_written = 0

    def events(self, driver: MissionDriver) -> None:
        """The events not written yet (leg changes, landings, faults, the wire's)."""
        for event in driver.events[self.events_written :]:
            self.recorder.event(event["t_s"], event["kind"], event["text"], event["data"])
        self.events_written = len(driver.events)

    def rows(self, driver: MissionDriver, rows: LogRows) -> None:
        """A request's events, then its rows, as soon as they are run."""
        self.events(driver)
        if len(rows):
            sim = driver.sim
            self.recorder.write_log(
                rows.data, crane_tip_n=sim.crane_tip_n, wire_length_m=sim.wire_length_m
            )


def drive(
    driver: MissionDriver, recorder: SessionRecorder | None = None, show: bool = False
) -> MissionResult:
    """Run the mission to its end and score it (``MissionDriver.run_to_end``), with a progress
    bar over its legs when ``show``. With a recorder, each request's events and rows go into
    it as they are run, and the events still unwritten when the run ends or fails; the caller
    closes it."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    recording = None if recorder is None else _Recording(recorder)
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("leg {task.completed:.0f}/{task.total:.0f}"),
        TextColumn("sim {task.fields[sim]:7.0f} s"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, disable=not show, transient=True) as bar:
        task = bar.add_task(driver.mission.name, total=len(driver.mission.legs), sim=0.0)

        def show_leg(driver: MissionDriver) -> None:
            leg = driver.current_leg
            bar.update(
                task,
                completed=max(driver.leg_index, 0),
                sim=driver.sim.t_s,
                description=f"{driver.mission.name}: {leg.type if leg else 'done'}",
            )

        try:
            return driver.run_to_end(
                record=None if recording is None else recording.rows, progress=show_leg
            )
        finally:
            if recording is not None:
                recording.events(driver)


def open_recorder(
    path: str, spec: Mission, sim: Simulation, seed: int | None, numeric_rate_hz: float = 20.0
) -> SessionRecorder:
    """A recorder for ``run --log``, with the setup metadata every recording has; its rows at
    ``numeric_rate_hz`` (the plant's rate, 1 / dt, keeps every step: ``rov-console shadow``
    then reproduces the run step for step)."""
    from app.recording import SessionRecorder, session_metadata

    metadata = session_metadata(sim, spec, seed=seed)  # seed None: the mission's
    return SessionRecorder(
        path,
        metadata=metadata,
        params=sim.ps,
        n_thrusters=sim.n_thrusters,
        docking=sim.docking_frame,
        numeric_rate_hz=numeric_rate_hz,
    )
