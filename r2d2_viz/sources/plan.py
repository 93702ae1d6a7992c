"""The plan of a run, built once before anything is shown: the robot and its kinematics, what drives it (a generated
motion, or a bag's one pass: :mod:`r2d2_viz.sources.playback`), the static transforms, the fixed frame, and what the
view is fitted to. A bag's plan reads only what must be known before the first frame, through the storages' indexes
and a bounded look-ahead: the latest ``/robot_description``, ``/tf_static``, the first seconds of ``/tf``, joint
states and display messages, and ``/tf`` sampled at a few times over the bag — never a whole extra pass.

``--start-offset``: the pass starts there, with the state a seek needs (as Foxglove's): the transforms and joint
states of the last seconds before it, the latest map before it, every static transform. Pure: no rerun import.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from r2d2_viz.errors import BagError, listed
from r2d2_viz.kinematics.tree import KinematicTree, compile_tree
from r2d2_viz.msgs.registry import in_3d
from r2d2_viz.robot.model import Robot, parse_urdf
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.sources.bag_displays import TopicMessage, display_topics, first_messages, frames_of, video_preroll
from r2d2_viz.sources.bag_joints import TimeSource, read_robot_description
from r2d2_viz.sources.bag_tf import TF_MESSAGE, TfDecoder, concatenate
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.base import JointState, SampleChunk, Source, TfRecords, tf_root
from r2d2_viz.sources.motion import ODOM
from r2d2_viz.sources.playback import (
    JOINTS,
    TF,
    WINDOW_BYTES,
    BagPass,
    Segment,
    Window,
    bag_topics_read,
    source_windows,
)
from r2d2_viz.sources.robots import (
    SHARED_FRAMES,
    RobotPlan,
    description_namespaces,
    joint_topics_of,
    namespaced_robots,
    parents_of,
    renamed,
    robots_read,
    tf_frames,
    tf_topics,
    unreached,
)
from r2d2_viz.sources.tf_check import disagreement, urdf_edges

S = 1_000_000_000
LOOKAHEAD_NS = 2 * S
"""What the plan reads of the bag's start (joint states, /tf, display messages)…"""
TF_SAMPLES, TF_SAMPLE_NS = 16, S // 5
"""…and /tf at this many times spread over the bag, this long each (the view follows the robot's trajectory)."""
PREVIEW_MESSAGES = 16
"""Display messages the view is fitted to (the first ones; past the look-ahead when the displays start late)."""
PREROLL_NS = 5 * S
"""A seek replays the transforms and joint states of this long before the offset (their latest values apply)."""
SEEK_LATEST = ("nav_msgs/msg/OccupancyGrid",)
"""Display types whose latest message before a seek is shown from the start (a map is sent once, latched)."""


@dataclass(frozen=True)
class BagReplay:
    """How a bag is replayed: the storage, the stretches and topics its one pass reads."""

    bag: Bag
    segments: tuple[Segment, ...]
    time: TimeSource
    span: tuple[int, int]
    """The replayed stretch, ``(first, last)`` receive time in ns (progress)."""
    tf_topics: tuple[tuple[str, str], ...] = ((TF, ""),)
    """The TF topics read and the prefix their frames take (several robots: :mod:`r2d2_viz.sources.robots`)."""
    shared_frames: tuple[str, ...] = SHARED_FRAMES


