"""Generated motions: sources (:mod:`r2d2_viz.sources.base`) that need nothing but the robot.

* ``tutorial`` — exactly what the tutorial's ``state_publisher.py`` publishes at 30 Hz, odom → root included;
* ``sweep`` — joint_state_publisher's ``delta`` behaviour, for any robot;
* ``still`` — every joint at zero;
* ``sliders`` — a slider per joint in the page (:mod:`r2d2_viz.sources.sliders`).

Sample ``k`` is at ``t = k / rate`` (a duration since the start). Motions yield chunks of consecutive samples,
so a 24 h run never holds all of them at once. Pure numpy; no rerun import.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Literal

import numpy as np

from r2d2_viz.arrays import F64, I64
from r2d2_viz.errors import UsageError
from r2d2_viz.sources.base import Clock, FrameTrack, SampleChunk
from r2d2_viz.sources.sliders import SliderBoard

if TYPE_CHECKING:  # the model imports lxml; the CLI imports this module for --help
    from r2d2_viz.robot.model import Joint, Robot

MotionName = Literal["tutorial", "sweep", "still", "sliders"]
MOTIONS: tuple[MotionName, ...] = ("tutorial", "sweep", "still", "sliders")
TUTORIAL_JOINTS = ("swivel", "tilt", "periscope")
ODOM = "odom"
"""The tutorial's fixed frame: state_publisher.py publishes ``odom → axis``."""
DEGREE = math.pi / 180.0
SWEEP_STEP = DEGREE
"""joint_state_publisher's ``delta``: one step per sample, radians or metres."""
SWEEP_MAX_STEPS = 100_000
"""A joint whose limits are further apart than this many steps (about 1,745 rad or m: ±1e16, ±1e300, inf
mean "unlimited") sweeps like a continuous joint, over [−π, π]: a cycle over its whole range would never end."""


class GeneratedMotion(ABC):
    """A source computed from the sample index: ``times_ns = rint(k · 10⁹ / rate)``.

    ``n_samples`` None: forever (live runs until Ctrl-C)."""

    name: MotionName
    clock: Clock = "duration"

    def __init__(self, robot: Robot, *, rate: float = 30.0, n_samples: int | None = None) -> None:
        self.robot = robot
        self.rate = rate
        self.n_samples = n_samples
        self.joints: tuple[str, ...] = tuple(j.name for j in robot.actuated_joints)
        self.frames: tuple[tuple[str, str], ...] = ()
        self.before_chunk: Callable[[int], None] | None = None
        """``--watch`` (:mod:`r2d2_viz.viewer.workbench.watch`): called with the index of each chunk's first sample,
        before it is computed (chunks are then a sample each); it may re-initialise this motion for a new robot."""

    def chunks(self, max_samples: int) -> Iterator[SampleChunk]:
        start = 0
        while self.n_samples is None or start < self.n_samples:
            if self.before_chunk is not None:
                self.before_chunk(start)
                max_samples = 1
            n = max_samples if self.n_samples is None else min(max_samples, self.n_samples - start)
            k = np.arange(start, start + n, dtype=np.int64)
            positions, frames = self.at(k)
            yield SampleChunk(np.rint(k * (1e9 / self.rate)).astype(np.int64), self.joints, positions, frames)
            start += n

    @abstractmethod
    def at(self, k: I64) -> tuple[F64, tuple[FrameTrack, ...]]:
        """Positions ``(n, len(joints))`` and frame tracks of samples ``k``."""


def default_motion(robot: Robot) -> MotionName:
    names = {j.name for j in robot.actuated_joints}
    return "tutorial" if set(TUTORIAL_JOINTS) <= names else "sweep"


def make_motion(
    robot: Robot, name: str | None = None, *, rate: float = 30.0, n_samples: int | None = None
) -> GeneratedMotion:
    """The named motion for ``robot`` (``default_motion`` when None)."""
    name = name or default_motion(robot)
    if name == "tutorial":
        return TutorialMotion(robot, rate=rate, n_samples=n_samples)
    if name == "sweep":
        return SweepMotion(robot, rate=rate, n_samples=n_samples)
    if name == "still":
        return StillMotion(robot, rate=rate, n_samples=n_samples)
    if name == "sliders":
        return SlidersMotion(robot, rate=rate, n_samples=n_samples)
    raise UsageError(f"unknown motion {name!r}; expected one of {', '.join(MOTIONS)}")


# --- tutorial --------------------------------------------------------------------------------------


TILT_START, TILT_STEP, TILT_LOWER, TILT_UPPER = 0.0, DEGREE, -0.5, 0.0
HEIGHT_START, HEIGHT_STEP, HEIGHT_LOWER, HEIGHT_UPPER = 0.0, 0.005, 0.0, 0.2


