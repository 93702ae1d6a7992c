"""``--bag run.bag --save out.mcap``: a ROS 1 bag written as a ROS 2 bag (rosbag2, MCAP storage), every topic, its
types converted as ``rosbags-convert`` does: ROS 2 names (``pkg/msg/Type``), CDR, each topic's own definition
carried along (Humble's where the messages were converted to Humble's layout), topic names with their slash.
Atomic: written into a temporary folder beside the target and renamed when complete. Pure: no rerun import."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from r2d2_viz.errors import BagError
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.ros_out.bag_write import cause, move_into_place, written_by_us
from r2d2_viz.sources.bags.bag import Bag


def convert_bag(bag: Bag, path: Path) -> int:
    """Write every message of ``bag`` to the ROS 2 bag ``path``; how many were written."""
    from rosbags.rosbag2 import StoragePlugin, Writer, WriterError

    from r2d2_viz.msgs.definitions import own_store

    if path.exists() and not written_by_us(path):
        raise BagError(f"{path}: exists and is not a bag r2d2-viz wrote; not replacing it")
    if not path.parent.is_dir():
        raise BagError(f"{path}: directory {path.parent} does not exist")
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        out = tmp / "bag"
        with Writer(out, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
            writer.set_custom_data("converted_by", "r2d2-viz")
            connections = {}
            for topic, info in sorted(bag.topics.items()):
                own = info.definition and topic not in bag.humble_topics
                store = own_store(info.msgtype, info.definition, info.encoding) if own else typestore()
                connections[topic] = writer.add_connection(topic, info.msgtype, typestore=store)
            written = 0
            for block in bag.blocks(list(bag.topics)):
                for t, topic, data in block.messages():
                    writer.write(connections[topic], t, bytes(data))
                    written += 1
        move_into_place(out, path, aside=tmp / "replaced")  # the bag r2d2-viz wrote there before, replaced
    except (OSError, WriterError) as exc:
        raise BagError(f"{path}: not saved: {cause(exc)}") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return written