@dataclass(frozen=True)
class RunPlan:
    """Everything a run shows, decided before the first frame (see the module docstring)."""

    tree: KinematicTree | None
    fixed_frame: str
    source: Source | None = None
    """What moves the robot in a run without a bag (a generated motion)."""
    replay: BagReplay | None = None
    static_tf: TfRecords | None = None
    moving_tf: TfRecords | None = None
    """A bag's /tf as far as the plan read it (look-ahead and samples), not all of it."""
    skip_edges: frozenset[tuple[str, str]] = frozenset()
    """Recorded edges the URDF defines: drawn by the kinematics instead."""
    notes: tuple[str, ...] = ()
    description: str | None = None
    """The URDF text from the bag's /robot_description, when that is where the robot came from."""
    displays: dict[str, str] = field(default_factory=dict)
    """Display topics (topic → type) the run shows."""
    undisplayed: dict[str, str] = field(default_factory=dict)
    """The bag's other topics (no display draws their types)."""
    preview_joints: SampleChunk | None = None
    """The first joint states (the view is fitted to the robot in them)."""
    preview_messages: tuple[TopicMessage, ...] = ()
    """The first display messages and the first two of each topic (the view frames them; their frames are checked)."""
    seek_messages: tuple[TopicMessage, ...] = ()
    """Shown first: the latest maps before a seek, passed-through videos from their keyframe before it."""
    robots: tuple[RobotPlan, ...] = ()
    """Several robots (namespaces with a robot_description; the first is ``tree``); empty for one robot."""

    def placed(self, root: str) -> bool:
        """Whether the recorded TF gives the frame ``root`` a parent (or it is the fixed frame)."""
        return root == self.fixed_frame or any(root in r.children for r in (self.static_tf, self.moving_tf) if r)

    @property
    def root_placed(self) -> bool:
        """Whether the recorded /tf gives the robot's root a parent (then it is not pinned to the fixed frame)."""
        return self.tree is None or self.placed(self.tree.robot.root)

    @property
    def moves_robot(self) -> bool:
        """Whether something drives the robot's joints (a motion, or a bag's joint states)."""
        if self.replay is not None:
            topic = self.robots[0].joints_topic if self.robots else JOINTS
            return self.tree is not None and any(topic in s.topics for s in self.replay.segments)
        return self.source is not None

    def windows(
        self,
        max_samples: int,
        *,
        max_bytes: int = WINDOW_BYTES,
        **decoders: Any,
    ) -> Iterator[Window]:
        """The run, stretch by stretch (a bag's one pass, a motion's chunks); ``decoders``: BagPass's keywords."""
        if self.replay is not None:
            r = self.replay
            actuated = self.tree.actuated if self.tree is not None else None
            bag_pass = BagPass(
                r.bag,
                r.segments,
                actuated=actuated,
                displays=self.displays,
                time=r.time,
                **decoders,
                robots=[(x.joints_topic, x.tree.actuated) for x in self.robots],
                tf_topics=dict(r.tf_topics),
                shared=r.shared_frames,
            )
            yield from bag_pass.windows(max_samples, max_bytes)
        elif self.source is not None:
            yield from source_windows(self.source, max_samples)


@dataclass(frozen=True)
class BagChoice:
    """What of a bag to replay (``ros2 bag play``'s ``--start-offset`` and ``--topics``, and ``--duration``)."""

    start_offset_s: float = 0.0
    duration_s: float | None = None
    topics: tuple[str, ...] | None = None
    joined: tuple[str, ...] = ()  # read as display topics too: an RViz Effort display's JointState topic


