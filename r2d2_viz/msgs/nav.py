"""nav_msgs Path, OccupancyGrid (RViz's map / costmap / raw palettes) and GridCells."""

from __future__ import annotations

import numpy as np

from r2d2_viz.msgs.colormaps import PALETTES
from r2d2_viz.msgs.geometry import header_of, one_color, points3, pose_of
from r2d2_viz.msgs.shapes import Boxes, Decoded, DecodeOptions, GridMap, LineStrips
from r2d2_viz.msgs.typestore import MsgError, deserialize

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
    index = np.asarray(cells).view(np.uint8).reshape(height, width)
    rgba = PALETTES[options.map_scheme][index]
    return Decoded(frame, stamp, (GridMap(rgba, resolution, pose_of(info.origin)),))


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
