"""Other topics of a bag through Rerun's MCAP decoders: on their topic's entity, on our timeline at the bag's
receive times, and a list of what Rerun cannot show. The bag is written by rosbags; the .rrd read back by
Rerun's own reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from bagmaker import T0, TS, TYPES, BagSpec, joint_state, storage_file, string, write_bag
from conftest import REPO, cli
from rerun.chunk import RrdReader

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.viewer.bag_topics import log_other_topics

T = TS.types


def _read(path: Path) -> dict[str, dict[str, list[tuple[int, object]]]]:
    """Entity → component → [(time ns, value)] of the temporal rows on our ``time`` timeline."""
    reader = RrdReader(path)
    out: dict[str, dict[str, list[tuple[int, object]]]] = {}
    for chunk in reader.stream(store=reader.recordings()[0]):
        batch = chunk.to_record_batch()
        if chunk.is_static or "time" not in batch.schema.names:
            continue
        rows = out.setdefault(chunk.entity_path, {})
        times = batch.column("time").cast("int64").to_pylist()
        for name, column in zip(batch.schema.names, batch.columns, strict=True):
            if ":" in name:
                rows.setdefault(name, []).extend(zip(times, column.to_pylist(), strict=True))
    return out


def _header(t: int, frame: str):
    return T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(t, 10**9)), frame)


def _cloud(t: int, points: np.ndarray) -> bytes:
    fields = [T["sensor_msgs/msg/PointField"](n, 4 * i, 7, 1) for i, n in enumerate("xyz")]  # 7: FLOAT32
    data = np.frombuffer(points.astype("<f4").tobytes(), np.uint8)
    msg = T["sensor_msgs/msg/PointCloud2"](
        _header(t, "lidar"), 1, len(points), fields, False, 12, 12 * len(points), data, True
    )
    return bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/PointCloud2"))


def _image(t: int) -> bytes:
    msg = T["sensor_msgs/msg/Image"](_header(t, "camera"), 2, 3, "rgb8", 0, 9, np.arange(18, dtype=np.uint8))
    return bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/Image"))


def _scan(t: int) -> bytes:
    ranges = np.array([1, 2, 3], np.float32)
    msg = T["sensor_msgs/msg/LaserScan"](
        _header(t, "laser"), -1.0, 1.0, 1.0, 0.0, 0.1, 0.1, 10.0, ranges, np.zeros(0, np.float32)
    )
    return bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/LaserScan"))


def test_point_clouds_and_images_land_on_their_topics(tmp_path: Path) -> None:
    types = {
        "/points": "sensor_msgs/msg/PointCloud2",
        "/camera/image_raw": "sensor_msgs/msg/Image",
        "/scan": "sensor_msgs/msg/LaserScan",
        "/joint_states": "sensor_msgs/msg/JointState",
    }
    spec = BagSpec(types=types)
    clouds = [np.arange(12, dtype=float).reshape(4, 3) + k for k in range(3)]
    for k in range(3):
        t = T0 + k * 10**8
        spec.add("/points", t + 1, _cloud(t, clouds[k]))
        spec.add("/camera/image_raw", t + 2, _image(t))
        spec.add("/scan", t + 3, _scan(t))
        spec.add("/joint_states", t + 4, joint_state(t, ["a"], [k]))
    mcap = storage_file(write_bag(tmp_path / "bag", spec))

    out = tmp_path / "out.rrd"
    rec = rr.RecordingStream("test_bag_topics")
    rec.save(out)
    result = log_other_topics(rec, [mcap])
    rec.flush()
    rec.disconnect()

    assert result.logged == ("/camera/image_raw", "/points")
    assert result.skipped == (("/scan", "sensor_msgs/msg/LaserScan"),)  # Rerun 0.41 has no LaserScan decoder
    assert "/scan (sensor_msgs/msg/LaserScan)" in result.summary()
    recording = _read(out)
    assert "/joint_states" not in recording and "/joint_states/position" not in recording  # ours, not Rerun's
    assert "/scan" not in recording
    points = recording["/points"]
    positions = sorted(points["Points3D:positions"])
    assert [t for t, _ in positions] == [T0 + k * 10**8 + 1 for k in range(3)]  # receive times, our timeline
    for k in range(3):
        np.testing.assert_allclose(np.array(positions[k][1]), clouds[k])
    assert points["CoordinateFrame:frame"][0][1] == ["lidar"]
    assert not any(name.startswith("sensor_msgs") for name in points)  # no raw copies of the message
    image = recording["/camera/image_raw"]
    assert sorted(t for t, _ in image["Image:buffer"]) == [T0 + k * 10**8 + 2 for k in range(3)]
    assert image["CoordinateFrame:frame"][0][1] == ["camera_image_plane"]  # Rerun: in the pinhole of frame "camera"
    assert list(image["Image:buffer"][0][1][0]) == list(range(18))


def _warnings(stderr: str) -> list[str]:
    lines = [line for line in stderr.strip().splitlines() if not line.startswith("r2d2-viz: ")]  # the summary
    assert not [line for line in lines if not line.startswith("warning: ")], stderr  # no error, no traceback
    assert all(len(line) <= 300 for line in lines)
    return lines


@pytest.mark.slow
def test_a_cut_recording_with_a_topic_without_display_replays_what_it_holds(
    tmp_path: Path, tutorial_urdf: Path
) -> None:
    """A recorder killed mid-way (a rosbags bag cut at 60 %: no summary, no footer): exit 0, one warning (ours: the
    file breaks off), and the String topic's recovered messages in the recording."""
    spec = BagSpec(types={**TYPES, "/chatter": "std_msgs/msg/String"})
    for k in range(400):  # 10 kB strings: rosbags closes a chunk past 1 MiB, so the cut leaves whole chunks
        t = T0 + k * 10**7
        spec.add("/joint_states", t, joint_state(t, ["tilt"], [-k * 1e-3]))
        spec.add("/chatter", t + 1, string(f"{k} " + "x" * 10_000))
    data = storage_file(write_bag(tmp_path / "bag", spec)).read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.6)])
    with open_bag(cut, warn=lambda _: None) as bag:
        chatter = [t for t, _ in bag.raw("/chatter")]
    assert 0 < len(chatter) < 400

    out = tmp_path / "out.rrd"
    run = cli("--bag", str(cut), "--urdf", str(tutorial_urdf), "--save", str(out))
    assert run.returncode == 0, run.stderr
    assert _warnings(run.stderr) == [
        f"warning: {cut}: the file breaks off (no footer, no index): recovered {2 * len(chatter)} messages"
    ]
    shown = _read(out)["/chatter"]["TextLog:text"]  # (a String is a log line of ours)
    assert sorted({t for t, _ in shown}) == chatter


@pytest.mark.slow
def test_a_file_rerun_cannot_read_is_one_warning(tmp_path: Path) -> None:
    """The spec's unchunked variant without a summary: ours reads it, Rerun's reader refuses it (it recovers only
    chunked files). Exit 0; one line names the file and says its undisplayed topic was not shown, and why."""
    mcap = REPO / "tests" / "data" / "mcap_conformance" / "TenMessages" / "TenMessages.mcap"
    rec = rr.RecordingStream("test_bag_topics")
    rec.save(tmp_path / "direct.rrd")
    result = log_other_topics(rec, [mcap])
    rec.disconnect()
    assert result.logged == () and [f for f, _ in result.failed] == [mcap]

    run = cli("--bag", str(mcap), "--save", str(tmp_path / "out.rrd"))
    assert run.returncode == 0, run.stderr
    (line,) = [line for line in _warnings(run.stderr) if "example" in line]
    assert line.startswith(f"warning: {mcap}: 1 topic with no display, not shown: /example (Example)")
    assert "Rerun's MCAP reader cannot read TenMessages.mcap" in line
