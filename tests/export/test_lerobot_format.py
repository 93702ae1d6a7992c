"""LeRobot v3.0's names and files (as huggingface/lerobot v0.6.1's datasets/utils.py defines them)."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq

from r2d2_viz.export import lerobot_format as fmt


def test_paths_are_lerobots() -> None:
    assert fmt.DATA_PATH.format(chunk_index=0, file_index=12) == "data/chunk-000/file-012.parquet"
    assert fmt.VIDEO_PATH.format(video_key="observation.images.top", chunk_index=1, file_index=0) == (
        "videos/observation.images.top/chunk-001/file-000.mp4"
    )
    assert fmt.EPISODES_PATH.format(chunk_index=0, file_index=0) == "meta/episodes/chunk-000/file-000.parquet"
    assert fmt.chunk_file(0) == (0, 0) and fmt.chunk_file(1001) == (1, 1) and fmt.file_number(1, 1) == 1001


def test_info_json_has_lerobots_keys() -> None:
    info = fmt.info_json(dict(fmt.DEFAULT_FEATURES), fps=30, episodes=2, frames=9, tasks=1, robot_type=None)
    keys = {
        *("codebase_version", "fps", "features", "total_episodes", "total_frames", "total_tasks", "chunks_size"),
        *("data_files_size_in_mb", "video_files_size_in_mb", "data_path", "video_path", "robot_type", "splits"),
    }
    assert set(info) == keys and info["splits"] == {"train": "0:2"} and info["video_path"] is None
    camera = fmt.video_feature(240, 320, 30, "av1")
    assert camera["info"]["video.g"] == 2 and camera["info"]["video.crf"] == 30 and camera["shape"] == [240, 320, 3]


def test_tasks_round_trip_with_the_pandas_index(tmp_path: Path) -> None:
    path = tmp_path / fmt.TASKS_PATH
    fmt.write_parquet(path, fmt.tasks_table(["pick", "place"]))
    table = pq.read_table(path)
    meta = json.loads(table.schema.metadata[b"pandas"])
    assert meta["index_columns"] == ["task"] and table.column("task").to_pylist() == ["pick", "place"]
    assert fmt.read_tasks(tmp_path) == ["pick", "place"] and not list(path.parent.glob(".*partial"))
