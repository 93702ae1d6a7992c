"""nav2_msgs VoxelGrid (nav2's voxel layer, ``publish_voxel_map``) as nav2's own viewer of it draws it
(``nav2_costmap_2d/src/costmap_2d_markers.cpp``: a CUBE_LIST of the MARKED voxels, red, alpha 1): a box per
occupied voxel, ``resolutions`` in size, centred on ``origin + (index + 0.5) · resolutions``, in the header frame.

The bits, as ``nav2_voxel_grid/voxel_grid.hpp`` lays them out: ``data[y · size_x + x]`` is the column (x, y); voxel
z (< 16) is its bits z and z + 16 — both set: MARKED; one: UNKNOWN; none: FREE (``VoxelGrid::getVoxel``).
Decoded for every column at once with numpy.
"""

from __future__ import annotations

import numpy as np

from r2d2_viz.msgs.geometry import FLOAT32_MAX, header_of, one_color, xyz
from r2d2_viz.msgs.shapes import Boxes, Decoded, DecodeOptions, Rgba8
from r2d2_viz.msgs.typestore import MsgError, deserialize

MARKED_COLOR: Rgba8 = (255, 0, 0, 255)  # costmap_2d_markers' g_colors_{r,g,b,a}[MARKED]
MAX_Z = 16


def marked(data: np.ndarray, size_x: int, size_y: int, size_z: int) -> np.ndarray:
    """The ``(N, 3)`` indices (x, y, z) of the MARKED voxels, ordered as nav2's viewer visits them (y, x, z)."""
    columns = np.asarray(data, dtype=np.uint32)
    both = columns & (columns >> 16) & np.uint32((1 << size_z) - 1)  # bit z set: voxel z MARKED
    index = np.flatnonzero(both)  # only the columns with a marked voxel are looked into
    bits = (both[index, None] >> np.arange(size_z, dtype=np.uint32)) & 1
    row, k = np.nonzero(bits)
    y, x = np.divmod(index[row], size_x)
    return np.stack([x, y, k], axis=1)


def decode_voxel_grid(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """The occupied voxels as boxes."""
    msg = deserialize(data, "nav2_msgs/msg/VoxelGrid")
    frame, stamp = header_of(msg)
    sx, sy, sz = int(msg.size_x), int(msg.size_y), int(msg.size_z)
    if sz > MAX_Z:
        raise MsgError(f"{sz} voxels high: a VoxelGrid holds 16 at most")
    if len(msg.data) != sx * sy:
        raise MsgError(f"{sx}x{sy} voxel grid with {len(msg.data)} columns")
    res = np.array(xyz(msg.resolutions), dtype=np.float64)
    origin = np.array(xyz(msg.origin), dtype=np.float64)
    if not np.all(res > 0) or max(sx, sy, sz) * float(res.max()) > FLOAT32_MAX:
        raise MsgError(f"voxel resolutions {res.tolist()}")
    index = marked(msg.data, sx, sy, sz)
    centers = (origin + (index + 0.5) * res).astype(np.float32)
    n = len(centers)
    half = np.tile((res / 2).astype(np.float32), (n, 1))
    q = np.zeros((n, 4), dtype=np.float32)
    q[:, 3] = 1.0
    return Decoded(frame, stamp, (Boxes(centers, half, q, one_color(options.display_color or MARKED_COLOR)),))
