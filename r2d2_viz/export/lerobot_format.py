"""LeRobot's dataset format v3.0, as LeRobot 0.4–0.6.1 writes and reads it (``lerobot/datasets/utils.py``,
``dataset_metadata.py``, ``dataset_writer.py``, ``video_utils.py`` of huggingface/lerobot v0.6.1):

``meta/info.json``, ``meta/stats.json``, ``meta/tasks.parquet`` (the task as the pandas index ``task``, its
``task_index``), ``meta/episodes/chunk-CCC/file-FFF.parquet`` (one row per episode: its tasks, length, where its
rows and videos are, its stats flattened as ``stats/<feature>/<stat>``), ``data/chunk-CCC/file-FFF.parquet``
(``timestamp``, ``frame_index``, ``episode_index``, ``index``, ``task_index`` and the features) and
``videos/<key>/chunk-CCC/file-FFF.mp4``. A chunk holds up to 1,000 files.

Pure: pyarrow and json only.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

CODEBASE_VERSION = "v3.0"
CHUNKS_SIZE = 1000
DATA_FILE_SIZE_IN_MB = 100
VIDEO_FILE_SIZE_IN_MB = 200
INFO_PATH = "meta/info.json"
STATS_PATH = "meta/stats.json"
TASKS_PATH = "meta/tasks.parquet"
EPISODES_PATH = "meta/episodes/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
VIDEO_PATH = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
SOURCES_PATH = "meta/r2d2-viz-sources.json"
"""Ours, beside LeRobot's (which reads only its own files): which bag each episode came from, so a run again skips
the bags already in the dataset."""

DEFAULT_FEATURES: dict[str, dict[str, Any]] = {
    "timestamp": {"dtype": "float32", "shape": [1], "names": None},
    "frame_index": {"dtype": "int64", "shape": [1], "names": None},
    "episode_index": {"dtype": "int64", "shape": [1], "names": None},
    "index": {"dtype": "int64", "shape": [1], "names": None},
    "task_index": {"dtype": "int64", "shape": [1], "names": None},
}
"""LeRobot's ``DEFAULT_FEATURES`` (``lerobot/utils/constants.py``), every dataset's own columns."""

STATE, ACTION, IMAGES = "observation.state", "action", "observation.images."


def chunk_file(n: int) -> tuple[int, int]:
    """The ``n``-th file of a kind (0-based) as ``(chunk_index, file_index)``: 1,000 files a chunk."""
    return n // CHUNKS_SIZE, n % CHUNKS_SIZE


def file_number(chunk_index: int, file_index: int) -> int:
    return chunk_index * CHUNKS_SIZE + file_index


def vector_feature(names: list[str]) -> dict[str, Any]:
    return {"dtype": "float32", "shape": [len(names)], "names": list(names)}


def video_feature(height: int, width: int, fps: int, codec: str) -> dict[str, Any]:
    """A camera's feature as LeRobot's ``update_video_info`` fills it (the stream's size, codec, pixel format and
    rate, then the encoder's settings: :data:`r2d2_viz.export.lerobot_video.SETTINGS`)."""
    from r2d2_viz.export.lerobot_video import SETTINGS

    settings = SETTINGS[codec]
    info: dict[str, Any] = {
        "video.height": height,
        "video.width": width,
        "video.codec": "av1" if codec == "av1" else "h264",
        "video.pix_fmt": "yuv420p",
        "video.fps": fps,
        "video.channels": 3,
        "has_audio": False,
    }
    for key in ("g", "crf", "preset", "fast_decode"):
        if key in settings:
            info[f"video.{key}"] = settings[key]
    info |= {"video.extra_options": {}, "video.video_backend": "pyav", "is_depth_map": False}
    return {"dtype": "video", "shape": [height, width, 3], "names": ["height", "width", "channels"], "info": info}


def info_json(
    features: dict[str, dict[str, Any]], *, fps: int, episodes: int, frames: int, tasks: int, robot_type: str | None
) -> dict[str, Any]:
    """``meta/info.json`` (the keys of LeRobot's ``DatasetInfo.to_dict``)."""
    videos = any(f["dtype"] == "video" for f in features.values())
    return {
        "codebase_version": CODEBASE_VERSION,
        "fps": fps,
        "features": features,
        "total_episodes": episodes,
        "total_frames": frames,
        "total_tasks": tasks,
        "chunks_size": CHUNKS_SIZE,
        "data_files_size_in_mb": DATA_FILE_SIZE_IN_MB,
        "video_files_size_in_mb": VIDEO_FILE_SIZE_IN_MB,
        "data_path": DATA_PATH,
        "video_path": VIDEO_PATH if videos else None,
        "robot_type": robot_type,
        "splits": {"train": f"0:{episodes}"},
    }


def write_json(path: Path, value: Any) -> None:
    """``value`` as JSON at ``path``, written beside it and renamed into place (never half-written)."""
    write_atomic(path, (json.dumps(value, indent=4, ensure_ascii=False) + "\n").encode())


def write_atomic(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_parquet(path: Path, table: pa.Table) -> None:
    """``table`` at ``path`` (snappy, as LeRobot's writer), written beside it and renamed into place."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        pq.write_table(table, tmp, compression="snappy")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def tasks_table(tasks: list[str]) -> pa.Table:
    """``meta/tasks.parquet`` as pandas writes LeRobot's ``DataFrame({"task_index": …}, index=Index(tasks,
    name="task"))``: the index a column ``task`` named in the schema's ``pandas`` metadata, so that
    ``pd.read_parquet`` gives it back as the index (LeRobot looks tasks up by it)."""
    pandas_meta = {
        "index_columns": ["task"],
        "column_indexes": [],
        "columns": [
            {"name": "task_index", "field_name": "task_index", "pandas_type": "int64", "numpy_type": "int64",
             "metadata": None},
            {"name": "task", "field_name": "task", "pandas_type": "unicode", "numpy_type": "object", "metadata": None},
        ],
        "creator": {"library": "pyarrow", "version": pa.__version__},
        "pandas_version": "2.2.3",
    }  # fmt: skip
    schema = pa.schema([("task_index", pa.int64()), ("task", pa.string())]).with_metadata(
        {b"pandas": json.dumps(pandas_meta).encode()}
    )
    return pa.table({"task_index": np.arange(len(tasks), dtype=np.int64), "task": tasks}, schema=schema)


def read_tasks(root: Path) -> list[str]:
    path = root / TASKS_PATH
    if not path.exists():
        return []
    table = pq.read_table(path)
    order = np.argsort(table.column("task_index").to_numpy())
    names = table.column("task").to_pylist()
    return [names[i] for i in order]
