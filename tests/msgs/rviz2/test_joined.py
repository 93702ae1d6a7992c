"""RViz 2's displays of issue 46 through the real CLI: a bag written by rosbags (tests/rvizdisplaybags.py) replayed
with tests/data/rviz/all_displays.rviz (one display of each of RViz 2's 32 classes), the recording read back with
Rerun's reader. Expected values by hand or with numpy from rosbags' own deserialisation, RViz's formulas as
transcribed in each test (ros2/rviz, rviz_default_plugins)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import REPO, cli, made_once
from msgs_build import TS, rviz_rainbow
from rrd import Rows, blueprint_components, read_recording
from rvizdisplaybags import ACCEL, EFFORTS, IM_TIMES, SCALARS, T0, URDF, write_rviz_displays_bag

CONFIG = REPO / "tests" / "data" / "rviz" / "all_displays.rviz"


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Rows], str, Path]:
    def make(folder: Path) -> None:
        write_rviz_displays_bag(folder / "bag")
        (folder / "arm.urdf").write_text(URDF)
        args = ("--bag", str(folder / "bag"), "--urdf", str(folder / "arm.urdf"), "--rviz", str(CONFIG))
        result = cli(*args, "--save", str(folder / "out.rrd"))
        assert result.returncode == 0, result.stderr
        (folder / "stderr.txt").write_text(result.stderr)

    folder = made_once(tmp_path_factory, "rviz2-displays", make)
    return read_recording(folder / "out.rrd"), (folder / "stderr.txt").read_text(), folder


def _at(rows: Rows, column: str, time_ns: int) -> Any:
    """The value of ``column`` logged at ``time_ns`` (the last such row)."""
    found = [v for t, v in zip(rows.times, rows.temporal[column], strict=True) if t == time_ns and v is not None]
    assert found, f"{column} at {time_ns}"
    return found[-1]


def _rgba(packed: int) -> tuple[int, int, int, int]:
    return ((packed >> 24) & 255, (packed >> 16) & 255, (packed >> 8) & 255, packed & 255)


def _message(folder: Path, topic: str) -> Any:
    """The bag's first message on ``topic``, deserialised by rosbags."""
    from rosbags.highlevel import AnyReader

    with AnyReader([folder / "bag"], default_typestore=TS) as reader:
        connections = [c for c in reader.connections if c.topic == topic]
        for connection, _, raw in reader.messages(connections=connections):
            return reader.deserialize(raw, connection.msgtype)
    raise AssertionError(topic)


def test_no_display_class_is_left_out(run) -> None:
    _, stderr, _ = run
    assert "no counterpart" not in stderr and "cannot be shown" not in stderr, stderr


def test_accel_stamped_draws_its_linear_and_angular_arrows(run) -> None:
    recording, _, _ = run
    # as RViz's Twist/Accel visual: linear (204, 51, 51), angular (204, 204, 51), x 1, in the header frame
    for k, (vector, color) in enumerate(zip(ACCEL, ((204, 51, 51, 255), (204, 204, 51, 255)), strict=True)):
        rows = recording[f"/accel/{k}"]
        assert _at(rows, "Arrows3D:vectors", T0) == [list(vector)]
        assert _rgba(_at(rows, "Arrows3D:colors", T0)[0]) == color
        assert _at(rows, "CoordinateFrame:frame", T0) == ["base_link"]


# RViz's bounds per display (<type>_display.cpp: Min/Max Intensity, Invert Rainbow); the config sets Temperature's
# Size (m) 0.05 (radius 0.025); the others keep r2d2-viz's point radius 0.005 (RViz's 0.01 m Size)
LEVELS = {
    "/temperature": (25.0 - 0.0) / 100.0,  # inverted: 1 - (1 - (v - min) / (max - min))
    "/pressure": 1 - (101325.0 - 98000.0) / 7000.0,
    "/illuminance": 1 - (500.0 - 0.0) / 1000.0,
    "/humidity": 1 - (0.4 - 0.0) / 1.0,
}


