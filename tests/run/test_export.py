"""``r2d2-viz --bag … --export-lerobot DIR``, driven as a user runs it (the CLI in a subprocess): three bags in
parallel (``--jobs 2``) make three episodes, a fourth appended by a second run; read back with pyarrow and PyAV
(LeRobot's layout as its v0.6.1 code defines it) and — in ``test_lerobot_loads_it`` — by LeRobot 0.6.1's own
``LeRobotDataset`` in a venv of its own. Golden values: the bags' messages decoded by rosbags and held at each
frame's time by a plain loop (``lerobotbags.expected``), stats by numpy."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from conftest import made_once
from lerobotbags import JOINTS_URDF_ORDER, ArmBag, expected, write_arm_bag

FPS = 30
ACTION = "/arm_controller/joint_trajectory"
CAMERA = "observation.images.camera_image_raw"


def cli(*args: str | Path) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-c", "from r2d2_viz.cli import main; raise SystemExit(main())", *map(str, args)]
    return subprocess.run(command, capture_output=True, text=True, timeout=600)


def digests(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Made once per test run for every xdist worker (``made_once``): four bags, the first three exported, then all
    four (the fourth appended); each run's exit code and stderr, the dataset's files' digests between the runs."""

    def make(tmp: Path) -> None:
        bags = [write_arm_bag(tmp / f"arm{k}", seed=k, seconds=1.5 + 0.5 * k) for k in range(4)]
        root = tmp / "dataset"
        first = cli("--bag", *(b.path for b in bags[:3]), "--export-lerobot", root, "--action", ACTION,
                    "--task", "wave the arm", "--jobs", "2")  # fmt: skip
        before = digests(root)
        again = cli("--bag", *(b.path for b in bags), "--export-lerobot", root, "--action", ACTION,
                    "--task", "wave the arm")  # fmt: skip
        runs = {"first": [first.returncode, first.stderr], "again": [again.returncode, again.stderr]}
        (tmp / "runs.json").write_text(json.dumps({**runs, "before": before, "after": digests(root)}))

    tmp = made_once(tmp_path_factory, "lerobot-export", make)
    runs = json.loads((tmp / "runs.json").read_text())
    bags = [ArmBag(tmp / f"arm{k}", k, 1.5 + 0.5 * k, "trajectory") for k in range(4)]
    done = {k: subprocess.CompletedProcess([], runs[k][0], "", runs[k][1]) for k in ("first", "again")}
    return {"root": tmp / "dataset", "bags": bags, **done, "before": runs["before"], "after": runs["after"]}


def psnr_luma(a: np.ndarray, b: np.ndarray) -> float:
    """PSNR of BT.601 luma (numpy), in dB."""
    weights = np.array([0.299, 0.587, 0.114])
    ya, yb = a.astype(np.float64) @ weights, b.astype(np.float64) @ weights
    mse = float(np.mean((ya - yb) ** 2))
    return 10 * np.log10(255.0**2 / max(mse, 1e-12))


def decoded(path: Path) -> list[np.ndarray]:
    import av

    with av.open(str(path)) as container:
        return [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]


def test_both_runs_succeed_and_say_what_they_did(exported: dict[str, Any]) -> None:
    assert exported["first"].returncode == 0, exported["first"].stderr
    assert "3 episodes" in exported["first"].stderr
    assert exported["again"].returncode == 0, exported["again"].stderr
    assert "1 episode " in exported["again"].stderr and "3 already in it" in exported["again"].stderr


def test_layout_is_lerobots_v30(exported: dict[str, Any]) -> None:
    root = exported["root"]
    info = json.loads((root / "meta/info.json").read_text())
    assert info["codebase_version"] == "v3.0" and info["fps"] == FPS
    assert info["total_episodes"] == 4 and info["total_tasks"] == 1 and info["splits"] == {"train": "0:4"}
    assert info["data_path"] == "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
    assert info["video_path"] == "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
    assert info["robot_type"] == "two_joint_arm"
    features = info["features"]
    assert features["observation.state"] == {"dtype": "float32", "shape": [2], "names": JOINTS_URDF_ORDER}
    assert features["action"]["names"] == JOINTS_URDF_ORDER
    camera = features[CAMERA]
    assert camera["dtype"] == "video" and camera["shape"] == [240, 320, 3]
    assert camera["info"]["video.codec"] == "av1" and camera["info"]["video.pix_fmt"] == "yuv420p"
    for name in ("timestamp", "frame_index", "episode_index", "index", "task_index"):
        assert name in features
    for rel in ("data/chunk-000/file-000.parquet", "meta/episodes/chunk-000/file-000.parquet",
                f"videos/{CAMERA}/chunk-000/file-000.mp4", "meta/tasks.parquet", "meta/stats.json"):  # fmt: skip
        assert (root / rel).is_file(), rel
    tasks = pq.read_table(root / "meta/tasks.parquet")
    assert tasks.to_pylist() == [{"task_index": 0, "task": "wave the arm"}]
    assert json.loads(tasks.schema.metadata[b"pandas"])["index_columns"] == ["task"]  # pandas' index, as LeRobot


