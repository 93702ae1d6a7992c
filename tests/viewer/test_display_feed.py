"""Display topics through the real CLI, read back with Rerun's reader: each message in its TF frame at its
receive time, from both storages, the same in a live (paced) replay as in a saved one; what cannot be shown is
said once. Expected values are worked out by hand in tests/displaybags.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from displaybags import (
    CUBE_LIFETIME_S,
    EMPTY_FRAME_TIME,
    GARBAGE_TIME,
    MAP_TIME,
    MARKER_TIME,
    SCAN_POINTS,
    SCAN_TIMES,
    SPHERE_DELETED,
    T0,
    S,
    write_display_bag,
)
from rrd import read_recording

from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.viewer.display_feed import DisplayFeed


def _replay(tmp_path: Path, storage: str, *extra: str) -> tuple[dict, str]:
    name = f"{storage}_{len(list(tmp_path.iterdir()))}"
    bag = write_display_bag(tmp_path / f"bag_{name}", storage=storage)
    out = tmp_path / f"{name}.rrd"
    result = cli("--bag", str(bag), "--save", str(out), *extra)
    assert result.returncode == 0, result.stderr
    return read_recording(out), result.stderr


def _drawn(rows, column: str) -> list[int]:
    """The times at which ``column`` was logged (not the frame-only rows every display entity starts with)."""
    return [t for t, v in zip(rows.times, rows.temporal.get(column, []), strict=False) if v is not None]


def _clears(rows) -> list[int]:
    return [t for t, v in zip(rows.times, rows.temporal.get("Clear:is_recursive", []), strict=False) if v == [True]]


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bags_displays_land_in_their_frames_at_their_times(tmp_path: Path, storage: str) -> None:
    recording, stderr = _replay(tmp_path, storage)
    scan = recording["/scan"]
    good = [t for t, p in zip(scan.times, scan.temporal["Points3D:positions"], strict=True) if p is not None]
    assert good == sorted([*SCAN_TIMES, EMPTY_FRAME_TIME + 1])  # the garbage message drew nothing
    for positions in scan.temporal["Points3D:positions"]:
        if positions is not None:
            np.testing.assert_allclose(positions, SCAN_POINTS, atol=1e-6)
    frames = dict(zip(scan.times, scan.temporal["CoordinateFrame:frame"], strict=True))
    assert frames[SCAN_TIMES[1]] == ["base_laser"]  # '/base_laser': the leading slash stripped
    assert frames[EMPTY_FRAME_TIME + 1] == ["odom"]  # empty frame id: the fixed frame (the root of /tf)
    # the map: a 4 x 2 grid of 0.5 m cells, a 2 m x 1 m quad at its origin, in odom
    grid = recording["/map"]
    assert _drawn(grid, "Mesh3D:vertex_positions") == [MAP_TIME]
    at = grid.times.index(MAP_TIME, 1)  # (row 0: the frame every display entity starts with)
    assert grid.temporal["Mesh3D:vertex_positions"][at] == [[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]]
    assert grid.temporal["InstancePoses3D:translations"][at] == [[-1, -0.5, 0]]
    # markers: the cube kept its 1 s lifetime, the sphere was deleted
    cube, ball = recording["/markers/boxes/1"], recording["/markers/balls/7"]
    drawn_at = cube.times.index(MARKER_TIME)
    assert cube.temporal["InstancePoses3D:translations"][drawn_at] == [[1, 1, 0]]
    # each marker entity sits in its frame from the first display message on, like the topics' entities below
    assert cube.times[0] == T0 and cube.temporal["CoordinateFrame:frame"][0] == ["odom"]
    assert _clears(cube) == [MARKER_TIME + CUBE_LIFETIME_S * S]
    assert _clears(ball) == [SPHERE_DELETED]
    # odometry keeps RViz's history (Keep 100): three poses on three entities, each still drawn
    assert [_drawn(recording[f"/odom/{k}"], "Arrows3D:vectors") for k in range(3)] == [[T0], [T0 + S], [T0 + 2 * S]]
    # every display entity, each slot of the history too, sits in the fixed frame from the first message on
    # (else the viewer reports "no transform path" for each entity not drawn yet)
    assert recording["/odom/99"].times == [T0] and recording["/odom/99"].temporal["CoordinateFrame:frame"] == [["odom"]]
    assert recording["/map"].temporal["CoordinateFrame:frame"][0] == ["odom"] and recording["/map"].times[0] == T0
    # said once each: the empty frame id, the garbage message; the topic no display draws is decoded as fields
    lines = [line for line in stderr.splitlines() if line.startswith("warning:")]
    assert sum("/scan: messages with an empty frame_id are drawn in the fixed frame [odom]" in x for x in lines) == 1
    assert sum("/scan: a sensor_msgs/msg/LaserScan message cannot be shown" in x for x in lines) == 1
    assert not any("not shown" in x for x in lines), lines  # every topic is decoded, in both storages
    chatter = recording["/topics/chatter"].temporal  # its fields, as tests/displaybags.py wrote them
    assert [chatter[f"std_msgs/msg/ColorRGBA:{c}"] for c in "rgba"] == [[[1.0]], [[0.5]], [[0.0]], [[1.0]]]
    assert GARBAGE_TIME + 1 not in recording["/scan"].times  # the garbage message logged nothing at all


def test_a_live_replay_shows_the_same_displays_at_the_same_times(tmp_path: Path) -> None:
    saved, _ = _replay(tmp_path, "mcap")
    live, _ = _replay(tmp_path, "mcap", "--realtime", "--speed", "4")  # paced on the wall clock, 4x
    for entity in ("/scan", "/map", "/markers/boxes/1", "/markers/balls/7", "/odom/2"):
        assert live[entity].times == saved[entity].times, entity
    drawn = [[p for p in r["/scan"].temporal["Points3D:positions"] if p is not None] for r in (live, saved)]
    assert drawn[0] == drawn[1] and len(drawn[0]) == len(SCAN_TIMES) + 1


def test_the_feed_pulls_messages_up_to_a_time_and_odometry_goes_round_its_keep() -> None:
    sent: list[tuple[str, int]] = []

    class _Notices:
        rec = None

        def report(self, *args: object, **kwargs: object) -> None:
            pass

    import r2d2_viz.viewer.display_feed as feed_module

    original = feed_module.log_decoded
    feed_module.log_decoded = lambda rec, entity, decoded, **kw: sent.append((entity, kw["time_ns"]))  # type: ignore[assignment]
    try:
        from displaybags import odometry

        messages = [TopicMessage(t, "/odom", "nav_msgs/msg/Odometry", odometry(1, float(t))) for t in (1, 2, 3, 4)]
        feed = DisplayFeed(_Notices(), clock="timestamp", fixed_frame="odom")  # type: ignore[arg-type]
        feed.styles["/odom"] = feed_module.DisplayStyle(keep=2)

        class _Runs:  # a pose is one arrow: it goes out as columns (viewer/blocks), on its slot's entity
            def add(self, message: TopicMessage, entity: str, *args: object, **kwargs: object) -> None:
                sent.append((entity, message.time_ns))

            def interrupt(self, *entities: str, everything: bool = False) -> None:
                pass

        feed.columns = _Runs()  # type: ignore[assignment]
        assert feed.next_time_ns is None and feed.until(None) == 0  # nothing read yet
        feed.push(messages[:3])  # one stretch of the replay
        assert feed.next_time_ns == 1
        assert feed.until(2) == 2 and feed.next_time_ns == 3
        assert feed.until(None) == 1 and feed.next_time_ns is None
        feed.push(messages[3:])  # the next stretch
        assert feed.next_time_ns == 4 and feed.until(3) == 0 and feed.until(4) == 1
    finally:
        feed_module.log_decoded = original
    assert sent == [("/odom/0", 1), ("/odom/1", 2), ("/odom/0", 3), ("/odom/1", 4)]


STYLED_CONFIG = """Visualization Manager:
  Global Options:
    Fixed Frame: odom
  Displays:
    - Class: rviz_default_plugins/LaserScan
      Name: LaserScan
      Enabled: true
      Topic:
        Value: /scan
      Color: 255; 0; 0
      Alpha: 0.5
      Color Transformer: FlatColor
      Size (m): 0.1
    - Class: rviz_default_plugins/Odometry
      Name: Odometry
      Enabled: false
      Topic:
        Value: /odom
      Keep: 2
