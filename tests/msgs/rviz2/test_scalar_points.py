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
