"""A real ROS 2 node (rclpy, run by the cached venv's Python) for ``benchmarks/live_app.py``: sensor streams.

``--joints N --joint-rate HZ``: ``/joint_states`` (the URDF's movable joints, or ``joint_<i>``); ``--image-rate
HZ``: ``/camera/image_raw`` (640x480 rgb8); ``--cloud-rate HZ``: ``/points`` (``--cloud-points`` points, x y z
rgb float32; ``--cloud-fields xyz``: x y z only, 12 bytes a point); ``--compressed-rate HZ``:
``/camera/image_raw/compressed`` (a real 640x480 JPEG, made once with Pillow when the venv has it, else the JPEG
file ``--jpeg``); ``--scan-rate HZ``: ``/scan`` (LaserScan, 720 ranges). A rate of 0 leaves a stream out. Each
message differs from the last (a counter in its first bytes); ``--digests PATH``: one line per message published,
``topic sec nanosec sha256`` of its payload (``data``; a scan's ranges then intensities as float32). Not of
its CDR: rclpy's ``serialize_message`` leaves the alignment padding between fields uninitialised (seen here: a
different digest for the same message each call).. Waits for a reader of every stream (up to ``--wait`` s), then
publishes each on an absolute schedule for ``--seconds``, header stamps = the node's clock; lingers ``--linger`` s.
Prints one JSON line: the messages published per topic and the seconds the streams took.
"""

from __future__ import annotations

import argparse
import array
import hashlib
import io
import json
import sys
import time
import xml.etree.ElementTree as ET
from typing import Any


def joint_names(urdf: str, joints: int) -> list[str]:
    """The URDF's movable joints, padded with ``joint_<i>`` (or cut) to ``joints``."""
    names = [j.get("name", "") for j in ET.fromstring(urdf).iter("joint") if j.get("type") != "fixed"]
    return (names + [f"joint_{i}" for i in range(len(names), joints)])[:joints]


def payload(msg: Any) -> bytes:
    """What the digest covers: ``data``, or a LaserScan's ranges then intensities as little-endian float32."""
    import numpy as np

    if hasattr(msg, "ranges"):
        return np.asarray(msg.ranges, "<f4").tobytes() + np.asarray(msg.intensities, "<f4").tobytes()
    return bytes(msg.data)


