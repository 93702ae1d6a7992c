"""``r2d2-viz --ros`` against real nodes, run INSIDE a loopback-only network namespace (``ros_node.in_netns``).

A real ROS 2 node (``nodes/publish_robot.py``) publishes a latched ``/robot_description`` first; optionally a
cyclonedds peer puts the wrong type on ``/joint_states``. Then ``r2d2-viz --ros --list`` runs, and the CLI runs
given as JSON lists of arguments run at the same time (late joiners; the node streams once all have subscribed).
Once the node has sent everything (its JSON line) and a grace period has passed, each run still going gets SIGINT,
as a user stops a live run (each run's ``--duration`` is only the bound). Prints one JSON: the list's output, each
run's exit code and stderr, the node's report.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

NODES = Path(__file__).resolve().parent / "nodes"


def _wait_for_port(port: int, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with socket.socket() as probe:
            if probe.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise SystemExit(f"cli_scenario: the rerun server did not listen on {port}")


GRACE = 1.5
"""Seconds between the node's last message and the runs' SIGINT: loopback delivers in milliseconds; a run polls
every few ms and drains its reader once more when stopped."""


def _lines(stream: Any, into: list[str], sent: threading.Event) -> None:
    for line in stream:
        into.append(line)
        if line.startswith("{"):
            sent.set()


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ros-python", required=True)
    parser.add_argument("--urdf", required=True)
    parser.add_argument("--cli", required=True, help="the r2d2-viz command")
    parser.add_argument("--node", default="[]", help="JSON list of extra arguments of publish_robot.py")
    parser.add_argument("--wrong-type-peer", action="store_true")
    parser.add_argument("--runs", required=True, help="JSON list of argument lists")
    parser.add_argument("--rerun", default=None, help="start this rerun binary as a gRPC server first (--connect)")
    parser.add_argument("--server-port", type=int, default=9877)
    parser.add_argument("--server-save", default=None, help="what the server received, saved here at the end")
    args = parser.parse_args()
    runs = json.loads(args.runs)
    server = None
    if args.rerun:
        server = subprocess.Popen(
            [args.rerun, "--port", str(args.server_port), "--bind", "127.0.0.1", "--save", args.server_save],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
        )  # fmt: skip
        _wait_for_port(args.server_port)
    node = subprocess.Popen(
        [args.ros_python, str(NODES / "publish_robot.py"), "--urdf", args.urdf, "--subscribers", str(len(runs)),
         *json.loads(args.node)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    node_out: list[str] = []
    sent = threading.Event()
    node_err: list[str] = []
    readers = [
        threading.Thread(target=_lines, args=(node.stdout, node_out, sent), daemon=True),
        threading.Thread(target=_lines, args=(node.stderr, node_err, threading.Event()), daemon=True),
    ]
    for reader in readers:
        reader.start()
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
        if sent.wait(timeout=60):
            time.sleep(GRACE)
            for proc in procs:
                if proc.poll() is None:
                    proc.send_signal(signal.SIGINT)
        for proc in procs:
            _, stderr = proc.communicate(timeout=60)
            out["runs"].append({"rc": proc.returncode, "stderr": stderr})  # type: ignore[union-attr]
        if server is not None:  # the server writes what it received when interrupted
            time.sleep(1.0)
            os.killpg(server.pid, signal.SIGINT)
            out["server_rc"] = server.wait(timeout=30)
    finally:
        if server is not None and server.poll() is None:
            os.killpg(server.pid, signal.SIGKILL)
        for p in (node, peer):
            if p is not None and p.poll() is None:
                p.kill()
    node.wait(timeout=10)
    for reader in readers:
        reader.join(timeout=10)
    stderr = "".join(node_err)
    lines = [line for line in node_out if line.strip()]
    out["node"] = json.loads(lines[-1]) if lines else {"stderr": stderr[-2000:]}
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
