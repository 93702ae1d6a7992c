"""nav2's and vision_msgs' displays in a recording: the stack bag (:mod:`stackbags`, written by rosbags with the
upstream .msg files) through the real CLI, read back with Rerun's own reader. Values by hand, as in the decoders'
tests: what the viewer gets is what the messages say."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rrd import Rows, read_recording
from stackbags import T0, VOXEL_CENTERS, stack_recordings

S = 1_000_000_000
AT = T0 + S // 10  # every display message's receive time


@pytest.fixture(scope="module")
def plain(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Rows]:
    return read_recording(stack_recordings(tmp_path_factory)["plain"])


def _at(rows: Rows, component: str, drawn: str = "") -> list:
    """The values of ``component`` in the row logged at the messages' time that has it (and ``drawn``: the row of
    the drawing, not the one that placed the entity in the fixed frame from the start)."""
    have = [i for i, t in enumerate(rows.times) if t == AT and rows.temporal[drawn or component][i] is not None]
    found = [rows.temporal[component][i] for i in have]
    assert len(found) == 1, (component, found)
    return found[0]


def test_particles_in_their_frame(plain: dict[str, Rows]) -> None:
    rows = plain["/particlecloud"]
    assert _at(rows, "CoordinateFrame:frame", "LineStrips3D:strips") == ["map"]
    strips = np.array(_at(rows, "LineStrips3D:strips"))
    assert strips.shape == (64, 5, 3)
    np.testing.assert_allclose(strips[0], [[1, 2, 0], [1.16, 2, 0], [1.12, 2.032, 0], [1.16, 2, 0], [1.12, 1.968, 0]],
                               atol=1e-6)  # fmt: skip
    assert _at(rows, "LineStrips3D:colors") == [0xFF1900FF]  # (255, 25, 0), alpha 1


def test_voxels_in_their_frame(plain: dict[str, Rows]) -> None:
    rows = plain["/voxel_grid"]
    assert _at(rows, "CoordinateFrame:frame", "Boxes3D:centers") == ["odom"]
    np.testing.assert_allclose(_at(rows, "Boxes3D:centers"), VOXEL_CENTERS, atol=1e-6)
    np.testing.assert_allclose(_at(rows, "Boxes3D:half_sizes"), [[0.1, 0.1, 0.125]] * 3, atol=1e-7)
    assert _at(rows, "Boxes3D:colors") == [0xFF0000FF]


def test_3d_detections(plain: dict[str, Rows]) -> None:
    rows = plain["/detections_3d"]
    assert _at(rows, "CoordinateFrame:frame", "Boxes3D:centers") == ["map"]
    np.testing.assert_allclose(_at(rows, "Boxes3D:centers"), [[2, 0, 0.5], [-2, 1, 0.1]], atol=1e-6)
    np.testing.assert_allclose(_at(rows, "Boxes3D:quaternions")[0], [0, 0, 0.5**0.5, 0.5**0.5], atol=1e-6)
    assert _at(rows, "Boxes3D:labels") == ["Car 0.75", "tree 0.50"]
    assert _at(rows, "Boxes3D:colors") == [0xFFA500FF, 0xBEBEBEFF]
    assert _at(rows, "Boxes3D:fill_mode") == [3]  # Solid (Only Edge off)


def test_nothing_said_about_them(tmp_path_factory: pytest.TempPathFactory) -> None:
    stderr = Path(stack_recordings(tmp_path_factory)["plain"]).with_suffix(".stderr").read_text()
    assert "cannot be shown" not in stderr and "particlecloud" not in stderr and "detections" not in stderr