def test_every_frame_holds_the_bags_values(exported: dict[str, Any]) -> None:
    root = exported["root"]
    data = _data(root)
    episodes = _episodes(root)
    assert sorted(episodes["episode_index"]) == [0, 1, 2, 3]
    for k, bag in enumerate(exported["bags"]):
        want = expected(bag, FPS)
        rows = data["episode_index"] == k
        n = len(want["frames_ns"])
        assert rows.sum() == n == episodes["length"][k]
        assert np.array_equal(data["frame_index"][rows], np.arange(n))
        assert np.allclose(data["timestamp"][rows], np.arange(n, dtype=np.float32) / FPS)
        assert np.array_equal(data["observation.state"][rows], want["state"])
        assert np.array_equal(data["action"][rows], want["action"])
        start = episodes["dataset_from_index"][k]
        assert np.array_equal(data["index"][rows], start + np.arange(n))
        assert episodes["dataset_to_index"][k] == start + n


def test_decoded_frames_match_the_bags_images(exported: dict[str, Any]) -> None:
    root = exported["root"]
    episodes = _episodes(root)
    for k, bag in enumerate(exported["bags"]):
        file = episodes[f"videos/{CAMERA}/file_index"][k]
        frames = decoded(root / f"videos/{CAMERA}/chunk-000/file-{file:03d}.mp4")
        want = expected(bag, FPS)["images"]
        assert len(frames) == len(want)
        worst = min(psnr_luma(f, w) for f, w in zip(frames, want, strict=True))
        assert worst >= 35.0, worst
        assert episodes[f"videos/{CAMERA}/to_timestamp"][k] == pytest.approx(len(want) / FPS)


def test_stats_json_is_numpys_over_the_data(exported: dict[str, Any]) -> None:
    root = exported["root"]
    data = _data(root)
    stats = json.loads((root / "meta/stats.json").read_text())
    for key in ("observation.state", "action", "timestamp", "index"):
        values = data[key].astype(np.float64).reshape(len(data[key]), -1)
        assert np.allclose(stats[key]["min"], values.min(axis=0))
        assert np.allclose(stats[key]["max"], values.max(axis=0))
        assert np.allclose(stats[key]["mean"], values.mean(axis=0))
        assert np.allclose(stats[key]["std"], values.std(axis=0))
        assert stats[key]["count"] == [len(values)]
    assert np.asarray(stats[CAMERA]["mean"]).shape == (3, 1, 1)


def test_the_fourth_bag_appends_and_leaves_the_first_three_unchanged(exported: dict[str, Any]) -> None:
    before, after = exported["before"], exported["after"]
    for rel, digest in before.items():
        if rel.startswith(("data/", "videos/", "meta/episodes/")):
            assert after.get(rel) == digest, rel
    new = sorted(set(after) - set(before))
    assert "data/chunk-000/file-001.parquet" in new and f"videos/{CAMERA}/chunk-000/file-003.mp4" in new


def test_a_bag_with_no_joint_states_and_no_camera_is_one_line(tmp_path: Path) -> None:
    bag = write_arm_bag(tmp_path / "empty", joints=False, camera=False)
    done = cli("--bag", bag.path, "--export-lerobot", tmp_path / "ds", "--action", ACTION)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 2 and "Traceback" not in done.stderr  # the error, then the summary
    assert f"{bag.path}: no /joint_states and no camera topic" in done.stderr
    assert not (tmp_path / "ds").exists()  # nothing written, not even the folder
    assert "0 episodes (0 frames) exported, 1 failed in " in done.stderr  # and no "→ ds" to a folder not there
    assert "→" not in done.stderr


def test_a_full_disk_is_one_line_naming_the_file_and_leaves_nothing(tmp_path: Path) -> None:
    bag = write_arm_bag(tmp_path / "b")
    disk = tmp_path / "disk"  # a 32 kB tmpfs: the 2 s episode (its video, parquet and meta files) does not fit
    disk.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=32k", "tmpfs", str(disk)], capture_output=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here (needs root): {mounted.stderr.decode().strip()}")
    try:
        done = cli("--bag", bag.path, "--export-lerobot", disk / "ds", "--action", ACTION)
        left = list(disk.iterdir())
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    first = done.stderr.splitlines()[0]  # the bag's error (it said "unexpected OSError" before), then the summary
    assert first.startswith(f"error: {bag.path}: cannot write {disk / 'ds'}/") and "No space left on device" in first
    assert left == []  # no dataset folder, no work folder


