"""Two robots on one live graph, run INSIDE a loopback-only network namespace (``ros_node.in_netns``).

Two real ROS 2 nodes (``nodes/publish_robot.py --namespace``) publish ``/robot1/…`` and ``/robot2/…`` descriptions
and joint states; cyclonedds peers (``nodes/tf_peer.py``) publish robot1's base on ``/tf`` with prefixed frames
(convention A) and robot2's on its own ``/robot2/tf`` with bare frames (convention B); a third robot, if given, has
no TF at all. ``r2d2-viz --ros --save``
runs as a late joiner. Prints one JSON: the run's exit code and stderr, the nodes' reports.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

NODES = Path(__file__).resolve().parent / "nodes"
ID = [0.0, 0.0, 0.0, 1.0]
TF = {
    "/tf": [["map", "robot1/base_link", [1.0, 0.0, 0.0], ID]],
    "/robot2/tf": [["map", "odom", [0.0, 0.0, 0.0], ID], ["odom", "base_link", [0.0, -1.0, 0.0], ID]],
}
SHIFT = {"/robot1": 0.0, "/robot2": 0.5, "/robot3": 0.0}


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ros-python", required=True)
    parser.add_argument("--urdf", nargs="+", required=True, help="robot1's and robot2's (and robot3's: no TF)")
    parser.add_argument("--cli", required=True, help="the r2d2-viz command")
    parser.add_argument("--run", required=True, help="JSON list of the run's arguments")
    parser.add_argument("--count", type=int, default=150)
    parser.add_argument("--rate", type=float, default=50)
    args = parser.parse_args()
    nodes = [
        subprocess.Popen(
            [
                args.ros_python,
                str(NODES / "publish_robot.py"),
                "--urdf",
                urdf,
                "--namespace",
                ns,
                "--shift",
                str(SHIFT[ns]),
                "--count",
                str(args.count),
                "--rate",
                str(args.rate),
                "--wait",
                "30",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for ns, urdf in zip(("/robot1", "/robot2", "/robot3"), args.urdf, strict=False)
    ]
    peers = [
        subprocess.Popen([sys.executable, str(NODES / "tf_peer.py"), "40", topic, json.dumps(transforms)])
        for topic, transforms in TF.items()
    ]
    out: dict[str, object] = {}
    try:
        done = subprocess.run([args.cli, "--ros", *json.loads(args.run)], capture_output=True, text=True, timeout=90)
        out["rc"], out["stderr"] = done.returncode, done.stderr
    finally:
        for p in (*nodes, *peers):
            if p.poll() is None:
                p.kill()
    out["nodes"] = []
    for node in nodes:
        stdout, stderr = node.communicate(timeout=10)
        lines = stdout.strip().splitlines()
        out["nodes"].append(json.loads(lines[-1]) if lines else {"stderr": stderr[-2000:]})  # type: ignore[attr-defined]
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
