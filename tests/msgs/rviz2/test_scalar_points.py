"""The scalar sensors as RViz's point displays: a point at the frame's origin, coloured by RViz's Intensity
transformer over the display's fixed bounds (rviz_default_plugins' <type>_display.cpp and
intensity_pc_transformer.cpp, transcribed in tests/msgs_build.py's rviz_rainbow), and the value plotted."""

from __future__ import annotations

import pytest
from msgs_build import T, cdr, header, rviz_rainbow

from r2d2_viz.msgs.registry import decode, in_3d
from r2d2_viz.msgs.shapes import DecodeOptions, Points, Series


def _illuminance(value: float) -> bytes:
    return cdr(T("sensor_msgs/msg/Illuminance")(header=header("lux_sensor"), illuminance=value, variance=0.0))


@pytest.mark.parametrize(("value", "level"), [(0.0, 1.0), (250.0, 0.75), (1000.0, 0.0), (5000.0, 0.0)])
def test_rvizs_bounds_give_the_colour(value: float, level: float) -> None:
    decoded = decode("sensor_msgs/msg/Illuminance", _illuminance(value))  # Illuminance: 0..1000, not inverted
    point, series = decoded.items
    assert isinstance(point, Points) and isinstance(series, Series)
    assert decoded.frame_id == "lux_sensor" and point.positions.tolist() == [[0.0, 0.0, 0.0]]
    assert tuple(point.colors[0, :3].tolist()) == rviz_rainbow(level)
    assert series.values.tolist() == [value]


def test_the_configs_bounds_and_equal_bounds() -> None:
    options = DecodeOptions(value_range=(200.0, 300.0))
    (point, _) = decode("sensor_msgs/msg/Illuminance", _illuminance(250.0), options).items
    assert tuple(point.colors[0, :3].tolist()) == rviz_rainbow(0.5)
    # equal bounds: RViz divides by 1e20 — every value the colour of level 1
    (point, _) = decode("sensor_msgs/msg/Illuminance", _illuminance(7.0), DecodeOptions(value_range=(3.0, 3.0))).items
    assert tuple(point.colors[0, :3].tolist()) == rviz_rainbow(1.0)


def test_they_draw_in_3d_and_plot() -> None:
    assert in_3d("sensor_msgs/msg/Temperature") and in_3d("sensor_msgs/msg/FluidPressure")


def test_the_webots_e_pucks_light_sensors() -> None:
    """Real data: the e-puck's eight light sensors (``/ls0`` … ``/ls7``, Illuminance in lux, Webots), each message
    deserialised by rosbags; its point in the sensor's frame, in RViz's colour over 0..1000 lux by hand."""
    from conftest import REPO
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    bag = next(
        (
            p
            for p in (REPO / "tests/data/bags/real", REPO.parent / "shared/bags/real")
            if (p / "webots_epuck" / "metadata.yaml").is_file()
        ),
        None,
    )
    if bag is None:
        pytest.skip("the third-party bag webots_epuck is not in this clone (tests/data/bags/real/README.md)")
    with AnyReader([bag / "webots_epuck"], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        conns = [c for c in reader.connections if c.msgtype == "sensor_msgs/msg/Illuminance"]
        assert len(conns) == 8
        seen = set()
        for connection, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, connection.msgtype)
            decoded = decode(connection.msgtype, bytes(raw))
            point, series = decoded.items
            assert decoded.frame_id == msg.header.frame_id and series.values.tolist() == [msg.illuminance]
            assert tuple(point.colors[0, :3].tolist()) == rviz_rainbow(1.0 - msg.illuminance / 1000.0)
            seen.add(msg.illuminance)
    assert len(seen) > 1  # not one value throughout