def plan_bag(
    bag: Bag,
    *,
    load_robot: Callable[[], Robot] | None = None,
    time: TimeSource = "receive",
    fixed_frame: str | None = None,
    packages: PackageIndex | None = None,
    choice: BagChoice = BagChoice(),
    shared_frames: Sequence[str] = SHARED_FRAMES,
) -> RunPlan:
    """Read what a replay must know before its first frame (see the module docstring)."""
    span = bag.span
    if span is None:
        raise BagError(f"{bag.path}: empty bag (no messages)")
    start, stop = _stretch(bag, span, choice)
    selected = _selected(bag, choice.topics)
    robot = load_robot() if load_robot is not None else None
    notes: list[str] = []
    text = None
    namespaces = description_namespaces(bag.topics) if robot is None else []
    if robot is None and namespaces == [""]:
        text = read_robot_description(bag)
        if text is not None:
            name = f"{bag.path.name}:/robot_description"
            robot = parse_urdf(text, source=name, base_dir=bag.path.parent, packages=packages)
    shown, undisplayed = display_topics(bag, choice.joined if robot is not None or any(namespaces) else ())
    shown = {t: m for t, m in shown.items() if t in selected}
    undisplayed = {t: m for t, m in undisplayed.items() if t in selected}
    static = _static_tf(bag) if "/tf_static" in selected else None
    moving = _tf_preview(bag, time, start, stop) if TF in selected else None
    robots: tuple[RobotPlan, ...] = ()
    tf_read: tuple[tuple[str, str], ...] = ((TF, ""),)
    shared = tuple(shared_frames)
    if robot is None and any(namespaces):  # several robots, or one in a namespace
        robots = namespaced_robots(bag, namespaces, tf_frames((static, moving)), packages)
        robot, text = (robots[0].tree.robot, robots[0].description) if robots else (None, None)
        tf_read = tuple(tf_topics(robots, selected, "tf").items())
        static, moving = _robots_tf(bag, robots, selected, (static, moving), time, start, stop, shared)
    tree = robots[0].tree if robots else compile_tree(robot) if robot is not None else None
    undisplayed |= {JOINTS: bag.topics[JOINTS].msgtype} if tree is None and JOINTS in selected else {}  # fields
    records = [r for r in (static, moving) if r is not None]
    actuated = tree.actuated if tree is not None and JOINTS in selected and not robots else None
    joint_topics = joint_topics_of(bag, robots, selected)
    robot_topics = (*(t for t, a in joint_topics if a), *(t for t, _ in tf_read[1:]))
    read = (*bag_topics_read(bag, None if robots else actuated, shown), *robot_topics)
    read = tuple(dict.fromkeys(t for t in read if t in selected))  # --topics: /tf only when named
    lookahead = [Segment(read, start, min(stop, start + LOOKAHEAD_NS))]
    preview = BagPass(
        bag,
        lookahead,
        actuated=actuated,
        displays=shown,
        time=time,
        quiet=True,
        robots=joint_topics,
        tf_topics=dict(tf_read),
        shared=shared,
    )
    joints, messages, more_joints = _preview(preview)
    if len(messages) < PREVIEW_MESSAGES and shown and stop > start + LOOKAHEAD_NS:
        messages += first_messages(bag, shown, start + LOOKAHEAD_NS, stop, PREVIEW_MESSAGES - len(messages))
    if robot is None:
        what = "its transforms and display topics" if shown else "a TF-only replay (frames, axes, arrows)"
        ros1 = any(f.suffix == ".bag" for f in bag.files) and JOINTS in bag.topics
        why = " (in ROS 1, robot_description is a parameter, not a topic: give the robot with --urdf)" if ros1 else ""
        notes.append(f"{bag.path}: no --urdf and no /robot_description: no robot, {what}{why}")
    frame = fixed_frame or tf_root(records) or _one_display_frame(records, robot, messages) or ODOM
    skip: frozenset[tuple[str, str]] = frozenset()
    if tree is not None:
        trees = [r.tree for r in robots] or [tree]
        skip = frozenset(e for r in records for e in r.edges() if any(e in urdf_edges(t) for t in trees))
        checked = [(r.tree, j, r.joints_topic) for r, j in zip(robots, (joints, *more_joints), strict=False)]
        for checked_tree, checked_joints, topic in checked or [(tree, joints, JOINTS)]:
            message = _check(checked_tree, checked_joints, records, topic) if skip else None
            if message:
                notes.append(f"{bag.path}: {message}")
    if len(robots) > 1:
        notes += [f"{bag.path}: {line}" for r in robots if (line := unreached(r, frame, parents_of(records)))]
    segments = [Segment(read, start, stop)]
    if start > span[0]:  # a seek: the state before it
        before = tuple(t for t in (JOINTS, TF, *robot_topics) if t in segments[0].topics)
        segments.insert(0, Segment(before, max(span[0], start - PREROLL_NS), start))
    seek = tuple(
        TopicMessage(found[0], topic, msgtype, found[1])
        for topic, msgtype in shown.items()
        if start > span[0] and msgtype in SEEK_LATEST and (found := bag.last(topic, before_ns=start)) is not None
    ) + (video_preroll(bag, shown, start) if start > span[0] else ())
    return RunPlan(
        tree,
        frame,
        replay=BagReplay(bag, tuple(segments), time, (start, min(stop, span[1])), tf_read, shared),
        static_tf=static,
        moving_tf=moving,
        skip_edges=skip,
        notes=tuple(notes),
        description=text,
        displays=shown,
        undisplayed={t: m for t, m in undisplayed.items() if t not in robots_read(robots)},
        preview_joints=joints,
        preview_messages=messages,
        seek_messages=seek,
        robots=robots,
    )


def _robots_tf(
    bag: Bag,
    robots: Sequence[RobotPlan],
    selected: set[str],
    tf: tuple[TfRecords | None, TfRecords | None],
    time: TimeSource,
    start: int,
    stop: int,
    shared: Sequence[str],
) -> tuple[TfRecords | None, TfRecords | None]:
    """``tf`` (static, moving: the plan's reads) with the robots' ``/<ns>/tf_static``, ``/<ns>/tf`` merged, prefixed."""
    static, moving = [tf[0]], [tf[1]]
    for topic, prefix in tf_topics(robots, selected, "tf_static").items():
        if prefix and (records := _static_tf(bag, topic)) is not None:
            static.append(renamed(records, prefix, shared))
    for topic, prefix in tf_topics(robots, selected, "tf").items():
        if prefix and (records := _tf_preview(bag, time, start, stop, topic)) is not None:
            moving.append(renamed(records, prefix, shared))
    return concatenate([r for r in static if r is not None]), concatenate([r for r in moving if r is not None])


def _stretch(bag: Bag, span: tuple[int, int], choice: BagChoice) -> tuple[int, int]:
    """``[start, stop)`` of the replay in receive time."""
    length = (span[1] - span[0]) / S
    if not 0 <= choice.start_offset_s <= length:
        raise BagError(
            f"{bag.path}: start offset {choice.start_offset_s:g} s is past the bag's end (it lasts {length:.1f} s)"
        )
    start = span[0] + round(choice.start_offset_s * S)
    stop = span[1] + 1 if choice.duration_s is None else start + round(choice.duration_s * S)
    return start, stop


