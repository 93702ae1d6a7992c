"""A real camera and lidar node against ``r2d2-viz --ros --save``, run INSIDE a loopback-only network namespace.

Starts ``nodes/publish_sensors.py`` (the node's arguments as JSON), then the app with the given arguments (it
joins late, the node waits for its readers and streams); when the node is done and has lingered, the app gets
SIGINT (a live save is finalised on it). Prints one JSON line: the app's exit code and stderr, the node's report.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

NODES = Path(__file__).resolve().parent / "nodes"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ros-python", required=True)
    parser.add_argument("--cli", required=True, help="the r2d2-viz command")
    parser.add_argument("--node", required=True, help="JSON list of arguments of publish_sensors.py")
    parser.add_argument("--app", required=True, help="JSON list of arguments of r2d2-viz after --ros")
    args = parser.parse_args()
    node = subprocess.Popen(
        [args.ros_python, str(NODES / "publish_sensors.py"), *json.loads(args.node)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    app = subprocess.Popen(
        [args.cli, "--ros", *json.loads(args.app)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    try:
        node_out, node_err = node.communicate(timeout=120)
        if app.poll() is None:
            app.send_signal(signal.SIGINT)
        _, app_err = app.communicate(timeout=60)
    finally:
        for p in (node, app):
            if p.poll() is None:
                p.kill()
    lines = node_out.strip().splitlines()
    report = json.loads(lines[-1]) if lines else {"stderr": node_err[-2000:]}
    print(json.dumps({"rc": app.returncode, "stderr": app_err, "node": report}))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
