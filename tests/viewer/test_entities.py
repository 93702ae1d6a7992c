"""Entity paths from URDF names: any link name stays one path part, and reads back as itself."""

from __future__ import annotations

from pathlib import Path

import rerun as rr
from rrd import read_recording

from r2d2_viz.viewer import entities

ODD = ["base link", "arm/2", "ünïcode", "dots.and-dashes", "#hash"]


def test_odd_names_are_one_part_each_and_read_back(tmp_path: Path) -> None:
    out = tmp_path / "e.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    for name in ODD:
        rec.log(entities.tf_axes(name), rr.CoordinateFrame(name), static=True)
    rec.flush()
    rec.disconnect()
    recording = read_recording(out)
    for name in ODD:
        path = entities.tf_axes(name)
        assert path.replace("\\/", "").count("/") == 2  # /tf_axes/<one part>, whatever the name holds
        assert recording[path].static["CoordinateFrame:frame"][-1] == [name]
    assert entities.robot_shape("visual", "arm/2", 0) == "/robot/visual/" + rr.escape_entity_path_part("arm/2") + "/0"


def test_several_robots_each_have_their_own_paths_and_one_robot_keeps_the_old_ones() -> None:
    assert entities.robot_root() == entities.robot_root("") == "/robot"
    assert entities.robot_shape("visual", "base_link", 1) == "/robot/visual/base_link/1"
    assert entities.robot_shape("collision", "base_link", 0, "/robot2") == "/robots/robot2/collision/base_link/0"
    assert entities.robot_shape("visual", "l", 0, "/fleet/r1") == "/robots/fleet/r1/visual/l/0"
    assert entities.joints_root() == "/joints" and entities.joints_root("/robot2") == "/joints/robot2"
