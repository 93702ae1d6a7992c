"""Live ROS 2 transport (issue 19): a real node's 1 kHz JointState of 30 joints, received by r2d2-viz's reader.

A real rclpy node (PyPI's ``ros-rclpy[fastrtps]``, in the tests' cached venv) publishes ``/joint_states`` at
1 kHz for ``--seconds`` (60) inside a loopback-only network namespace (``unshare -n``: root); our ``LiveGraph``
joins late, polls every 5 ms and checks every message. Reports the share received and the lateness (the
writer's source timestamp → the poll that returned it), p50 / p99 / max. Needs root; nothing leaves loopback.

    python benchmarks/live_dds.py [--seconds 60] [--distro jazzy|kilted|both]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1] / "tests"
sys.path.insert(0, str(TESTS))

from live import ros_node  # noqa: E402


def run(distro: str, seconds: float) -> dict[str, object]:
    """One run of ``tests/sources/live/scenario.py`` at 1 kHz, 30 joints; its JSON result."""
    missing = ros_node.netns_missing()
    if missing:
        raise SystemExit(f"live_dds: {missing}")
    python = ros_node.ensure_venv(distro)
    count = int(seconds * 1000)
    command = [
        sys.executable, str(TESTS / "sources" / "live" / "scenario.py"), "--ros-python", str(python),
        "--urdf", str(TESTS.parent / "assets" / "r2d2.urdf"), "--rate", "1000", "--count", str(count),
        "--joints", "30", "--deadline", str(seconds + 60),
    ]  # fmt: skip
    done = ros_node.in_netns(command, timeout=seconds + 120)
    if done.returncode != 0:
        raise SystemExit(f"live_dds: scenario failed: {done.stderr[-2000:]}")
    result: dict[str, object] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--distro", choices=["jazzy", "kilted", "both"], default="both")
    args = parser.parse_args()
    for distro in ["jazzy", "kilted"] if args.distro == "both" else [args.distro]:
        r = run(distro, args.seconds)
        node = r["node"]
        assert isinstance(node, dict)
        sent, got = int(node["sent"]), int(str(r["joint_states"]))
        print(
            f"{distro}: {got}/{sent} JointStates (30 joints, 1 kHz, {node['seconds']:.1f} s) = {100 * got / sent:.2f} %"
            f" received, {r['mismatches']} wrong, dropped {r['dropped']}; lateness p50 {r['lateness_ms_p50']:.2f} ms,"
            f" p99 {r['lateness_ms_p99']:.2f} ms, max {r['lateness_ms_max']:.2f} ms"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
