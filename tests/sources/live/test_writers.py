"""Writing to the graph (the page's tools): what is written is what rosbags serialised, byte for byte, read back
by a reader of the same participant — inside a loopback-only network namespace. (A real rclpy node receiving
each tool's message: tests/ros_out/test_tools_to_node.py; through the browser: tests/e2e/test_web_tools.py.)"""

from __future__ import annotations

import json
import sys

from . import ros_node

SCRIPT = """
import json, time
from rosbags.typesys import Stores, get_typestore
from r2d2_viz.sources.live.dds import LiveGraph
from r2d2_viz.sources.live.names import LiveError
ts = get_typestore(Stores.ROS2_JAZZY)
T = ts.types
msg = T["geometry_msgs/msg/PointStamped"](
    header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=1, nanosec=2), frame_id="map"),
    point=T["geometry_msgs/msg/Point"](x=1.5, y=-2.0, z=0.25))
data = bytes(ts.serialize_cdr(msg, "geometry_msgs/msg/PointStamped"))
out = {}
with LiveGraph({"ROS_DOMAIN_ID": "42"}) as graph:
    graph.subscribe("/clicked_point", "geometry_msgs/msg/PointStamped", wait=0)
    got = []
    for _ in range(50):
        graph.publish("/clicked_point", "geometry_msgs/msg/PointStamped", data)
        graph.wait(0.1)
        got += graph.poll()
        if got:
            break
    out["same_bytes"] = bool(got) and all(s.data == data for s in got)
    try:
        graph.publish("/clicked_point", "geometry_msgs/msg/PoseStamped", data)
    except LiveError as exc:
        out["wrong_type"] = str(exc)
print(json.dumps(out))
"""


def test_a_tool_message_goes_out_as_rosbags_serialised_it() -> None:
    missing = ros_node.netns_missing()
    if missing:
        ros_node.unavailable(missing)
    done = ros_node.in_netns([sys.executable, "-c", SCRIPT], timeout=60)
    assert done.returncode == 0, done.stderr[-2000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["same_bytes"] is True
    assert out["wrong_type"] == "/clicked_point is published as geometry_msgs/msg/PointStamped, not " + (
        "geometry_msgs/msg/PoseStamped"
    )
