"""LeRobot's statistics: golden values by numpy over the whole data and LeRobot's own documented figures."""

from __future__ import annotations

import numpy as np

from r2d2_viz.export.lerobot_stats import aggregate, as_json, feature_stats, image_stats, sample_indices, thinned


def test_feature_stats_are_numpys() -> None:
    values = np.random.default_rng(1).normal(size=(50, 3)).astype(np.float32)
    stats = feature_stats(values)
    data = values.astype(np.float64)
    assert np.allclose(stats["mean"], data.mean(0)) and np.allclose(stats["std"], data.std(0))
    assert np.allclose(stats["min"], data.min(0)) and np.allclose(stats["max"], data.max(0))
    assert np.allclose(stats["q50"], np.median(data, 0)) and stats["count"].tolist() == [50]
    assert feature_stats(np.arange(4))["mean"].shape == (1,)  # a (n,) column: (1,), LeRobot's keepdims


def test_aggregated_episodes_are_the_whole_datas() -> None:
    rng = np.random.default_rng(2)
    parts = [rng.normal(size=(n, 2)) for n in (10, 31, 7)]
    whole = np.concatenate(parts)
    got = aggregate([{"x": feature_stats(p)} for p in parts])["x"]
    assert np.allclose(got["mean"], whole.mean(0)) and np.allclose(got["std"], whole.std(0))
    assert np.allclose(got["min"], whole.min(0)) and np.allclose(got["max"], whole.max(0))
    assert got["count"].tolist() == [48]
    assert as_json({"x": got})["x"]["count"] == [48]


def test_sample_indices_follow_lerobots_documented_counts() -> None:
    # compute_stats.estimate_num_samples's docstring: up to ~500 -> 100, 1000 -> 177, 2000 -> 299, 5000 -> 594
    assert [len(sample_indices(n)) for n in (50, 400, 1000, 2000, 5000)] == [50, 100, 177, 299, 594]
    assert sample_indices(10).tolist() == list(range(10))


def test_image_stats_per_channel_in_unit_range() -> None:
    frames = [np.full((4, 6, 3), (0, 51, 255), dtype=np.uint8), np.full((4, 6, 3), (0, 102, 255), dtype=np.uint8)]
    stats = image_stats(frames)
    assert stats["mean"].shape == (3, 1, 1)
    assert np.allclose(stats["mean"].ravel(), [0.0, 0.3, 1.0]) and np.allclose(stats["std"].ravel(), [0, 0.1, 0])
    assert stats["count"].tolist() == [2]
    assert thinned(np.zeros((480, 640, 3))).shape == (120, 160, 3)  # int(640 / 150) = 4, as LeRobot's
    assert thinned(np.zeros((240, 320, 3))).shape == (120, 160, 3)  # 320 >= 300: int(320 / 150) = 2
    assert thinned(np.zeros((200, 298, 3))).shape == (200, 298, 3)
