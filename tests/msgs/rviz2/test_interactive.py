"""InteractiveMarkerUpdate as RViz's InteractiveMarkers display shows it (display only): controls' markers at
the interactive marker's pose, pose updates, erases."""

from __future__ import annotations

import math

import numpy as np
from msgs_build import T, cdr, header, marker_msg, pose, quat

from r2d2_viz.msgs.rviz2.interactive import InteractiveMarkers, compose, decode_interactive_update
from r2d2_viz.msgs.shapes import DecodeOptions, Pose


def _im(name: str, markers: list, at: tuple[float, float, float] = (0.0, 0.0, 0.0), yaw: float = 0.0) -> object:
    control = T("visualization_msgs/msg/InteractiveMarkerControl")(
        name="c", orientation=quat(), orientation_mode=0, interaction_mode=0, always_visible=True,
        markers=markers, independent_marker_orientation=False, description="",
    )  # fmt: skip
    q = quat(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return T("visualization_msgs/msg/InteractiveMarker")(
        header=header("map"), pose=pose(*at, q=q), name=name, description="", scale=1.0, menu_entries=[],
        controls=[control],
    )  # fmt: skip


def _update(markers: list, poses: list = (), erases: list = ()) -> bytes:
    msg = T("visualization_msgs/msg/InteractiveMarkerUpdate")(
        server_id="s", seq_num=1, type=1, markers=markers, poses=list(poses), erases=list(erases)
    )
    return cdr(msg)


def test_a_control_marker_without_a_frame_is_relative_to_the_interactive_marker() -> None:
    cube = marker_msg(1, header=header(""), pose=pose(1.0, 0.0, 0.0))
    arrow = marker_msg(0, header=header("tool"), pose=pose(0.0, 0.0, 2.0))  # its own frame: stays there
    ops = decode_interactive_update(
        _update([_im("knob", [cube, arrow], (5.0, 0.0, 0.0), yaw=math.pi / 2)]), DecodeOptions()
    )
    assert [(op.action, op.ns, op.id) for op in ops] == [
        ("deleteall", "knob", 0),
        ("add", "knob", 0),
        ("add", "knob", 1),
    ]
    placed, own = ops[1].decoded, ops[2].decoded
    assert placed.frame_id == "map" and own.frame_id == "tool"
    # by hand: (1, 0, 0) turned 90° about z is (0, 1, 0), plus (5, 0, 0)
    np.testing.assert_allclose(placed.items[0].T_frame_item.translation, (5.0, 1.0, 0.0), atol=1e-9)
    assert own.items[0].T_frame_item.translation == (0.0, 0.0, 2.0)


def test_pose_updates_need_the_markers_seen_before_and_erases_forget_them() -> None:
    cube = marker_msg(1, header=header(""))
    moved = T("visualization_msgs/msg/InteractiveMarkerPose")(header=header("map"), pose=pose(0.0, 3.0, 0.0), name="k")
    state = InteractiveMarkers()
    assert decode_interactive_update(_update([], [moved]), DecodeOptions()) == []  # alone: nothing known
    state.decode(_update([_im("k", [cube])]))
    (op,) = state.decode(_update([], [moved]))
    assert op.action == "add" and op.decoded.items[0].T_frame_item.translation == (0.0, 3.0, 0.0)
    assert [(o.action, o.ns) for o in state.decode(_update([], [], ["k"]))] == [("deleteall", "k")]
    assert state.decode(_update([], [moved])) == []


def test_compose_is_the_matrix_product() -> None:
    a = Pose((1.0, 2.0, 3.0), (0.0, 0.0, math.sin(0.3), math.cos(0.3)))
    b = Pose((0.5, -1.0, 0.0), (math.sin(0.2), 0.0, 0.0, math.cos(0.2)))

    def matrix(p: Pose) -> np.ndarray:
        x, y, z, w = p.xyzw
        R = np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ])  # fmt: skip
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = R, p.translation
        return m

    np.testing.assert_allclose(matrix(compose(a, b)), matrix(a) @ matrix(b), atol=1e-12)