def make_jpeg() -> bytes:
    """A real 640x480 JPEG of a gradient, made by Pillow (quality 80)."""
    import numpy as np
    from PIL import Image as PILImage

    yy, xx = np.indices((480, 640))
    rgb = np.stack([xx % 256, yy % 256, (xx + yy) % 256], axis=2).astype(np.uint8)
    out = io.BytesIO()
    PILImage.fromarray(rgb).save(out, format="JPEG", quality=80)
    return out.getvalue()


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--urdf", default="")
    parser.add_argument("--joints", type=int, default=30)
    parser.add_argument("--joint-rate", type=float, default=0.0)
    parser.add_argument("--image-rate", type=float, default=0.0)
    parser.add_argument("--cloud-rate", type=float, default=0.0)
    parser.add_argument("--cloud-points", type=int, default=50_000)
    parser.add_argument("--cloud-fields", default="xyzrgb", choices=["xyzrgb", "xyz"])
    parser.add_argument("--compressed-rate", type=float, default=0.0)
    parser.add_argument("--jpeg", default="")
    parser.add_argument("--scan-rate", type=float, default=0.0)
    parser.add_argument("--digests", default="")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--wait", type=float, default=30.0)
    parser.add_argument("--linger", type=float, default=1.0)
    args = parser.parse_args()

    import numpy as np
    import rclpy
    from sensor_msgs.msg import CompressedImage, Image, JointState, LaserScan, PointCloud2, PointField

    rclpy.init()
    node = rclpy.create_node("r2d2_viz_bench_sensors")
    streams: list[tuple[str, Any, Any, float]] = []  # topic, publisher, message, rate
    if args.joint_rate > 0:
        urdf = open(args.urdf, encoding="utf-8").read() if args.urdf else "<robot name='r'/>"
        js = JointState()
        js.name = joint_names(urdf, args.joints)
        js.position = [0.0] * args.joints
        js.header.frame_id = "base"
        streams.append(("/joint_states", node.create_publisher(JointState, "/joint_states", 10), js, args.joint_rate))
    if args.image_rate > 0:
        img = Image()
        img.height, img.width, img.encoding, img.step = 480, 640, "rgb8", 640 * 3
        img.header.frame_id = "camera"
        pattern = np.indices((480, 640)).sum(axis=0) % 256
        img.data = np.repeat(pattern.astype(np.uint8)[:, :, None], 3, axis=2).tobytes()
        streams.append(
            ("/camera/image_raw", node.create_publisher(Image, "/camera/image_raw", 10), img, args.image_rate)
        )
    if args.cloud_rate > 0:
        n, names = args.cloud_points, ("x", "y", "z", "rgb")[: 4 if args.cloud_fields == "xyzrgb" else 3]
        cloud = PointCloud2()
        cloud.header.frame_id = "base"
        step = 4 * len(names)
        cloud.height, cloud.width, cloud.point_step, cloud.row_step = 1, n, step, step * n
        cloud.fields = [PointField(name=c, offset=4 * i, datatype=PointField.FLOAT32, count=1) for i, c in
                        enumerate(names)]  # fmt: skip
        cloud.is_dense = True
        rng = np.random.default_rng(0)
        points = rng.uniform(-2, 2, (n, 4)).astype(np.float32)
        points[:, 3] = np.frombuffer(rng.integers(0, 1 << 24, n, dtype=np.uint32).tobytes(), dtype=np.float32)
        cloud.data = np.ascontiguousarray(points[:, : len(names)]).tobytes()
        streams.append(("/points", node.create_publisher(PointCloud2, "/points", 10), cloud, args.cloud_rate))
    if args.compressed_rate > 0:
        jpeg = CompressedImage()
        jpeg.header.frame_id, jpeg.format = "camera", "jpeg"
        jpeg.data = make_jpeg() if not args.jpeg else open(args.jpeg, "rb").read()
        topic = "/camera/image_raw/compressed"
        streams.append((topic, node.create_publisher(CompressedImage, topic, 10), jpeg, args.compressed_rate))
    if args.scan_rate > 0:
        scan = LaserScan()
        scan.header.frame_id = "laser"
        scan.angle_min, scan.angle_max, scan.angle_increment = -3.1241390705108643, 3.1415927410125732, 0.00872664619
        scan.range_min, scan.range_max, scan.scan_time = 0.1, 30.0, 1.0 / args.scan_rate
        angles = np.arange(720) * scan.angle_increment
        scan.ranges = (2.0 + np.sin(3 * angles)).astype(np.float32).tolist()
        scan.intensities = np.linspace(0, 100, 720, dtype=np.float32).tolist()
        streams.append(("/scan", node.create_publisher(LaserScan, "/scan", 10), scan, args.scan_rate))
    digests = open(args.digests, "w", encoding="utf-8") if args.digests else None
    deadline = time.monotonic() + args.wait
    while any(p.get_subscription_count() < 1 for _, p, _, _ in streams) and time.monotonic() < deadline:
        time.sleep(0.01)
    matched = all(p.get_subscription_count() >= 1 for _, p, _, _ in streams)
    time.sleep(0.2)  # the reader's side of the match settles too
    counts = [max(1, round(args.seconds * rate)) for _, _, _, rate in streams]
    sent = [0] * len(streams)
    start = time.perf_counter()
    while True:
        due = [(start + k / streams[i][3], i) for i, k in enumerate(sent) if k < counts[i]]
        if not due:
            break
        when, i = min(due)
        delay = when - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        topic, publisher, msg, _ = streams[i]
        now = time.time_ns()
        msg.header.stamp.sec, msg.header.stamp.nanosec = now // 1_000_000_000, now % 1_000_000_000
        if topic == "/joint_states":
            msg.position = [0.001 * sent[i] + j for j in range(args.joints)]
        elif topic == "/scan":
            msg.ranges[0] = float(sent[i])
        elif topic.endswith("/compressed"):
            pass  # a JPEG must stay a JPEG: the stamp alone tells them apart
        else:  # Image, PointCloud2: the counter in the first 4 bytes of the data
            msg.data[0:4] = array.array("B", sent[i].to_bytes(4, "little"))
        publisher.publish(msg)
        if digests is not None:
            stamp = msg.header.stamp
            digests.write(f"{topic} {stamp.sec} {stamp.nanosec} {hashlib.sha256(payload(msg)).hexdigest()}\n")
        sent[i] += 1
    elapsed = time.perf_counter() - start
    if digests is not None:
        digests.close()
    report = {"sent": {s[0]: n for s, n in zip(streams, sent, strict=True)}, "matched": matched, "seconds": elapsed}
    print(json.dumps(report), flush=True)
    time.sleep(args.linger)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
