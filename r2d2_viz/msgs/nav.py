"""nav_msgs Path, OccupancyGrid (RViz's map / costmap / raw palettes), map_msgs OccupancyGridUpdate (applied to its
map) and GridCells."""

from __future__ import annotations

import numpy as np

from r2d2_viz.msgs.colormaps import PALETTES
from r2d2_viz.msgs.geometry import FLOAT32_MAX, header_of, one_color, points3, pose_of
from r2d2_viz.msgs.shapes import Boxes, Decoded, DecodeOptions, GridMap, LineStrips
from r2d2_viz.msgs.typestore import MsgError, deserialize, typestore

PATH_COLOR = (25, 255, 0, 255)  # RViz's Path and GridCells default
MAX_CELLS = 1 << 28


def decode_path(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A Path as one line strip through its poses' positions (in the header frame, as RViz draws it)."""
    msg = deserialize(data, "nav_msgs/msg/Path")
    frame, stamp = header_of(msg)
    p = np.array([pose_of(s.pose).translation for s in msg.poses], dtype=np.float32).reshape(-1, 3)
    strips = (p,) if p.shape[0] > 1 else ()
    return Decoded(frame, stamp, (LineStrips(strips, one_color(PATH_COLOR), 0.0),))


def decode_occupancy_grid(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """An OccupancyGrid coloured with RViz's ``map`` (default), ``costmap`` or ``raw`` palette; row 0 is y = 0 and
    the origin pose is cell (0, 0)'s corner."""
    msg = deserialize(data, "nav_msgs/msg/OccupancyGrid")
    frame, stamp = header_of(msg)
    info = msg.info
    width, height, resolution = int(info.width), int(info.height), float(info.resolution)
    cells: np.ndarray = msg.data
    if width * height != len(cells):
        raise MsgError(f"{width}x{height} map with {len(cells)} cells")
    if width * height > MAX_CELLS:
        raise MsgError(f"{width}x{height} map is too big")
    if not (np.isfinite(resolution) and resolution > 0):
        raise MsgError(f"map resolution {resolution}")
    if max(width, height) * resolution > FLOAT32_MAX:  # its corners would be infinite where the viewer draws them
        raise MsgError(f"{width}x{height} map of {resolution:g} m cells is beyond float32")
    index = np.asarray(cells).view(np.uint8).reshape(height, width)
    rgba = PALETTES[options.map_scheme][index]
    return Decoded(frame, stamp, (GridMap(rgba, resolution, pose_of(info.origin)),))


def apply_grid_update(map_data: bytes | memoryview, update_data: bytes | memoryview) -> memoryview:
    """The OccupancyGrid ``map_data`` (CDR) with the ``map_msgs/msg/OccupancyGridUpdate`` ``update_data`` (CDR)
    applied, as RViz's Map display does (nav2's costmap updates): the update's ``width`` x ``height`` cells copied row
    by row to cell (``x``, ``y``) on; the map's header and info kept. An update outside the map is refused, as RViz
    refuses it ("Update area outside of original map area"): ``MsgError``; so is one with fewer cells than it says.
    (RViz 2's ``updateMapDataInMemory`` copies the update's first row to every row; this copies each row, as RViz 1
    and nav2's costmap subscriber do.)"""
    grid = deserialize(map_data, "nav_msgs/msg/OccupancyGrid")
    update = deserialize(update_data, "map_msgs/msg/OccupancyGridUpdate")
    width, height = int(grid.info.width), int(grid.info.height)
    x, y, w, h = int(update.x), int(update.y), int(update.width), int(update.height)
    if len(grid.data) != width * height:
        raise MsgError(f"{width}x{height} map with {len(grid.data)} cells")
    if x < 0 or y < 0 or x + w > width or y + h > height:
        raise MsgError(f"update area {w}x{h} at ({x}, {y}) outside of the {width}x{height} map")
    if len(update.data) < w * h:
        raise MsgError(f"{w}x{h} update with {len(update.data)} cells")
    cells = np.array(grid.data, dtype=np.int8).reshape(height, width)
    cells[y : y + h, x : x + w] = np.asarray(update.data[: w * h], dtype=np.int8).reshape(h, w)
    grid.data = cells.reshape(-1)
    return typestore().serialize_cdr(grid, "nav_msgs/msg/OccupancyGrid")


def decode_grid_cells(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """GridCells as flat boxes, ``cell_width`` x ``cell_height``, centred on the cells."""
    msg = deserialize(data, "nav_msgs/msg/GridCells")
    frame, stamp = header_of(msg)
    centers = points3(msg.cells)
    half = np.array([msg.cell_width / 2, msg.cell_height / 2, 0.0], dtype=np.float32)
    if not np.all(np.isfinite(half)):
        raise MsgError(f"cell size {msg.cell_width} x {msg.cell_height}")
    n = centers.shape[0]
    q = np.zeros((n, 4), dtype=np.float32)
    q[:, 3] = 1.0
    return Decoded(frame, stamp, (Boxes(centers, np.tile(half, (n, 1)), q, one_color(PATH_COLOR)),))
