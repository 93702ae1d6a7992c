"""A LeRobot dataset's statistics (``lerobot/datasets/compute_stats.py`` of v0.6.1): per feature ``min``, ``max``,
``mean``, ``std`` (population), ``count`` and the quantiles ``q01 q10 q50 q90 q99``; per episode, then the dataset's
as LeRobot aggregates episodes (count-weighted means, the pooled variance, quantiles averaged by count).

Vectors per dimension (a ``(1,)`` column's stats have shape ``(1,)``); a camera per channel over a sample of its
frames (LeRobot's ``sample_indices``: 100 frames up to 500, ``n**0.75`` after, at most 10,000; frames of 300
pixels or more thinned to about 150, ``auto_downsample_height_width``), in ``[0, 1]``, shape ``(3, 1, 1)``.
Quantiles are numpy's exact ones (LeRobot estimates them from 5,000-bin histograms).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

QUANTILES = (0.01, 0.10, 0.50, 0.90, 0.99)
QUANTILE_KEYS = tuple(f"q{int(q * 100):02d}" for q in QUANTILES)
Stats = dict[str, npt.NDArray[np.float64]]


def feature_stats(values: np.ndarray) -> Stats:
    """Stats of a column: ``(n,)`` scalars or ``(n, d)`` vectors."""
    data = np.asarray(values, dtype=np.float64)
    data = data.reshape(len(data), -1)
    stats: Stats = {
        "min": data.min(axis=0),
        "max": data.max(axis=0),
        "mean": data.mean(axis=0),
        "std": data.std(axis=0),
        "count": np.array([len(data)], dtype=np.float64),
    }
    for key, q in zip(QUANTILE_KEYS, QUANTILES, strict=True):
        stats[key] = np.quantile(data, q, axis=0)
    return stats


def sample_indices(n: int) -> npt.NDArray[np.int64]:
    """The frames of an episode of ``n`` whose pixels count (LeRobot's ``sample_indices``)."""
    wanted = max(min(100, n), min(int(n**0.75), 10_000))
    return np.round(np.linspace(0, n - 1, wanted)).astype(np.int64)


def thinned(image: np.ndarray) -> np.ndarray:
    """An ``(H, W, 3)`` frame thinned as LeRobot's ``auto_downsample_height_width`` (to about 150 pixels)."""
    height, width = image.shape[:2]
    if max(width, height) < 300:
        return image
    step = int(width / 150) if width > height else int(height / 150)
    return image[::step, ::step]


def image_stats(frames: list[np.ndarray]) -> Stats:
    """Per-channel stats of sampled ``(H, W, 3)`` uint8 frames, in ``[0, 1]``, shape ``(3, 1, 1)``; ``count`` is
    the frames."""
    pixels = np.concatenate([f.reshape(-1, 3) for f in frames]).astype(np.float64) / 255.0
    stats = feature_stats(pixels)
    out: Stats = {k: v.reshape(3, 1, 1) for k, v in stats.items() if k != "count"}
    out["count"] = np.array([len(frames)], dtype=np.float64)
    return out


def aggregate(episodes: list[dict[str, Stats]]) -> dict[str, Stats]:
    """The dataset's stats from its episodes' (LeRobot's ``aggregate_stats``)."""
    keys = sorted({key for ep in episodes for key in ep})
    return {key: _aggregate([ep[key] for ep in episodes if key in ep]) for key in keys}


def _aggregate(parts: list[Stats]) -> Stats:
    means = np.stack([p["mean"] for p in parts])
    variances = np.stack([p["std"] ** 2 for p in parts])
    counts = np.stack([p["count"] for p in parts])
    total = counts.sum(axis=0)
    while counts.ndim < means.ndim:
        counts = np.expand_dims(counts, axis=-1)
    mean = (means * counts).sum(axis=0) / total
    variance = ((variances + (means - mean) ** 2) * counts).sum(axis=0) / total
    out: Stats = {
        "min": np.min(np.stack([p["min"] for p in parts]), axis=0),
        "max": np.max(np.stack([p["max"] for p in parts]), axis=0),
        "mean": mean,
        "std": np.sqrt(variance),
        "count": total,
    }
    for key in QUANTILE_KEYS:
        out[key] = (np.stack([p[key] for p in parts]) * counts).sum(axis=0) / total
    return out


def as_json(stats: dict[str, Stats]) -> dict[str, dict[str, Any]]:
    """Stats as ``meta/stats.json`` holds them (nested lists; ``count`` as integers)."""
    return {
        key: {name: (value.astype(np.int64) if name == "count" else value).tolist() for name, value in s.items()}
        for key, s in stats.items()
    }


def from_json(data: dict[str, dict[str, Any]]) -> dict[str, Stats]:
    return {key: {name: np.asarray(v, dtype=np.float64) for name, v in s.items()} for key, s in data.items()}


def flattened(stats: dict[str, Stats]) -> dict[str, list[Any]]:
    """An episode's stats as its row's ``stats/<feature>/<stat>`` columns (LeRobot's ``flatten_dict``)."""
    return {
        f"stats/{key}/{name}": as_json({key: {name: v}})[key][name] for key, s in stats.items() for name, v in s.items()
    }
