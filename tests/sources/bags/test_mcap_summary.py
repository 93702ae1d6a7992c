"""What a summary lacks, found in the data section, reading only what that needs: counts from the message indexes
without opening a chunk, a chunk without them walked once; missing channels looked for until found. The file is
written by rosbags; its chunk index and channels as rosbags' own MCAP reader reads them; the counts as written."""

from __future__ import annotations

import mmap
from collections import Counter
from pathlib import Path

import pytest
from bagmaker import T0, TYPES, BagSpec, joint_state, storage_file, string, write_bag
from rosbags.rosbag2.storage_mcap import McapReader

import r2d2_viz.sources.bags.mcap_summary as mcap_summary
from r2d2_viz.sources.bags.mcap_records import ChunkIndex, chunk_data
from r2d2_viz.sources.bags.mcap_summary import Definitions, count_messages, find_definitions

MS = 1_000_000


def _bag(tmp_path: Path) -> tuple[Path, BagSpec]:
    """Two topics over several chunks (rosbags closes a chunk past 1 MiB: 20 kB strings every 10th ms)."""
    spec = BagSpec()
    for k in range(1000):
        spec.add("/joint_states", T0 + k * MS, joint_state(T0 + k, ["a"], [k]))
        if k % 10 == 0:
            spec.add("/robot_description", T0 + k * MS + 1, string(f"{k}" * 10_000))
    return storage_file(write_bag(tmp_path / "b", spec)), spec


def _rosbags_index(file: Path) -> tuple[list[ChunkIndex], dict[int, tuple[str, str]]]:
    """The chunk index (with its message index offsets) and channel id → (topic, type), as rosbags reads them."""
    reader = McapReader(file)
    reader.open()
    try:
        chunks = [
            ChunkIndex(
                c.message_start_time,
                c.message_end_time,
                c.chunk_start_offset,
                c.chunk_length,
                dict(c.message_index_offsets),
            )
            for c in reader.chunks
        ]
        return chunks, {c.id: (c.topic, c.schema) for c in reader.channels.values()}
    finally:
        reader.close()


@pytest.fixture
def opened(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The chunks opened (decompressed) through ``mcap_summary``, by file offset."""
    seen: list[int] = []

    def counted(buf: mmap.mmap, start: int, end: int) -> memoryview:
        seen.append(start)
        return chunk_data(buf, start, end)

    monkeypatch.setattr(mcap_summary, "chunk_data", counted)
    return seen


def _expected(spec: BagSpec) -> tuple[Counter[str], tuple[int, int]]:
    times = [t for _, t, _ in spec.messages]
    return Counter(topic for topic, _, _ in spec.messages), (min(times), max(times))


def test_counts_come_from_the_message_indexes_without_opening_a_chunk(tmp_path: Path, opened: list[int]) -> None:
    file, spec = _bag(tmp_path)
    chunks, channels = _rosbags_index(file)
    assert len(chunks) > 2
    with file.open("rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as buf:
        counts, span, damaged = count_messages(buf, chunks, Definitions())
    counted = Counter({channels[c][0]: n for c, n in counts.items()})
    assert (counted, span, damaged) == (*_expected(spec), {})
    assert opened == []


def test_chunks_without_message_indexes_are_walked_once_each(tmp_path: Path, opened: list[int]) -> None:
    file, spec = _bag(tmp_path)
    chunks, channels = _rosbags_index(file)
    bare = [ChunkIndex(c.start_ns, c.end_ns, c.offset, c.length, {}) for c in chunks]
    with file.open("rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as buf:
        counts, span, damaged = count_messages(buf, bare, Definitions())
    counted = Counter({channels[c][0]: n for c, n in counts.items()})
    assert (counted, span, damaged) == (*_expected(spec), {})
    assert sorted(opened) == sorted(c.offset for c in chunks)


def test_missing_channels_are_looked_for_until_found(tmp_path: Path, opened: list[int]) -> None:
    """rosbags writes the Schema and Channel records into the first chunk that uses them (here the first chunk
    holds both topics): the walk opens that chunk and stops; a channel that is nowhere takes it to the end of the
    data section, every chunk opened once."""
    file, _ = _bag(tmp_path)
    chunks, channels = _rosbags_index(file)
    with file.open("rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as buf:
        found = Definitions()
        find_definitions(buf, len(buf), set(channels), found)
        assert {c.id: (c.topic, found.schemas[c.schema_id].name) for c in found.channels.values()} == channels
        assert opened == [min(c.offset for c in chunks)] and not found.missing(channels)
        opened.clear()

        nowhere = Definitions()
        find_definitions(buf, len(buf), {999}, nowhere)
        assert nowhere.missing({999}) and set(nowhere.channels) == set(channels)
        assert sorted(opened) == sorted(c.offset for c in chunks)  # every chunk looked into, once
    assert {t: m for t, m in channels.values()} == {t: TYPES[t] for t in ("/joint_states", "/robot_description")}
