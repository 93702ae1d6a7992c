"""The definitions r2d2-viz carries for live graphs lay every type out as the upstream .msg files do (registered
in rosbags' own typestore by :mod:`stackbags`), in every distro's store; a message written with the upstream files
reads back the same through the app's store."""

from __future__ import annotations

import pytest
from stack_msgs import MSG_FILES
from stackbags import STORE, T0, detections_2d, detections_3d, particle_cloud, voxel_grid

from r2d2_viz.msgs.stacks.definitions import STACK_TYPES
from r2d2_viz.msgs.typestore import DISTROS, deserialize, typestore


def test_every_upstream_type_is_carried() -> None:
    assert set(STACK_TYPES) == set(MSG_FILES)


@pytest.mark.parametrize("distro", list(DISTROS))
def test_same_fields_as_upstream(distro: str) -> None:
    store = typestore(distro)
    for name in MSG_FILES:
        assert store.fielddefs[name] == STORE.fielddefs[name], name


@pytest.mark.parametrize(
    ("name", "make"),
    [
        ("nav2_msgs/msg/ParticleCloud", particle_cloud),
        ("nav2_msgs/msg/VoxelGrid", voxel_grid),
        ("vision_msgs/msg/Detection2DArray", detections_2d),
        ("vision_msgs/msg/Detection3DArray", detections_3d),
    ],
)
def test_round_trip(name: str, make) -> None:
    data = make(T0)
    assert bytes(typestore().serialize_cdr(deserialize(data, name), name)) == data
