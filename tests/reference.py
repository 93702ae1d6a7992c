"""Independent reimplementations the tests compare against (nothing here imports r2d2_viz).

* ``state_publisher`` — a line-by-line port of the tutorial's ``state_publisher.py`` main loop
  (../shared/seeds/000_*.txt, section 3): publish, then advance the state.
* ``euler_to_quaternion`` — the tutorial's own function, verbatim.
* ``joint_state_publisher_delta`` — joint_state_publisher's ``update(delta)`` loop (ROS 1/2
  joint_state_publisher.py): start at 0 (or mid-range when 0 is outside the limits), move by
  ``delta``, stop at a limit and turn back; continuous joints wrap from max to min.
"""

from __future__ import annotations

from math import cos, pi, sin


def euler_to_quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """Verbatim from state_publisher.py; returns (x, y, z, w)."""
    qx = sin(roll / 2) * cos(pitch / 2) * cos(yaw / 2) - cos(roll / 2) * sin(pitch / 2) * sin(yaw / 2)
    qy = cos(roll / 2) * sin(pitch / 2) * cos(yaw / 2) + sin(roll / 2) * cos(pitch / 2) * sin(yaw / 2)
    qz = cos(roll / 2) * cos(pitch / 2) * sin(yaw / 2) - sin(roll / 2) * sin(pitch / 2) * cos(yaw / 2)
    qw = cos(roll / 2) * cos(pitch / 2) * cos(yaw / 2) + sin(roll / 2) * sin(pitch / 2) * sin(yaw / 2)
    return (qx, qy, qz, qw)


def state_publisher(n_samples: int) -> list[dict[str, object]]:
    """What state_publisher.py publishes on each of its first ``n_samples`` loop iterations."""
    degree = pi / 180.0
    tilt = 0.0
    tinc = degree
    swivel = 0.0
    angle = 0.0
    height = 0.0
    hinc = 0.005
    out: list[dict[str, object]] = []
    for _ in range(n_samples):
        out.append(
            {
                "joint_state": {"swivel": swivel, "tilt": tilt, "periscope": height},
                "odom_translation": (cos(angle) * 2, sin(angle) * 2, 0.7),
                "odom_rotation_xyzw": euler_to_quaternion(0, 0, angle + pi / 2),
            }
        )
        tilt += tinc
        if tilt < -0.5 or tilt > 0.0:
            tinc *= -1
        height += hinc
        if height > 0.2 or height < 0.0:
            hinc *= -1
        swivel += degree
        angle += degree / 4
    return out


def joint_state_publisher_delta(
    lower: float, upper: float, *, continuous: bool, delta: float, n_samples: int
) -> list[float]:
    """joint_state_publisher's ``update(delta)`` for one free joint, published before each update."""
    if continuous:
        lower, upper = -pi, pi
    position = 0.0 if lower <= 0.0 <= upper else (lower + upper) / 2
    forward = True
    out = []
    for _ in range(n_samples):
        out.append(position)
        if forward:
            position += delta
            if position > upper:
                if continuous:
                    position = lower
                else:
                    position = upper
                    forward = not forward
        else:
            position -= delta
            if position < lower:
                position = lower
                forward = not forward
    return out


def quat_xyzw_to_matrix(q):  # type: ignore[no-untyped-def]
    """Textbook unit-quaternion → rotation matrix, vectorised over leading axes."""
    import numpy as np

    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def state_publisher_bounces(n: int) -> tuple[list[float], list[float]]:
    """Tilt and periscope height of state_publisher.py's first ``n`` iterations: its loop, literally, with
    nothing else (fast enough for a day of samples)."""
    degree = pi / 180.0
    tilt, tinc, height, hinc = 0.0, degree, 0.0, 0.005
    tilts, heights = [0.0] * n, [0.0] * n
    for k in range(n):
        tilts[k] = tilt
        heights[k] = height
        tilt += tinc
        if tilt < -0.5 or tilt > 0.0:
            tinc *= -1
        height += hinc
        if height > 0.2 or height < 0.0:
            hinc *= -1
    return tilts, heights