@pytest.mark.parametrize("topic", sorted(SCALARS))
def test_scalar_sensors_are_rvizs_coloured_point_and_a_plot(run, topic: str) -> None:
    recording, _, _ = run
    rows = recording[topic]
    assert _at(rows, "Points3D:positions", T0) == [[0.0, 0.0, 0.0]]
    assert _rgba(_at(rows, "Points3D:colors", T0)[0]) == (*rviz_rainbow(LEVELS[topic]), 255)
    assert _at(rows, "Points3D:radii", T0) == pytest.approx([0.025 if topic == "/temperature" else 0.005])
    plot = recording[f"{topic}/{SCALARS[topic][1]}"]  # its own entity: a plot row on the point's cleared its frame
    assert _at(plot, "Scalars:scalars", T0) == pytest.approx([SCALARS[topic][2]])


def test_depth_cloud_is_the_pinhole_projection_coloured_by_the_rgb_image(run) -> None:
    recording, _, folder = run
    depth = _message(folder, "/camera/depth/image_raw")
    info = _message(folder, "/camera/depth/camera_info")
    rgb = _message(folder, "/camera/color/image_raw")
    mm = np.frombuffer(bytes(depth.data), dtype="<u2").reshape(depth.height, depth.width)
    pixels = np.frombuffer(bytes(rgb.data), dtype=np.uint8).reshape(rgb.height, rgb.width, 3)
    fx, fy, cx, cy = info.p[0], info.p[5], info.p[2], info.p[6]  # RViz's MultiLayerDepth reads P
    points, colors = [], []
    for v in range(depth.height):  # by hand: each pixel with a depth (16UC1: mm, 0 none)
        for u in range(depth.width):
            if mm[v, u]:
                d = mm[v, u] / 1000.0
                points.append([(u - cx) * d / fx, (v - cy) * d / fy, d])
                colors.append((*pixels[v, u].tolist(), 255))
    assert len(points) == 9
    rows = recording["/camera/depth/image_raw/depth_cloud/0"]
    at = int(depth.header.stamp.sec) * 1_000_000_000 + int(depth.header.stamp.nanosec)
    np.testing.assert_allclose(_at(rows, "Points3D:positions", at), points, rtol=1e-6)
    assert [_rgba(c) for c in _at(rows, "Points3D:colors", at)] == colors
    assert _at(rows, "CoordinateFrame:frame", at) == ["camera_depth_optical_frame"]


def test_effort_draws_rvizs_arc_at_each_revolute_joint(run) -> None:
    recording, _, _ = run
    arc, head = recording["/joint_states/effort/0/0"], recording["/joint_states/effort/0/1"]
    # shoulder: axis y, limit 10; RViz turns the arc by Quaternion(y × z, angle(y, z)) = 90° about x: (a, b, 0) →
    # (a, 0, b). e = min(|effort| / 10, 1) + 0.05, r = 0.05 + e / 2; a negative effort mirrors x
    for (t, (effort, _)), e in zip(EFFORTS, (0.55, 1.05), strict=True):
        r = 0.05 + e * 0.5
        sign = -1.0 if effort < 0 else 1.0
        expected = [
            [sign * r * math.sin(i * 2 * math.pi / 32), 0.0, r * math.cos(i * 2 * math.pi / 32)] for i in range(30)
        ]
        np.testing.assert_allclose(_at(arc, "LineStrips3D:strips", t)[0], expected, atol=1e-6)
        assert _rgba(_at(arc, "LineStrips3D:colors", t)[0]) == (*rviz_rainbow(e), 255)
        assert _at(arc, "LineStrips3D:radii", t) == pytest.approx([0.01])  # Width 0.02
        np.testing.assert_allclose(_at(head, "Arrows3D:origins", t), [[0.0, 0.0, r]], atol=1e-6)
        np.testing.assert_allclose(_at(head, "Arrows3D:vectors", t), [[-sign * 0.04, 0.0, 0.0]], atol=1e-6)
        assert _at(arc, "CoordinateFrame:frame", t) == ["arm"]  # the joint's child link
    assert not any(e.startswith("/joint_states/effort/1") for e in recording)  # spin: continuous, not drawn


