"""geometry_msgs/AccelStamped as RViz 2's AccelStamped display draws it: the same arrows as its Twist display
(``rviz_default_plugins/displays/accel/accel_display.cpp`` hands ``accel.linear`` and ``accel.angular`` to the
shared twist/accel visual): linear acceleration (204, 51, 51) and angular acceleration (204, 204, 51), each along
its vector, x 1, in the header frame."""

from __future__ import annotations

from r2d2_viz.msgs.geometry import header_of
from r2d2_viz.msgs.poses import FORCE_COLOR, TORQUE_COLOR, vector_pair
from r2d2_viz.msgs.shapes import Decoded, DecodeOptions
from r2d2_viz.msgs.typestore import deserialize


def decode_accel_stamped(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """An AccelStamped as a linear-acceleration arrow and an angular-acceleration arrow (along its axis)."""
    msg = deserialize(data, "geometry_msgs/msg/AccelStamped")
    frame, stamp = header_of(msg)
    items = vector_pair(msg.accel.linear, msg.accel.angular, 1.0, (FORCE_COLOR, TORQUE_COLOR), 0.05)
    return Decoded(frame, stamp, items)
