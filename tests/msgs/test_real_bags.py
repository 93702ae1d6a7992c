"""Real ROS 2 bags (recorded by robots and simulators, found in public repositories) through ``decode``.

Every message of every topic whose type has a decoder is decoded; none may raise. Each result is checked against
values this file computes itself from the bag: the message as ``rosbags``' own CDR deserializer reads it, and
plain numpy (RViz's rules written out here), never from ``r2d2_viz``. The bags are read with
``rosbags.highlevel.AnyReader``, not with the app's reader. What each bag holds and where it came from is in
``tests/data/bags/real/<bag>/README.md``; a bag whose files are not in this checkout (they may live in
``../shared/bags/real/<bag>/`` instead) is skipped, and says so.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.msgs.registry import DECODERS, decode
from r2d2_viz.msgs.shapes import Arrows, Decoded, GridMap, LineStrips, MarkerOp, Points

REPO = Path(__file__).resolve().parents[2]
PLACES = (REPO / "tests" / "data" / "bags" / "real", REPO.parent / "shared" / "bags" / "real")
TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)

# Per bag: topic -> (type, message count). Types and counts are those `ros2 bag record` wrote into the bag's own
# metadata.yaml (copied unchanged from the source repository; see each README).
BAGS: dict[str, dict[str, tuple[str, int]]] = {
    "lightware_sf45b": {"/points": ("sensor_msgs/msg/PointCloud2", 18)},
    "webots_epuck": {
        "/scan": ("sensor_msgs/msg/LaserScan", 3120),
        "/odom": ("nav_msgs/msg/Odometry", 780),
        "/tof": ("sensor_msgs/msg/Range", 809),
        **{f"/ps{i}": ("sensor_msgs/msg/Range", 809) for i in range(8)},
        "/tf": ("tf2_msgs/msg/TFMessage", 1028),
        "/tf_static": ("tf2_msgs/msg/TFMessage", 9),
        "/joint_states": ("sensor_msgs/msg/JointState", 792),
        "/robot_description": ("std_msgs/msg/String", 2),
    },
    "cdrr_rehab": {
        "/mes_marker": ("visualization_msgs/msg/Marker", 1561),
        "/ref_marker": ("visualization_msgs/msg/Marker", 1561),
    },
}

# Topics where r2d2_viz and RViz disagree, kept as strict xfails (they pass once the decoder is fixed).
KNOWN_BUGS: dict[tuple[str, str], str] = {}

# Hand-read from the first message of a topic (`ros2 bag` era metadata has no frames): frame id and a size.
FIRST: dict[tuple[str, str], dict[str, Any]] = {
    # LightWare SF45/B driver: 1500 readings per cloud, frame parameter `laser_sensor_frame` (README of the bag).
    ("lightware_sf45b", "/points"): {"frame_id": "laser_sensor_frame", "width": 1500, "height": 1},
    # Webots e-puck (webots_ros2_epuck driver): the frames its scanner, odometry and ToF sensor publish in.
    ("webots_epuck", "/scan"): {"frame_id": "laser_scanner"},
    ("webots_epuck", "/odom"): {"frame_id": "odom"},
    ("webots_epuck", "/tof"): {"frame_id": "tof"},
    # cdrr_bayes_ros: the measured / reference positions as SPHERE markers in `world`.
    ("cdrr_rehab", "/mes_marker"): {"frame_id": "world"},
    ("cdrr_rehab", "/ref_marker"): {"frame_id": "world"},
}


def bag_dir(name: str) -> Path:
    for place in PLACES:
        if (place / name / "metadata.yaml").is_file():
            return place / name
    pytest.skip(
        f"the third-party bag {name} is not in this clone: put its files in tests/data/bags/real/{name}/ "
        "(tests/data/bags/real/README.md says where it comes from)"
    )


def messages(name: str, topic: str) -> list[tuple[bytes, Any]]:
    """Every message of ``topic``: its raw CDR bytes and rosbags' own deserialisation of them."""
    with AnyReader([bag_dir(name)], default_typestore=TYPESTORE) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        return [(bytes(raw), reader.deserialize(raw, c.msgtype)) for c, _, raw in reader.messages(connections=conns)]


def frame(msg: Any) -> str:
    return str(msg.header.frame_id).lstrip("/")


def stamp_ns(msg: Any) -> int:
    return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)


def check_header(out: Decoded, msg: Any) -> None:
    assert (out.frame_id, out.stamp_ns) == (frame(msg), stamp_ns(msg))


