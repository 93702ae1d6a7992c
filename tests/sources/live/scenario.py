"""One live scenario, run INSIDE a loopback-only network namespace (see ``ros_node.in_netns``); prints one JSON.

A real ROS 2 node (``nodes/publish_robot.py``, by the distro venv's Python) and optionally a cyclonedds-python
``/tf`` peer start first; then our subscriber joins late: lists the topics, subscribes to ``/robot_description``,
``/joint_states`` (and ``/tf``), polls every 5 ms until the node is done, and checks every message it got.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

NODES = Path(__file__).resolve().parent / "nodes"
sys.path.insert(0, str(NODES))

from publish_robot import joint_state_values  # noqa: E402
from tf_peer import tf_message  # noqa: E402

from r2d2_viz.msgs.typestore import typestore  # noqa: E402
from r2d2_viz.sources.live.dds import LiveGraph, Sample  # noqa: E402


def _percentile(values: list[float], q: float) -> float | None:
    return sorted(values)[min(len(values) - 1, int(q * len(values)))] if values else None


def check(samples: list[Sample], tf_expected: bytes, t_received: dict[int, int]) -> dict[str, Any]:
    """Decode what arrived with rosbags and compare it with what the node and the peer sent."""
    store = typestore("jazzy")
    out: dict[str, Any] = {"descriptions": [], "joint_states": 0, "mismatches": 0, "tf": 0, "tf_equal": 0}
    lateness: list[float] = []
    for i, s in enumerate(samples):
        msg: Any = store.deserialize_cdr(s.data, s.ros_type)
        if s.topic == "/robot_description":
            out["descriptions"].append(msg.data)
        elif s.topic == "/joint_states":
            out["joint_states"] += 1
            k = (msg.header.stamp.sec - 1000) * 1000 + msg.header.stamp.nanosec // 1_000_000
            sec, nanosec, position, velocity = joint_state_values(k, len(msg.name))
            same = (msg.header.stamp.sec, msg.header.stamp.nanosec, list(msg.position), list(msg.velocity)) == (
                sec,
                nanosec,
                position,
                velocity,
            )
            out["mismatches"] += 0 if same and msg.header.frame_id == "base" else 1
            out["names"] = list(msg.name)
            lateness.append((t_received[i] - s.source_timestamp_ns) / 1e6)
        elif s.topic == "/tf":
            out["tf"] += 1
            out["tf_equal"] += int(s.data == tf_expected)
            out["tf_len"] = [len(s.data), len(tf_expected)]
    out["lateness_ms_p50"], out["lateness_ms_p99"] = _percentile(lateness, 0.5), _percentile(lateness, 0.99)
    out["lateness_ms_max"] = max(lateness, default=None)
    return out


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ros-python", required=True)
    parser.add_argument("--urdf", required=True)
    parser.add_argument("--rate", type=float, default=200)
    parser.add_argument("--count", type=int, default=400)
    parser.add_argument("--joints", type=int, default=0)
    parser.add_argument("--tf-peer", action="store_true")
    parser.add_argument("--deadline", type=float, default=60)
    args = parser.parse_args()
    end = time.monotonic() + args.deadline
    node = subprocess.Popen(
        [args.ros_python, str(NODES / "publish_robot.py"), "--urdf", args.urdf, "--rate", str(args.rate),
         "--count", str(args.count), "--joints", str(args.joints)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    peer = None
    if args.tf_peer:
        peer = subprocess.Popen([sys.executable, str(NODES / "tf_peer.py"), str(args.deadline)])
    result: dict[str, Any] = {}
    try:
        with LiveGraph() as graph:
            topics: list[tuple[str, str, int]] = []
            # the node came first: we are the late joiner. Each writer is discovered on its own (seen: /joint_states
            # listed before /robot_description on a busy machine), so wait for all of them
            wanted = {"/joint_states", "/robot_description"} | ({"/tf"} if args.tf_peer else set())
            while not wanted <= {t[0] for t in topics} and time.monotonic() < end:
                topics = graph.topics(0.25)
            result["topics"] = topics
            qos = [graph.subscribe("/robot_description", "std_msgs/msg/String")]
            qos.append(graph.subscribe("/joint_states", "sensor_msgs/msg/JointState"))
            if args.tf_peer:
                qos.append(graph.subscribe("/tf", "tf2_msgs/msg/TFMessage"))
            result["qos"] = [[p.topic, p.reliable, p.transient_local] for p in qos]
            samples: list[Sample] = []
            received: dict[int, int] = {}
            while time.monotonic() < end:
                done = node.poll() is not None
                got = graph.poll()
                now = time.time_ns()
                for s in got:
                    received[len(samples)] = now
                    samples.append(s)
                if done:
                    break
                time.sleep(0.005)
            result["dropped"] = graph.dropped
    finally:
        for proc in (node, peer):
            if proc is not None and proc.poll() is None:
                proc.kill()
    stdout, stderr = node.communicate(timeout=10)
    result["node"] = json.loads(stdout.strip().splitlines()[-1]) if stdout.strip() else {"stderr": stderr[-2000:]}
    store = typestore("jazzy")
    tf_expected = bytes(store.serialize_cdr(tf_message(lambda t: store.types[t]), "tf2_msgs/msg/TFMessage"))
    result.update(check(samples, tf_expected, received))
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
