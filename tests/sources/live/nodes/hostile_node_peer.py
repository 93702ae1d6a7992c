"""A cyclonedds-python participant that lies in ``ros_discovery_info`` (rmw_dds_common's ParticipantEntitiesInfo,
as every ROS 2 participant publishes it, latched): it names one node ``/evil`` followed by a line break and the
lines of a node and a topic that do not exist, with its writer of ``/chatter`` (std_msgs/String) as the node's.
Runs for ``seconds`` (argv[1])."""

from __future__ import annotations

import sys
import time

NODE_NAME = "evil\nnode /fake\n  publishes /fake_topic [std_msgs/msg/String]"


def main() -> int:
    import cyclonedds.idl
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    from r2d2_viz.msgs.typestore import typestore
    from r2d2_viz.sources.live.idl_types import IdlTypes

    types = IdlTypes(typestore("jazzy"), cyclonedds.idl)
    string, info = types.struct("std_msgs/msg/String"), types.struct("rmw_dds_common/msg/ParticipantEntitiesInfo")
    gid, node = types.struct("rmw_dds_common/msg/Gid"), types.struct("rmw_dds_common/msg/NodeEntitiesInfo")
    participant = DomainParticipant(0)
    chatter = DataWriter(participant, Topic(participant, "rt/chatter", string))
    latched = Qos(Policy.Reliability.Reliable(0), Policy.Durability.TransientLocal, Policy.History.KeepLast(1))
    discovery = DataWriter(participant, Topic(participant, "ros_discovery_info", info), qos=latched)
    own = gid(data=list(participant.guid.bytes))
    lie = node(
        node_namespace="/", node_name=NODE_NAME, reader_gid_seq=[], writer_gid_seq=[gid(data=list(chatter.guid.bytes))]
    )
    discovery.write(info(gid=own, node_entities_info_seq=[lie]))
    end = time.monotonic() + float(sys.argv[1] if len(sys.argv) > 1 else 10)
    while time.monotonic() < end:
        chatter.write(string(data="hello"))
        time.sleep(0.1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