def bounce_cycle(start: float, step: float, lower: float, upper: float, max_steps: int = 1_000_000) -> tuple[F64, int]:
    """One variable of state_publisher.py's bouncing loop (``x += inc; if x < lower or x > upper: inc *= -1``),
    as ``(values, loop_start)`` like :func:`sweep_cycle`.

    The loop's whole state is the pair ``(x, inc)`` of floats, and the next state is a function of it
    alone, so once a state (compared bit for bit) comes back, everything after repeats exactly: the
    published value of sample ``k`` is ``values[k]`` for ``k < len(values)``, then
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


def _cycle_values(cycle: tuple[F64, int], k: I64) -> F64:
    values, loop = cycle
    period = len(values) - loop
    index = np.where(k < len(values), k, loop + (k - loop) % period)
    out: F64 = values[index]
    return out


class TutorialMotion(GeneratedMotion):
    """state_publisher.py, step for step: publish the state, then advance it (see :func:`bounce_cycle`)."""

    name: MotionName = "tutorial"

    def __init__(self, robot: Robot, *, rate: float = 30.0, n_samples: int | None = None) -> None:
        super().__init__(robot, rate=rate, n_samples=n_samples)
        missing = [name for name in TUTORIAL_JOINTS if name not in self.joints]
        if missing:
            raise UsageError(
                f"{robot.source}: motion 'tutorial' needs the joints {', '.join(TUTORIAL_JOINTS)}; "
                f"missing {', '.join(missing)}; use --motion sweep or still"
            )
        self.frames = ((ODOM, robot.root),)
        self._tilt = bounce_cycle(TILT_START, TILT_STEP, TILT_LOWER, TILT_UPPER)
        self._height = bounce_cycle(HEIGHT_START, HEIGHT_STEP, HEIGHT_LOWER, HEIGHT_UPPER)
        self._column = {name: i for i, name in enumerate(self.joints)}

    def at(self, k: I64) -> tuple[F64, tuple[FrameTrack, ...]]:
        n = len(k)
        positions = np.zeros((n, len(self.joints)))
        positions[:, self._column["swivel"]] = k * DEGREE  # swivel += degree, never wrapped
        positions[:, self._column["tilt"]] = _cycle_values(self._tilt, k)
        positions[:, self._column["periscope"]] = _cycle_values(self._height, k)
        angle = k * (DEGREE / 4)  # angle += degree / 4
        translation = np.stack([2 * np.cos(angle), 2 * np.sin(angle), np.full(n, 0.7)], axis=-1)
        yaw = angle + math.pi / 2  # euler_to_quaternion(0, 0, angle + pi/2)
        quat = np.stack([np.zeros(n), np.zeros(n), np.sin(yaw / 2), np.cos(yaw / 2)], axis=-1)
        return positions, (FrameTrack(ODOM, self.robot.root, translation, quat),)


# --- sweep -----------------------------------------------------------------------------------------


def sweep_cycle(joint: Joint, step: float = SWEEP_STEP) -> tuple[F64, int]:
    """The exact sequence of one joint under joint_state_publisher's ``delta`` update.

    Returns ``(values, loop_start)``: sample ``k`` is ``values[k]`` for ``k < len(values)``, after
    which the sequence repeats ``values[loop_start:]``. Like joint_state_publisher, a joint starts
    at 0 (or mid-range if 0 is outside its limits), moves ``step`` per sample, stops at a limit and
    turns back; a continuous joint keeps turning (wrapping from +π to −π), and so does a joint whose
    limits are too far apart to mean anything (see :data:`SWEEP_MAX_STEPS`).
    """
    limit = joint.limit
    continuous = (
        joint.type == "continuous"
        or limit is None
        or not (math.isfinite(limit.lower) and math.isfinite(limit.upper))
        or (limit.upper - limit.lower) / step > SWEEP_MAX_STEPS
    )
    lo, hi = (-math.pi, math.pi) if continuous or limit is None else (limit.lower, limit.upper)
    pos = 0.0 if lo <= 0.0 <= hi else (lo + hi) / 2
    forward = True
    # sample at which each (position, direction) state was first seen; one dict per direction, keyed by
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


class SweepMotion(GeneratedMotion):
    name: MotionName = "sweep"

    def __init__(self, robot: Robot, *, rate: float = 30.0, n_samples: int | None = None) -> None:
        super().__init__(robot, rate=rate, n_samples=n_samples)
        self._cycles = [sweep_cycle(robot.joint(name)) for name in self.joints]

    def at(self, k: I64) -> tuple[F64, tuple[FrameTrack, ...]]:
        positions = np.empty((len(k), len(self._cycles)))
        for c, cycle in enumerate(self._cycles):
            positions[:, c] = _cycle_values(cycle, k)
        return positions, ()


class StillMotion(GeneratedMotion):
    name: MotionName = "still"

    def at(self, k: I64) -> tuple[F64, tuple[FrameTrack, ...]]:
        return np.zeros((len(k), len(self.joints))), ()


class SlidersMotion(GeneratedMotion):
    """The page's sliders as a source (:mod:`r2d2_viz.sources.sliders`): every sample holds the values the sliders
    had when it was taken."""

    name: MotionName = "sliders"

    def __init__(self, robot: Robot, *, rate: float = 30.0, n_samples: int | None = None) -> None:
        super().__init__(robot, rate=rate, n_samples=n_samples)
        self.board = SliderBoard(robot)

    def chunks(self, max_samples: int) -> Iterator[SampleChunk]:
        """A sample a chunk, whatever ``max_samples``: a live run takes each when it is due, so a move shows at the
        next sample (blocks of several would show it only when the next block is computed)."""
        return super().chunks(1)

    def at(self, k: I64) -> tuple[F64, tuple[FrameTrack, ...]]:
        return np.tile(self.board.values(), (len(k), 1)), ()
