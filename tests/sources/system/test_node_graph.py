"""rqt_graph's graph of nodes and topics from node lists (as ``ros2 node info`` gives them), and the nodes of
``ros_discovery_info`` messages matched with DDS endpoints by GUID — stand-ins for the discovery data, the expected
vertices and edges written by hand (rqt_graph's "Nodes/Topics (all)" with "Hide Debug")."""

from __future__ import annotations

from types import SimpleNamespace

from r2d2_viz.sources.live.dds import Node
from r2d2_viz.sources.system.node_graph import graph_parts, nodes_of, positions

JS = "sensor_msgs/msg/JointState"
LOG = "rcl_interfaces/msg/Log"


def test_publisher_topic_subscriber_edges_and_debug_topics_hidden() -> None:
    robot = Node("/robot", (("/joint_states", JS), ("/rosout", LOG)), ())
    viewer = Node("/ns/viewer", (("/rosout", LOG),), (("/joint_states", JS), ("/cmd_vel", "geometry_msgs/msg/Twist")))
    graph = graph_parts([viewer, robot])
    assert graph.ids == ("node /ns/viewer", "node /robot", "topic /cmd_vel", "topic /joint_states")
    assert graph.labels == ("/ns/viewer", "/robot", "/cmd_vel", "/joint_states")
    assert graph.is_node == (True, True, False, False)
    assert set(graph.edges) == {
        ("node /robot", "topic /joint_states"),
        ("topic /joint_states", "node /ns/viewer"),
        ("topic /cmd_vel", "node /ns/viewer"),
    }
    assert graph_parts([robot, viewer]) == graph  # the order nodes come in does not matter
    assert graph_parts([]) == ((), (), (), ())


def test_a_node_and_a_topic_of_the_same_name_are_two_vertices() -> None:
    graph = graph_parts([Node("/scan", (("/scan", "sensor_msgs/msg/LaserScan"),), ())])
    assert graph.ids == ("node /scan", "topic /scan") and graph.edges == (("node /scan", "topic /scan"),)


def gid(n: int) -> SimpleNamespace:
    return SimpleNamespace(data=bytes([n]) * 16 + bytes(8))  # rmw's gid: the 16-byte GUID, zero-padded


def test_nodes_of_discovery_info_matched_by_guid() -> None:
    info = SimpleNamespace(
        gid=gid(9),
        node_entities_info_seq=[
            SimpleNamespace(node_namespace="/", node_name="talker", writer_gid_seq=[gid(1)], reader_gid_seq=[]),
            SimpleNamespace(
                node_namespace="/robot1", node_name="listener", writer_gid_seq=[], reader_gid_seq=[gid(2), gid(3)]
            ),
        ],
    )
    endpoints = {bytes([1]) * 16: ("/chatter", "std_msgs/msg/String", True)}
    endpoints[bytes([2]) * 16] = ("/chatter", "std_msgs/msg/String", False)  # gid 3: not discovered (gone)
    assert nodes_of([info], endpoints) == [
        Node("/robot1/listener", (), (("/chatter", "std_msgs/msg/String"),)),
        Node("/talker", (("/chatter", "std_msgs/msg/String"),), ()),
    ]


def test_positions_left_to_right_publishers_topics_subscribers() -> None:
    talker = Node("/talker", (("/chatter", "std_msgs/msg/String"),), ())
    relay = Node("/relay", (("/out", "std_msgs/msg/String"),), (("/chatter", "std_msgs/msg/String"),))
    loop = Node("/loop", (("/self", "std_msgs/msg/String"),), (("/self", "std_msgs/msg/String"),))
    graph = graph_parts([talker, relay, loop])
    x = {v: p[0] for v, p in zip(graph.ids, positions(graph), strict=True)}
    # by hand: talker → /chatter → relay → /out, one layer each
    assert x["node /talker"] < x["topic /chatter"] < x["node /relay"] < x["topic /out"]
    assert len(set(positions(graph))) == len(graph.ids)  # no two vertices on one spot (the loop's included)