def only(out: Decoded, kind: type) -> Any:
    items = [i for i in out.items if isinstance(i, kind)]
    assert len(items) == 1, out.items
    return items[0]


# --- expected values, from the deserialised message and numpy ----------------------------------------------------


def scan_points(msg: Any) -> np.ndarray:
    """Beam i at ``angle_min + i * angle_increment``, kept when finite and range_min <= r <= range_max, z = 0."""
    r = np.asarray(msg.ranges, dtype=np.float64)
    a = float(msg.angle_min) + np.arange(r.size) * float(msg.angle_increment)
    with np.errstate(invalid="ignore"):
        keep = np.isfinite(r) & (r >= float(msg.range_min)) & (r <= float(msg.range_max))
    return np.stack([r[keep] * np.cos(a[keep]), r[keep] * np.sin(a[keep]), np.zeros(int(keep.sum()))], axis=1)


FIELD_DTYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def cloud_xyz(msg: Any) -> np.ndarray:
    """x, y, z of every point, read from ``data`` at the PointFields' offsets (row_step and point_step honoured)."""
    fields = {f.name: f for f in msg.fields}
    n_rows, n_cols, step = int(msg.height), int(msg.width), int(msg.point_step)
    raw = np.frombuffer(bytes(msg.data), dtype=np.uint8)
    rows = raw[: n_rows * int(msg.row_step)].reshape(n_rows, int(msg.row_step))[:, : n_cols * step]
    points = rows.reshape(n_rows * n_cols, step)
    out = np.empty((n_rows * n_cols, 3), dtype=np.float64)
    for k, axis in enumerate("xyz"):
        f = fields[axis]
        dtype = np.dtype((">" if msg.is_bigendian else "<") + FIELD_DTYPES[f.datatype])
        out[:, k] = np.ascontiguousarray(points[:, f.offset : f.offset + dtype.itemsize]).view(dtype)[:, 0]
    return out


MARKER_ACTIONS = {
    0: "add",
    2: "delete",
    3: "deleteall",
}  # visualization_msgs/Marker: ADD=MODIFY=0, DELETE=2, DELETEALL=3


def position(pose: Any) -> tuple[float, float, float]:
    return (float(pose.position.x), float(pose.position.y), float(pose.position.z))


# --- one check per type: decoded output vs the expected values ---------------------------------------------------


