"""nav2's VoxelGrid: the MARKED voxels as boxes, decoded from the bits as ``nav2_voxel_grid/voxel_grid.hpp`` lays
them out. Expected centres by hand (:data:`stackbags.VOXEL_CENTERS`), and a random grid against nav2's
``VoxelGrid::getVoxel`` transcribed below voxel by voxel."""

from __future__ import annotations

import numpy as np
import pytest
from stackbags import STORE, T0, VOXEL_CENTERS, VOXEL_RES, voxel_grid

from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.shapes import Boxes
from r2d2_viz.msgs.stacks.voxels import marked
from r2d2_viz.msgs.typestore import MsgError

TYPE = "nav2_msgs/msg/VoxelGrid"
FREE, UNKNOWN, MARKED = 0, 1, 2


def get_voxel(x: int, y: int, z: int, size_x: int, size_y: int, size_z: int, data: list[int]) -> int:
    """nav2_voxel_grid's ``VoxelGrid::getVoxel``, line by line."""
    if x >= size_x or y >= size_y or z >= size_z:
        return UNKNOWN
    full_mask = ((1 << z) << 16) | (1 << z)
    result = data[y * size_x + x] & full_mask
    bits = bin(result).count("1")
    if bits < 2:
        return FREE if bits < 1 else UNKNOWN
    return MARKED


def test_marked_voxels_by_hand() -> None:
    decoded = decode(TYPE, voxel_grid(T0))
    (item,) = decoded.items
    assert isinstance(item, Boxes) and decoded.frame_id == "odom"
    np.testing.assert_allclose(item.centers, VOXEL_CENTERS, atol=1e-6)
    np.testing.assert_allclose(item.half_sizes, [np.array(VOXEL_RES) / 2] * 3, atol=1e-7)
    assert tuple(item.colors[0]) == (255, 0, 0, 255)  # costmap_2d_markers' MARKED colour


def test_random_grid_against_get_voxel() -> None:
    rng = np.random.default_rng(46)
    sx, sy, sz = 7, 5, 16
    data = rng.integers(0, 2**32, sx * sy, dtype=np.uint64).astype(np.uint32)
    expected = [(x, y, z) for y in range(sy) for x in range(sx) for z in range(sz)
                if get_voxel(x, y, z, sx, sy, sz, [int(v) for v in data]) == MARKED]  # fmt: skip
    assert expected and marked(data, sx, sy, sz).tolist() == [list(v) for v in expected]
    assert marked(data, sx, sy, 3).tolist() == [list(v) for v in expected if v[2] < 3]  # the bits above size_z unread


def _grid(**changes: object) -> bytes:
    msg = STORE.deserialize_cdr(voxel_grid(T0), TYPE)
    for key, value in changes.items():
        setattr(msg, key, value)
    return bytes(STORE.serialize_cdr(msg, TYPE))


@pytest.mark.parametrize(
    ("changes", "words"),
    [({"size_z": 17}, "16 at most"), ({"size_x": 4}, "columns"), ({"data": np.zeros(0, np.uint32)}, "columns")],
)
def test_bad_grids_are_refused(changes: dict[str, object], words: str) -> None:
    with pytest.raises(MsgError, match=words):
        decode(TYPE, _grid(**changes))
