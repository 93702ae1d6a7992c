"""A real ROS 2 node (rclpy, run by the cached venv's Python) listening to RViz's tools' topics, as a navigation
stack would: ``/clicked_point``, ``/goal_pose``, ``/initialpose`` (reliable, volatile) and ``/cmd_vel``; and, as
map_server does, publishes :data:`MAP` once on ``/map`` (reliable, transient local: a late subscriber gets it).

Prints ``ready`` once it is up (with ``--ready-when TOPIC``: once it sees a publisher of TOPIC) and ``got TOPIC JSON``
as each message arrives, so that a scenario polls instead of sleeping. Runs until SIGINT/SIGTERM (or ``--seconds``),
then prints one JSON line: every message received, per topic, as plain numbers (the point, the pose's position and
quaternion xyzw, the covariance, the twist), with the frame.
"""

from __future__ import annotations

import argparse
import array
import json
import signal
import sys
import time

MAP_RESOLUTION, MAP_SIZE, MAP_ORIGIN = 0.1, (600, 400), (-30.0, -20.0)
"""The map: 600 x 400 free cells of 0.1 m from (-30, -20) in frame ``map``, wider than the 50 m default ground."""


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=300.0)
    parser.add_argument("--ready-when", default=None, help="say ready once this topic has a publisher")
    args = parser.parse_args()
    import rclpy
    from geometry_msgs.msg import PointStamped, PoseStamped, PoseWithCovarianceStamped, Twist
    from nav_msgs.msg import OccupancyGrid
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    rclpy.init()
    node = rclpy.create_node("tool_listener", enable_rosout=False)  # no /rosout: no log view in the layout
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
    got: dict[str, list[dict[str, object]]] = {
        "/clicked_point": [],
        "/goal_pose": [],
        "/initialpose": [],
        "/cmd_vel": [],
    }

    def record(topic: str, item: dict[str, object]) -> None:
        got[topic].append(item)
        print(f"got {topic} {json.dumps(item)}", flush=True)

    def pose(p: object) -> dict[str, object]:
        o = p.orientation  # type: ignore[attr-defined]
        return {"position": [p.position.x, p.position.y, p.position.z], "xyzw": [o.x, o.y, o.z, o.w]}  # type: ignore[attr-defined]

    node.create_subscription(PointStamped, "/clicked_point", lambda m: record("/clicked_point",
        {"frame": m.header.frame_id, "point": [m.point.x, m.point.y, m.point.z]}), qos)  # fmt: skip
    node.create_subscription(PoseStamped, "/goal_pose", lambda m: record("/goal_pose",
        {"frame": m.header.frame_id, **pose(m.pose)}), qos)  # fmt: skip
    node.create_subscription(PoseWithCovarianceStamped, "/initialpose", lambda m: record("/initialpose",
        {"frame": m.header.frame_id, **pose(m.pose.pose), "covariance": list(m.pose.covariance)}), qos)  # fmt: skip
    node.create_subscription(Twist, "/cmd_vel", lambda m: record("/cmd_vel",
        {"linear": m.linear.x, "angular": m.angular.z, "t": time.monotonic()}), qos)  # fmt: skip
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    grid = OccupancyGrid()
    grid.header.frame_id = "map"
    grid.header.stamp = node.get_clock().now().to_msg()
    grid.info.resolution = MAP_RESOLUTION
    grid.info.width, grid.info.height = MAP_SIZE
    grid.info.origin.position.x, grid.info.origin.position.y = MAP_ORIGIN
    grid.info.origin.orientation.w = 1.0
    grid.data = array.array("b", bytes(grid.info.width * grid.info.height))
    node.create_publisher(OccupancyGrid, "/map", latched).publish(grid)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    deadline = time.monotonic() + args.seconds
    while args.ready_when and not stop and time.monotonic() < deadline and not node.count_publishers(args.ready_when):
        rclpy.spin_once(node, timeout_sec=0.05)
    print("ready", flush=True)
    while not stop and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    print(json.dumps(got), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