def test_interactive_markers_appear_move_with_pose_updates_and_are_erased(run) -> None:
    recording, _, _ = run
    box = recording["/basic_controls/update/box/0"]
    # the control's cube (0, 0, 0.5) relative to the interactive marker at (1, 0, 0), then at (2, 0, 0)
    assert _at(box, "InstancePoses3D:translations", IM_TIMES[0]) == [[1.0, 0.0, 0.5]]
    assert _at(box, "InstancePoses3D:translations", IM_TIMES[1]) == [[2.0, 0.0, 0.5]]
    np.testing.assert_allclose(_at(box, "Boxes3D:half_sizes", IM_TIMES[0]), [[0.1, 0.1, 0.1]], rtol=1e-6)
    assert _at(box, "Clear:is_recursive", IM_TIMES[2]) == [True]


def test_axes_display_draws_three_cylinders_in_its_reference_frame(run) -> None:
    recording, _, _ = run
    rows = recording["/rviz_axes/Axes"]  # Reference Frame base_link, Length 0.5, Radius 0.05
    assert _at(rows, "CoordinateFrame:frame", T0) == ["base_link"]
    assert _at(rows, "Cylinders3D:lengths", T0) == [0.5] * 3
    np.testing.assert_allclose(_at(rows, "Cylinders3D:centers", T0), np.eye(3) * 0.25)
    colors = [_rgba(c) for c in _at(rows, "Cylinders3D:colors", T0)]
    assert colors == [(255, 0, 0, 255), (0, 255, 0, 255), (0, 0, 255, 255)]
    # each cylinder's own z turned onto its axis
    for q, axis in zip(_at(rows, "Cylinders3D:quaternions", T0), np.eye(3), strict=True):
        x, y, z, w = q
        turned_z = [2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)]
        np.testing.assert_allclose(turned_z, axis, atol=1e-6)


def test_camera_info_is_its_frustum_far_clip_deep(run) -> None:
    recording, _, folder = run
    info = _message(folder, "/camera/depth/camera_info")
    K = np.array(info.k).reshape(3, 3)
    far = 2.0  # the config's Far clip
    corners = [
        ((u - K[0, 2]) / K[0, 0] * far, (v - K[1, 2]) / K[1, 1] * far, far) for u, v in [(0, 0), (4, 0), (4, 3), (0, 3)]
    ]
    overrides = {
        k: v for k, v in blueprint_components(folder / "out.rrd").items() if "/overrides/camera/depth/camera_info/" in k
    }
    (frustum,) = [v for v in overrides.values() if "Pinhole:image_plane_distance" in v]
    assert frustum["Pinhole:image_plane_distance"] == [far]
    assert _rgba(frustum["Pinhole:color"][0]) == (85, 255, 255, 128)  # Color, Alpha 0.5
    rows = recording["/camera/depth/camera_info"]
    logged = np.array(_at(rows, "Pinhole:image_from_camera", T0)).reshape(3, 3).T  # Rerun's columns: column-major
    w, h = _at(rows, "Pinhole:resolution", T0)[0]
    drawn = [tuple(np.linalg.solve(logged, [u, v, 1.0]) * far) for u, v in [(0, 0), (w, 0), (w, h), (0, h)]]
    np.testing.assert_allclose(drawn, corners, atol=1e-9)