"""


def test_an_rviz_configs_displays_style_the_topics(tmp_path: Path) -> None:
    config = tmp_path / "styled.rviz"
    config.write_text(STYLED_CONFIG)
    recording, _ = _replay(tmp_path, "mcap", "--rviz", str(config))
    scan = recording["/scan"]
    drawn = [i for i, p in enumerate(scan.temporal["Points3D:positions"]) if p is not None]
    # Color 255; 0; 0 with Alpha 0.5 as RGBA 0xFF000080, Size (m) 0.1 a diameter: radius 0.05
    assert {tuple(scan.temporal["Points3D:colors"][i]) for i in drawn} == {(0xFF000080,)}
    assert {tuple(np.round(scan.temporal["Points3D:radii"][i], 6)) for i in drawn} == {(0.05,)}
    # Odometry's Keep 2: its poses go round two entities
    assert sorted(k for k in recording if k.startswith("/odom/")) == ["/odom/0", "/odom/1"]
    assert _drawn(recording["/odom/0"], "Arrows3D:vectors") == [T0, T0 + 2 * S]


def test_a_cameras_images_get_its_pinhole_and_a_2d_view(tmp_path: Path) -> None:
    from bagmaker import BagSpec, write_bag
    from msgs_build import T, cdr, header

    image = T("sensor_msgs/msg/Image")(
        header=header("cam_optical"), height=2, width=2, encoding="rgb8", is_bigendian=0, step=6,
        data=np.arange(12, dtype=np.uint8),
    )  # fmt: skip
    K = [100.0, 0, 1, 0, 100.0, 1, 0, 0, 1]
    info = T("sensor_msgs/msg/CameraInfo")(
        header=header("cam_optical"), height=2, width=2, distortion_model="plumb_bob", d=np.zeros(5),
        k=np.array(K), r=np.eye(3).reshape(-1), p=np.zeros(12), binning_x=0, binning_y=0,
        roi=T("sensor_msgs/msg/RegionOfInterest")(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
    )  # fmt: skip
    spec = BagSpec(types={"/cam/image_raw": "sensor_msgs/msg/Image", "/cam/camera_info": "sensor_msgs/msg/CameraInfo"})
    spec.add("/cam/camera_info", T0, cdr(info)).add("/cam/image_raw", T0 + 1, cdr(image))
    bag = write_bag(tmp_path / "cam", spec)
    out = tmp_path / "cam.rrd"
    result = cli("--bag", str(bag), "--save", str(out))
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    pinned = recording["/cam/image_raw"]
    # the CameraInfo's K on the image's entity (so the image shows in 3D, in its frame) beside the image itself
    k = next(v for v in pinned.temporal["Pinhole:image_from_camera"] if v is not None)
    assert np.allclose(np.reshape(k, (3, 3)).T, np.reshape(K, (3, 3)))  # Rerun stores the matrix column-major
    assert any(v is not None for v in pinned.temporal["Image:buffer"])


def test_each_map_drawn_is_handed_on_with_its_frame() -> None:
    """The tools' ground is told of each map (tests/displaybags.py: 4 x 2 cells of 0.5 m from (-1, -0.5) in odom,
    so (-1, -0.5) to (1, 0.5) by hand)."""
    import rerun as rr
    from displaybags import occupancy_grid

    from r2d2_viz.viewer.notices import Notices
    from r2d2_viz.viewer.web.draw import ToolDrawing

    rec = rr.RecordingStream("test_display_feed")
    feed = DisplayFeed(Notices(rec), clock="timestamp", fixed_frame="odom")
    drawing = ToolDrawing(rec, "odom")
    seen: list[str] = []
    feed.on_map = lambda frame, grid: seen.append(frame) or drawing.cover(frame, grid)
    feed.log(TopicMessage(MAP_TIME, "/map", "nav_msgs/msg/OccupancyGrid", occupancy_grid()))
    assert seen == ["odom"] and drawing.extent == (-1.0, -0.5, 1.0, 0.5)


def test_a_batch_feed_leaves_backpressure_to_the_runner_and_a_live_one_flushes_itself() -> None:
    """Issue 48: a batch run flushed twice per mark (the runner's marks and this feed's own); its only marks are now
    the runner's, which wait for the previous mark's flush (viewer/files/flush_ahead.py). A live feed keeps its own."""
    import r2d2_viz.viewer.display_feed as feed_module

    class _Rec:
        flushes = 0

        def flush(self, *args: object, **kwargs: object) -> None:
            self.flushes += 1

    class _Notices:
        def __init__(self) -> None:
            self.rec = _Rec()

    big = TopicMessage(1, "/points", "sensor_msgs/msg/PointCloud2", bytes(feed_module.FLUSH_BYTES // 2 + 1))
    for hold, flushes in ((True, 0), (False, 1)):  # hold: a batch run's feed (runner.py)
        feed = DisplayFeed(_Notices(), clock="timestamp", fixed_frame="odom", hold=hold)  # type: ignore[arg-type]
        feed_module._count(feed, big)
        feed_module._count(feed, big)  # past FLUSH_BYTES
        assert feed.rec.flushes == flushes, hold
