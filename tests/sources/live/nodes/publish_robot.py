"""A real ROS 2 node (rclpy, run by the cached venv's Python): a latched ``/robot_description`` and ``/joint_states``.

Publishes the URDF's text once on a transient-local ``/robot_description`` (std_msgs/String) right away, waits
for a subscriber of ``/joint_states`` (up to ``--wait`` s), then publishes ``--count`` JointStates at ``--rate``
Hz, message *k* being :func:`joint_state_values` of *k* (so a reader can rebuild what was sent), lingers
``--linger`` s and exits. Prints one JSON line: what it sent and when the stream started.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import xml.etree.ElementTree as ET


def joint_names(urdf: str, joints: int) -> list[str]:
    """The URDF's movable joints, padded with ``extra_<i>`` (or cut) to ``joints`` when given."""
    names = [j.get("name", "") for j in ET.fromstring(urdf).iter("joint") if j.get("type") != "fixed"]
    if joints > 0:
        names = (names + [f"extra_{i}" for i in range(joints)])[:joints]
    return names


def joint_state_values(k: int, count: int, shift: float = 0.0) -> tuple[int, int, list[float], list[float]]:
    """Message ``k``: header stamp (sec, nanosec), positions (``shift`` added) and velocities of ``count`` joints."""
    position = [0.001 * k + i + shift for i in range(count)]
    return 1000 + k // 1000, (k % 1000) * 1_000_000, position, [float(k)] * count


def bad_samples(names: list[str]) -> list[bytes]:
    """Raw serialized /joint_states that a robot should survive: bad CDR, an absurd sequence length, NaN positions,
    name/position lengths that differ, 10,000 names (the last three are valid CDR and reach a reader)."""
    import struct

    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState

    def message(names: list[str], position: list[float]) -> bytes:
        msg = JointState()
        msg.name, msg.position = names, position
        msg.header.stamp.sec = 999  # before the good stream's stamps
        return bytes(serialize_message(msg))

    absurd = b"\x00\x01\x00\x00" + struct.pack("<iI", 999, 0) + struct.pack("<I", 0x7FFFFFF0) + b"x" * 16
    return [
        b"\x00\x01\x00\x00\xff\xff",
        absurd,
        message(names, [float("nan")] * len(names)),
        message(names, [0.0]),
        message([f"n{i}" for i in range(10_000)], [0.0] * 10_000),
    ]


LOG_LINES = (("DEBUG", "debug"), ("INFO", "info"), ("WARN", "warning"), ("ERROR", "error"), ("CRITICAL", "fatal"))
"""What ``--log`` logs: Rerun's name of each line's level and the rclpy logger's method (levels 10 … 50)."""


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--urdf", required=True)
    parser.add_argument("--rate", type=float, default=100.0)
    parser.add_argument("--count", type=int, default=100)
    parser.add_argument("--joints", type=int, default=0)
    parser.add_argument("--wait", type=float, default=20.0)
    parser.add_argument("--linger", type=float, default=2.0)
    parser.add_argument("--subscribers", type=int, default=1, help="wait for this many /joint_states readers")
    parser.add_argument("--bad", action="store_true", help="first publish the malformed samples of bad_samples()")
    parser.add_argument("--namespace", default="", help="publish /<namespace>/robot_description and joint_states")
    parser.add_argument("--shift", type=float, default=0.0, help="added to every position")
    parser.add_argument("--log", action="store_true", help="log one line at each level (to /rosout) once matched")
    args = parser.parse_args()

    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String

    urdf = open(args.urdf, encoding="utf-8").read()
    names = joint_names(urdf, args.joints)
    rclpy.init()
    node = rclpy.create_node("r2d2_viz_test_robot")
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    description = node.create_publisher(String, f"{args.namespace}/robot_description", latched)
    states = node.create_publisher(JointState, f"{args.namespace}/joint_states", 10)
    description.publish(String(data=urdf))
    deadline = time.monotonic() + args.wait
    while states.get_subscription_count() < args.subscribers and time.monotonic() < deadline:
        time.sleep(0.01)
    matched = states.get_subscription_count() >= args.subscribers
    time.sleep(0.2)  # the reader's side of the match settles too
    if args.log:
        from rclpy.logging import LoggingSeverity

        logger = node.get_logger()
        logger.set_level(LoggingSeverity.DEBUG)
        # one call site per level: rclpy refuses two severities from the same line
        logger.debug("DEBUG line")
        logger.info("INFO line")
        logger.warning("WARN line")
        logger.error("ERROR line")
        logger.fatal("CRITICAL line")
    if args.bad:
        for data in bad_samples(names):
            states.publish(data)  # bytes: rclpy publishes them as an already serialized message
            time.sleep(0.01)
    msg = JointState()
    msg.name = names
    msg.header.frame_id = "base"
    start = time.perf_counter()
    for k in range(args.count):
        sec, nanosec, position, velocity = joint_state_values(k, len(names), args.shift)
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        msg.position, msg.velocity = position, velocity
        states.publish(msg)
        delay = start + (k + 1) / args.rate - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
    elapsed = time.perf_counter() - start
    print(json.dumps({"sent": args.count, "joints": names, "matched": matched, "seconds": elapsed}), flush=True)
    time.sleep(args.linger)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
