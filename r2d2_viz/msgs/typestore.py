"""The ROS 2 Humble typestore, and CDR deserialisation that fails only with ``MsgError``."""

from __future__ import annotations

import functools
from typing import Any

from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from r2d2_viz.errors import one_line

MAX_MESSAGE_BYTES = 1 << 30


class MsgError(ValueError):
    """A message that cannot be decoded: bad bytes, inconsistent sizes, unknown encoding."""


@functools.cache
def typestore() -> Typestore:
    """rosbags' typestore of ROS 2 Humble (built once)."""
    return get_typestore(Stores.ROS2_HUMBLE)


def deserialize(data: bytes | memoryview, typename: str) -> Any:
    """The message ``typename`` held in CDR ``data``; anything rosbags raises becomes ``MsgError``."""
    if len(data) > MAX_MESSAGE_BYTES:
        raise MsgError(f"{typename}: message of {len(data)} bytes is too big")
    if len(data) < 4:
        raise MsgError(f"{typename}: {len(data)} bytes, too short for CDR")
    try:
        return typestore().deserialize_cdr(data, typename)
    except Exception as exc:  # rosbags raises struct.error, IndexError, ValueError, UnicodeDecodeError ...
        raise MsgError(f"{typename}: cannot deserialize: {one_line(exc)}") from None
