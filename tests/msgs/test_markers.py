"""Marker / MarkerArray: every type and action, sizes per RViz's marker conventions (worked out by hand)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from msgs_build import T, cdr, color, duration, header, marker_msg, pose, quat, vec

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.markers import decode_marker, decode_marker_array
from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.shapes import DecodeOptions, MarkerOp, Pose
from r2d2_viz.msgs.typestore import MsgError

OPTIONS = DecodeOptions()
Q90Z = quat(0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))  # 90° about z


def marker(kind: int, action: int = 0, **kw: object) -> object:
    args: dict[str, object] = {
        "header": header("/odom", 3, 0),
        "ns": "demo",
        "id": 7,
        "pose": pose(1.0, 2.0, 3.0, Q90Z),
        "scale": vec(0.2, 0.4, 0.6),
        "color": color(1.0, 0.5, 0.0, 1.0),
        "lifetime": duration(2, 500),
    }
    args.update(kw)
    return marker_msg(kind, action=action, **args)


def one(kind: int, **kw: object) -> MarkerOp:
    (op,) = decode_marker(cdr(marker(kind, **kw)), OPTIONS)
    return op


def item(op: MarkerOp) -> object:
    assert op.action == "add" and op.decoded is not None
    (shape,) = op.decoded.items
    return shape


ORANGE = [255, 128, 0, 255]  # color(1, 0.5, 0): 0.5·255 = 127.5 rounds to 128
MARKER_POSE = Pose((1.0, 2.0, 3.0), (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)))


def test_key_frame_stamp_lifetime_and_pose() -> None:
    op = one(1)
    assert (op.ns, op.id, op.lifetime_ns, op.frame_locked) == ("demo", 7, 2_000_000_500, False)
    assert op.decoded is not None and op.decoded.frame_id == "odom" and op.decoded.stamp_ns == 3_000_000_000
    box = item(op)
    assert isinstance(box, shapes.Boxes)
    assert box.T_frame_item.translation == MARKER_POSE.translation
    np.testing.assert_allclose(box.T_frame_item.xyzw, MARKER_POSE.xyzw)


def test_arrow_pose_form_and_two_point_form() -> None:
    arrow = item(one(0))
    assert isinstance(arrow, shapes.Arrows)
    # pose form: scale.x = length along the pose's x, scale.y = shaft diameter
    np.testing.assert_allclose(arrow.vectors, [[0.2, 0, 0]])
    assert arrow.radius == pytest.approx(0.2) and arrow.colors.tolist() == [ORANGE]
    arrow = item(one(0, points=[vec(1, 1, 1, "Point"), vec(1, 1, 3, "Point")]))
    assert isinstance(arrow, shapes.Arrows)
    # two-point form: from points[0] to points[1], scale.x = shaft diameter
    np.testing.assert_allclose(arrow.origins, [[1, 1, 1]])
    np.testing.assert_allclose(arrow.vectors, [[0, 0, 2]])
    assert arrow.radius == pytest.approx(0.1)


def test_cube_sphere_cylinder_sizes() -> None:
    box, sphere, cylinder = (item(one(k)) for k in (1, 2, 3))
    assert isinstance(box, shapes.Boxes) and isinstance(sphere, shapes.Ellipsoids)
    np.testing.assert_allclose(box.half_sizes, [[0.1, 0.2, 0.3]])  # scale is the full size
    np.testing.assert_allclose(sphere.half_sizes, [[0.1, 0.2, 0.3]])
    assert isinstance(cylinder, shapes.Cylinders)
    np.testing.assert_allclose(cylinder.lengths, [0.6])
    np.testing.assert_allclose(cylinder.radii, [0.15])  # mean of the base's half diameters 0.1 and 0.2


def test_line_strip_and_line_list_with_per_point_colours() -> None:
    p = [vec(0, 0, 0, "Point"), vec(1, 0, 0, "Point"), vec(1, 1, 0, "Point")]
    strip = item(one(4, points=p))
    assert isinstance(strip, shapes.LineStrips)
    assert len(strip.strips) == 1 and strip.strips[0].tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0]]
    assert strip.radius == pytest.approx(0.1)  # scale.x is the line width
    cs = [color(1, 0, 0), color(0, 1, 0), color(0, 0, 1)]
    strip = item(one(4, points=p, colors=cs))
    assert isinstance(strip, shapes.LineStrips)
    assert [s.tolist() for s in strip.strips] == [[[0, 0, 0], [1, 0, 0]], [[1, 0, 0], [1, 1, 0]]]
    assert strip.colors.tolist() == [[255, 0, 0, 255], [0, 255, 0, 255]]
    lines = item(one(5, points=p, colors=cs))  # odd count: the last point has no partner
    assert isinstance(lines, shapes.LineStrips)
    assert [s.tolist() for s in lines.strips] == [[[0, 0, 0], [1, 0, 0]]]
    assert lines.colors.tolist() == [[255, 0, 0, 255]]


def test_cube_list_sphere_list_points() -> None:
    p = [vec(0, 0, 0, "Point"), vec(5, 0, 0, "Point")]
    cubes, spheres, points = (item(one(k, points=p)) for k in (6, 7, 8))
    assert isinstance(cubes, shapes.Boxes) and isinstance(spheres, shapes.Ellipsoids)
    np.testing.assert_allclose(cubes.centers, [[0, 0, 0], [5, 0, 0]])
    np.testing.assert_allclose(spheres.half_sizes, [[0.1, 0.2, 0.3]] * 2)
    assert isinstance(points, shapes.Points)
    assert points.radius == pytest.approx(0.1) and points.colors.tolist() == [ORANGE]


def test_text_mesh_and_triangles() -> None:
    text = item(one(9, text="hello"))
    assert isinstance(text, shapes.Text)
    assert text.text == "hello" and text.height == pytest.approx(0.6) and list(text.color) == ORANGE
    mesh = item(one(10, mesh_resource="package://pkg/m.dae", mesh_use_embedded_materials=True))
    assert isinstance(mesh, shapes.MeshResource)
    assert mesh.uri == "package://pkg/m.dae" and mesh.color is None
    assert mesh.scale == pytest.approx((0.2, 0.4, 0.6))
    tri = [vec(1, 0, 0, "Point"), vec(0, 1, 0, "Point"), vec(0, 0, 1, "Point"), vec(9, 9, 9, "Point")]
    mesh = item(one(11, points=tri, colors=[color(0, 0, 1)]))  # one colour per triangle
    assert isinstance(mesh, shapes.TriangleMesh)
    np.testing.assert_allclose(mesh.vertices, [[0.2, 0, 0], [0, 0.4, 0], [0, 0, 0.6]])  # scaled by scale
    assert mesh.indices.tolist() == [[0, 1, 2]]
    assert mesh.colors.tolist() == [[0, 0, 255, 255]] * 3


def test_actions_and_array() -> None:
    ops = decode_marker_array(
        cdr(
            T("visualization_msgs/msg/MarkerArray")(
                markers=[marker(1), marker(1, action=2, id=8), marker(1, action=3, ns="")]
            )
        ),
        OPTIONS,
    )
    assert [(o.action, o.ns, o.id) for o in ops] == [("add", "demo", 7), ("delete", "demo", 8), ("deleteall", "", 7)]
    assert ops[1].decoded is None


def test_bad_type_action_and_bytes() -> None:
    with pytest.raises(MsgError, match="type"):
        decode_marker(cdr(marker(42)), OPTIONS)
    with pytest.raises(MsgError, match="action"):
        decode_marker(cdr(marker(1, action=1)), OPTIONS)  # 1 is deprecated in ROS 2 and unknown here
    data = cdr(marker(4, points=[vec(0, 0, 0, "Point")] * 4))
    for cut in (10, 60, len(data) - 5):
        with pytest.raises(ValueError):
            decode("visualization_msgs/msg/Marker", data[:cut])
    with pytest.raises(MsgError, match="non-finite"):
        decode_marker(cdr(marker(1, pose=pose(math.nan))), OPTIONS)
