"""A cyclonedds-python peer publishing ``/tf`` with ROS 2's DDS names (``rt/tf``, ``tf2_msgs::msg::dds_::TFMessage_``).

Not a ROS node: the point is that bytes serialized by Cyclone's Python binding from our dynamically built types
equal rosbags' ``serialize_cdr`` of the same message. Publishes :data:`TRANSFORMS` every 50 ms for ``seconds``
(arguments: seconds, then optionally the topic and the transforms as JSON ``[[parent, child, xyz, xyzw], ...]``).
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

STAMP = (42, 7)
TRANSFORMS = (
    ("odom", "base_link", (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0)),
    ("base_link", "head", (0.0, -0.5, 0.25), (0.0, 0.0, 0.7071067811865476, 0.7071067811865476)),
)


def tf_message(struct: Any, transforms: Any = TRANSFORMS) -> Any:
    """``transforms`` as a message of ``struct(ros_type)`` classes (cyclonedds or rosbags alike)."""
    time_t, header_t = struct("builtin_interfaces/msg/Time"), struct("std_msgs/msg/Header")
    vec_t, quat_t = struct("geometry_msgs/msg/Vector3"), struct("geometry_msgs/msg/Quaternion")
    tr_t, stamped_t = struct("geometry_msgs/msg/Transform"), struct("geometry_msgs/msg/TransformStamped")
    return struct("tf2_msgs/msg/TFMessage")(
        transforms=[
            stamped_t(
                header=header_t(stamp=time_t(sec=STAMP[0], nanosec=STAMP[1]), frame_id=parent),
                child_frame_id=child,
                transform=tr_t(
                    translation=vec_t(x=t[0], y=t[1], z=t[2]), rotation=quat_t(x=q[0], y=q[1], z=q[2], w=q[3])
                ),
            )
            for parent, child, t, q in transforms
        ]
    )


def main() -> int:
    import cyclonedds.idl
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    from r2d2_viz.msgs.typestore import typestore
    from r2d2_viz.sources.live.idl_types import IdlTypes

    types = IdlTypes(typestore("jazzy"), cyclonedds.idl)
    participant = DomainParticipant(0)
    topic = sys.argv[2] if len(sys.argv) > 2 else "/tf"  # then, optionally, the transforms as JSON
    transforms = json.loads(sys.argv[3]) if len(sys.argv) > 3 else TRANSFORMS
    writer = DataWriter(participant, Topic(participant, "rt" + topic, types.struct("tf2_msgs/msg/TFMessage")))
    message = tf_message(types.struct, transforms)
    end = time.monotonic() + float(sys.argv[1] if len(sys.argv) > 1 else 5)
    while time.monotonic() < end:
        writer.write(message)
        time.sleep(0.05)
    return 0


if __name__ == "__main__":
    sys.exit(main())
