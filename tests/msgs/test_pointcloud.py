"""PointCloud2 / PointCloud decoding: layouts built by hand with numpy, expectations from the same source arrays."""

from __future__ import annotations

import math

import numpy as np
import pytest
from msgs_build import T, cdr, header, rviz_intensity, vec

from r2d2_viz.msgs.pointcloud import decode_pointcloud, decode_pointcloud2
from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.shapes import DecodeOptions, Points
from r2d2_viz.msgs.typestore import MsgError

OPTIONS = DecodeOptions()
FLOAT32, UINT32, UINT16 = 7, 6, 4


def field(name: str, offset: int, datatype: int) -> object:
    return T("sensor_msgs/msg/PointField")(name=name, offset=offset, datatype=datatype, count=1)


def cloud(
    points: np.ndarray,
    fields: list[object],
    *,
    width: int,
    height: int = 1,
    row_step: int | None = None,
    bigendian: bool = False,
    raw: bytes | None = None,
) -> bytes:
    step = points.dtype.itemsize
    data = raw if raw is not None else points.tobytes()
    msg = T("sensor_msgs/msg/PointCloud2")(
        header=header("/velodyne"),
        height=height,
        width=width,
        fields=fields,
        is_bigendian=bigendian,
        point_step=step,
        row_step=row_step if row_step is not None else width * step,
        data=np.frombuffer(data, dtype=np.uint8),
        is_dense=False,
    )
    return cdr(msg)


def xyz_dtype(order: str = "<", extra: dict[str, tuple[str, int]] | None = None, itemsize: int = 32) -> np.dtype:
    names, formats, offsets = ["x", "y", "z"], [order + "f4"] * 3, [0, 4, 8]
    for name, (fmt, offset) in (extra or {}).items():
        names.append(name)
        formats.append(order + fmt)
        offsets.append(offset)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": itemsize})


XYZ_FIELDS = [field("x", 0, FLOAT32), field("y", 4, FLOAT32), field("z", 8, FLOAT32)]


def test_padded_points_with_nan_dropped_and_packed_rgb() -> None:
    # point_step 32 with 16 bytes of padding: x y z at 0/4/8, rgb (float32 bit pattern) at 16
    dt = xyz_dtype(extra={"rgb": ("u4", 16)})
    pts = np.zeros(3, dtype=dt)
    pts["x"], pts["y"], pts["z"] = [1.0, math.nan, 3.0], [2.0, 0.0, -1.0], [0.5, 0.0, 0.25]
    pts["rgb"] = [0x00FF8040, 0x00000000, 0x000102FF]  # 0x00RRGGBB
    decoded = decode_pointcloud2(cloud(pts, [*XYZ_FIELDS, field("rgb", 16, FLOAT32)], width=3), OPTIONS)
    assert decoded.frame_id == "velodyne" and decoded.stamp_ns == 12_000_000_345
    (points,) = decoded.items
    assert isinstance(points, Points)
    np.testing.assert_array_equal(points.positions, [[1, 2, 0.5], [3, -1, 0.25]])
    assert points.colors.tolist() == [[0xFF, 0x80, 0x40, 255], [0x01, 0x02, 0xFF, 255]]


def test_rgba_keeps_its_alpha() -> None:
    dt = xyz_dtype(extra={"rgba": ("u4", 12)}, itemsize=16)
    pts = np.zeros(1, dtype=dt)
    pts["rgba"] = [0x80102030]
    (points,) = decode_pointcloud2(cloud(pts, [*XYZ_FIELDS, field("rgba", 12, UINT32)], width=1), OPTIONS).items
    assert isinstance(points, Points)
    assert points.colors.tolist() == [[0x10, 0x20, 0x30, 0x80]]


def test_big_endian_cloud() -> None:
    dt = xyz_dtype(">", {"intensity": ("f4", 12)}, itemsize=16)
    pts = np.zeros(2, dtype=dt)
    pts["x"], pts["y"], pts["z"], pts["intensity"] = [1.5, -2.0], [3.0, 4.0], [5.0, 6.0], [7.0, 9.0]
    fields = [*XYZ_FIELDS, field("intensity", 12, FLOAT32)]
    (points,) = decode_pointcloud2(cloud(pts, fields, width=2, bigendian=True), OPTIONS).items
    assert isinstance(points, Points)
    np.testing.assert_array_equal(points.positions, [[1.5, 3, 5], [-2, 4, 6]])
    assert [tuple(c[:3]) for c in points.colors.tolist()] == rviz_intensity([7.0, 9.0])