def check_laserscan(out: Any, msg: Any) -> None:
    check_header(out, msg)
    pts = only(out, Points).positions
    want = scan_points(msg)
    assert pts.shape == want.shape
    if len(want):
        np.testing.assert_allclose(pts[0], want[0], rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(pts, want, rtol=1e-5, atol=1e-5)


def check_range(out: Any, msg: Any) -> None:
    """RViz's RangeDisplay: the cone is ``range`` long when min_range <= range <= max_range; a fixed-distance
    ranger (min == max) reading -inf shows min_range; anything else shows a 0-length cone (nothing). The cone is
    ``2 * length * tan(fov / 2)`` wide at its base."""
    check_header(out, msg)
    r, lo, hi, fov = float(msg.range), float(msg.min_range), float(msg.max_range), float(msg.field_of_view)
    shown = r if lo <= r <= hi else (lo if lo == hi and r == -np.inf else 0.0)
    strips = only(out, LineStrips).strips
    if shown <= 0:
        assert strips == ()
        return
    pts = np.concatenate(strips)
    assert pts[:, 0].max() == pytest.approx(shown, rel=1e-5)
    assert np.hypot(pts[:, 1], pts[:, 2]).max() == pytest.approx(shown * np.tan(fov / 2), rel=1e-5)


def check_pointcloud2(out: Any, msg: Any) -> None:
    check_header(out, msg)
    pts = only(out, Points).positions
    xyz = cloud_xyz(msg)
    want = xyz[np.isfinite(xyz).all(axis=1)]
    assert pts.shape == want.shape
    if len(want):
        np.testing.assert_allclose(pts[0], want[0], rtol=1e-6)
        np.testing.assert_allclose(pts, want.astype(np.float32), rtol=1e-6)


def check_markers(ops: Any, markers: list[Any]) -> None:
    assert isinstance(ops, list) and all(isinstance(op, MarkerOp) for op in ops)
    assert [(op.ns, op.id, op.action) for op in ops] == [
        (str(m.ns), int(m.id), MARKER_ACTIONS[int(m.action)]) for m in markers
    ]
    for op, m in zip(ops, markers, strict=True):
        if op.action == "add":
            assert op.decoded is not None
            assert op.decoded.frame_id == frame(m)


def check_marker(out: Any, msg: Any) -> None:
    check_markers(out, [msg])


def check_marker_array(out: Any, msg: Any) -> None:
    check_markers(out, list(msg.markers))


def check_occupancy_grid(out: Any, msg: Any) -> None:
    check_header(out, msg)
    grid = only(out, GridMap)
    info = msg.info
    assert grid.rgba.shape[:2] == (int(info.height), int(info.width))
    assert grid.resolution == pytest.approx(float(info.resolution))
    assert grid.T_frame_item.translation == pytest.approx(position(info.origin))


def check_path(out: Any, msg: Any) -> None:
    check_header(out, msg)
    strips = only(out, LineStrips).strips
    want = np.array([position(p.pose) for p in msg.poses]).reshape(-1, 3)
    if len(want) > 1:  # RViz draws no line through fewer than two poses
        assert len(strips) == 1 and strips[0].shape == want.shape
        np.testing.assert_allclose(strips[0], want, rtol=1e-6, atol=1e-6)


def check_pose_like(pose: Any) -> Callable[[Any, Any], None]:
    """A display drawn as arrows from the pose positions (PoseStamped, Odometry, PoseArray, ...)."""

    def check(out: Any, msg: Any) -> None:
        check_header(out, msg)
        poses = pose(msg)
        arrows = next(i for i in out.items if isinstance(i, Arrows))
        want = np.array([position(p) for p in poses]).reshape(-1, 3)
        assert arrows.origins.shape == want.shape
        np.testing.assert_allclose(arrows.origins, want, rtol=1e-6, atol=1e-6)

    return check


CHECKS: dict[str, Callable[[Any, Any], None]] = {
    "sensor_msgs/msg/LaserScan": check_laserscan,
    "sensor_msgs/msg/PointCloud2": check_pointcloud2,
    "sensor_msgs/msg/Range": check_range,
    "visualization_msgs/msg/Marker": check_marker,
    "visualization_msgs/msg/MarkerArray": check_marker_array,
    "nav_msgs/msg/OccupancyGrid": check_occupancy_grid,
    "nav_msgs/msg/Path": check_path,
    "nav_msgs/msg/Odometry": check_pose_like(lambda m: [m.pose.pose]),
    "geometry_msgs/msg/PoseStamped": check_pose_like(lambda m: [m.pose]),
    "geometry_msgs/msg/PoseWithCovarianceStamped": check_pose_like(lambda m: [m.pose.pose]),
    "geometry_msgs/msg/PoseArray": check_pose_like(lambda m: list(m.poses)),
}

CASES = [
    pytest.param(
        bag,
        topic,
        typename,
        count,
        id=f"{bag}{topic}",
        marks=[pytest.mark.xfail(strict=True, raises=AssertionError, reason=KNOWN_BUGS[bag, topic])]
        if (bag, topic) in KNOWN_BUGS
        else [],
    )
    for bag, topics in BAGS.items()
    for topic, (typename, count) in topics.items()
    if typename in DECODERS
]


@pytest.mark.parametrize("bag", sorted(BAGS))
def test_bag_topics_are_as_its_metadata_says(bag: str) -> None:
    with AnyReader([bag_dir(bag)], default_typestore=TYPESTORE) as reader:
        found = {c.topic: (c.msgtype, c.msgcount) for c in reader.connections}
    assert {t: found.get(t) for t in BAGS[bag]} == BAGS[bag]


@pytest.mark.parametrize(("bag", "topic", "typename", "count"), CASES)
def test_every_message_decodes_to_what_the_message_says(bag: str, topic: str, typename: str, count: int) -> None:
    msgs = messages(bag, topic)
    assert len(msgs) == count
    first = FIRST.get((bag, topic), {})
    if "frame_id" in first:
        assert frame(msgs[0][1]) == first["frame_id"]
    for key in ("width", "height"):
        if key in first:
            assert int(getattr(msgs[0][1], key)) == first[key]
    check = CHECKS.get(typename)
    for raw, msg in msgs:
        out = decode(typename, raw)  # must not raise
        if check is not None:
            check(out, msg)


def test_a_missing_bag_is_skipped_in_words_a_clone_understands() -> None:
    # a user's clone has no ../shared folder (issue 29): the reason names where the bag goes and where it comes from
    with pytest.raises(pytest.skip.Exception) as info:
        bag_dir("no_such_bag")
    reason = str(info.value)
    assert "shared" not in reason and "tests/data/bags/real/no_such_bag/" in reason and "README.md" in reason
