"""A cyclonedds-python peer publishing ``std_msgs/String`` on ``/joint_states`` (``rt/joint_states``): the wrong
type on a topic the robot pipeline reads. Publishes every 50 ms for ``seconds`` (argv[1])."""

from __future__ import annotations

import sys
import time


def main() -> int:
    import cyclonedds.idl
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    from r2d2_viz.msgs.typestore import typestore
    from r2d2_viz.sources.live.idl_types import IdlTypes

    types = IdlTypes(typestore("jazzy"), cyclonedds.idl)
    string = types.struct("std_msgs/msg/String")
    participant = DomainParticipant(0)
    writer = DataWriter(participant, Topic(participant, "rt/joint_states", string))
    end = time.monotonic() + float(sys.argv[1] if len(sys.argv) > 1 else 5)
    while time.monotonic() < end:
        writer.write(string(data="not a joint state"))
        time.sleep(0.05)
    return 0


if __name__ == "__main__":
    sys.exit(main())
