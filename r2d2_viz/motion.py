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


TILT_START, TILT_STEP, TILT_LOWER, TILT_UPPER = 0.0, DEGREE, -0.5, 0.0
HEIGHT_START, HEIGHT_STEP, HEIGHT_LOWER, HEIGHT_UPPER = 0.0, 0.005, 0.0, 0.2


def tutorial_reference(n: int) -> tuple[F64, F64]:
    """Tilt and periscope height of frames ``0 … n-1``: state_publisher.py's loop, literally.

    The reference for :func:`bounce_cycle` (the tests check one against the other)."""
    tilt, tinc, height, hinc = TILT_START, TILT_STEP, HEIGHT_START, HEIGHT_STEP
    tilts, heights = np.empty(n), np.empty(n)
    for k in range(n):
        tilts[k] = tilt
        heights[k] = height
        tilt += tinc
        if tilt < TILT_LOWER or tilt > TILT_UPPER:
            tinc *= -1
        height += hinc
        if height > HEIGHT_UPPER or height < HEIGHT_LOWER:
            hinc *= -1
    return tilts, heights


def bounce_cycle(start: float, step: float, lower: float, upper: float, max_steps: int = 1_000_000) -> tuple[F64, int]:
    """One variable of state_publisher.py's bouncing loop (``x += inc; if x < lower or x > upper: inc *= -1``),
    as ``(values, loop_start)`` like :func:`sweep_cycle`.

    The loop's whole state is the pair ``(x, inc)`` of floats, and the next state is a function of it
    alone, so once a state (compared bit for bit) comes back, everything after repeats exactly: the
    published value of frame ``k`` is ``values[k]`` for ``k < len(values)``, then
    ``values[loop_start + (k - loop_start) % (len(values) - loop_start)]`` — the literal loop's
    floating-point values, rounding included, at any ``k``. (Tilt repeats after 89 steps, the
    periscope after 105.)
    """
    x, inc = start, step
    seen: dict[tuple[str, str], int] = {}  # float.hex(): bit for bit (tells -0.0 from 0.0)
    values: list[float] = []
    while (state := (x.hex(), inc.hex())) not in seen:
        if len(values) >= max_steps:
            raise RuntimeError("bouncing motion does not repeat")  # cannot happen for finite steps and bounds
        seen[state] = len(values)
        values.append(x)
        x += inc
        if x < lower or x > upper:
            inc *= -1
    return np.array(values), seen[state]


def _cycle_values(cycle: tuple[F64, int], frame: npt.NDArray[np.int64]) -> F64:
    values, loop = cycle
    period = len(values) - loop
    index = np.where(frame < len(values), frame, loop + (frame - loop) % period)
    out: F64 = values[index]
    return out


def _tutorial(motion: Motion) -> _Source:
    """state_publisher.py, step for step: publish the state, then advance it (see :func:`bounce_cycle`)."""
    tilt = bounce_cycle(TILT_START, TILT_STEP, TILT_LOWER, TILT_UPPER)
    height = bounce_cycle(HEIGHT_START, HEIGHT_STEP, HEIGHT_LOWER, HEIGHT_UPPER)
    column = {name: i for i, name in enumerate(motion.joints)}

    def source(start: int, n: int) -> MotionChunk:
        frame = np.arange(start, start + n, dtype=np.int64)
        positions = np.zeros((n, len(motion.joints)))
        positions[:, column["swivel"]] = frame * DEGREE  # swivel += degree, never wrapped
        positions[:, column["tilt"]] = _cycle_values(tilt, frame)
        positions[:, column["periscope"]] = _cycle_values(height, frame)
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
    # frame at which each (position, direction) state was first seen; one dict per direction, keyed by
    # float, because tuples would be tracked by the cyclic collector (and trigger it every few hundred)
    seen: dict[bool, dict[float, int]] = {True: {}, False: {}}
    values: list[float] = []
    while pos not in seen[forward]:
        seen[forward][pos] = len(values)
        values.append(pos)
        if forward:
            pos += step
            if pos > hi:
                pos, forward = (lo, True) if continuous else (hi, False)
        else:
            pos -= step
            if pos < lo:
                pos, forward = lo, True
    return np.array(values), seen[forward][pos]


def _sweep(motion: Motion) -> _Source:
    cycles = [sweep_cycle(motion.robot.joint(name)) for name in motion.joints]

    def source(start: int, n: int) -> MotionChunk:
        frame = np.arange(start, start + n, dtype=np.int64)
        positions = np.empty((n, len(cycles)))
        for c, cycle in enumerate(cycles):
            positions[:, c] = _cycle_values(cycle, frame)
        return MotionChunk(frame, positions, None, None)

    return source


def _still(motion: Motion) -> _Source:
    def source(start: int, n: int) -> MotionChunk:
        frame = np.arange(start, start + n, dtype=np.int64)
        return MotionChunk(frame, np.zeros((n, len(motion.joints))), None, None)

    return source


_GENERATORS: dict[str, Callable[[Motion], _Source]] = {"tutorial": _tutorial, "sweep": _sweep, "still": _still}
