"""The one place message definitions come from — rosbags' typestores (Humble for bags and decoding, a live graph's
distro for its DDS types) — and CDR deserialisation that fails only with ``MsgError``."""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any

from r2d2_viz.errors import one_line
from r2d2_viz.msgs.stacks.definitions import STACK_TYPES

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

MAX_MESSAGE_BYTES = 1 << 30


class MsgError(ValueError):
    """A message that cannot be decoded: bad bytes, inconsistent sizes, unknown encoding."""


DISTROS = {"humble": "ROS2_HUMBLE", "jazzy": "ROS2_JAZZY", "kilted": "ROS2_KILTED"}
EXTRA_TYPES = {
    "map_msgs/msg/OccupancyGridUpdate": "std_msgs/Header header\nint32 x\nint32 y\nuint32 width\nuint32 height\n"
    "int8[] data\n",
    "rosgraph_msgs/msg/Log": "std_msgs/Header header\nbyte level\nstring name\nstring msg\nstring file\n"
    "string function\nuint32 line\nstring[] topics\n",
    "foxglove_msgs/msg/CompressedVideo": "builtin_interfaces/Time timestamp\nstring frame_id\nuint8[] data\n"
    "string format\n",
    **STACK_TYPES,
}
"""Types the app shows that rosbags' stores lack (nav2's costmap updates; ROS 1's log, as ROS 1 bags hold it once
converted to CDR: its header without ``seq``; Foxglove's compressed video; nav2's and vision_msgs' displays:
:data:`r2d2_viz.msgs.stacks.definitions.STACK_TYPES`), added to every store."""


@functools.cache
def typestore(distro: str = "humble") -> Typestore:
    """rosbags' typestore of a ROS 2 distro with :data:`EXTRA_TYPES` (built once each; rosbags is imported on first
    use)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    if distro not in DISTROS:
        raise MsgError(f"unknown ROS 2 distro {distro!r} (known: {', '.join(DISTROS)})")
    store = get_typestore(getattr(Stores, DISTROS[distro]))
    for name, text in EXTRA_TYPES.items():
        store.register(get_types_from_msg(text, name))
    return store


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
