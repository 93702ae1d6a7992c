"""A real ROS 2 node (rclpy, run by the cached venv's Python) listening to ``/joint_states`` as
robot_state_publisher or ``ros2 topic echo`` would: ``sensor_msgs/msg/JointState``, rclpy's default QoS (reliable,
volatile, depth 10).

Prints ``ready`` once it is up (with ``--ready-when TOPIC``: once it sees a publisher of TOPIC) and ``got JSON`` as
each message arrives (names, positions, the header's stamp in seconds), so that a scenario polls instead of
sleeping. Runs until SIGINT/SIGTERM (or ``--seconds``), then prints one JSON line: how many messages it received.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import time


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=300.0)
    parser.add_argument("--ready-when", default=None, help="say ready once this topic has a publisher")
    args = parser.parse_args()
    import rclpy
    from sensor_msgs.msg import JointState

    rclpy.init()
    node = rclpy.create_node("joint_states_listener", enable_rosout=False)
    count = [0]

    def record(m: JointState) -> None:
        count[0] += 1
        stamp = m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
        item = {"name": list(m.name), "position": list(m.position), "stamp": stamp}
        print(f"got {json.dumps(item)}", flush=True)

    node.create_subscription(JointState, "/joint_states", record, 10)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    deadline = time.monotonic() + args.seconds
    while args.ready_when and not stop and time.monotonic() < deadline and not node.count_publishers(args.ready_when):
        rclpy.spin_once(node, timeout_sec=0.05)
    print("ready", flush=True)
    while not stop and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    print(json.dumps({"received": count[0]}), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
