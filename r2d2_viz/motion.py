"""Motion generators: what drives the joints (and the odom → root transform) frame by frame.

* ``tutorial`` — exactly what the tutorial's ``state_publisher.py`` publishes at 30 Hz;
* ``sweep`` — joint_state_publisher's ``delta`` behaviour, for any robot;
* ``still`` — every joint at zero.

Every generator yields :class:`MotionChunk` s of consecutive frames, so a 24 h run never holds all
its frames at once. Frame ``k`` is at ``t = k / rate``. Pure numpy; no rerun import.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from .errors import UsageError
from .model import Joint, Robot

F64 = npt.NDArray[np.float64]
MotionName = Literal["tutorial", "sweep", "still"]
MOTIONS: tuple[MotionName, ...] = ("tutorial", "sweep", "still")
TUTORIAL_JOINTS = ("swivel", "tilt", "periscope")
_Source = Callable[[int, int], "MotionChunk"]
"""Frames ``start … start+n-1`` of a motion."""
DEGREE = math.pi / 180.0
SWEEP_STEP = DEGREE
"""joint_state_publisher's ``delta``: one step per frame, radians or metres."""


@dataclass(frozen=True, eq=False)
class MotionChunk:
    """Frames ``frame[0] … frame[-1]`` (consecutive)."""

    frame: npt.NDArray[np.int64]  # (n,)
    positions: F64  # (n, A), columns in ``Motion.joints`` order
    odom_translation: F64 | None  # (n, 3) T_odom_root translation, or None: root stays at odom
    odom_quat_xyzw: F64 | None  # (n, 4)


@dataclass(frozen=True, eq=False)
class Motion:
    name: MotionName
    robot: Robot
    joints: tuple[str, ...]
    """Columns of ``positions``: the robot's actuated joints, in the robot's order."""
    moves_root: bool
    """Whether odom → root changes over time (True only for ``tutorial``)."""

    def chunks(self, n_frames: int | None, chunk_size: int) -> Iterator[MotionChunk]:
        """Frames ``0 … n_frames-1`` (forever when None) in chunks of at most ``chunk_size``."""
        source = _GENERATORS[self.name](self)
        start = 0
        while n_frames is None or start < n_frames:
            n = chunk_size if n_frames is None else min(chunk_size, n_frames - start)
            yield source(start, n)
            start += n


def default_motion(robot: Robot) -> MotionName:
    names = {j.name for j in robot.actuated_joints}
    return "tutorial" if set(TUTORIAL_JOINTS) <= names else "sweep"


def make_motion(robot: Robot, name: MotionName | None = None) -> Motion:
    """The named motion for ``robot`` (``default_motion`` when None)."""
    name = name or default_motion(robot)
    if name not in MOTIONS:
        raise UsageError(f"unknown motion {name!r}; expected one of {', '.join(MOTIONS)}")
    joints = tuple(j.name for j in robot.actuated_joints)
    if name == "tutorial" and not set(TUTORIAL_JOINTS) <= set(joints):
        missing = sorted(set(TUTORIAL_JOINTS) - set(joints))
        raise UsageError(
            f"{robot.source}: motion 'tutorial' needs the joints {', '.join(TUTORIAL_JOINTS)}; "
            f"missing {', '.join(missing)}; use --motion sweep or still"
        )
    return Motion(name, robot, joints, moves_root=name == "tutorial")


# --- tutorial --------------------------------------------------------------------------------------


def _tutorial(motion: Motion) -> _Source:
    """state_publisher.py, step for step: publish the state, then advance it."""
    tilt, tinc, height, hinc = 0.0, DEGREE, 0.0, 0.005
    column = {name: i for i, name in enumerate(motion.joints)}
    last = 0

    def source(start: int, n: int) -> MotionChunk:
        nonlocal tilt, tinc, height, hinc, last
        assert start == last, "tutorial frames must be generated in order"
        tilts = np.empty(n)
        heights = np.empty(n)
        for k in range(n):  # the bouncing state machine is sequential by nature: ~0.3 µs a frame
            tilts[k] = tilt
            heights[k] = height
            tilt += tinc
            if tilt < -0.5 or tilt > 0.0:
                tinc *= -1
            height += hinc
            if height > 0.2 or height < 0.0:
                hinc *= -1
        last = start + n
        frame = np.arange(start, start + n, dtype=np.int64)
        positions = np.zeros((n, len(motion.joints)))
        positions[:, column["swivel"]] = frame * DEGREE  # swivel += degree, never wrapped
        positions[:, column["tilt"]] = tilts
        positions[:, column["periscope"]] = heights
        angle = frame * (DEGREE / 4)  # angle += degree / 4
        translation = np.stack([2 * np.cos(angle), 2 * np.sin(angle), np.full(n, 0.7)], axis=-1)
        yaw = angle + math.pi / 2  # euler_to_quaternion(0, 0, angle + pi/2)
        quat = np.stack([np.zeros(n), np.zeros(n), np.sin(yaw / 2), np.cos(yaw / 2)], axis=-1)
        return MotionChunk(frame, positions, translation, quat)

    return source


# --- sweep -----------------------------------------------------------------------------------------


def sweep_cycle(joint: Joint, step: float = SWEEP_STEP) -> tuple[F64, int]:
    """The exact sequence of one joint under joint_state_publisher's ``delta`` update.

    Returns ``(values, loop_start)``: frame ``k`` is ``values[k]`` for ``k < len(values)``, after
    which the sequence repeats ``values[loop_start:]``. Like joint_state_publisher, a joint starts
    at 0 (or mid-range if 0 is outside its limits), moves ``step`` per frame, stops at a limit and
    turns back; a continuous joint keeps turning (wrapping from +π to −π).
    """
    continuous = joint.type == "continuous" or joint.limit is None
    lo, hi = (-math.pi, math.pi) if continuous else (joint.limit.lower, joint.limit.upper)  # type: ignore[union-attr]
    pos = 0.0 if lo <= 0.0 <= hi else (lo + hi) / 2
    forward = True
    seen: dict[tuple[float, bool], int] = {}
    values: list[float] = []
    while (pos, forward) not in seen:
        seen[(pos, forward)] = len(values)
        values.append(pos)
        if forward:
            pos += step
            if pos > hi:
                pos, forward = (lo, True) if continuous else (hi, False)
        else:
            pos -= step
            if pos < lo:
                pos, forward = lo, True
    return np.array(values), seen[(pos, forward)]


def _sweep(motion: Motion) -> _Source:
    cycles = [sweep_cycle(motion.robot.joint(name)) for name in motion.joints]

    def source(start: int, n: int) -> MotionChunk:
        frame = np.arange(start, start + n, dtype=np.int64)
        positions = np.empty((n, len(cycles)))
        for c, (values, loop) in enumerate(cycles):
            period = len(values) - loop
            index = np.where(frame < len(values), frame, loop + (frame - loop) % period)
            positions[:, c] = values[index]
        return MotionChunk(frame, positions, None, None)

    return source


def _still(motion: Motion) -> _Source:
    def source(start: int, n: int) -> MotionChunk:
        frame = np.arange(start, start + n, dtype=np.int64)
        return MotionChunk(frame, np.zeros((n, len(motion.joints))), None, None)

    return source


_GENERATORS: dict[str, Callable[[Motion], _Source]] = {"tutorial": _tutorial, "sweep": _sweep, "still": _still}
