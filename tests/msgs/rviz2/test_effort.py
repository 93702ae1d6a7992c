"""RViz's Effort display maths (effort_display.cpp, effort_visual.cpp; tf2's Quaternion(axis, angle)), by hand."""

from __future__ import annotations

import math

import numpy as np
from msgs_build import rviz_rainbow

from r2d2_viz.msgs.geometry import quat_matrix
from r2d2_viz.msgs.rviz2.effort import EffortJoint, axis_rotation, effort_ops, effort_value


def test_the_arc_turns_about_the_cross_product_of_the_axis_and_z() -> None:
    assert axis_rotation((0.0, 0.0, 1.0)) == (0.0, 0.0, 0.0, 1.0)  # along z: NaN in tf2, identity
    assert axis_rotation((0.0, 0.0, -1.0)) == (0.0, 0.0, 0.0, 1.0)
    # x: x × z = (0, -1, 0), 90°: a quarter turn about -y, which takes z to -x (the arc's plane ⟂ the axis)
    R = quat_matrix(axis_rotation((1.0, 0.0, 0.0)))
    np.testing.assert_allclose(R @ [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], atol=1e-12)


def test_effort_value_and_limits() -> None:
    assert effort_value(5.0, 10.0) == 0.55
    assert effort_value(-50.0, 10.0) == 1.05
    assert effort_value(0.3, 0.0) == 0.3 + 0.05  # no limit: |effort| + 0.05


def test_ops_per_joint_of_the_model_and_what_is_not_drawn() -> None:
    joints = {
        "a": EffortJoint("a", "link_a", (0.0, 0.0, 1.0), 2.0),
        "b": EffortJoint("b", "link_b", (0.0, 0.0, 1.0), 0.0),
    }
    ops = effort_ops(["b", "unknown", "a"], [float("nan"), 1.0, 1.0], joints, 7)
    assert [(op.ns, op.id) for op in ops] == [("effort", 0)]  # b: NaN; unknown: not in the model
    line, arrow = ops[0].decoded.items
    assert ops[0].decoded.frame_id == "link_a" and ops[0].decoded.stamp_ns == 7
    e = 0.5 + 0.05
    r = 0.05 + e * 0.5
    np.testing.assert_allclose(line.strips[0][0], [0.0, r, 0.0], atol=1e-7)  # i = 0: (r sin 0, r cos 0, 0)
    np.testing.assert_allclose(line.strips[0][8], [r, r * math.cos(math.pi / 2), 0.0], atol=1e-7)
    assert tuple(line.colors[0, :3].tolist()) == rviz_rainbow(e)
    np.testing.assert_allclose(arrow.vectors, [[-0.04, 0.0, 0.0]], atol=1e-7)  # positive: along -x
    assert effort_ops(["a"], [1.0, 2.0], joints, 0) == []  # counts differ: RViz refuses the message
