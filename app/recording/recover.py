"""Rewriting a killed recording as a complete MCAP file: ``recover_session``.

A recorder that is killed leaves a file without summary and footer (``writer``'s module
docstring says how much it loses). The product's reader reads such a file up to its last whole
record, but the stock readers do not: ``mcap``'s ``make_reader`` (seeking or not) raises at
the missing footer before it yields a message (the non-seeking reader sorts by log time, so it
reads to the end first), and readers that index the file want the summary.

``recover_session`` reads every whole record (``scan_file``: header, schemas, channels,
metadata, messages; the chunk cut by the kill and anything after it are left out) and writes
them to a new file with ``mcap``'s writer, which ends it with the summary (statistics, chunk
indexes) and footer every reader expects. The source is never changed. Schemas and channels
are registered in the order of their ids; message times, sequence numbers and bytes are kept
as they were.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mcap.writer import CompressionType, Writer

from app.recording.reader import FileScan, scan_file


@dataclass(frozen=True)
class Recovered:
    """What ``recover_session`` wrote."""

    output: Path
    messages: int
    """Messages written (every whole one of the source)."""
    source_complete: bool
    """The source already had its footer (the rewrite then only copies it)."""
    dropped_bytes: int
    """Bytes of the source after its last whole record (the cut chunk), left out."""
    problem: str
    """Why the source was not complete ('' when it was)."""


def recovered_path(source: Path) -> Path:
    """Where the rewrite goes by default: ``NAME.mcap`` -> ``NAME-recovered.mcap``."""
    return source.with_name(f"{source.stem}-recovered.mcap")


def recover_session(
    source: str | Path, output: str | Path | None = None, *, overwrite: bool = False
) -> Recovered:
    """Rewrite ``source`` (an MCAP file, killed or cut off) as a complete MCAP file at
    ``output`` (default ``recovered_path``). Refuses an existing output unless ``overwrite``,
    and the source itself; raises ValueError when the source is not an MCAP file."""
    source = Path(source)
    output = recovered_path(source) if output is None else Path(output)
    if output.exists() and output.resolve() == source.resolve():
        raise ValueError(f"{output}: the output must not be the file being recovered")
    scan = scan_file(source)
    with open(output, "wb" if overwrite else "xb") as f:
        try:
            _write_complete(f, scan)
        except BaseException:
            f.close()
            output.unlink(missing_ok=True)
            raise
    return Recovered(
        output,
        len(scan.in_order),
        scan.complete,
        scan.file_bytes - scan.intact_bytes,
        scan.problem,
    )


def _write_complete(stream: object, scan: FileScan) -> None:
    """Everything ``scan`` found, as one complete MCAP file (schemas and channels first, in
    their ids' order, so they keep their ids)."""
    assert scan.header is not None  # scan_file raises without one
    writer = Writer(stream, compression=CompressionType.ZSTD)  # type: ignore[arg-type]
    writer.start(profile=scan.header.profile, library=scan.header.library)
    schema_ids = {0: 0}
    for sid, schema in sorted(scan.schemas.items()):
        schema_ids[sid] = writer.register_schema(schema.name, schema.encoding, schema.data)
    channel_ids = {}
    for ch in scan.channels_in_order():
        channel_ids[ch.id] = writer.register_channel(
            ch.topic, ch.message_encoding, schema_ids.get(ch.schema_id, 0), dict(ch.metadata)
        )
    for name, record in scan.metadata.items():
        writer.add_metadata(name, record)
    for m in scan.in_order:
        writer.add_message(
            channel_ids[m.channel_id],
            log_time=m.log_time,
            data=m.data,
            publish_time=m.publish_time,
            sequence=m.sequence,
        )
    writer.finish()
