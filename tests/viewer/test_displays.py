"""Decoded messages logged to an .rrd and read back with Rerun's own reader."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import rerun as rr
from msgs_build import T, cdr, color, duration, header, marker_msg, pose, quat, vec
from rrd import Rows, read_recording

from r2d2_viz.msgs.registry import decode
from r2d2_viz.viewer.displays import MarkerBook, log_decoded

S = 1_000_000_000


def record(tmp_path: Path, body: Callable[[rr.RecordingStream], None]) -> dict[str, Rows]:
    out = tmp_path / "out.rrd"
    rec = rr.RecordingStream("test_displays")
    rec.save(out)
    body(rec)
    rec.flush()
    rec.disconnect()
    return read_recording(out)


def scan_bytes() -> bytes:
    msg = T("sensor_msgs/msg/LaserScan")(
        header=header("/laser"),
        angle_min=0.0,
        angle_max=math.pi / 2,
        angle_increment=math.pi / 2,
        time_increment=0.0,
        scan_time=0.1,
        range_min=0.1,
        range_max=10.0,
        ranges=np.array([1.0, 2.0], dtype=np.float32),
        intensities=np.zeros(0, np.float32),
    )
    return cdr(msg)


def marker(action: int, ns: str, key: int, lifetime_s: int = 0) -> object:
    return marker_msg(
        1,
        action=action,
        ns=ns,
        id=key,
        pose=pose(1.0, 0.0, 0.0, quat(0, 0, 0, 1)),
        scale=vec(2, 2, 2),
        color=color(0, 0, 1),
        lifetime=duration(lifetime_s),
    )


def markers(*ms: object) -> bytes:
    return cdr(T("visualization_msgs/msg/MarkerArray")(markers=list(ms)))


def test_scan_points_in_their_frame(tmp_path: Path) -> None:
    def body(rec: rr.RecordingStream) -> None:
        log_decoded(rec, "/scan", decode("sensor_msgs/msg/LaserScan", scan_bytes()), timeline="time", time_ns=5 * S)

    rows = record(tmp_path, body)["/scan"]
    assert rows.times == [5 * S]
    assert rows.temporal["CoordinateFrame:frame"] == [["laser"]]
    np.testing.assert_allclose(rows.temporal["Points3D:positions"][0], [[1, 0, 0], [0, 2, 0]], atol=1e-6)


def test_map_is_a_textured_quad_at_its_origin(tmp_path: Path) -> None:
    info = T("nav_msgs/msg/MapMetaData")(
        map_load_time=T("builtin_interfaces/msg/Time")(sec=0, nanosec=0),
        resolution=0.5,
        width=3,
        height=2,
        origin=pose(-1.0, -2.0, 0.0),
    )
    data = cdr(T("nav_msgs/msg/OccupancyGrid")(header=header("map"), info=info, data=np.zeros(6, np.int8)))

    def body(rec: rr.RecordingStream) -> None:
        log_decoded(rec, "/map", decode("nav_msgs/msg/OccupancyGrid", data), timeline="time", time_ns=S)

    rows = record(tmp_path, body)["/map"]
    # 3 x 2 cells of 0.5 m: a 1.5 m x 1 m quad, placed at the origin pose by the instance pose
    assert rows.temporal["Mesh3D:vertex_positions"][0] == [[0, 0, 0], [1.5, 0, 0], [1.5, 1, 0], [0, 1, 0]]
    assert rows.temporal["InstancePoses3D:translations"][0] == [[-1, -2, 0]]
    assert rows.temporal["CoordinateFrame:frame"] == [["map"]]


def test_marker_add_delete_deleteall_and_lifetime(tmp_path: Path) -> None:
    book = MarkerBook()

    def log(rec: rr.RecordingStream, t: int, data: bytes) -> None:
        ops = decode("visualization_msgs/msg/MarkerArray", data)
        log_decoded(rec, "/markers", ops, timeline="time", time_ns=t * S, markers=book)

    def body(rec: rr.RecordingStream) -> None:
        log(rec, 1, markers(marker(0, "a", 1), marker(0, "a", 2), marker(0, "b", 1, lifetime_s=2)))
        log(rec, 2, markers(marker(2, "a", 2)))  # DELETE a/2
        log(rec, 4, markers(marker(3, "a", 0)))  # DELETEALL of ns a; b/1 expired at t = 3 on the way
        log(rec, 5, markers(marker(0, "", 9), marker(3, "", 0)))  # add then DELETEALL everything

    recording = record(tmp_path, body)
    a1, b1 = recording["/markers/a/1"], recording["/markers/b/1"]
    assert a1.temporal["CoordinateFrame:frame"][0] == ["odom"]
    assert a1.temporal["Boxes3D:half_sizes"][0] == [[1, 1, 1]]
    assert a1.temporal["InstancePoses3D:translations"][0] == [[1, 0, 0]]
    clears = {
        path: [t for t, v in zip(rows.times, rows.temporal["Clear:is_recursive"], strict=True) if v == [True]]
        for path, rows in recording.items()
        if "Clear:is_recursive" in rows.temporal
    }
    # each marker shown is cleared once, when it goes: a DELETEALL clears only what is still shown
    assert clears == {
        "/markers/a/2": [2 * S],  # DELETE a/2
        "/markers/b/1": [3 * S],  # lifetime 2 s from t = 1
        "/markers/a/1": [4 * S],  # DELETEALL with ns 'a' (a/2 is gone already)
        "/markers/_/9": [5 * S],  # DELETEALL without ns (the rest is gone already)
    }
    assert recording["/markers/_/9"].times == [5 * S, 5 * S, 5 * S]  # drawn, cleared, placed again
    # a cleared marker stays in a frame (else Rerun's implicit tf#/markers/a/2, which no transform reaches,
    # would be reported by the view): its frame is logged again with each clear
    framed = {
        path: [t for t, v in zip(rows.times, rows.temporal["CoordinateFrame:frame"], strict=True) if v == ["odom"]]
        for path, rows in recording.items()
        if "CoordinateFrame:frame" in rows.temporal
    }
    assert framed["/markers/a/2"] == [S, 2 * S] and framed["/markers/b/1"] == [S, 3 * S]
    assert framed["/markers/a/1"] == [S, 4 * S] and framed["/markers/_/9"] == [5 * S, 5 * S]
    assert b1.temporal["Boxes3D:half_sizes"][0] == [[1, 1, 1]]
    assert book.live == {}


def test_every_display_type_logs(tmp_path: Path) -> None:
    """One message of every type: each lands with its natural archetype."""
    from msgs_build import samples

    stl = b"solid x\nendsolid x\n"

    def body(rec: rr.RecordingStream) -> None:
        for typename, data in samples().items():
            entity = "/" + typename.split("/")[-1]
            log_decoded(
                rec,
                entity,
                decode(typename, data),
                timeline="time",
                time_ns=S,
                markers=MarkerBook(),
                load_mesh=lambda uri: (stl, "model/stl") if uri.endswith(".stl") else None,
            )

    recording = record(tmp_path, body)
    components = {path: set(rows.temporal) for path, rows in recording.items()}
    expected = {
        "/LaserScan": "Points3D:positions",
        "/Range": "LineStrips3D:strips",
        "/PointCloud2": "Points3D:colors",
        "/PointCloud": "Points3D:positions",
        "/Image": "Image:buffer",
        "/CompressedImage": "EncodedImage:blob",
        "/CameraInfo": "Pinhole:image_from_camera",
        "/Marker/ns/2": "Ellipsoids3D:half_sizes",
        "/MarkerArray/ns/0": "Arrows3D:vectors",
        "/MarkerArray/ns/1": "Boxes3D:half_sizes",
        "/MarkerArray/ns/3": "Cylinders3D:lengths",
        "/MarkerArray/ns/4": "LineStrips3D:strips",
        "/MarkerArray/ns/9": "Points3D:labels",
        "/MarkerArray/ns/10": "Asset3D:blob",
        "/MarkerArray/ns/11": "Mesh3D:triangle_indices",
        "/Path": "LineStrips3D:strips",
        "/Odometry": "Arrows3D:vectors",  # its covariance only when a config asks (Covariance)
        "/OccupancyGrid": "Mesh3D:albedo_texture_buffer",
        "/GridCells": "Boxes3D:centers",
        "/PoseStamped": "Arrows3D:origins",
        "/PoseArray": "Arrows3D:origins",
        "/PoseWithCovarianceStamped/1": "Ellipsoids3D:centers",
        "/PointStamped": "Ellipsoids3D:centers",
        "/PolygonStamped": "LineStrips3D:strips",
        "/WrenchStamped/1": "Arrows3D:vectors",
        "/TwistStamped/0": "Arrows3D:vectors",
    }
    missing = {path: c for path, c in expected.items() if c not in components.get(path, set())}
    assert not missing, {path: sorted(components.get(path, set())) for path in missing}
    assert "CoordinateFrame:frame" not in components["/Image"]  # 2D: no frame
    np.testing.assert_allclose(recording["/MarkerArray/ns/10"].temporal["InstancePoses3D:scales"][0], [[0.2] * 3])
