"""geometry_msgs stamped poses, points, polygons, wrenches and twists, and nav_msgs Odometry.

Colours and sizes are RViz's display defaults: pose arrows (255, 25, 0), 1 m shaft + 0.3 m head, shaft radius
0.05; PoseArray arrows 0.3 m; points (204, 41, 204) radius 0.2; polygons (25, 255, 0); covariance ellipsoids
(204, 51, 204, alpha 0.3) at 1 sigma; wrench force (204, 51, 51) and torque (204, 204, 51) arrows x 2.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from r2d2_viz.msgs.geometry import covariance_ellipsoid, header_of, one_color, points3, pose_arrows, pose_of, xyz
from r2d2_viz.msgs.shapes import Arrows, Decoded, DecodeOptions, Ellipsoids, LineStrips, Pose, Shape
from r2d2_viz.msgs.typestore import deserialize

POSE_COLOR = (255, 25, 0, 255)
POSE_LENGTH = 1.3  # shaft 1 + head 0.3
POSE_RADIUS = 0.05
POSE_ARRAY_LENGTH = 0.3
POINT_COLOR = (204, 41, 204, 255)
POINT_RADIUS = 0.2
POLYGON_COLOR = (25, 255, 0, 255)
COVARIANCE_COLOR = (204, 51, 204, 77)
FORCE_COLOR = (204, 51, 51, 255)
TORQUE_COLOR = (204, 204, 51, 255)
WRENCH_SCALE = 2.0


def _arrows(poses: list[Pose], length: float, radius: float) -> Arrows:
    origins, vectors = pose_arrows(poses, length)
    return Arrows(origins, vectors, one_color(POSE_COLOR), radius)


def _with_covariance(msg: Any, pose_msg: Any, options: DecodeOptions, *, covariance: bool = True) -> Decoded:
    """A pose arrow and (``covariance``) its position covariance ellipsoid (an empty one when the covariance is
    not finite)."""
    frame, stamp = header_of(msg)
    pose = pose_of(pose_msg.pose)
    arrow = _arrows([pose], POSE_LENGTH, POSE_RADIUS)
    if not covariance:
        return Decoded(frame, stamp, (arrow,))
    ellipsoid: Ellipsoids = covariance_ellipsoid(pose_msg.covariance, pose, options.covariance_scale, COVARIANCE_COLOR)
    return Decoded(frame, stamp, (arrow, ellipsoid))


def decode_pose_stamped(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A PoseStamped as an arrow along the pose's x axis."""
    msg = deserialize(data, "geometry_msgs/msg/PoseStamped")
    frame, stamp = header_of(msg)
    return Decoded(frame, stamp, (_arrows([pose_of(msg.pose)], POSE_LENGTH, POSE_RADIUS),))


def decode_pose_array(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A PoseArray as one short arrow per pose."""
    msg = deserialize(data, "geometry_msgs/msg/PoseArray")
    frame, stamp = header_of(msg)
    poses = [pose_of(p) for p in msg.poses]
    return Decoded(frame, stamp, (_arrows(poses, POSE_ARRAY_LENGTH, POSE_RADIUS / 5),))


def decode_pose_with_covariance(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A PoseWithCovarianceStamped: arrow and position covariance ellipsoid."""
    msg = deserialize(data, "geometry_msgs/msg/PoseWithCovarianceStamped")
    return _with_covariance(msg, msg.pose, options)


def decode_odometry(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """An Odometry's pose (in the header frame): an arrow, and its position covariance ellipsoid when asked
    (``options.odometry_covariance``: RViz's Covariance property)."""
    msg = deserialize(data, "nav_msgs/msg/Odometry")
    return _with_covariance(msg, msg.pose, options, covariance=options.odometry_covariance)


def decode_point_stamped(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A PointStamped as a sphere."""
    msg = deserialize(data, "geometry_msgs/msg/PointStamped")
    frame, stamp = header_of(msg)
    center = np.array([xyz(msg.point)], dtype=np.float32)
    half = np.full((1, 3), POINT_RADIUS, dtype=np.float32)
    q = np.array([[0.0, 0.0, 0.0, 1.0]], dtype=np.float32)
    return Decoded(frame, stamp, (Ellipsoids(center, half, q, one_color(POINT_COLOR)),))


def decode_polygon_stamped(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A PolygonStamped as a closed line strip."""
    msg = deserialize(data, "geometry_msgs/msg/PolygonStamped")
    frame, stamp = header_of(msg)
    p = points3(msg.polygon.points)
    strips = (np.concatenate([p, p[:1]]),) if p.shape[0] > 1 else ()
    return Decoded(frame, stamp, (LineStrips(strips, one_color(POLYGON_COLOR), 0.0),))


def vector_pair(first: Any, second: Any, scale: float, colors: tuple[Any, Any], radius: float) -> tuple[Shape, Shape]:
    zero = np.zeros((1, 3), dtype=np.float32)
    return (
        Arrows(zero, np.array([xyz(first)], dtype=np.float32) * scale, one_color(colors[0]), radius),
        Arrows(zero, np.array([xyz(second)], dtype=np.float32) * scale, one_color(colors[1]), radius),
    )


def decode_wrench_stamped(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A WrenchStamped as a force arrow and a torque arrow (the torque straight, along its axis)."""
    msg = deserialize(data, "geometry_msgs/msg/WrenchStamped")
    frame, stamp = header_of(msg)
    items = vector_pair(msg.wrench.force, msg.wrench.torque, WRENCH_SCALE, (FORCE_COLOR, TORQUE_COLOR), 0.05)
    return Decoded(frame, stamp, items)


def decode_twist_stamped(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A TwistStamped as a linear-velocity arrow and an angular-velocity arrow (along its axis), x 1."""
    msg = deserialize(data, "geometry_msgs/msg/TwistStamped")
    frame, stamp = header_of(msg)
    items = vector_pair(msg.twist.linear, msg.twist.angular, 1.0, (FORCE_COLOR, TORQUE_COLOR), 0.05)
    return Decoded(frame, stamp, items)
