"""Session logs: one MCAP file per session, readable in Foxglove and by any MCAP reader.

- ``channels``: what a file holds (topics, the setup record, plot channels read from the log
  row by block name);
- ``schemas``: the JSON schema of every channel (Foxglove's well-known types and ours);
- ``messages``: pure builders of each message from one log row, and the scene's geometry;
- ``writer``: ``SessionRecorder`` (decimation by simulation time, crash safety);
- ``reader``: ``load_session``, ``check_session``, ``SessionData`` (rows by block name in
  whatever layout they were recorded);
- ``export``: ``export_csv``;
- ``metadata``: ``session_metadata``, the one setup layout of every recording.
"""

from app.recording.channels import (
    COLUMNS,
    EVENTS_TOPIC,
    FORMAT_VERSION,
    SESSION_TOPIC,
    SETUP_RECORD,
    WIRE_FIELDS,
    PlotChannel,
    PlotField,
    column_names,
    plot_channels,
)
from app.recording.export import export_csv
from app.recording.messages import (
    SceneGeometry,
    foxglove_quaternion,
    plot_message,
    scene_geometry,
    scene_message,
    session_row_message,
    tf_message,
    wire_message,
)
from app.recording.metadata import (
    recorded_docking_frame,
    recorded_mission_name,
    recorded_mission_toml,
    session_metadata,
)
from app.recording.reader import MCAP_MAGIC, SessionData, check_session, load_session
from app.recording.writer import Decimator, RecordingError, SessionRecorder, software_version

__all__ = [
    "COLUMNS",
    "EVENTS_TOPIC",
    "FORMAT_VERSION",
    "MCAP_MAGIC",
    "SESSION_TOPIC",
    "SETUP_RECORD",
    "WIRE_FIELDS",
    "Decimator",
    "PlotChannel",
    "PlotField",
    "RecordingError",
    "SceneGeometry",
    "SessionData",
    "SessionRecorder",
    "check_session",
    "column_names",
    "export_csv",
    "foxglove_quaternion",
    "load_session",
    "plot_channels",
    "plot_message",
    "recorded_docking_frame",
    "recorded_mission_name",
    "recorded_mission_toml",
    "scene_geometry",
    "scene_message",
    "session_metadata",
    "session_row_message",
    "software_version",
    "tf_message",
    "wire_message",
]
