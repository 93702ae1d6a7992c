"""What :func:`~.tf_tree.analyse` needs, read from a bag in one pass of its storage blocks: ``/tf`` rows (receive
time and header stamp, decoded in bulk by :class:`~r2d2_viz.sources.bag_tf.TfDecoder`), ``/tf_static``'s edges, and
the frame and stamp of every message whose type starts with a ``std_msgs/Header``, gathered from the CDR bytes with
numpy (no message is deserialised for it). Pure; no rerun import."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from r2d2_viz.arrays import I64
from r2d2_viz.msgs.definitions import own_store
from r2d2_viz.msgs.typestore import MsgError, typestore
from r2d2_viz.sources.bag_joints import JOINT_STATE, JointStateDecoder
from r2d2_viz.sources.bag_tf import TF_MESSAGE, TfDecoder
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.bags.storage import Block, TopicInfo
from r2d2_viz.sources.base import SampleChunk
from r2d2_viz.sources.plan import RunPlan
from r2d2_viz.sources.playback import JOINTS
from r2d2_viz.sources.robots import SHARED_FRAMES, renamed, tf_topics
from r2d2_viz.sources.system.tf_robot import RobotFrames, Rows
from r2d2_viz.sources.system.tf_tree import NO_HEADERS, HeaderRows, TfRows, TfTree, analyse, tf_rows

TF_TOPICS = ("/tf", "/tf_static")
MAX_FRAME_ID = 256
"""Longer frame ids are taken for damage and left out."""
HEADER_TYPE = "std_msgs/msg/Header"


def has_header(msgtype: str, definition: str = "", encoding: str = "") -> bool:
    """Whether messages of ``msgtype`` start with a ``std_msgs/Header``: by the message ``definition`` their bag
    carries (in ``encoding``: a vendor's type that only the bag defines), else by Humble's."""
    store = typestore()
    if definition:
        try:
            store = own_store(msgtype, definition, encoding)
        except MsgError:
            pass  # a definition that cannot be read: as Humble has the type, if it does
    defs = store.fielddefs.get(msgtype)
    if not defs or not defs[1]:
        return False
    name, (_, kind) = defs[1][0]
    return bool(name == "header" and kind == HEADER_TYPE)


def header_first(topic: TopicInfo) -> bool:
    """:func:`has_header` of a bag's topic, by the definition the bag carries for it."""
    return has_header(topic.msgtype, topic.definition, topic.encoding)


def header_columns(block: Block, rows: np.ndarray) -> tuple[np.ndarray, I64, np.ndarray]:
    """The frame ids (str array), stamps (ns) and which of ``rows`` had a readable header (bool), in the endianness
    its CDR encapsulation says (byte 1: 1 little, 0 big): bytes 4..12 the stamp, 12..16 the frame id's length with
    its NUL, then its characters."""
    buf = np.frombuffer(block.buffer, dtype=np.uint8)
    starts, lengths = block.starts[rows], block.lengths[rows]
    ok = lengths >= 17
    s = np.where(ok, starts, 0)
    head = buf[s[:, None] + np.arange(16)] if len(s) else np.zeros((0, 16), np.uint8)
    ok &= (head[:, 0] == 0) & (head[:, 1] <= 1)  # CDR_BE (0, 0) or CDR_LE (0, 1)
    big = head[:, 1] == 0
    head = np.ascontiguousarray(head)

    def number(at: int, kind: str) -> I64:
        cells = head[:, at : at + 4].copy()
        out: I64 = np.where(big, cells.view(">" + kind)[:, 0], cells.view("<" + kind)[:, 0]).astype(np.int64)
        return out

    sec, nsec, size = number(4, "i4"), number(8, "u4"), number(12, "u4")
    ok &= (size >= 1) & (size <= MAX_FRAME_ID) & (16 + size <= lengths)
    chars = np.where(ok, size - 1, 0)
    width = int(chars.max()) if len(chars) else 0
    if width:
        at = np.minimum(s[:, None] + 16 + np.arange(width), len(buf) - 1)
        text = np.where(np.arange(width) < chars[:, None], buf[at], 0).astype(np.uint8)
        raw = text.view(f"S{width}")[:, 0]
    else:
        raw = np.zeros(len(rows), dtype="S1")
    uniq, inverse = np.unique(raw, return_inverse=True)
    names = np.array([u.decode("utf-8", "replace").removeprefix("/") for u in uniq], dtype=object)
    return names[inverse], sec * 1_000_000_000 + nsec, ok


@dataclass(frozen=True)
class TfSources:
    """What of a bag makes its TF tree, as the replay reads it: the TF topics and the prefix their frames take
    (a robot's own ``/robot2/tf``: ``robot2/``, but for the ``shared`` frames), and the robots the replay draws
    from their descriptions (``robot``, moved by the joint states of ``joints``: one topic per tree)."""

    moving: Mapping[str, str] = field(default_factory=lambda: {"/tf": ""})
    static: Mapping[str, str] = field(default_factory=lambda: {"/tf_static": ""})
    shared: tuple[str, ...] = SHARED_FRAMES
    robot: RobotFrames | None = None
    joints: tuple[str, ...] = ()


def read_bag(
    bag: Bag, *, headers: bool = True, sources: TfSources | None = None
) -> tuple[TfRows, list[tuple[str, str]], HeaderRows]:
    """The TF topics' dynamic rows and static edges (a robot's frames added where the recorded TF lacks them) and
    (``headers``) the header frames of every other topic."""
    src = sources or TfSources()
    moving = [t for t in src.moving if bag.require_type(t, TF_MESSAGE)]
    statics = [t for t in src.static if bag.require_type(t, TF_MESSAGE)]
    robot = src.robot
    joint_topics = [t if robot is not None and bag.require_type(t, JOINT_STATE) else "" for t in src.joints]
    tf_read = {*moving, *statics, *TF_TOPICS}
    named = sorted(t for t, info in bag.topics.items() if headers and t not in tf_read and header_first(info))
    receive = TfDecoder(bag.deserialize, static=False, time="receive")
    stamped = TfDecoder(bag.deserialize, static=False, time="header")
    static = TfDecoder(bag.deserialize, static=True, time="receive")
    joints = [JointStateDecoder(tree.actuated, deserialize=bag.deserialize) for tree in robot.trees] if robot else []
    parts: list[tuple[Sequence[str], Sequence[str], I64, I64]] = []
    static_edges: set[tuple[str, str]] = set()
    robot_parts: list[Rows] = []
    cols: list[tuple[np.ndarray, np.ndarray, I64, I64]] = []
    topics = tuple(named)
    read = sorted({*moving, *statics, *(t for t in joint_topics if t), *named})
    for block in bag.blocks(read):
        for topic in moving:
            if topic in block.topics and (pairs := block.take(block.rows(topic)).pairs()):
                a, b = receive.decode(pairs), stamped.decode(pairs)
                a = renamed(a, src.moving[topic], src.shared)
                parts.append((a.parents, a.children, a.times_ns, b.times_ns))
        for topic in statics:
            if topic in block.topics and len(latched := block.rows(topic)):
                decoded = renamed(static.decode(block.take(latched).pairs()), src.static[topic], src.shared)
                static_edges |= decoded.edges()
        if robot is not None:
            chunks: list[SampleChunk | None] = [
                decoder.decode_block(block.take(block.rows(t))) if t in block.topics else None
                for decoder, t in zip(joints, joint_topics, strict=True)
            ]
            if any(c is not None for c in chunks):
                robot_parts.append(robot.rows(chunks))
        wanted = np.flatnonzero(np.isin(block.topic_index, [block.topics.index(t) for t in named if t in block.topics]))
        if len(wanted):
            frames, stamps, ok = header_columns(block, wanted)
            index = np.array([topics.index(t) if t in topics else -1 for t in block.topics], dtype=np.int32)
            index = index[block.topic_index[wanted]]
            cols.append((index[ok], frames[ok], stamps[ok], block.times_ns[wanted][ok]))
    bad = receive.bad + static.bad
    if bad:
        bag.warn(f"{bag.path}: {', '.join([*moving, *statics])}: skipped {bad} messages that cannot be decoded")
    rows = tf_rows(
        [f for p in parts for f in p[0]],
        [f for p in parts for f in p[1]],
        np.concatenate([p[2] for p in parts]) if parts else np.zeros(0, np.int64),
        np.concatenate([p[3] for p in parts]) if parts else np.zeros(0, np.int64),
    )
    if robot is not None:
        recorded = static_edges | set(zip(rows.parents, rows.children, strict=True))
        rows = _with_robot(rows, robot_parts, recorded & robot.moving_edges())
        static_edges |= set(robot.static_edges()) - recorded
    if not cols:
        return rows, sorted(static_edges), NO_HEADERS
    found = HeaderRows(
        topics,
        np.concatenate([c[0] for c in cols]).astype(np.int32),
        np.concatenate([c[1] for c in cols]),
        np.concatenate([c[2] for c in cols]),
        np.concatenate([c[3] for c in cols]),
    )
    return rows, sorted(static_edges), found


def _with_robot(rows: TfRows, robot: list[Rows], recorded: set[tuple[str, str]]) -> TfRows:
    """``rows`` and the robot's rows but those of the ``recorded`` edges (stamped when published)."""
    if not robot:
        return rows
    parents = np.concatenate([r[0] for r in robot])
    children = np.concatenate([r[1] for r in robot])
    times = np.concatenate([r[2] for r in robot])
    keep = np.ones(len(times), bool)
    for p, c in recorded:
        keep &= ~((parents == p) & (children == c))
    return TfRows(
        np.r_[rows.parents, parents[keep]].astype(object),
        np.r_[rows.children, children[keep]].astype(object),
        np.r_[rows.receive_ns, times[keep]],
        np.r_[rows.stamps_ns, times[keep]],
    )


def tf_sources(plan: RunPlan) -> TfSources:
    """The TF topics a replay of ``plan`` reads (with their prefixes) and the robots it draws from descriptions."""
    replay = plan.replay
    if replay is None:
        return TfSources()
    statics = tf_topics(plan.robots, replay.bag.topics, "tf_static")
    if plan.robots:
        trees, joints = tuple(r.tree for r in plan.robots), tuple(r.joints_topic for r in plan.robots)
    else:
        trees, joints = ((plan.tree,), (JOINTS,)) if plan.tree is not None else ((), ())
    robot = RobotFrames(trees, skip=plan.skip_edges) if trees else None
    return TfSources(dict(replay.tf_topics), statics, replay.shared_frames, robot, joints)


def bag_tree(bag: Bag, sources: TfSources | None = None) -> TfTree:
    """The TF tree of a bag, over its whole span."""
    rows, static_edges, headers = read_bag(bag, sources=sources)
    return analyse(rows, static_edges, headers, span_ns=bag.span)
