"""A bag whose header-first messages the Humble typestore alone does not show: ``/reading`` of a vendor's type that
only the bag defines (``vendor_msgs/msg/Reading``: a ``std_msgs/Header`` and a float, its definition written into
the bag by rosbags' writer) in frame ``sensor``, and ``/points_be``, Humble's ``PointStamped`` serialised big-endian
(rosbags' ``little_endian=False``) in frame ``camera``; ``/tf`` gives only ``map → base``, so neither frame is
reached. 10 Hz for 5 s each, stamped 30 and 40 ms before they are received."""

from __future__ import annotations

from pathlib import Path

from bagmaker import STORAGES, Header, stamp, tf_message
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

READING = "vendor_msgs/msg/Reading"
POINT = "geometry_msgs/msg/PointStamped"
T0 = 1_700_000_000 * 10**9
MS = 1_000_000
COUNT = 50
READING_LAG_NS, POINT_LAG_NS = 30 * MS, 40 * MS


def vendor_store():  # type: ignore[no-untyped-def]
    """Humble's types and the vendor's."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg("std_msgs/Header header\nfloat64 value\n", READING))
    return store


def write(path: Path, storage: str = "mcap") -> Path:
    store = vendor_store()
    reading, point = store.types[READING], store.types[POINT]
    with Writer(path, version=9, storage_plugin=STORAGES[storage]) as writer:
        tf = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
        vendor = writer.add_connection("/reading", READING, typestore=store)
        big = writer.add_connection("/points_be", POINT, typestore=store)
        for k in range(COUNT):
            t = T0 + k * 100 * MS
            writer.write(tf, t, tf_message([(t, "map", "base", (1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))]))
            msg = reading(Header(stamp(t - READING_LAG_NS), "sensor"), 1.5)
            writer.write(vendor, t + 5 * MS, bytes(store.serialize_cdr(msg, READING)))
            xyz = store.types["geometry_msgs/msg/Point"](1.0, 2.0, 3.0)
            be = store.serialize_cdr(point(Header(stamp(t - POINT_LAG_NS), "camera"), xyz), POINT, little_endian=False)
            writer.write(big, t + 6 * MS, bytes(be))
    return path
