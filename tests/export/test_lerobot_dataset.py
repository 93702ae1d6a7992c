"""Appending episodes to a dataset: what may be appended to, what fits, new files only."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from r2d2_viz.errors import UsageError
from r2d2_viz.export.lerobot_dataset import NewEpisode, append, features_of, mismatch, open_dataset
from r2d2_viz.export.lerobot_episode import EpisodePart


def part(n: int, names: list[str]) -> EpisodePart:
    state = np.arange(n * len(names), dtype=np.float32).reshape(n, len(names))
    return EpisodePart(frames=n, start_ns=0, state_names=names, state=state)


def test_open_refuses_what_is_not_a_dataset_of_this_rate(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(UsageError, match="not empty and not a LeRobot dataset"):
        open_dataset(tmp_path, 30)
    root = tmp_path / "ds"
    append(open_dataset(root, 30), [NewEpisode("k", "b", part(3, ["a"]), root)], task="t", codec="av1")
    with pytest.raises(UsageError, match="at 30 fps; give --fps 30"):
        open_dataset(root, 15)


def test_two_appends_make_new_files_and_keep_indices_running(tmp_path: Path) -> None:
    root = tmp_path / "ds"
    append(open_dataset(root, 10), [NewEpisode("a", "a", part(3, ["j"]), root)], task="t", codec="av1")
    first = (root / "data/chunk-000/file-000.parquet").read_bytes()
    state = open_dataset(root, 10)
    assert state.has("a") and not state.has("b")
    append(state, [NewEpisode("b", "b", part(4, ["j"]), root)], task="u", codec="av1")
    assert (root / "data/chunk-000/file-000.parquet").read_bytes() == first
    second = pq.read_table(root / "data/chunk-000/file-001.parquet").to_pydict()
    assert second["index"] == [3, 4, 5, 6] and second["episode_index"] == [1] * 4 and second["task_index"] == [1] * 4
    info = json.loads((root / "meta/info.json").read_text())
    assert info["total_episodes"] == 2 and info["total_frames"] == 7 and info["total_tasks"] == 2
    episodes = pq.read_table(root / "meta/episodes/chunk-000/file-001.parquet").to_pydict()
    assert episodes["dataset_from_index"] == [3] and episodes["meta/episodes/file_index"] == [1]


def test_features_must_match() -> None:
    have = features_of(part(2, ["a", "b"]), 30, "av1")
    assert mismatch(have, features_of(part(2, ["a", "b"]), 30, "av1")) is None
    assert "observation.state" in str(mismatch(have, features_of(part(2, ["b", "a"]), 30, "av1")))


def test_a_data_file_takes_episodes_up_to_its_size(tmp_path: Path) -> None:
    root = tmp_path / "ds"
    new = [NewEpisode(k, k, part(10, ["j"]), root) for k in "abc"]  # 10 rows: 2 x 40 + 4 x 80 = 400 bytes each
    append(open_dataset(root, 10), new, task="t", codec="av1", data_file_bytes=900)
    files = sorted(p.name for p in (root / "data/chunk-000").iterdir())
    assert files == ["file-000.parquet", "file-001.parquet"]  # a and b (800 bytes), then c
    episodes = pq.read_table(root / "meta/episodes/chunk-000/file-000.parquet").to_pydict()
    assert episodes["data/file_index"] == [0, 0, 1] and episodes["dataset_from_index"] == [0, 10, 20]
    assert pq.read_table(root / "data/chunk-000/file-001.parquet").column("index").to_pylist() == list(range(20, 30))
