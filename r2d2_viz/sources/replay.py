"""What a bag replay shows: the robot (``--urdf``, else the bag's latest ``/robot_description``, else none: a
TF-only replay), its ``/joint_states`` as a source, its ``/tf`` and ``/tf_static`` as recorded, and the fixed frame
(``--fixed-frame``, else the root of the recorded TF tree). Pure: no rerun import.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from r2d2_viz.kinematics.tree import KinematicTree, compile_tree
from r2d2_viz.robot.model import Robot, parse_urdf
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.bag_displays import TopicMessage, bag_messages, display_frames, display_topics
from r2d2_viz.sources.bag_joints import BagSource, TimeSource, read_robot_description
from r2d2_viz.sources.bag_tf import read_tf
from r2d2_viz.sources.base import JointState, Source, TfRecords, tf_root
from r2d2_viz.sources.motion import ODOM
from r2d2_viz.sources.tf_check import disagreement, urdf_edges

CHECK_SAMPLES = 10_000
"""Recorded /tf is compared with the kinematics over the first this many joint states (each edge checked there)."""


@dataclass
class Replay:
    tree: KinematicTree | None
    source: Source | None
    static_tf: TfRecords | None
    moving_tf: TfRecords | None
    fixed_frame: str
    skip_edges: set[tuple[str, str]] = field(default_factory=set)
    """Recorded edges the URDF defines: drawn by the kinematics instead."""
    notes: list[str] = field(default_factory=list)
    mcap_files: list[Path] = field(default_factory=list)
    """The bag's MCAP storage files, for the topics no display of ours draws (Rerun's own decoders)."""
    description: str | None = None
    """The URDF text from the bag's /robot_description, when that is where the robot came from."""
    displays: dict[str, str] = field(default_factory=dict)
    """Display topics (topic → type): scans, clouds, markers, maps… (:mod:`r2d2_viz.sources.bag_displays`)."""
    undisplayed: dict[str, str] = field(default_factory=dict)
    """The bag's other topics: no display draws their types."""
    display_messages: Callable[[], Iterator[TopicMessage]] | None = None
    """A fresh stream of the display topics' messages, in receive-time order."""

    @property
    def root_placed(self) -> bool:
        """Whether the recorded /tf gives the robot's root a parent (then it is not pinned to the fixed frame)."""
        if self.tree is None:
            return True
        root = self.tree.robot.root
        if root == self.fixed_frame:
            return True
        return any(root in r.children for r in (self.static_tf, self.moving_tf) if r is not None)


def open_replay(
    bag: Bag,
    *,
    load_robot: Callable[[], Robot] | None = None,
    time: TimeSource = "receive",
    fixed_frame: str | None = None,
    packages: PackageIndex | None = None,
) -> Replay:
    """Read what the replay needs up front (robot, transforms); joint states stay in the bag, read in chunks."""
    robot = load_robot() if load_robot is not None else None
    notes: list[str] = []
    text = None
    if robot is None:
        text = read_robot_description(bag)
        if text is not None:
            name = f"{bag.path.name}:/robot_description"
            robot = parse_urdf(text, source=name, base_dir=bag.path.parent, packages=packages)
    records = read_tf(bag, time=time)
    static_tf = next((r for r in records if r.static), None)
    moving_tf = next((r for r in records if not r.static), None)
    shown, undisplayed = display_topics(bag)
    if robot is None:
        what = "its transforms and display topics" if shown else "a TF-only replay (frames, axes, arrows)"
        notes.append(f"{bag.path}: no --urdf and no /robot_description: no robot, {what}")
    tree = compile_tree(robot) if robot is not None else None
    frame = fixed_frame or tf_root(records) or _one_display_frame(bag, shown, records, robot) or ODOM
    replay = Replay(tree, None, static_tf, moving_tf, frame, notes=notes, description=text)
    replay.displays, replay.undisplayed = shown, undisplayed
    if shown:
        replay.display_messages = lambda: bag_messages(bag, shown)
    if tree is not None:
        replay.skip_edges = {e for r in records for e in r.edges() if e in urdf_edges(tree)}
        source = BagSource(bag, tree.actuated, time=time)
        replay.source = source if source.present else None
        message = _check(tree, source, records) if replay.skip_edges else None
        if message:
            replay.notes.append(f"{bag.path}: {message}")
    return replay


def _one_display_frame(bag: Bag, shown: dict[str, str], records: list[TfRecords], robot: Robot | None) -> str | None:
    """A bag without TF and without a robot whose displays are all in one frame opens in that frame (in ``odom``,
    where nothing of it could be placed, it would show nothing)."""
    if records or robot is not None or not shown:
        return None
    frames = display_frames(bag, shown)
    return frames.pop() if len(frames) == 1 else None


def _check(tree: KinematicTree, source: BagSource, records: list[TfRecords]) -> str | None:
    """Recorded /tf against the kinematics of the first joint states (one message, or None when they agree)."""
    if not source.present:
        return None
    chunk = next(iter(source.chunks(CHECK_SAMPLES)), None)
    if chunk is None:
        return None
    q = JointState(tree.actuated).update(chunk)
    last = int(chunk.times_ns[-1])
    for r in records:
        window = r if r.static else _until(r, last)
        message = disagreement(tree, window, chunk.times_ns, q)
        if message:
            return message
    return None


def _until(r: TfRecords, last_ns: int) -> TfRecords:
    return r.rows(np.flatnonzero(r.times_ns <= last_ns))
