"""A 60 s R2D2 bag for ``--render`` (issue 45), written by rosbags (tests/bagmaker.py): still, then moving, then
still again, so a rendered video must change in the middle third and nowhere else.

/joint_states and /tf (``odom → axis``) every 0.5 s from 0 to 60 s (121 each): for t < 20 s every joint at 0 and the
base at the origin; for 20 ≤ t ≤ 40 s swivel turns at 0.3 rad/s and the base drives along x at 0.1 m/s (2 m in
all); from 40 s everything holds where it got to (swivel 6 rad, base at x = 2 m). /robot_description at 0.
"""

from __future__ import annotations

from pathlib import Path

from bagmaker import T0, BagSpec, joint_state, string, tf_message, write_bag

from r2d2_viz.robot.model import default_urdf_path

S = 1_000_000_000
DURATION_S = 60
STEP_NS = S // 2
MOVING_S = (20.0, 40.0)
"""The robot moves between these times (s from the bag's start) and holds still before and after."""
JOINTS = ["swivel", "tilt", "periscope"]
IDENTITY = (0.0, 0.0, 0.0, 1.0)


def moved(t_s: float) -> float:
    """Seconds of motion done by ``t_s``: 0 before 20 s, 20 from 40 s."""
    return min(max(t_s - MOVING_S[0], 0.0), MOVING_S[1] - MOVING_S[0])


def write_render_bag(path: Path) -> Path:
    spec = BagSpec()
    spec.add("/robot_description", T0, string(default_urdf_path().read_text()))
    for k in range(DURATION_S * S // STEP_NS + 1):
        t = T0 + k * STEP_NS
        done = moved(k * STEP_NS / S)
        spec.add("/joint_states", t, joint_state(t, JOINTS, [0.3 * done, 0.0, 0.0]))
        spec.add("/tf", t, tf_message([(t, "odom", "axis", (0.1 * done, 0.0, 0.0), IDENTITY)]))
    return write_bag(path, spec)