def test_organised_cloud_with_row_padding_and_nan_holes() -> None:
    # 2 rows x 2 columns, 16-byte points, rows padded to 40 bytes; 'intensities' (uint16) is the fallback channel
    dt = xyz_dtype(extra={"intensities": ("u2", 12)}, itemsize=16)
    grid = np.zeros((2, 2), dtype=dt)
    grid["x"] = [[0.0, 1.0], [math.nan, 3.0]]
    grid["y"] = [[10.0, 11.0], [12.0, 13.0]]
    grid["intensities"] = [[100, 200], [300, 400]]
    raw = b"".join(row.tobytes() + b"\xee" * 8 for row in grid)
    fields = [*XYZ_FIELDS, field("intensities", 12, UINT16)]
    (points,) = decode_pointcloud2(cloud(grid, fields, width=2, height=2, row_step=40, raw=raw), OPTIONS).items
    assert isinstance(points, Points)
    np.testing.assert_array_equal(points.positions, [[0, 10, 0], [1, 11, 0], [3, 13, 0]])
    # RViz computes the bounds over every point of the cloud (the NaN one too): 100..400
    expected = rviz_intensity([100.0, 200.0, 300.0, 400.0])
    assert [tuple(c[:3]) for c in points.colors.tolist()] == [expected[0], expected[1], expected[3]]


def test_no_colour_field_is_flat() -> None:
    pts = np.zeros(2, dtype=xyz_dtype(itemsize=12))
    (points,) = decode_pointcloud2(cloud(pts, XYZ_FIELDS, width=2), OPTIONS).items
    assert isinstance(points, Points) and points.colors.tolist() == [[255, 255, 255, 255]]


def test_inconsistent_sizes_are_refused_without_allocating() -> None:
    pts = np.zeros(2, dtype=xyz_dtype(itemsize=12))
    with pytest.raises(MsgError, match="need"):
        decode_pointcloud2(cloud(pts, XYZ_FIELDS, width=2, height=100_000_000), OPTIONS)
    with pytest.raises(MsgError, match="too many"):
        decode_pointcloud2(cloud(pts, XYZ_FIELDS, width=2**31, height=2**31, row_step=2**32 - 1), OPTIONS)
    with pytest.raises(MsgError, match="row_step"):
        decode_pointcloud2(cloud(pts, XYZ_FIELDS, width=2, height=2, row_step=8), OPTIONS)
    with pytest.raises(MsgError, match="does not fit"):
        decode_pointcloud2(cloud(pts, [*XYZ_FIELDS, field("rgb", 10, FLOAT32)], width=2), OPTIONS)
    with pytest.raises(MsgError, match="x, y, z"):
        decode_pointcloud2(cloud(pts, XYZ_FIELDS[:2], width=2), OPTIONS)
    with pytest.raises(MsgError, match="datatype"):
        decode_pointcloud2(cloud(pts, [*XYZ_FIELDS[:2], field("z", 8, 42)], width=2), OPTIONS)


@pytest.mark.parametrize("junk", [b"", b"\x00\x01\x00\x00", b"\x00\x01\x00\x00" + b"\xff" * 64, bytes(range(256))])
def test_garbage_raises_value_error(junk: bytes) -> None:
    with pytest.raises(ValueError):
        decode("sensor_msgs/msg/PointCloud2", junk)


def test_old_pointcloud_with_rgb_and_intensity_channels() -> None:
    channel = T("sensor_msgs/msg/ChannelFloat32")
    pts = [vec(1, 2, 3, "Point32"), vec(math.nan, 0, 0, "Point32"), vec(4, 5, 6, "Point32")]
    packed = np.array([0x00FF0000, 0, 0x0000FF00], dtype=np.uint32).view(np.float32)
    msg = T("sensor_msgs/msg/PointCloud")(
        header=header("cam"), points=pts, channels=[channel(name="rgb", values=packed)]
    )
    (points,) = decode_pointcloud(cdr(msg), OPTIONS).items
    assert isinstance(points, Points)
    np.testing.assert_array_equal(points.positions, [[1, 2, 3], [4, 5, 6]])
    assert points.colors.tolist() == [[255, 0, 0, 255], [0, 255, 0, 255]]
    msg = T("sensor_msgs/msg/PointCloud")(
        header=header("cam"),
        points=pts,
        channels=[channel(name="intensity", values=np.array([1.0, 2.0, 3.0], dtype=np.float32))],
    )
    (points,) = decode_pointcloud(cdr(msg), OPTIONS).items
    assert isinstance(points, Points)
    assert [tuple(c[:3]) for c in points.colors.tolist()] == [rviz_intensity([1.0, 2.0, 3.0])[i] for i in (0, 2)]
    bad = T("sensor_msgs/msg/PointCloud")(
        header=header("cam"), points=pts, channels=[channel(name="intensity", values=np.zeros(2, np.float32))]
    )
    with pytest.raises(MsgError, match="channel"):
        decode_pointcloud(cdr(bad), OPTIONS)
