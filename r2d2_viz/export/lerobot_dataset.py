"""Episodes appended to a LeRobot v3.0 dataset (made when missing): the rows of a run's new episodes in one new data
file, their rows of episode metadata in one new episodes file, each camera's video of an episode in a file of its
own — new files only, as LeRobot itself starts new files when it resumes a dataset, so what was there stays byte for
byte — then ``tasks.parquet``, ``stats.json`` (the old stats aggregated with the new episodes', as LeRobot's
``save_episode``), ``info.json`` and our list of the bags taken in, each replaced whole.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from r2d2_viz.errors import UsageError
from r2d2_viz.export import lerobot_format as fmt
from r2d2_viz.export import lerobot_stats
from r2d2_viz.export.lerobot_episode import EpisodePart


@dataclass
class DatasetState:
    root: Path
    fps: int
    features: dict[str, dict[str, Any]] = field(default_factory=dict)
    episodes: int = 0
    frames: int = 0
    tasks: list[str] = field(default_factory=list)
    stats: dict[str, lerobot_stats.Stats] | None = None
    sources: list[dict[str, Any]] = field(default_factory=list)
    robot_type: str | None = None

    def has(self, bag_key: str) -> bool:
        return any(s.get("key") == bag_key for s in self.sources)


def open_dataset(root: Path, fps: int) -> DatasetState:
    """The dataset at ``root`` (empty when it has no ``meta/info.json``); UsageError when it is another version,
    another rate, or a folder that is something else."""
    info_path = root / fmt.INFO_PATH
    if not info_path.exists():
        if root.exists() and not root.is_dir():
            raise UsageError(f"--export-lerobot {root}: not a directory")
        if root.exists() and any(p.name != ".DS_Store" for p in root.iterdir()):
            raise UsageError(f"--export-lerobot {root}: a folder that is not empty and not a LeRobot dataset")
        return DatasetState(root, fps)
    try:
        info = json.loads(info_path.read_text())
        version, have_fps = info["codebase_version"], int(info["fps"])
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise UsageError(f"--export-lerobot {root}: unreadable {fmt.INFO_PATH} ({exc})") from None
    if version != fmt.CODEBASE_VERSION:
        raise UsageError(f"--export-lerobot {root}: a LeRobot {version} dataset; this writes {fmt.CODEBASE_VERSION}")
    if have_fps != fps:
        raise UsageError(f"--export-lerobot {root}: its frames are at {have_fps} fps; give --fps {have_fps}")
    stats_path, sources_path = root / fmt.STATS_PATH, root / fmt.SOURCES_PATH
    return DatasetState(
        root,
        fps,
        info["features"],
        int(info["total_episodes"]),
        int(info["total_frames"]),
        fmt.read_tasks(root),
        lerobot_stats.from_json(json.loads(stats_path.read_text())) if stats_path.exists() else None,
        json.loads(sources_path.read_text()) if sources_path.exists() else [],
        info.get("robot_type"),
    )


def features_of(part: EpisodePart, fps: int, codec: str) -> dict[str, dict[str, Any]]:
    """The features an episode gives (LeRobot's order: the episode's own, then the default columns)."""
    features: dict[str, dict[str, Any]] = {}
    if part.state is not None:
        features[fmt.STATE] = fmt.vector_feature(part.state_names)
    if part.action is not None:
        features[fmt.ACTION] = fmt.vector_feature(part.action_names)
    for key, (height, width) in sorted(part.cameras.items()):
        features[key] = fmt.video_feature(height, width, fps, codec)
    return features | fmt.DEFAULT_FEATURES


def mismatch(have: dict[str, dict[str, Any]], new: dict[str, dict[str, Any]]) -> str | None:
    """Why an episode with features ``new`` does not fit a dataset with ``have`` (None: it fits)."""
    if set(have) != set(new):
        missing, extra = sorted(set(have) - set(new)), sorted(set(new) - set(have))
        return f"its features differ from the dataset's (missing {missing or 'none'}, extra {extra or 'none'})"
    for key, feature in new.items():
        if list(feature["shape"]) != list(have[key]["shape"]) or feature.get("names") != have[key].get("names"):
            return f"its {key} is {feature['shape']} {feature.get('names')}, the dataset's {have[key]['shape']}"
    return None


def _next_number(root: Path, folder: str, suffix: str) -> int:
    """The number of the next file under ``root/folder/chunk-CCC/file-FFF.suffix``."""
    found = [-1]
    for path in (root / folder).glob(f"chunk-*/file-*{suffix}"):
        match = re.fullmatch(rf"chunk-(\d+)/file-(\d+){re.escape(suffix)}", f"{path.parent.name}/{path.name}")
        if match:
            found.append(fmt.file_number(int(match[1]), int(match[2])))
    return max(found) + 1


@dataclass(frozen=True)
class NewEpisode:
    key: str
    """The bag's identity (skipped when run again)."""
    name: str
    part: EpisodePart
    videos: Path
    """The folder holding the part's ``<camera key>.mp4``."""