def test_a_depth_image_before_its_camera_info_draws_nothing_and_bad_bytes_are_one_error() -> None:
    from rvizdisplaybags import DEPTH_MM, OPTICAL, camera_info, image

    from r2d2_viz.msgs.rviz2.joined import Joins
    from r2d2_viz.msgs.shapes import DecodeOptions
    from r2d2_viz.msgs.typestore import MsgError

    depth = DecodeOptions(depth_cloud=("/d/camera_info", ""))
    joins = Joins({"/d/image": depth})
    data = image(T0, OPTICAL, "16UC1", DEPTH_MM)
    assert joins.decode("/d/image", "sensor_msgs/msg/Image", data, depth) == []  # RViz waits for the camera too
    joins.decode("/d/camera_info", "sensor_msgs/msg/CameraInfo", camera_info(T0), DecodeOptions())
    (op,) = joins.decode("/d/image", "sensor_msgs/msg/Image", data, depth)
    assert len(op.decoded.items[0].positions) == int((DEPTH_MM != 0).sum())
    update = "visualization_msgs/msg/InteractiveMarkerUpdate"
    for cut in range(0, 64, 3):  # a cut message: one MsgError, nothing else
        with pytest.raises(MsgError):
            joins.decode("/im", update, b"\x00\x01\x00\x00" + bytes(cut), DecodeOptions())


def test_the_live_path_joins_too(run) -> None:
    """A live run calls ``DisplayFeed.log`` per message as it arrives: the depth cloud and the interactive marker's
    pose update come out as in a replay (the bag's messages, in receive order)."""
    import rerun as rr
    from rosbags.highlevel import AnyReader

    from r2d2_viz.msgs.shapes import DecodeOptions, MarkerOp
    from r2d2_viz.sources.bag_displays import TopicMessage
    from r2d2_viz.viewer import display_feed as feed_module
    from r2d2_viz.viewer.display_feed import DisplayFeed, DisplayStyle
    from r2d2_viz.viewer.notices import Notices

    _, _, folder = run
    rec = rr.RecordingStream("test_joined_live")
    depth = DecodeOptions(depth_cloud=("/camera/depth/camera_info", "/camera/color/image_raw"))
    feed = DisplayFeed(
        Notices(rec),
        clock="timestamp",
        fixed_frame="base_link",
        styles={"/camera/depth/image_raw": DisplayStyle(depth)},
    )
    sent: list[tuple[str, object]] = []
    original = feed_module.log_decoded
    feed_module.log_decoded = lambda rec, entity, decoded, **kw: sent.append((entity, decoded))  # type: ignore[assignment]
    try:
        with AnyReader([folder / "bag"], default_typestore=TS) as reader:
            for connection, t, raw in reader.messages():
                if connection.topic not in ("/joint_states", "/tf_static"):
                    feed.log(TopicMessage(t, connection.topic, connection.msgtype, bytes(raw)))
    finally:
        feed_module.log_decoded = original
    clouds = [d for e, d in sent if e == "/camera/depth/image_raw" and isinstance(d, list) and d]
    assert len(clouds) == 1 and len(clouds[0][0].decoded.items[0].positions) == 9
    moves = [d for e, d in sent if e == "/basic_controls/update" and isinstance(d, list)]
    added = [op for ops in moves for op in ops if isinstance(op, MarkerOp) and op.action == "add"]
    assert [op.decoded.items[0].T_frame_item.translation for op in added] == [(1.0, 0.0, 0.5), (2.0, 0.0, 0.5)]


def test_without_a_robot_effort_reads_nothing_and_says_nothing(run, tmp_path: Path) -> None:
    """No URDF: the Effort display has no joints to draw at; /joint_states is not read as a display (no "cannot be
    shown" line for it), the other displays draw as before."""
    _, _, folder = run
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(folder / "bag"), "--rviz", str(CONFIG), "--save", str(out))
    assert result.returncode == 0 and "cannot be shown" not in result.stderr, result.stderr
    recording = read_recording(out)
    assert not any(e.startswith("/joint_states/") for e in recording) and "/accel/0" in recording
