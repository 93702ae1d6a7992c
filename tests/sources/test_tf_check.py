"""Recorded /tf against the kinematics: quiet within 1 mm / 1 mrad, one message beyond."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.sources.base import TfRecords
from r2d2_viz.sources.tf_check import disagreement, urdf_edges

# a base, a link turning about z 0.5 m up (revolute), a camera fixed 0.1 m along its x
URDF = """<robot name="r"><link name="base"/><link name="arm"/><link name="cam"/>
<joint name="turn" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.5"/>
<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
<joint name="mount" type="fixed"><parent link="arm"/><child link="cam"/><origin xyz="0.1 0 0"/></joint></robot>"""


@pytest.fixture
def tree(tmp_path: Path):
    path = tmp_path / "r.urdf"
    path.write_text(URDF)
    return compile_tree(load_urdf(path))


def _records(rows: list[tuple[int, str, str, tuple, tuple]]) -> TfRecords:
    return TfRecords(
        np.array([r[0] for r in rows], dtype=np.int64),
        tuple(r[1] for r in rows),
        tuple(r[2] for r in rows),
        np.array([r[3] for r in rows], dtype=np.float64),
        np.array([r[4] for r in rows], dtype=np.float64),
    )


def _yaw(angle: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2))


def test_urdf_edges_name_every_joint_with_a_transform(tree) -> None:
    assert set(urdf_edges(tree)) == {("base", "arm"), ("arm", "cam")}


def test_agreeing_tf_is_quiet_and_each_record_uses_the_state_held_at_its_time(tree) -> None:
    times = np.array([100, 200], dtype=np.int64)
    q = np.array([[0.3], [0.9]])
    # base → arm at t=150 uses the state of t=100 (0.3 rad); at t=250 the state of t=200 (0.9 rad)
    records = _records(
        [
            (150, "base", "arm", (0, 0, 0.5), _yaw(0.3)),
            (250, "base", "arm", (0, 0, 0.5), _yaw(0.9)),
            (250, "arm", "cam", (0.1, 0, 0), (0, 0, 0, 1)),
            (250, "map", "base", (5, 5, 0), (0, 0, 0, 1)),  # not the URDF's: not checked
            (50, "base", "arm", (9, 9, 9), (0, 0, 0, 1)),  # before the first state: not checked
        ]
    )
    assert disagreement(tree, records, times, q) is None


def test_two_millimetres_or_two_milliradians_off_is_reported(tree) -> None:
    times, q = np.array([100], dtype=np.int64), np.array([[0.3]])
    off_t = _records([(150, "base", "arm", (0, 0, 0.502), _yaw(0.3))])
    message = disagreement(tree, off_t, times, q)
    assert message is not None and "2 mm" in message and "base → arm" in message
    off_r = _records([(150, "base", "arm", (0, 0, 0.5), _yaw(0.302))])
    message = disagreement(tree, off_r, times, q)
    assert message is not None and "2 mrad" in message
    near = _records([(150, "base", "arm", (0, 0, 0.5005), _yaw(0.3005))])  # 0.5 mm, 0.5 mrad
    assert disagreement(tree, near, times, q) is None