def append(
    state: DatasetState,
    episodes: Sequence[NewEpisode],
    *,
    task: str,
    codec: str,
    data_file_bytes: int = fmt.DATA_FILE_SIZE_IN_MB * 1_000_000,
) -> list[Path]:
    """Write ``episodes`` (their features already checked) after the dataset's; the new files' paths. A data file
    takes episodes until their rows (in memory, more than on disk) would pass ``data_file_bytes``, LeRobot's 100 MB."""
    root, fps = state.root, state.fps
    if not state.features:
        state.features = features_of(episodes[0].part, fps, codec)
        state.robot_type = episodes[0].part.robot_type
    if task not in state.tasks:
        state.tasks.append(task)
    task_index = state.tasks.index(task)
    written: list[Path] = []
    try:
        rows: list[dict[str, np.ndarray]] = []
        metas, stats = [], []
        video_keys = [k for k, f in state.features.items() if f["dtype"] == "video"]
        data_number = _next_number(root, "data", ".parquet")
        meta_chunk, meta_file = fmt.chunk_file(_next_number(root, "meta/episodes", ".parquet"))
        video_numbers = {k: _next_number(root, f"videos/{k}", ".mp4") for k in video_keys}
        index = state.frames
        for n, episode in enumerate(episodes):
            part, episode_index = episode.part, state.episodes + n
            columns = _columns(part, episode_index, index, task_index, fps)
            size = sum(v.nbytes for v in columns.values())
            if rows and sum(v.nbytes for r in rows for v in r.values()) + size > data_file_bytes:
                written.append(_write_data(root, data_number, rows, state.features))
                data_number, rows = data_number + 1, []
            rows.append(columns)
            data_chunk, data_file = fmt.chunk_file(data_number)
            ep_stats = {k: lerobot_stats.feature_stats(v) for k, v in columns.items()}
            ep_stats |= part.camera_stats
            stats.append(ep_stats)
            meta: dict[str, Any] = {
                "episode_index": episode_index,
                "tasks": [task],
                "length": part.frames,
                "data/chunk_index": data_chunk,
                "data/file_index": data_file,
                "dataset_from_index": index,
                "dataset_to_index": index + part.frames,
            }
            for key in video_keys:
                chunk, file = fmt.chunk_file(video_numbers[key])
                video_numbers[key] += 1
                target = root / fmt.VIDEO_PATH.format(video_key=key, chunk_index=chunk, file_index=file)
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(episode.videos / f"{key}.mp4", target)
                written.append(target)
                meta |= {
                    f"videos/{key}/chunk_index": chunk,
                    f"videos/{key}/file_index": file,
                    f"videos/{key}/from_timestamp": 0.0,
                    f"videos/{key}/to_timestamp": part.frames / fps,
                }
            meta |= lerobot_stats.flattened(ep_stats)
            meta |= {"meta/episodes/chunk_index": meta_chunk, "meta/episodes/file_index": meta_file}
            metas.append(meta)
            index += part.frames
        written.append(_write_data(root, data_number, rows, state.features))
        meta_path = root / fmt.EPISODES_PATH.format(chunk_index=meta_chunk, file_index=meta_file)
        written.append(meta_path)
        fmt.write_parquet(meta_path, _episodes_table(metas))
    except BaseException:
        for path in written:
            path.unlink(missing_ok=True)
        raise
    state.stats = lerobot_stats.aggregate(([state.stats] if state.stats else []) + stats)
    state.episodes += len(episodes)
    state.frames = index
    state.sources += [
        {"episode_index": state.episodes - len(episodes) + n, "bag": e.name, "key": e.key}
        for n, e in enumerate(episodes)
    ]
    _write_meta(state)
    return written


