"""geometry_msgs poses / points / polygons / wrenches / twists and nav_msgs Odometry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from msgs_build import T, cdr, header, pose, quat, vec

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.poses import (
    decode_odometry,
    decode_point_stamped,
    decode_polygon_stamped,
    decode_pose_array,
    decode_pose_stamped,
    decode_pose_with_covariance,
    decode_twist_stamped,
    decode_wrench_stamped,
)
from r2d2_viz.msgs.shapes import DecodeOptions

OPTIONS = DecodeOptions()
Q90Z = quat(0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))


def quat_matrix(q: tuple[float, float, float, float]) -> np.ndarray:
    """Rotation matrix of xyzw via Rodrigues (axis-angle), independent of the code under test."""
    x, y, z, w = q
    angle = 2 * math.atan2(math.sqrt(x * x + y * y + z * z), w)
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-12:
        return np.eye(3)
    k = np.array([x, y, z]) / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def test_pose_stamped_arrow_along_the_pose_x_axis() -> None:
    msg = T("geometry_msgs/msg/PoseStamped")(header=header("/base"), pose=pose(1, 2, 3, Q90Z))
    decoded = decode_pose_stamped(cdr(msg), OPTIONS)
    assert decoded.frame_id == "base"
    (arrow,) = decoded.items
    assert isinstance(arrow, shapes.Arrows)
    np.testing.assert_allclose(arrow.origins, [[1, 2, 3]])
    np.testing.assert_allclose(arrow.vectors, [[0, 1.3, 0]], atol=1e-6)  # x turned 90° about z; 1 m + 0.3 m head


def test_pose_array() -> None:
    msg = T("geometry_msgs/msg/PoseArray")(header=header(), poses=[pose(0, 0, 0), pose(1, 0, 0, Q90Z)])
    (arrows,) = decode_pose_array(cdr(msg), OPTIONS).items
    assert isinstance(arrows, shapes.Arrows)
    np.testing.assert_allclose(arrows.vectors, [[0.3, 0, 0], [0, 0.3, 0]], atol=1e-6)


@pytest.mark.parametrize("kind", ["odometry", "pose_with_covariance"])
def test_covariance_ellipsoid_reproduces_the_covariance(kind: str) -> None:
    rng = np.random.default_rng(3)
    A = rng.normal(size=(3, 3))
    cov3 = A @ A.T + 0.1 * np.eye(3)
    cov = np.zeros((6, 6))
    cov[:3, :3] = cov3
    with_cov = T("geometry_msgs/msg/PoseWithCovariance")(pose=pose(4, 5, 6), covariance=cov.reshape(-1))
    if kind == "odometry":
        twist = T("geometry_msgs/msg/TwistWithCovariance")(
            twist=T("geometry_msgs/msg/Twist")(linear=vec(), angular=vec()), covariance=np.zeros(36)
        )
        msg = T("nav_msgs/msg/Odometry")(header=header("odom"), child_frame_id="base", pose=with_cov, twist=twist)
        assert len(decode_odometry(cdr(msg), OPTIONS).items) == 1  # the arrow alone, unless asked
        decoded = decode_odometry(cdr(msg), DecodeOptions(odometry_covariance=True))
    else:
        msg = T("geometry_msgs/msg/PoseWithCovarianceStamped")(header=header("odom"), pose=with_cov)
        decoded = decode_pose_with_covariance(cdr(msg), OPTIONS)
    arrow, ellipsoid = decoded.items
    assert isinstance(arrow, shapes.Arrows) and isinstance(ellipsoid, shapes.Ellipsoids)
    np.testing.assert_allclose(ellipsoid.centers, [[4, 5, 6]])
    # 1 sigma: R·diag(half²)·Rᵀ must give the covariance back
    R = quat_matrix(tuple(float(v) for v in ellipsoid.xyzw[0]))  # type: ignore[arg-type]
    np.testing.assert_allclose(R @ np.diag(ellipsoid.half_sizes[0].astype(float) ** 2) @ R.T, cov3, rtol=1e-4)
    sigmas = np.sqrt(np.linalg.eigvalsh(cov3))
    np.testing.assert_allclose(sorted(ellipsoid.half_sizes[0]), sigmas, rtol=1e-5)


def test_point_polygon_wrench_twist() -> None:
    (sphere,) = decode_point_stamped(
        cdr(T("geometry_msgs/msg/PointStamped")(header=header(), point=vec(1, 2, 3, "Point"))), OPTIONS
    ).items
    assert isinstance(sphere, shapes.Ellipsoids)
    np.testing.assert_allclose(sphere.centers, [[1, 2, 3]])
    np.testing.assert_allclose(sphere.half_sizes, [[0.2, 0.2, 0.2]])
    polygon = T("geometry_msgs/msg/Polygon")(
        points=[vec(0, 0, 0, "Point32"), vec(1, 0, 0, "Point32"), vec(1, 1, 0, "Point32")]
    )
    (strips,) = decode_polygon_stamped(
        cdr(T("geometry_msgs/msg/PolygonStamped")(header=header(), polygon=polygon)), OPTIONS
    ).items
    assert isinstance(strips, shapes.LineStrips)
    assert strips.strips[0].tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 0]]  # closed
    wrench = T("geometry_msgs/msg/Wrench")(force=vec(1, 0, 0), torque=vec(0, 0, 3))
    force, torque = decode_wrench_stamped(
        cdr(T("geometry_msgs/msg/WrenchStamped")(header=header(), wrench=wrench)), OPTIONS
    ).items
    assert isinstance(force, shapes.Arrows) and isinstance(torque, shapes.Arrows)
    np.testing.assert_allclose(force.vectors, [[2, 0, 0]])  # RViz's default force scale 2
    np.testing.assert_allclose(torque.vectors, [[0, 0, 6]])
    twist = T("geometry_msgs/msg/Twist")(linear=vec(0.5, 0, 0), angular=vec(0, 0, 1))
    linear, angular = decode_twist_stamped(
        cdr(T("geometry_msgs/msg/TwistStamped")(header=header(), twist=twist)), OPTIONS
    ).items
    assert isinstance(linear, shapes.Arrows) and isinstance(angular, shapes.Arrows)
    np.testing.assert_allclose(linear.vectors, [[0.5, 0, 0]])
    np.testing.assert_allclose(angular.vectors, [[0, 0, 1]])
