"""``/tf`` and ``/tf_static`` messages (``tf2_msgs/msg/TFMessage``) as transform rows
(:class:`~r2d2_viz.sources.base.TfRecords`): each transform at its message's receive time, or at its own header
stamp (``time="header"``).

Decoded in bulk like JointState (:mod:`r2d2_viz.msgs.layouts`): messages with the same frames share a layout; others
go through rosbags' deserializer; ones that cannot be decoded are skipped and counted in one warning. Pure.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from r2d2_viz.errors import BagError
from r2d2_viz.msgs.layouts import TfLayout, tf_layout
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bag_joints import MAX_LAYOUTS, TimeSource, stamps_ns
from r2d2_viz.sources.base import TfRecords

TF_MESSAGE = "tf2_msgs/msg/TFMessage"
_STAMP = np.dtype([("sec", "<i4"), ("nsec", "<u4")])


def concatenate(parts: list[TfRecords]) -> TfRecords | None:
    """Several TfRecords (of one kind) as one; None when there are none."""
    if not parts:
        return None
    if len(parts) == 1:
        return parts[0]
    return TfRecords(
        np.concatenate([p.times_ns for p in parts]),
        tuple(x for p in parts for x in p.parents),
        tuple(x for p in parts for x in p.children),
        np.vstack([p.translation for p in parts]),
        np.vstack([p.quat_xyzw for p in parts]),
        parts[0].static,
    )


class TfDecoder:
    """TFMessage CDR bytes to :class:`TfRecords`, in bulk; ``deserialize(data, msgtype)`` (raising BagError or
    MsgError) decodes what no byte layout fits; :attr:`bad` counts the messages that could not be decoded."""

    def __init__(
        self, deserialize: Callable[[bytes | memoryview, str], Any], *, static: bool, time: TimeSource
    ) -> None:
        self._deserialize, self.static, self.time = deserialize, static, time
        self.layouts: list[TfLayout] = []
        self.bad = 0

    def decode(self, messages: Sequence[tuple[int, bytes | memoryview]]) -> TfRecords:
        """``(receive time ns, CDR bytes)`` pairs to transform rows (a message's transforms in order)."""
        receive: list[int] = []
        stamps: list[bytes | memoryview] = []
        numbers: list[bytes | memoryview] = []
        parents: list[str] = []
        children: list[str] = []
        for receive_ns, data in messages:
            layout = next((lay for lay in self.layouts if lay.matches(data)), None)
            if layout is None:
                try:
                    layout = tf_layout(data)
                except ValueError:
                    try:
                        msg = self._deserialize(data, TF_MESSAGE)
                    except (BagError, MsgError):
                        self.bad += 1
                        continue
                    for t in msg.transforms:
                        s, v, q = t.header.stamp, t.transform.translation, t.transform.rotation
                        stamps.append(np.array([(s.sec, s.nanosec)], dtype=_STAMP).tobytes())
                        numbers.append(np.array([v.x, v.y, v.z, q.x, q.y, q.z, q.w], dtype="<f8").tobytes())
                        receive.append(receive_ns)
                        parents.append(t.header.frame_id)
                        children.append(t.child_frame_id)
                    continue
                if len(self.layouts) >= MAX_LAYOUTS:  # frames that change every message: memory stays bounded
                    self.layouts.pop(0)
                self.layouts.append(layout)
            for stamp, translation in zip(layout.stamps, layout.translations, strict=True):
                stamps.append(data[stamp : stamp + 8])
                numbers.append(data[translation : translation + 56])
            receive.extend([receive_ns] * len(layout.stamps))
            parents.extend(layout.parents)
            children.extend(layout.children)
        values = np.frombuffer(b"".join(numbers), dtype="<f8").reshape(-1, 7)
        times = np.asarray(receive, dtype=np.int64) if self.time == "receive" else stamps_ns(b"".join(stamps))
        return TfRecords(
            times, tuple(parents), tuple(children), values[:, :3].copy(), values[:, 3:].copy(), self.static
        )