def _columns(part: EpisodePart, episode_index: int, start: int, task_index: int, fps: int) -> dict[str, np.ndarray]:
    """An episode's rows (LeRobot's ``timestamp`` is ``frame_index / fps``, float32)."""
    n = part.frames
    columns: dict[str, np.ndarray] = {}
    if part.state is not None:
        columns[fmt.STATE] = part.state
    if part.action is not None:
        columns[fmt.ACTION] = part.action
    frame_index = np.arange(n, dtype=np.int64)
    columns |= {
        "timestamp": (frame_index / fps).astype(np.float32),
        "frame_index": frame_index,
        "episode_index": np.full(n, episode_index, dtype=np.int64),
        "index": start + frame_index,
        "task_index": np.full(n, task_index, dtype=np.int64),
    }
    return columns


def _write_data(root: Path, number: int, rows: list[dict[str, np.ndarray]], features: dict[str, Any]) -> Path:
    chunk, file = fmt.chunk_file(number)
    path = root / fmt.DATA_PATH.format(chunk_index=chunk, file_index=file)
    fmt.write_parquet(path, _data_table(rows, features))
    return path


def _data_table(rows: list[dict[str, np.ndarray]], features: dict[str, dict[str, Any]]) -> pa.Table:
    arrays, names = [], []
    for key, feature in features.items():
        if feature["dtype"] == "video":
            continue
        values = np.concatenate([r[key] for r in rows])
        if feature["shape"] == [1] or feature["shape"] == (1,):
            arrays.append(pa.array(values.reshape(-1), type=pa.from_numpy_dtype(np.dtype(feature["dtype"]))))
        else:
            width = int(feature["shape"][0])
            flat = pa.array(values.reshape(-1).astype(np.float32), type=pa.float32())
            arrays.append(pa.FixedSizeListArray.from_arrays(flat, width))
        names.append(key)
    return pa.table(arrays, names=names)


def _episodes_table(metas: list[dict[str, Any]]) -> pa.Table:
    columns: dict[str, pa.Array] = {}
    for key in metas[0]:
        values = [m[key] for m in metas]
        if key == "tasks":
            columns[key] = pa.array(values, type=pa.list_(pa.string()))
        elif key.startswith("stats/"):
            kind = pa.int64() if key.endswith("/count") else pa.float64()
            columns[key] = pa.array([np.asarray(v).reshape(-1).tolist() for v in values], type=pa.list_(kind))
        elif key.endswith("_timestamp"):
            columns[key] = pa.array(values, type=pa.float64())
        else:
            columns[key] = pa.array(values, type=pa.int64())
    return pa.table(columns)


def _write_meta(state: DatasetState) -> None:
    root = state.root
    fmt.write_parquet(root / fmt.TASKS_PATH, fmt.tasks_table(state.tasks))
    assert state.stats is not None
    fmt.write_json(root / fmt.STATS_PATH, lerobot_stats.as_json(state.stats))
    info = fmt.info_json(
        state.features,
        fps=state.fps,
        episodes=state.episodes,
        frames=state.frames,
        tasks=len(state.tasks),
        robot_type=state.robot_type,
    )
    fmt.write_json(root / fmt.INFO_PATH, info)
    fmt.write_json(root / fmt.SOURCES_PATH, state.sources)
