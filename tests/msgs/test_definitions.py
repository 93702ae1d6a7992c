"""Messages decoded with their bag's own definitions: an MCAP written with Noetic's Marker (as ``rosbags-convert``
writes a ROS 2 bag from a ROS 1 bag) decodes to the values written; Humble-shaped definitions pass through; a
definition that cannot be used says so; ROS 1 bytes become CDR with the definition given."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.msgs.definitions import from_ros1, own_store, same_layout, to_humble
from r2d2_viz.msgs.markers import decode_marker_array
from r2d2_viz.msgs.shapes import Boxes, DecodeOptions, LineStrips, Text
from r2d2_viz.msgs.typestore import MsgError, deserialize, typestore

NOETIC = get_typestore(Stores.ROS1_NOETIC)
HUMBLE = get_typestore(Stores.ROS2_HUMBLE)


def _converted_store() -> Any:
    """The store ``rosbags-convert`` writes a ROS 2 bag from a ROS 1 bag with: Noetic's types, ROS 2's Header."""
    store = get_typestore(Stores.EMPTY)
    store.register({**NOETIC.fielddefs, "std_msgs/msg/Header": HUMBLE.fielddefs["std_msgs/msg/Header"]})
    return store


def _markers(store: Any) -> Any:
    t = store.types
    time = t["builtin_interfaces/msg/Time"](sec=3, nanosec=4)
    header = t["std_msgs/msg/Header"](stamp=time, frame_id="odom")

    def marker(kind: int, key: int, **kw: Any) -> Any:
        fields: dict[str, Any] = {
            "header": header,
            "ns": "n",
            "id": key,
            "type": kind,
            "action": 0,
            "pose": t["geometry_msgs/msg/Pose"](
                position=t["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=3.0),
                orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            ),
            "scale": t["geometry_msgs/msg/Vector3"](x=2.0, y=4.0, z=6.0),
            "color": t["std_msgs/msg/ColorRGBA"](r=1.0, g=0.0, b=0.0, a=1.0),
            "lifetime": t["builtin_interfaces/msg/Duration"](sec=0, nanosec=0),
            "frame_locked": False,
            "points": [],
            "colors": [],
            "text": "",
            "mesh_resource": "",
            "mesh_use_embedded_materials": False,
        }
        fields.update(kw)
        return t["visualization_msgs/msg/Marker"](**fields)

    points = [t["geometry_msgs/msg/Point"](x=float(k), y=0.0, z=0.5) for k in range(3)]
    return t["visualization_msgs/msg/MarkerArray"](
        markers=[marker(1, 4), marker(4, 5, points=points), marker(9, 6, text="hello")]
    )


def _noetic_mcap(tmp_path: Path) -> tuple[bytes, str, str]:
    """An MCAP written with Noetic's MarkerArray; its first message, and the definition and encoding its schema
    carries (read back with rosbags)."""
    store = _converted_store()
    assert "texture_resource" not in [n for n, _ in store.fielddefs["visualization_msgs/msg/Marker"][1]]
    with Writer(tmp_path / "b", version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/markers", "visualization_msgs/msg/MarkerArray", typestore=store)
        writer.write(conn, 10, bytes(store.serialize_cdr(_markers(store), "visualization_msgs/msg/MarkerArray")))
    with Reader(tmp_path / "b") as reader:
        ((conn, _, data),) = list(reader.messages())
        encoding = {"MSG": "ros2msg", "IDL": "ros2idl"}[conn.msgdef.format.name]
        return bytes(data), conn.msgdef.data, encoding


def test_a_noetic_marker_array_in_an_mcap_decodes_to_what_was_written(tmp_path: Path) -> None:
    data, definition, encoding = _noetic_mcap(tmp_path)
    assert encoding == "ros2msg" and "texture" not in definition
    with pytest.raises(MsgError):  # the symptom: Humble's layout does not fit
        decode_marker_array(data, DecodeOptions())
    convert = to_humble("visualization_msgs/msg/MarkerArray", definition, encoding)
    assert convert is not None
    humble = HUMBLE.deserialize_cdr(bytes(convert(data)), "visualization_msgs/msg/MarkerArray")
    assert humble.markers[0].texture_resource == "" and len(humble.markers[0].uv_coordinates) == 0
    cube, strip, text = decode_marker_array(convert(data), DecodeOptions())
    assert [(op.ns, op.id, op.action) for op in (cube, strip, text)] == [
        ("n", 4, "add"),
        ("n", 5, "add"),
        ("n", 6, "add"),
    ]
    assert cube.decoded is not None and cube.decoded.frame_id == "odom"
    assert cube.decoded.stamp_ns == 3_000_000_004
    (box,) = cube.decoded.items
    assert isinstance(box, Boxes)
    np.testing.assert_allclose(box.half_sizes, [[1.0, 2.0, 3.0]])
    np.testing.assert_array_equal(box.colors[0], [255, 0, 0, 255])
    assert strip.decoded is not None and isinstance(strip.decoded.items[0], LineStrips)
    np.testing.assert_allclose(strip.decoded.items[0].strips[0], [[0, 0, 0.5], [1, 0, 0.5], [2, 0, 0.5]])
    assert text.decoded is not None and isinstance(text.decoded.items[0], Text)
    assert text.decoded.items[0].text == "hello"


def test_humble_shaped_definitions_pass_through(tmp_path: Path) -> None:
    humble_def, _ = HUMBLE.generate_msgdef("visualization_msgs/msg/MarkerArray", ros_version=2)
    assert to_humble("visualization_msgs/msg/MarkerArray", humble_def, "ros2msg") is None
    assert to_humble("visualization_msgs/msg/MarkerArray", "", "") is None  # .db3: no definition
    for msgtype in ("sensor_msgs/msg/JointState", "sensor_msgs/msg/CameraInfo", "sensor_msgs/msg/PointCloud2"):
        noetic_def, _ = NOETIC.generate_msgdef(msgtype, ros_version=1)
        assert to_humble(msgtype, noetic_def, "ros1msg") is None, msgtype  # CameraInfo: D/K/R/P, same wire
    noetic_marker, _ = NOETIC.generate_msgdef("visualization_msgs/msg/Marker", ros_version=1)
    assert to_humble("visualization_msgs/msg/Marker", noetic_marker, "ros1msg") is not None
    assert to_humble("custom_msgs/msg/Thing", "int32 a\n", "ros2msg") is None  # nothing decodes it


def test_an_idl_definition() -> None:
    idl = "module geometry_msgs { module msg { struct Point { double y; double x; }; }; };\n"
    convert = to_humble("geometry_msgs/msg/Point", idl, "ros2idl")
    assert convert is not None
    data = own_store("geometry_msgs/msg/Point", idl, "ros2idl").serialize_cdr(
        own_store("geometry_msgs/msg/Point", idl, "ros2idl").types["geometry_msgs/msg/Point"](y=2.0, x=1.0),
        "geometry_msgs/msg/Point",
    )
    point = deserialize(convert(data), "geometry_msgs/msg/Point")
    assert (point.x, point.y, point.z) == (1.0, 2.0, 0.0)  # matched by name; z missing: its default


def test_unusable_definitions_say_so() -> None:
    with pytest.raises(MsgError, match="visualization_msgs/msg/Marker: its message definition cannot be used"):
        to_humble("visualization_msgs/msg/Marker", "this is } not a definition", "ros2msg")
    with pytest.raises(MsgError, match="does not define"):
        to_humble("nav_msgs/msg/Path", "nowhere_msgs/Missing[] poses\n", "ros2msg")
    with pytest.raises(MsgError, match="unknown encoding"):
        to_humble("nav_msgs/msg/Path", "int32 a\n", "jsonschema")
    humble_def, _ = HUMBLE.generate_msgdef("geometry_msgs/msg/PointStamped", ros_version=2)
    broken = humble_def.replace("float64 z", "float64 z\nfloat64 w")
    convert = to_humble("geometry_msgs/msg/PointStamped", broken, "ros2msg")
    assert convert is not None
    with pytest.raises(MsgError, match="cannot convert"):
        convert(b"\x00\x01\x00\x00\x01")


def test_occupancy_grid_update_is_decodable_through_its_definition() -> None:
    text = "std_msgs/Header header\nint32 x\nint32 y\nuint32 width\nuint32 height\nint8[] data\n"
    assert to_humble("map_msgs/msg/OccupancyGridUpdate", text, "ros2msg") is None
    assert same_layout(
        own_store("map_msgs/msg/OccupancyGridUpdate", text, "ros1msg"),
        "map_msgs/msg/OccupancyGridUpdate",
        typestore(),
        "map_msgs/msg/OccupancyGridUpdate",
    )


def test_ros1_bytes_to_cdr_with_a_pre_2010_header() -> None:
    definition, _ = NOETIC.generate_msgdef("geometry_msgs/msg/PointStamped", ros_version=1)
    old = definition.replace("std_msgs/Header", "roslib/Header")
    t = NOETIC.types
    msg = t["geometry_msgs/msg/PointStamped"](
        header=t["std_msgs/msg/Header"](seq=9, stamp=t["builtin_interfaces/msg/Time"](sec=1, nanosec=2), frame_id="f"),
        point=t["geometry_msgs/msg/Point"](x=0.5, y=1.5, z=2.5),
    )
    raw = NOETIC.serialize_ros1(msg, "geometry_msgs/msg/PointStamped")
    for text in (definition, old):
        got = deserialize(from_ros1("geometry_msgs/msg/PointStamped", text)(raw), "geometry_msgs/msg/PointStamped")
        assert (got.header.frame_id, got.header.stamp.sec, got.header.stamp.nanosec) == ("f", 1, 2)
        assert (got.point.x, got.point.y, got.point.z) == (0.5, 1.5, 2.5)
    with pytest.raises(MsgError, match="cannot convert from ROS 1"):
        from_ros1("geometry_msgs/msg/PointStamped", definition)(bytes(raw)[:-3])


def test_which_distros_definitions_need_converting() -> None:
    """Known history of the message packages: Humble added Marker's texture and mesh_file fields (Foxy and Noetic
    lack them, and so does InteractiveMarkerUpdate, whose controls hold Markers); Jazzy added Range's ``variance``.
    Everything else the app decodes kept its layout."""
    IM_UPDATE = "visualization_msgs/msg/InteractiveMarkerUpdate"
    from r2d2_viz.msgs.registry import DECODERS

    expected = {
        Stores.ROS2_HUMBLE: set(),
        Stores.ROS2_JAZZY: {"sensor_msgs/msg/Range"},
        Stores.ROS2_FOXY: {"visualization_msgs/msg/Marker", "visualization_msgs/msg/MarkerArray", IM_UPDATE},
        Stores.ROS1_NOETIC: {"visualization_msgs/msg/Marker", "visualization_msgs/msg/MarkerArray", IM_UPDATE},
    }
    for distro, differing in expected.items():
        store, ros1 = get_typestore(distro), distro == Stores.ROS1_NOETIC
        got = set()
        for msgtype in [*DECODERS, "sensor_msgs/msg/JointState"]:
            if msgtype not in store.fielddefs:  # ROS 1's rosgraph_msgs/Log in a ROS 2 store
                continue
            definition, _ = store.generate_msgdef(msgtype, ros_version=1 if ros1 else 2)
            if to_humble(msgtype, definition, "ros1msg" if ros1 else "ros2msg") is not None:
                got.add(msgtype)
        assert got == differing, distro
