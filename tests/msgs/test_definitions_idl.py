"""``ros2idl`` schemas as rosbag2 writes them for types defined in ``.idl`` files (Autoware's): every IDL file of
the type and of its fields' types, each after an 80-``=`` line and an ``IDL: pkg/msg/Type`` line, in any order, with
their ``#include`` lines (rosbag2's docs/message_definition_encoding.md). Refused before ("Could not parse").

The messages are serialised by rosbags from the same IDL files (its parser given each file without its
``#include`` lines, which it does not take); the values read back are the ones written here, by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_idl, get_typestore
from rrd import read_recording

from r2d2_viz.msgs.definitions import own_store

DELIMITER = "=" * 80 + "\n"
TIME_IDL = """// generated from rosidl_adapter/resource/msg.idl.em
// with input from builtin_interfaces/msg/Time.msg
// generated code does not contain a copyright notice


module builtin_interfaces {
  module msg {
    struct Time {
      int32 sec;

      uint32 nanosec;
    };
  };
};
"""
LATERAL_IDL = """#include "builtin_interfaces/msg/Time.idl"

module autoware_auto_control_msgs {
  module msg {
    @verbatim (language="comment", text=
      " Lateral control command for Ackermann vehicle")
    struct AckermannLateralCommand {
      builtin_interfaces::msg::Time stamp;

      @verbatim (language="comment", text=
        " Desired angle of the steering tire in radians left (positive)"
        " or right (negative) of center (0.0)")
      @default (value=0.0)
      float steering_tire_angle;

      @default (value=0.0)
      float steering_tire_rotation_rate;
    };
  };
};
"""
COMMAND_IDL = """#include "autoware_auto_control_msgs/msg/AckermannLateralCommand.idl"
#include "builtin_interfaces/msg/Time.idl"

module autoware_auto_control_msgs {
  module msg {
    typedef double double__3[3];
    module AckermannControlCommand_Constants {
      const uint8 MODE_AUTO = 2;
    };
    struct AckermannControlCommand {
      builtin_interfaces::msg::Time stamp;

      autoware_auto_control_msgs::msg::AckermannLateralCommand lateral;

      @default (value=0.0)
      double speed;

      double__3 gains;

      sequence<float, 8> accelerations;

      uint8 mode;
    };
  };
};
"""
COMMAND = "autoware_auto_control_msgs/msg/AckermannControlCommand"
LATERAL = "autoware_auto_control_msgs/msg/AckermannLateralCommand"
FILES = {COMMAND: COMMAND_IDL, "builtin_interfaces/msg/Time": TIME_IDL, LATERAL: LATERAL_IDL}
SCHEMA = "".join(f"{DELIMITER}IDL: {name}\n{text}" for name, text in FILES.items())
T0 = 1_700_000_000_000_000_000


def _writer_store():  # type: ignore[no-untyped-def]
    store = get_typestore(Stores.EMPTY)
    for text in FILES.values():
        store.register(get_types_from_idl("\n".join(x for x in text.splitlines() if not x.startswith("#include"))))
    return store


def _command(store, k: int):  # type: ignore[no-untyped-def]
    t = store.types
    stamp = t["builtin_interfaces/msg/Time"](sec=1_700_000_000 + k, nanosec=5)
    lateral = t[LATERAL](stamp=stamp, steering_tire_angle=0.25 * k, steering_tire_rotation_rate=-0.5)
    return t[COMMAND](
        stamp=stamp, lateral=lateral, speed=3.0 + k, gains=np.array([1.0, 2.0, 3.0 + k]),
        accelerations=np.array([0.5, -1.0 * k], dtype=np.float32), mode=2,
    )  # fmt: skip


def test_rosbags_itself_refuses_the_schema_whole() -> None:
    """The finding: the schema as one text is no IDL rosbags parses (the delimiters, the ``#include`` lines)."""
    from rosbags.typesys.base import TypesysError

    with pytest.raises(TypesysError, match="Could not parse"):
        get_types_from_idl(SCHEMA)


def test_a_ros2idl_schema_gives_every_type_of_its_files() -> None:
    store = own_store(COMMAND, SCHEMA, "ros2idl")
    writer = _writer_store()
    data = bytes(writer.serialize_cdr(_command(writer, 3), COMMAND))
    msg = store.deserialize_cdr(data, COMMAND)
    assert (msg.stamp.sec, msg.stamp.nanosec, msg.lateral.stamp.sec) == (1_700_000_003, 5, 1_700_000_003)
    assert (msg.lateral.steering_tire_angle, msg.lateral.steering_tire_rotation_rate) == (0.75, -0.5)
    assert (msg.speed, msg.gains.tolist(), msg.accelerations.tolist(), msg.mode) == (6.0, [1, 2, 6], [0.5, -3.0], 2)
    assert store.types[COMMAND].MODE_AUTO == 2  # the constants module of the same file
    # the files in another order, and with Windows line ends, give the same
    swapped = "".join(f"{DELIMITER}IDL: {name}\n{text}" for name, text in reversed(FILES.items()))
    assert own_store(COMMAND, swapped, "ros2idl").deserialize_cdr(data, COMMAND).lateral.steering_tire_angle == 0.75
    crlf = SCHEMA.replace("\n", "\r\n")
    assert own_store(COMMAND, crlf, "ros2idl").deserialize_cdr(data, COMMAND).speed == 6.0


def test_an_autoware_idl_topic_of_a_bag_is_recorded(tmp_path: Path) -> None:
    """As found: an MCAP (written by rosbags, the schema ``ros2idl`` as rosbag2 writes it) replayed through the
    CLI; read back, the topic's fields are the values written, and ``--plot`` of a nested one is the same."""
    writer_store = _writer_store()
    bag = tmp_path / "autoware"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/control/command", COMMAND, msgdef=SCHEMA, rihs01="RIHS01_" + "0" * 64)
        for k in range(3):
            writer.write(
                connection, T0 + k * 10**8, bytes(writer_store.serialize_cdr(_command(writer_store, k), COMMAND))
            )
    out = tmp_path / "out.rrd"
    plot = "/control/command.lateral.steering_tire_angle"
    result = cli("--bag", str(bag), "--save", str(out), "--plot", plot)
    assert result.returncode == 0, result.stderr
    assert "cannot be decoded" not in result.stderr and "Could not parse" not in result.stderr, result.stderr
    recording = read_recording(out)
    rows = recording["/topics/control/command"]
    assert rows.times == [T0, T0 + 10**8, T0 + 2 * 10**8]

    def field(name: str) -> list[object]:
        return [v[0] if v is not None else None for v in rows.temporal[f"{COMMAND}:{name}"]]

    assert field("lateral.steering_tire_angle") == [0.0, 0.25, 0.5]
    assert field("speed") == [3.0, 4.0, 5.0]
    assert field("stamp.sec") == [1_700_000_000, 1_700_000_001, 1_700_000_002]
    assert field("mode") == [2, 2, 2]
    [entity] = [e for e in recording if e.startswith("/plot/") and e.endswith("steering_tire_angle")]
    assert [v[0] for v in recording[entity].temporal["Scalars:scalars"]] == [0.0, 0.25, 0.5]
