"""``r2d2-viz --ros`` against real nodes, run INSIDE a loopback-only network namespace (``ros_node.in_netns``).

A real ROS 2 node (``nodes/publish_robot.py``) publishes a latched ``/robot_description`` first; optionally a
cyclonedds peer puts the wrong type on ``/joint_states``. Then ``r2d2-viz --ros --list`` runs, and the CLI runs
given as JSON lists of arguments run at the same time (late joiners; the node streams once all have subscribed).
Prints one JSON: the list's output, each run's exit code and stderr, the node's report.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

NODES = Path(__file__).resolve().parent / "nodes"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ros-python", required=True)
    parser.add_argument("--urdf", required=True)
    parser.add_argument("--cli", required=True, help="the r2d2-viz command")
    parser.add_argument("--node", default="[]", help="JSON list of extra arguments of publish_robot.py")
    parser.add_argument("--wrong-type-peer", action="store_true")
    parser.add_argument("--runs", required=True, help="JSON list of argument lists")
    args = parser.parse_args()
    runs = json.loads(args.runs)
    node = subprocess.Popen(
        [args.ros_python, str(NODES / "publish_robot.py"), "--urdf", args.urdf, "--subscribers", str(len(runs)),
         *json.loads(args.node)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    peer = None
    if args.wrong_type_peer:
        peer = subprocess.Popen([sys.executable, str(NODES / "wrong_type_peer.py"), "30"])
    out: dict[str, object] = {}
    try:
        listed = ""
        for _ in range(5):  # the node came first: wait until the graph shows it
            done = subprocess.run([args.cli, "--ros", "--list"], capture_output=True, text=True, timeout=30)
            listed = done.stdout
            if "/joint_states [sensor_msgs/msg/JointState]" in listed and (not peer or "std_msgs" in listed):
                break
            time.sleep(0.5)
        out["list"], out["list_rc"] = listed, done.returncode
        procs = [
            subprocess.Popen([args.cli, "--ros", *run], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for run in runs
        ]
        out["runs"] = []
        for proc in procs:
            stdout, stderr = proc.communicate(timeout=60)
            out["runs"].append({"rc": proc.returncode, "stderr": stderr})  # type: ignore[union-attr]
    finally:
        for p in (node, peer):
            if p is not None and p.poll() is None:
                p.kill()
    stdout, stderr = node.communicate(timeout=10)
    lines = stdout.strip().splitlines()
    out["node"] = json.loads(lines[-1]) if lines else {"stderr": stderr[-2000:]}
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
