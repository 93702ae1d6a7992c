"""A bag's topics that no display of ours draws, into the recording through Rerun's own MCAP decoders
(``rerun.chunk.McapReader``, public API of rerun-sdk 0.41): each topic lands on the entity of its name, on our
timeline. The display topics (scans, clouds, markers, maps, images…) are decoded by :mod:`r2d2_viz.msgs` and
excluded here; what is left that Rerun's ``ros2msg`` decoder makes something of: NavSatFix, MagneticField, Imu and
the other scalar sensors, ``std_msgs/String``, ``rcl_interfaces/Log``. ``.mcap`` storage only, saved runs only.

Rerun's chunks carry three timelines (``message_log_time``: receive time; ``message_publish_time``;
``ros2_timestamp``: header stamps); the one matching our ``time`` choice is renamed to our timeline, so the
topics move with the robot.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import pyarrow as pa
import rerun as rr
from rerun.chunk import Chunk, McapReader

from r2d2_viz.errors import listed
from r2d2_viz.viewer.entities import TIMELINE

OURS = ("/joint_states", "/tf", "/tf_static", "/robot_description")
"""Topics r2d2-viz draws itself."""
DECODERS = ("ros2msg", "ros2_reflection", "foxglove", "protobuf")
"""Rerun's decoders that make archetypes (in 0.41 sensor_msgs/Image comes out only with ``ros2_reflection`` on;
that decoder's own columns, raw copies of the message fields, are dropped)."""
_SOURCE_TIMELINE = {"receive": "message_log_time", "header": "ros2_timestamp"}


@dataclass(frozen=True)
class OtherTopics:
    logged: tuple[str, ...]
    skipped: tuple[tuple[str, str], ...]
    """(topic, its message type) of what no decoder understood."""
    failed: tuple[tuple[Path, str], ...] = ()
    """(file, why) where Rerun's reader failed: those files' topics were not (all) shown."""

    def summary(self) -> str:
        if not self.skipped:
            return ""
        shown = listed(f"{t} ({m})" for t, m in self.skipped)
        n = len(self.skipped)
        return f"{n} topic{'s' * (n != 1)} Rerun cannot show, skipped: {shown}"


def _semantic(chunk: Chunk, source: str, timeline: str) -> Chunk | None:
    """``chunk`` with ``source`` renamed to ``timeline`` and only Rerun archetypes' columns (not the reflection
    decoder's copies of the message fields); None when nothing is left."""
    batch = chunk.to_record_batch()
    fields, columns, data = [], [], 0
    for f, column in zip(batch.schema, batch.columns, strict=True):
        meta = f.metadata or {}
        if meta.get(b"rerun:kind") == b"data":
            if not meta.get(b"rerun:archetype", b"").startswith(b"rerun."):
                continue
            data += 1
        elif f.name == source:
            meta = {k: (timeline.encode() if k == b"rerun:index_name" else v) for k, v in meta.items()}
            f = pa.field(timeline, f.type, f.nullable, meta)
        fields.append(f)
        columns.append(column)
    if not data:
        return None
    (out,) = Chunk.from_record_batch(
        pa.RecordBatch.from_arrays(columns, schema=pa.schema(fields, batch.schema.metadata))
    )
    return out


def other_topic_chunks(
    mcap: Path, *, time: str = "receive", timeline: str = TIMELINE, exclude: Sequence[str] = OURS
) -> tuple[Iterator[Chunk], McapReader]:
    """Rerun's chunks of every topic of ``mcap`` but ``exclude``, on ``timeline`` (lazy)."""
    reader = McapReader(
        mcap,
        decoders=[d for d in DECODERS if d in McapReader.available_decoders()],
        exclude_topic_regex=[f"^{t}$" for t in exclude],
        recover=True,  # a file without a summary (a recording cut short) is scanned from the start
    )
    source = _SOURCE_TIMELINE[time]
    kept = (_semantic(c, source, timeline) for c in reader.stream())
    return (c for c in kept if c is not None), reader


def log_other_topics(
    rec: rr.RecordingStream,
    mcap_files: Sequence[Path],
    *,
    time: str = "receive",
    timeline: str = TIMELINE,
    exclude: Sequence[str] = OURS,
) -> OtherTopics:
    """Send the other topics of a bag's MCAP storage files to ``rec``; say which were skipped."""
    logged: set[str] = set()
    topics: dict[str, str] = {}
    failed: list[tuple[Path, str]] = []
    for mcap in mcap_files:
        try:
            chunks, reader = other_topic_chunks(mcap, time=time, timeline=timeline, exclude=exclude)
            for channel in reader.info().channels:
                if channel.topic not in exclude:
                    topics[channel.topic] = channel.schema.name if channel.schema else "?"

            def sent(chunks: Iterator[Chunk] = chunks) -> Iterator[Chunk]:
                for chunk in chunks:
                    if chunk.timeline_names and not chunk.is_empty:
                        logged.add(chunk.entity_path)
                    yield chunk

            rec.send_chunks(sent())
        except BaseException as exc:  # a second reader of a file ours has read: its failure is a warning
            if not isinstance(exc, Exception) and type(exc).__name__ != "PanicException":  # pyo3's Rust panic
                raise
            failed.append((mcap, _why(exc)))
    skipped = tuple(sorted((t, m) for t, m in topics.items() if t not in logged))
    return OtherTopics(tuple(sorted(logged & set(topics))), skipped, tuple(failed))


def _why(exc: BaseException) -> str:
    """The first line of an error, short enough for a warning line."""
    lines = str(exc).strip().splitlines()
    text = lines[0] if lines else type(exc).__name__
    return text if len(text) <= 60 else text[:59] + "…"
