"""Live camera and lidar from a real ROS 2 node: ``r2d2-viz --ros --save out.mcap`` receives what was published,
byte for byte.

A real Kilted rclpy node (PyPI's ``ros-rclpy`` + ``ros-sensor-msgs``, ``tests/sources/live/nodes/
publish_sensors.py``), started before the app in a loopback-only network namespace, publishes for 4 s:
``/camera/image_raw`` (Image 640x480 rgb8, 30 Hz), ``/camera/image_raw/compressed`` (CompressedImage: a real
JPEG Pillow wrote here, 30 Hz), ``/points`` (PointCloud2, 100,000 points x y z float32 = 1.2 MB, 10 Hz) and
``/scan`` (LaserScan, 720 ranges, 20 Hz); each message differs from the last. For every message it writes the
sha256 of its payload as rclpy holds it (``data``; a scan's ranges and intensities) — golden values from the
publisher, not from r2d2-viz. The recording is read back with rosbags: each payload must hash the same, the
other fields equal what the node set, and the bytes recorded must be the canonical CDR of the message (rosbags'
serializer, padding zeroed) — so nothing was altered on the way. Not compared with rclpy's own CDR: its
``serialize_message`` leaves the padding between fields uninitialised.
"""

from __future__ import annotations

import hashlib
import io
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image
from rosbags.rosbag2 import Reader
from sources.live import ros_node

from r2d2_viz.msgs.typestore import typestore

pytestmark = pytest.mark.slow

SECONDS = 4
RATES = {"/camera/image_raw": 30, "/camera/image_raw/compressed": 30, "/points": 10, "/scan": 20}
MIN_SHARE = 0.9
"""The share of each topic that must arrive. The app reads volatile topics best-effort (as the publishers'
sensor-data QoS needs), so a sample one UDP fragment of which is lost is lost. With the 8 MB receive buffer the
app asks of the kernel, every message arrived here in each of 6 runs (load 2 to 9 on 2 cores; two of them with
both cores busy-looped beside it); with Cyclone's default (the kernel's 208 KiB) 22 and 34 of 40 clouds did
(and 71/80 scans, 110/120 JPEGs in the first: those sent beside a cloud). 90 % fails on that regression and
leaves room for a slow machine: no timing is asserted."""


def _jpeg(path: Path) -> bytes:
    yy, xx = np.indices((480, 640))
    rgb = np.stack([xx % 256, yy % 256, (xx + yy) % 256], axis=2).astype(np.uint8)
    out = io.BytesIO()
    Image.fromarray(rgb).save(out, format="JPEG", quality=80)
    path.write_bytes(out.getvalue())
    return out.getvalue()


def _payload(msg: Any) -> bytes:
    """The node's digest input (``publish_sensors.payload``): ``data``, or ranges + intensities as <f4."""
    if hasattr(msg, "ranges"):
        return np.asarray(msg.ranges, "<f4").tobytes() + np.asarray(msg.intensities, "<f4").tobytes()
    return bytes(msg.data)


def _check_fields(topic: str, msg: Any, jpeg: bytes) -> None:
    """The fields besides the payload, as the node set them."""
    if topic == "/camera/image_raw":
        assert (msg.header.frame_id, msg.height, msg.width, msg.encoding, msg.step) == (
            "camera",
            480,
            640,
            "rgb8",
            1920,
        )
        assert len(msg.data) == 480 * 640 * 3
    elif topic.endswith("/compressed"):
        assert (msg.header.frame_id, msg.format, bytes(msg.data)) == ("camera", "jpeg", jpeg)
        assert Image.open(io.BytesIO(bytes(msg.data))).size == (640, 480)
    elif topic == "/points":
        assert (msg.header.frame_id, msg.height, msg.width, msg.point_step, msg.row_step) == (
            "base",
            1,
            100_000,
            12,
            1_200_000,
        )
        assert [(f.name, f.offset, f.datatype, f.count) for f in msg.fields] == [
            ("x", 0, 7, 1),
            ("y", 4, 7, 1),
            ("z", 8, 7, 1),
        ]
        assert len(msg.data) == 1_200_000 and msg.is_dense
    else:
        assert (msg.header.frame_id, len(msg.ranges), len(msg.intensities)) == ("laser", 720, 720)


