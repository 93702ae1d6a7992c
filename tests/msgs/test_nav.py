"""Path, OccupancyGrid (RViz palettes, values worked out from palette_builder.cpp by hand) and GridCells."""

from __future__ import annotations

import math

import numpy as np
import pytest
from msgs_build import TS, T, cdr, header, pose, quat, vec

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.nav import apply_grid_update, decode_grid_cells, decode_occupancy_grid, decode_path
from r2d2_viz.msgs.shapes import DecodeOptions
from r2d2_viz.msgs.typestore import MsgError


def grid(cells: list[int], width: int, height: int, resolution: float = 0.05) -> bytes:
    info = T("nav_msgs/msg/MapMetaData")(
        map_load_time=T("builtin_interfaces/msg/Time")(sec=0, nanosec=0),
        resolution=resolution,
        width=width,
        height=height,
        origin=pose(-1.0, -2.0, 0.0, quat(0, 0, math.sin(0.25), math.cos(0.25))),
    )
    return cdr(T("nav_msgs/msg/OccupancyGrid")(header=header("map"), info=info, data=np.array(cells, np.int8)))


CELLS = [0, 50, 100, -1, 99, 101, -128, -2]


def test_map_palette() -> None:
    (m,) = decode_occupancy_grid(grid(CELLS, 4, 2), DecodeOptions()).items
    assert isinstance(m, shapes.GridMap)
    assert m.rgba.shape == (2, 4, 4) and m.resolution == pytest.approx(0.05)
    assert m.T_frame_item.translation == (-1.0, -2.0, 0.0)
    # map: v = 255 - 255·i/100 (integer division); 101..127 green; 128..254 red→yellow; -1 (255) 0x708986
    expected = [
        [255, 255, 255, 255],
        [128, 128, 128, 255],  # 255 - 12750 // 100 = 255 - 127
        [0, 0, 0, 255],
        [0x70, 0x89, 0x86, 255],
        [3, 3, 3, 255],  # 255 - 25245 // 100 = 255 - 252
        [0, 255, 0, 255],
        [255, 0, 0, 255],  # -128 is palette index 128: red
        [255, 255, 0, 255],  # -2 is index 254: green (255·(254 - 128)) // 126 = 255, yellow
    ]
    assert m.rgba.reshape(-1, 4).tolist() == expected  # row 0 is y = 0: cells in message order


def test_costmap_and_raw_palettes() -> None:
    (m,) = decode_occupancy_grid(grid(CELLS, 8, 1), DecodeOptions(map_scheme="costmap")).items
    assert isinstance(m, shapes.GridMap)
    got = m.rgba.reshape(-1, 4).tolist()
    assert got[0] == [0, 0, 0, 0]  # free space is transparent
    assert got[1] == [127, 0, 128, 255]  # v = 255·50 // 100 = 127 → (v, 0, 255 - v)
    assert got[2] == [255, 0, 255, 255] and got[4] == [0, 255, 255, 255]  # lethal purple, inscribed cyan
    assert got[3] == [0x70, 0x89, 0x86, 255]
    (m,) = decode_occupancy_grid(grid(CELLS, 8, 1), DecodeOptions(map_scheme="raw")).items
    assert isinstance(m, shapes.GridMap)
    assert m.rgba[0, :, 0].tolist() == [0, 50, 100, 255, 99, 101, 128, 254]


def test_bad_grids() -> None:
    with pytest.raises(MsgError, match="cells"):
        decode_occupancy_grid(grid(CELLS, 100_000, 100_000), DecodeOptions())
    with pytest.raises(MsgError, match="resolution"):
        decode_occupancy_grid(grid(CELLS, 8, 1, resolution=0.0), DecodeOptions())
    with pytest.raises(ValueError):
        decode_occupancy_grid(grid(CELLS, 8, 1)[:-3], DecodeOptions())


def test_path_is_one_strip_through_the_positions() -> None:
    stamped = T("geometry_msgs/msg/PoseStamped")
    poses = [stamped(header=header("map"), pose=pose(float(i), 2.0 * i, 0.0)) for i in range(3)]
    (strips,) = decode_path(cdr(T("nav_msgs/msg/Path")(header=header("/map"), poses=poses)), DecodeOptions()).items
    assert isinstance(strips, shapes.LineStrips)
    assert [s.tolist() for s in strips.strips] == [[[0, 0, 0], [1, 2, 0], [2, 4, 0]]]
    (strips,) = decode_path(cdr(T("nav_msgs/msg/Path")(header=header(), poses=[])), DecodeOptions()).items
    assert isinstance(strips, shapes.LineStrips) and strips.strips == ()


def test_grid_cells_are_flat_boxes() -> None:
    msg = T("nav_msgs/msg/GridCells")(
        header=header("map"), cell_width=0.5, cell_height=0.25, cells=[vec(1, 2, 0, "Point"), vec(3, 4, 0, "Point")]
    )
    (boxes,) = decode_grid_cells(cdr(msg), DecodeOptions()).items
    assert isinstance(boxes, shapes.Boxes)
    np.testing.assert_allclose(boxes.centers, [[1, 2, 0], [3, 4, 0]])
    np.testing.assert_allclose(boxes.half_sizes, [[0.25, 0.125, 0]] * 2)


def _update(x: int, y: int, w: int, h: int, cells: list[int]) -> bytes:
    """A map_msgs/msg/OccupancyGridUpdate, serialised by rosbags from its ROS 2 definition (nav2's costmap
    updates; rosbags' stores lack the type)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    text = "std_msgs/Header header\nint32 x\nint32 y\nuint32 width\nuint32 height\nint8[] data\n"
    store.register(get_types_from_msg(text, "map_msgs/msg/OccupancyGridUpdate"))
    msg = store.types["map_msgs/msg/OccupancyGridUpdate"](
        header=header(), x=x, y=y, width=w, height=h, data=np.array(cells, dtype=np.int8)
    )
    return bytes(store.serialize_cdr(msg, "map_msgs/msg/OccupancyGridUpdate"))


def test_a_grid_update_is_applied_as_rviz_does() -> None:
    """A 4x3 map of zeros, a 2x2 update at (1, 1): by hand, rows 1-2 columns 1-2 take the update, row by row."""
    base = grid([0] * 12, 4, 3)
    new = apply_grid_update(base, _update(1, 1, 2, 2, [10, 20, 30, -1]))
    msg = TS.deserialize_cdr(bytes(new), "nav_msgs/msg/OccupancyGrid")  # rosbags' own Humble store
    assert msg.data.reshape(3, 4).tolist() == [[0, 0, 0, 0], [0, 10, 20, 0], [0, 30, -1, 0]]
    assert (msg.info.width, msg.info.height) == (4, 3)
    assert decode_occupancy_grid(new, DecodeOptions()).items  # the usual decoder draws the result
    with pytest.raises(MsgError, match="outside"):
        apply_grid_update(base, _update(3, 0, 2, 1, [1, 2]))
    with pytest.raises(MsgError, match="outside"):
        apply_grid_update(base, _update(-1, 0, 1, 1, [1]))
    with pytest.raises(MsgError, match="cells"):
        apply_grid_update(base, _update(0, 0, 2, 2, [1, 2, 3]))