def test_a_missing_action_topic_is_named_and_the_other_bag_goes_in(tmp_path: Path) -> None:
    good = write_arm_bag(tmp_path / "good")
    twist = write_arm_bag(tmp_path / "twist", command="twist")
    done = cli("--bag", good.path, twist.path, "--export-lerobot", tmp_path / "ds", "--action", ACTION, "--jobs", "1")
    assert done.returncode == 2
    assert f"{twist.path}: no topic {ACTION} (--action)" in done.stderr and "Traceback" not in done.stderr
    info = json.loads((tmp_path / "ds/meta/info.json").read_text())
    assert info["total_episodes"] == 1


def _data(root: Path) -> dict[str, np.ndarray]:
    table = pq.read_table(sorted((root / "data").rglob("*.parquet")))  # type: ignore[arg-type]
    out = {}
    for name in table.column_names:
        column = table.column(name).combine_chunks()
        if pa.types.is_fixed_size_list(column.type) or pa.types.is_list(column.type):
            out[name] = column.flatten().to_numpy().reshape(len(column), -1)
        else:
            out[name] = column.to_numpy()
    return out


def _episodes(root: Path) -> dict[str, list[Any]]:
    rows: dict[str, list[Any]] = {}
    for path in sorted((root / "meta/episodes").rglob("*.parquet")):
        for key, values in pq.read_table(path).to_pydict().items():
            rows.setdefault(key, []).extend(values)
    return rows


def test_lerobot_loads_it(exported: dict[str, Any], tmp_path: Path) -> None:
    from run.lerobot_venv import load, require_lerobot

    python = require_lerobot()
    done = load(python, exported["root"], tmp_path / "frames.npz")
    assert done.returncode == 0, done.stderr[-3000:]
    got = np.load(tmp_path / "frames.npz")
    meta = json.loads(str(got["meta"]))
    assert meta["total_episodes"] == meta["num_episodes"] == 4 and meta["camera_keys"] == [CAMERA]
    assert meta["tasks"] == ["wave the arm"]
    for k, bag in enumerate(exported["bags"]):
        want = expected(bag, FPS)
        rows = got["episode_index"] == k
        assert np.array_equal(got["observation.state"][rows], want["state"])
        assert np.array_equal(got["action"][rows], want["action"])
        frames = got[CAMERA][rows]
        worst = min(psnr_luma(f, w) for f, w in zip(frames, want["images"], strict=True))
        assert worst >= 35.0, worst
    assert set(got["task"].tolist()) == {"wave the arm"}


@pytest.mark.parametrize("stop", ["SIGINT", "SIGHUP"])  # Ctrl-C; a dropped ssh session (SIGTERM: the same handler)
def test_ctrl_c_appends_nothing_and_leaves_no_work_folder(tmp_path: Path, stop: str) -> None:
    import signal
    import time

    bag = write_arm_bag(tmp_path / "long", seconds=30.0)  # stopped at once (6 s: done first in CI)
    root = tmp_path / "ds"
    command = [sys.executable, "-c", "from r2d2_viz.cli import main; raise SystemExit(main())"]
    proc = subprocess.Popen([*command, "--bag", str(bag.path), "--export-lerobot", str(root)], stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while not list(root.glob(".r2d2-viz-export-*")) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    proc.send_signal(getattr(signal, stop))  # a hangup killed it before: its work folder was left in DIR
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err.decode()
    assert "interrupted; nothing appended" in err.decode() and b"Traceback" not in err
    assert not root.exists()


def test_a_terminal_shows_a_bar_of_bags(exported: dict[str, Any], tmp_path: Path) -> None:
    from terminal import on_a_terminal

    code, shown = on_a_terminal("--bag", str(exported["bags"][0].path), "--export-lerobot", str(tmp_path / "ds"))
    assert code == 0, shown
    assert "exporting" in shown and "0/1 bags" in shown  # the bar (rich, on stderr), drawn at the start
    assert "1 episode (" in shown


def test_ray_tasks_give_the_same_episodes(exported: dict[str, Any], tmp_path: Path) -> None:
    bags = exported["bags"][1:3]
    done = cli("--bag", *(b.path for b in bags), "--export-lerobot", tmp_path / "ds", "--action", ACTION,
               "--task", "wave the arm", "--ray", "--jobs", "2")  # fmt: skip
    assert done.returncode == 0, done.stderr
    ray, local = _data(tmp_path / "ds"), _data(exported["root"])
    for k in (0, 1):
        mine, theirs = ray["episode_index"] == k, local["episode_index"] == k + 1
        assert np.array_equal(ray["observation.state"][mine], local["observation.state"][theirs])
        assert np.array_equal(ray["action"][mine], local["action"][theirs])