def test_live_camera_and_lidar_arrive_byte_identical(tmp_path: Path) -> None:
    python = ros_node.require_live("kilted")
    jpeg, digests, bag = _jpeg(tmp_path / "cam.jpg"), tmp_path / "digests.txt", tmp_path / "out.mcap"
    node = ["--image-rate", "30", "--compressed-rate", "30", "--jpeg", str(tmp_path / "cam.jpg"),
            "--cloud-rate", "10", "--cloud-points", "100000", "--cloud-fields", "xyz", "--scan-rate", "20",
            "--seconds", str(SECONDS), "--digests", str(digests)]  # fmt: skip
    command = [
        sys.executable,
        str(Path(ros_node.__file__).with_name("sensors_scenario.py")),
        "--ros-python",
        str(python),
        "--cli",
        str(Path(sys.executable).parent / "r2d2-viz"),
        "--node",
        json.dumps(node),
        "--app",
        json.dumps(["--save", str(bag), "--duration", "120"]),
    ]
    done = ros_node.in_netns(command, timeout=240)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["rc"] == 0, result["stderr"]
    assert result["node"]["sent"] == {t: SECONDS * r for t, r in RATES.items()}, result["node"]

    published: dict[tuple[str, int, int], str] = {}
    for line in digests.read_text().splitlines():
        topic, sec, nanosec, sha = line.split()
        published[(topic, int(sec), int(nanosec))] = sha
    assert len(published) == sum(SECONDS * r for r in RATES.values())  # every stamp unique

    store = typestore()
    received: dict[str, int] = dict.fromkeys(RATES, 0)
    seen: set[tuple[str, int, int]] = set()
    with Reader(bag) as reader:
        for connection, _, raw in reader.messages():
            msg = store.deserialize_cdr(raw, connection.msgtype)
            key = (connection.topic, msg.header.stamp.sec, msg.header.stamp.nanosec)
            assert key in published and key not in seen, key
            seen.add(key)
            assert hashlib.sha256(_payload(msg)).hexdigest() == published[key], key
            canonical = store.serialize_cdr(msg, connection.msgtype)
            # DDS pads a payload to a multiple of 4 bytes with zeros; the recorded bytes keep them (as ros2 bag does)
            assert raw[: len(canonical)] == canonical and raw[len(canonical) :] == bytes(len(raw) - len(canonical))
            assert len(raw) - len(canonical) < 4, key
            _check_fields(connection.topic, msg, jpeg)
            received[connection.topic] += 1
    said = next(x for x in result["stderr"].splitlines() if x.startswith("r2d2-viz: received "))
    assert said == "r2d2-viz: received " + ", ".join(f"{t} {received[t]}" for t in sorted(received)), said
    for topic, rate in RATES.items():
        assert received[topic] >= MIN_SHARE * SECONDS * rate, (topic, received, result["stderr"])


def test_live_camera_as_video(tmp_path: Path) -> None:
    """``--ros --video``: a real node's 30 Hz camera recorded as AV1 samples as they arrive, a keyframe at least
    every second (live), every sample decodable by PyAV's dav1d (an independent decoder)."""
    import av
    from rrd import read_recording

    python = ros_node.require_live("kilted")
    out, seconds = tmp_path / "out.rrd", 3
    command = [
        sys.executable,
        str(Path(ros_node.__file__).with_name("sensors_scenario.py")),
        "--ros-python",
        str(python),
        "--cli",
        str(Path(sys.executable).parent / "r2d2-viz"),
        "--node",
        json.dumps(["--image-rate", "30", "--seconds", str(seconds)]),
        "--app",
        json.dumps(["--save", str(out), "--video", "--duration", "120"]),
    ]
    done = ros_node.in_netns(command, timeout=240)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["rc"] == 0, result["stderr"]
    camera = read_recording(out)["/camera/image_raw"]
    assert "Image:buffer" not in camera.temporal
    rows = [(t, s, k) for t, s, k in zip(camera.times, camera.temporal["VideoStream:sample"],
            camera.temporal["VideoStream:is_keyframe"], strict=True) if s is not None]  # fmt: skip
    assert len(rows) >= MIN_SHARE * seconds * 30, len(rows)
    keys = [t for t, _, k in rows if k[0]]
    gaps = [b - a for a, b in zip(keys, [*keys[1:], rows[-1][0]], strict=True)]
    assert keys[0] == rows[0][0] and max(gaps) <= 1.1e9, gaps  # 1 s and a frame or two lost
    decoder = av.CodecContext.create("libdav1d", "r")
    frames = sum(len(decoder.decode(av.Packet(bytes(s[0])))) for _, s, _ in rows) + len(decoder.decode(None))
    assert frames == len(rows)
