"""The definitions known to be Humble's layout (r2d2_viz.msgs.generic.known_layouts), checked against the long way:
each is what rosbags' writer puts in a bag for its type (rosbags' own Humble store generates it here), the long
way (parsing it into its own store and comparing layouts with Humble's) agrees, and nothing else is listed."""

from __future__ import annotations

from rosbags.typesys import Stores, get_typestore

from r2d2_viz.msgs.definitions import _to_humble
from r2d2_viz.msgs.generic.known_layouts import KNOWN, TYPES, key, known_humble
from r2d2_viz.msgs.registry import DECODERS


def test_every_entry_is_a_definition_rosbags_writes_and_is_humbles_layout_the_long_way() -> None:
    store = get_typestore(Stores.ROS2_HUMBLE)
    found = set()
    for msgtype in TYPES:
        text, _ = store.generate_msgdef(msgtype, ros_version=2)
        assert known_humble(msgtype, "ros2msg", text), msgtype
        found.add(key(msgtype, "ros2msg", text))
        _to_humble.cache_clear()
        assert _to_humble.__wrapped__(msgtype, text, "ros2msg") == (None, None)  # type: ignore[attr-defined]
    assert found == KNOWN
    assert {t for t in DECODERS if t in store.fielddefs} <= set(TYPES)  # all but ROS 1's and Foxglove's types


def test_another_layout_is_not_taken_for_humbles() -> None:
    store = get_typestore(Stores.ROS2_HUMBLE)
    text, _ = store.generate_msgdef("sensor_msgs/msg/JointState", ros_version=2)
    changed = text.replace("float64[] position", "float32[] position")
    assert not known_humble("sensor_msgs/msg/JointState", "ros2msg", changed)
    assert _to_humble("sensor_msgs/msg/JointState", changed, "ros2msg")[0] is not None  # converted, the long way
