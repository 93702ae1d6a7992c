"""A bag of a robot that stops, then drives, then turns in place, its Odometry written by rosbags itself (its
serializer and writer, independent of r2d2_viz), and RViz's rule for which poses its Odometry display keeps,
transcribed line by line from RViz's C++ (so the tests hold the code to RViz, not to itself).

RViz 2, rviz_default_plugins/src/rviz_default_plugins/displays/odometry/odometry_display.cpp (ros2/rviz)::

    bool OdometryDisplay::messageIsSimilarToPrevious(nav_msgs::msg::Odometry::ConstSharedPtr message)
    {
      if (!last_used_message_) { return false; }
      auto last_position = rviz_common::pointMsgToOgre(last_used_message_->pose.pose.position);
      auto current_position = rviz_common::pointMsgToOgre(message->pose.pose.position);
      auto last_orientation = rviz_common::quaternionMsgToOgre(last_used_message_->pose.pose.orientation);
      auto current_orientation = rviz_common::quaternionMsgToOgre(message->pose.pose.orientation);
      bool position_difference_is_within_tolerance =
        (last_position - current_position).length() < position_tolerance_property_->getFloat();
      bool angle_difference_is_within_tolerance =
        ogreQuaternionAngularDistance(last_orientation, current_orientation) <
        angle_tolerance_property_->getFloat();
      return position_difference_is_within_tolerance && angle_difference_is_within_tolerance;
    }

and ``processMessage`` drops a message that is similar (``last_used_message_ = msg`` only for one drawn), the
properties ``"Position Tolerance", 0.1f``, ``"Angle Tolerance", 0.1f``, ``"Keep", 100``; quaternion_helper.hpp::

    float ogreQuaternionAngularDistance(Ogre::Quaternion first, Ogre::Quaternion second)
    {
      Ogre::Quaternion product = first * Ogre::Quaternion(second.w, -second.x, -second.y, -second.z);
      float imaginary_norm = sqrtf(powf(product.x, 2.0f) + powf(product.y, 2.0f) + powf(product.z, 2.0f));
      return 2.0f * atan2f(imaginary_norm, sqrtf(powf(product.w, 2.0f)));
    }
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from bagmaker import BagSpec, write_bag
from msgs_build import TS, T, cdr, header, pose, quat, vec

S = 1_000_000_000
T0 = 1_700_000_000 * S
DT = S // 10  # 10 Hz
STOPPED, DRIVING, TURNING = 150, 160, 10
STEP = 0.07  # m per message while driving: RViz keeps every second pose (0.14 m >= 0.1, 0.07 m < 0.1)
TURN = 0.06  # rad per message while turning in place: every second pose again (0.12 rad >= 0.1)
RVIZ_KEEP = 100
RVIZ_TOLERANCE = (0.1, 0.1)


def poses() -> list[tuple[float, float, float]]:
    """(x, y, yaw) of each message: stopped at the origin with 0.2 mm and 1 mrad of jitter, then driving along x,
    then turning in place."""
    out = [(0.0002 * math.sin(k), 0.0002 * math.cos(k), 0.001 * math.sin(3 * k)) for k in range(STOPPED)]
    out += [(STEP * k, 0.0, 0.0) for k in range(1, DRIVING + 1)]
    out += [(STEP * DRIVING, 0.0, TURN * k) for k in range(1, TURNING + 1)]
    return out


def times() -> list[int]:
    return [T0 + k * DT for k in range(len(poses()))]


def odometry(t_ns: int, x: float, y: float, yaw: float) -> bytes:
    cov = np.zeros(36)
    q = quat(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return cdr(
        T("nav_msgs/msg/Odometry")(
            header=header("odom", *divmod(t_ns, S)),
            child_frame_id="base_link",
            pose=T("geometry_msgs/msg/PoseWithCovariance")(pose=pose(x, y, 0.0, q), covariance=cov),
            twist=T("geometry_msgs/msg/TwistWithCovariance")(
                twist=T("geometry_msgs/msg/Twist")(linear=vec(), angular=vec()), covariance=cov
            ),
        )
    )


def write_odometry_bag(path: Path) -> Path:
    spec = BagSpec(types={"/odom": "nav_msgs/msg/Odometry"})
    for t, (x, y, yaw) in zip(times(), poses(), strict=True):
        spec.add("/odom", t, odometry(t, x, y, yaw))
    return write_bag(path, spec)


def _f(value: float) -> float:
    """A C++ float: the value rounded to float32."""
    return float(np.float32(value))


def _angular_distance(first: tuple[float, ...], second: tuple[float, ...]) -> float:
    """ogreQuaternionAngularDistance, ``(w, x, y, z)`` as Ogre holds them; Ogre's ``operator*`` (float)."""
    w1, x1, y1, z1 = first
    w2, x2, y2, z2 = second[0], -second[1], -second[2], -second[3]
    w = _f(_f(_f(w1 * w2) - _f(x1 * x2)) - _f(y1 * y2)) - _f(z1 * z2)
    x = _f(_f(_f(w1 * x2) + _f(x1 * w2)) + _f(y1 * z2)) - _f(z1 * y2)
    y = _f(_f(_f(w1 * y2) + _f(y1 * w2)) + _f(z1 * x2)) - _f(x1 * z2)
    z = _f(_f(_f(w1 * z2) + _f(z1 * w2)) + _f(x1 * y2)) - _f(y1 * x2)
    imaginary_norm = _f(math.sqrt(_f(_f(_f(x * x) + _f(y * y)) + _f(z * z))))
    return _f(2.0 * _f(math.atan2(imaginary_norm, _f(math.sqrt(_f(w * w))))))


def rviz_kept(messages: list[bytes], tolerance: tuple[float, float] = RVIZ_TOLERANCE) -> list[int]:
    """The indices of the messages RViz's Odometry display draws (every message valid and transformable), each
    deserialised by rosbags."""
    position_tolerance, angle_tolerance = _f(tolerance[0]), _f(tolerance[1])
    kept: list[int] = []
    last = None
    for i, data in enumerate(messages):
        p = TS.deserialize_cdr(data, "nav_msgs/msg/Odometry").pose.pose
        position = (_f(p.position.x), _f(p.position.y), _f(p.position.z))  # pointMsgToOgre: Ogre::Vector3 (float)
        o = p.orientation
        orientation = (_f(o.w), _f(o.x), _f(o.y), _f(o.z))
        if last is not None:
            d = [_f(a - b) for a, b in zip(last[0], position, strict=True)]
            length = _f(math.sqrt(_f(_f(_f(d[0] * d[0]) + _f(d[1] * d[1])) + _f(d[2] * d[2]))))
            within_position = length < position_tolerance
            within_angle = _angular_distance(last[1], orientation) < angle_tolerance
            if within_position and within_angle:
                continue
        kept.append(i)
        last = (position, orientation)
    return kept
