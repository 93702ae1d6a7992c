#!/usr/bin/env python3
"""Log a robot following a numpy joint trajectory into your own Rerun recording, with r2d2-viz's API.

    python examples/log_trajectory.py --spawn              # the native viewer
    python examples/log_trajectory.py --save out.rrd       # a recording; open it with: rerun out.rrd
    python examples/log_trajectory.py --urdf my_robot.urdf --seconds 20

The robot (default: ``examples/arm6.urdf``, a six-joint arm) moves every actuated joint along a smooth
sinusoid inside its limits; the pose of every link comes from r2d2-viz's kinematics, as named frames.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import rerun as rr

import r2d2_viz

APPLICATION_ID = "r2d2_viz_log_trajectory"
DEFAULT_URDF = Path(__file__).with_name("arm6.urdf")


def trajectory(robot: r2d2_viz.Robot, joints: tuple[str, ...], times: np.ndarray) -> np.ndarray:
    """``(T, J)`` positions: joint j swings at its own frequency between 10 % and 90 % of its range."""
    positions = np.empty((len(times), len(joints)))
    for j, name in enumerate(joints):
        joint = robot.joint(name)
        limited = joint.limit is not None and joint.type != "continuous"
        lower, upper = (joint.limit.lower, joint.limit.upper) if joint.limit and limited else (-np.pi, np.pi)
        middle, half = (lower + upper) / 2, 0.4 * (upper - lower)
        positions[:, j] = middle + half * np.sin(2 * np.pi * (0.1 + 0.05 * j) * times + j)
    return positions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--urdf", type=Path, default=DEFAULT_URDF, help="a URDF file (default: a six-joint arm)")
    parser.add_argument("--seconds", type=float, default=10.0, help="length of the trajectory")
    parser.add_argument("--rate", type=float, default=100.0, help="samples per second")
    rr.script_add_args(parser)
    args = parser.parse_args()

    rr.script_setup(args, APPLICATION_ID, default_blueprint=r2d2_viz.generate_blueprint())
    robot = r2d2_viz.load_urdf(args.urdf)
    logger = r2d2_viz.RobotLogger(robot)
    logger.log_static()
    times = np.arange(0.0, args.seconds, 1.0 / args.rate)
    logger.log_joint_positions(times, trajectory(robot, logger.joints, times))
    logger.finish()
    rr.script_teardown(args)


if __name__ == "__main__":
    main()