def _selected(bag: Bag, topics: Sequence[str] | None) -> set[str]:
    """Topics replayed: all, or those named as ``ros2 bag play --topics`` does (/robot_description: the model)."""
    if topics is None:
        return set(bag.topics)
    if missing := [t for t in topics if t not in bag.topics]:
        raise BagError(
            f"{bag.path}: no topic {listed(missing)} in this bag; its {len(bag.topics)} topics: "
            f"{listed(sorted(bag.topics))} (--bag {bag.path} --list shows them all)"
        )
    return {*topics, "/robot_description"}


def _static_tf(bag: Bag, topic: str = "/tf_static") -> TfRecords | None:
    if not bag.require_type(topic, TF_MESSAGE):
        return None
    decoder = TfDecoder(bag.deserialize, static=True, time="receive")
    parts = [decoder.decode(block.pairs()) for block in bag.blocks([topic])]
    if decoder.bad:
        bag.warn(f"{bag.path}: {topic}: skipped {decoder.bad} messages that cannot be decoded")
    return concatenate([p for p in parts if len(p)])


def _tf_preview(bag: Bag, time: TimeSource, start: int, stop: int, topic: str = TF) -> TfRecords | None:
    """/tf at the start of the stretch and at a few times spread over it."""
    if not bag.require_type(topic, TF_MESSAGE):
        return None
    decoder = TfDecoder(bag.deserialize, static=False, time=time)
    parts = [
        decoder.decode(b.pairs()) for b in bag.blocks([topic], start_ns=start, stop_ns=min(stop, start + LOOKAHEAD_NS))
    ]
    end = min(stop, (bag.span or (start, start))[1])
    for t in np.linspace(start + LOOKAHEAD_NS, end, TF_SAMPLES).astype(np.int64) if end > start + LOOKAHEAD_NS else ():
        for block in bag.blocks([topic], start_ns=int(t), stop_ns=int(t) + TF_SAMPLE_NS):
            parts.append(decoder.decode(block.pairs()))
            break
    return concatenate([p for p in parts if len(p)])


def _preview(
    preview: BagPass,
) -> tuple[SampleChunk | None, tuple[TopicMessage, ...], tuple[SampleChunk | None, ...]]:
    """The look-ahead's joint states, its first display messages with the first two of every topic (the view frames
    what they draw; their frames are checked against the TF tree), and the other robots' joint states."""
    chunks: list[SampleChunk] = []
    messages: list[TopicMessage] = []
    per_topic: dict[str, int] = {}
    more: list[list[SampleChunk]] = [[] for _ in preview.others]
    for window in preview.windows(10_000):
        if window.joints is not None:
            chunks.append(window.joints)
        for i, chunk in enumerate(window.more_joints):
            if chunk is not None:
                more[i].append(chunk)
        for message in (m for m in window.displays if in_3d(m.msgtype)):  # a log line or a plot frames nothing
            per_topic[message.topic] = per_topic.get(message.topic, 0) + 1
            if len(messages) < PREVIEW_MESSAGES or per_topic[message.topic] <= 2:
                messages.append(message)
    others = tuple(_held(c, d.joints if d is not None else ()) for c, (_, d) in zip(more, preview.others, strict=True))
    return _held(chunks, preview.joints.joints if preview.joints is not None else ()), tuple(messages), others


def _held(chunks: list[SampleChunk], joints: Sequence[str]) -> SampleChunk | None:
    """Chunks of joint states as one, every joint held at its last value (None: no chunks, or no joints)."""
    if not chunks or not joints:
        return None
    state = JointState(joints)
    rows = np.vstack([state.update(c) for c in chunks])
    return SampleChunk(np.concatenate([c.times_ns for c in chunks]), state.joints, rows)


def _one_display_frame(records: list[TfRecords], robot: Robot | None, messages: Sequence[TopicMessage]) -> str | None:
    """A bag without TF and robot whose displays share one frame opens in it (in ``odom`` it would show nothing)."""
    if records or robot is not None or not messages:
        return None
    frames = frames_of(messages)
    return frames.pop() if len(frames) == 1 else None


def _check(
    tree: KinematicTree, joints: SampleChunk | None, records: list[TfRecords], topic: str = JOINTS
) -> str | None:
    """Recorded /tf against the kinematics of the first joint states (one message, or None when they agree)."""
    if joints is None or not len(joints):
        return None
    q = JointState(tree.actuated).update(joints)
    last = int(joints.times_ns[-1])
    for r in records:
        window = r if r.static else r.rows(np.flatnonzero(r.times_ns <= last))
        message = disagreement(tree, window, joints.times_ns, q, joints_topic=topic)
        if message:
            return message
    return None


def plan_motion(tree: KinematicTree, source: Source, fixed_frame: str) -> RunPlan:
    """A generated motion's plan."""
    return RunPlan(tree, fixed_frame, source=source)
