"""What :func:`~.tf_tree.analyse` needs, read from a bag in one pass of its storage blocks: ``/tf`` rows (receive
time and header stamp, decoded in bulk by :class:`~r2d2_viz.sources.bag_tf.TfDecoder`), ``/tf_static``'s edges, and
the frame and stamp of every message whose type starts with a ``std_msgs/Header``, gathered from the CDR bytes with
numpy (no message is deserialised for it). Pure; no rerun import."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from r2d2_viz.arrays import I64
from r2d2_viz.msgs.definitions import own_store
from r2d2_viz.msgs.typestore import MsgError, typestore
from r2d2_viz.sources.bag_tf import TF_MESSAGE, TfDecoder
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.bags.storage import Block, TopicInfo
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


def read_bag(bag: Bag, *, headers: bool = True) -> tuple[TfRows, list[tuple[str, str]], HeaderRows]:
    """``/tf``'s rows, ``/tf_static``'s edges and (``headers``) the header frames of every other topic."""
    tf_topics = [t for t in TF_TOPICS if bag.require_type(t, TF_MESSAGE)]
    named = sorted(t for t, info in bag.topics.items() if headers and t not in TF_TOPICS and header_first(info))
    receive = TfDecoder(bag.deserialize, static=False, time="receive")
    stamped = TfDecoder(bag.deserialize, static=False, time="header")
    static = TfDecoder(bag.deserialize, static=True, time="receive")
    parts: list[tuple[Sequence[str], Sequence[str], I64, I64]] = []
    static_edges: set[tuple[str, str]] = set()
    cols: list[tuple[np.ndarray, np.ndarray, I64, I64]] = []
    topics = tuple(named)
    for block in bag.blocks([*tf_topics, *named]):
        if "/tf" in block.topics:
            pairs = block.take(block.rows("/tf")).pairs()
            if pairs:
                a, b = receive.decode(pairs), stamped.decode(pairs)
                parts.append((a.parents, a.children, a.times_ns, b.times_ns))
        if "/tf_static" in block.topics and len(latched := block.rows("/tf_static")):
            static_edges |= static.decode(block.take(latched).pairs()).edges()
        wanted = np.flatnonzero(np.isin(block.topic_index, [block.topics.index(t) for t in named if t in block.topics]))
        if len(wanted):
            frames, stamps, ok = header_columns(block, wanted)
            index = np.array([topics.index(t) if t in topics else -1 for t in block.topics], dtype=np.int32)
            index = index[block.topic_index[wanted]]
            cols.append((index[ok], frames[ok], stamps[ok], block.times_ns[wanted][ok]))
    bad = receive.bad + static.bad
    if bad:
        bag.warn(f"{bag.path}: /tf, /tf_static: skipped {bad} messages that cannot be decoded")
    rows = tf_rows(
        [f for p in parts for f in p[0]],
        [f for p in parts for f in p[1]],
        np.concatenate([p[2] for p in parts]) if parts else np.zeros(0, np.int64),
        np.concatenate([p[3] for p in parts]) if parts else np.zeros(0, np.int64),
    )
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


def bag_tree(bag: Bag) -> TfTree:
    """The TF tree of a bag, over its whole span."""
    rows, static_edges, headers = read_bag(bag)
    return analyse(rows, static_edges, headers, span_ns=bag.span)
