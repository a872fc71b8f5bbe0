"""The operator console's core: one ``Console`` holds its settings, the ``PacedLoop`` (an
asyncio task stepping the ``Session`` in time with the wall clock), uploaded missions and the
token. Readers (HTTP routes, the telemetry stream, the 3D view) take immutable ``Snapshot``s;
writers submit ``commands``. This is the console's public API: ``app.api`` and ``web`` import
from here.

    settings.py   ConsoleSettings (options of ``rov-console serve``)
    instance.py   Console
    loop.py       PacedLoop: pacing, command queue, jitter statistics
    commands.py   the commands (Pause, SetTarget, StartRun, ...) and LoopControls, what they
                  may change of the loop
    session.py    Session: simulation, mission driver, alarms, recorder, replay
    replay.py     recordings on disk and their replay
    viewer_replay.py  one reader's (a browser's) own replay beside the live run
    water.py      the water's visibility (a session setting the 3D view's fog follows)
    snapshot.py   Snapshot and the other immutable views (FaultView among them)
    alarms.py     operator alarms from the log rows
    texts.py      the page's Markdown for results and signal-check counters
    faults.py     the instructor's commands (InjectFault, ClearFaults)
    criteria.py   the assessment's criteria in force (the instructor's file) and a trainee's
                  runs scored with them

It also passes on what reviewing a recording needs: its notes (``add_review_note``,
``notes_of``, ``Note``) and the comparison of two runs (``compare``, ``Comparison``,
``table_rows``, ``comparison_image``, ``CompareError``).

It also passes on the core's rotations (``Rzyx``, ``quaternion_wxyz_from_rpy_radians``) and the
wire's attachment point, so the view draws with the same geometry as the simulation.
"""

from app import scores
from app.compare import CompareError, Comparison, compare, comparison_image, table_rows
from app.console import commands, criteria
from app.console.alarms import ALARM_NAMES, Alarm
from app.console.commands import SPEED_MAX, SPEED_MIN, Command
from app.console.errors import ConsoleError
from app.console.faults import ClearFaults, InjectFault
from app.console.instance import Console, initial_run
from app.console.loop import PacedLoop
from app.console.operations import trainee_view
from app.console.replay import RECORDING_NAME, list_recordings, load_replay, recording_path
from app.console.session import (
    SCORES_DB,
    PreparedRun,
    Session,
    prepare_run,
    station_keeping_mission,
)
from app.console.settings import (
    PILOT_VIEW_PATH,
    ConsoleSettings,
    allowed_hosts,
    is_loopback,
    origin_allowed,
)
from app.console.snapshot import (
    FaultView,
    LoopStats,
    MissionStatus,
    ReplayStatus,
    SceneInfo,
    Snapshot,
    VesselAdvice,
    advice_words,
)
from app.console.texts import (
    alarm_meaning,
    alarm_title,
    compass_degrees,
    compass_heading_deg,
    counters_markdown,
    heading_text,
    md_code,
    md_text,
    result_markdown,
)
from app.console.tokens import INSTRUCTOR_TOKEN_ENV
from app.console.viewer_replay import ViewerReplay
from app.console.water import VISIBILITY_MAX_M, VISIBILITY_MIN_M, Water
from app.recording.notes import Note, add_review_note, notes_of
from control.config import ALLOCATIONS, MODES, Gains
from control.faults import FAULT_KINDS, THRUSTER_KINDS
from missions.scoring import SATURATED
from sim.drawing import attachment_point_n
from sim.gnc import Rzyx, quaternion_wxyz_from_rpy_radians

__all__ = [
    "ALARM_NAMES",
    "ALLOCATIONS",
    "FAULT_KINDS",
    "INSTRUCTOR_TOKEN_ENV",
    "MODES",
    "PILOT_VIEW_PATH",
    "RECORDING_NAME",
    "SATURATED",
    "SCORES_DB",
    "SPEED_MAX",
    "SPEED_MIN",
    "THRUSTER_KINDS",
    "VISIBILITY_MAX_M",
    "VISIBILITY_MIN_M",
    "Alarm",
    "ClearFaults",
    "Command",
    "CompareError",
    "Comparison",
    "Console",
    "ConsoleError",
    "ConsoleSettings",
    "FaultView",
    "Gains",
    "InjectFault",
    "LoopStats",
    "MissionStatus",
    "Note",
    "PacedLoop",
    "PreparedRun",
    "ReplayStatus",
    "Rzyx",
    "SceneInfo",
    "Session",
    "Snapshot",
    "VesselAdvice",
    "ViewerReplay",
    "Water",
    "add_review_note",
    "advice_words",
    "alarm_meaning",
    "alarm_title",
    "allowed_hosts",
    "attachment_point_n",
    "commands",
    "compare",
    "comparison_image",
    "compass_degrees",
    "compass_heading_deg",
    "counters_markdown",
    "criteria",
    "heading_text",
    "initial_run",
    "is_loopback",
    "list_recordings",
    "load_replay",
    "md_code",
    "md_text",
    "notes_of",
    "origin_allowed",
    "prepare_run",
    "quaternion_wxyz_from_rpy_radians",
    "recording_path",
    "result_markdown",
    "scores",
    "station_keeping_mission",
    "table_rows",
    "trainee_view",
]
