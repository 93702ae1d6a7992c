"""RViz 2's point displays of the scalar sensors — Temperature, FluidPressure, Illuminance, RelativeHumidity — and
the plot of their value.

RViz (``rviz_default_plugins/displays/<type>/<type>_display.cpp`` and ``pointcloud/point_cloud_scalar_display.hpp``)
turns each message into a one-point cloud at the origin of its header frame, coloured by the Intensity transformer
over fixed bounds (``Autocompute Intensity Bounds`` off): ``value = 1 - (v - min) / (max - min)`` (Temperature's
``Invert Rainbow``: ``1 - value``), then ``getRainbowColor`` (``intensity_pc_transformer.cpp``; equal bounds divide
by 1e20). The bounds each display sets (its Min / Max Intensity, which a config may change): Temperature 0..100,
FluidPressure 98000..105000, Illuminance 0..1000, RelativeHumidity 0..1.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from r2d2_viz.msgs.colormaps import rainbow
from r2d2_viz.msgs.geometry import header_of
from r2d2_viz.msgs.shapes import Decoded, DecodeOptions, Points, Series
from r2d2_viz.msgs.telemetry import SCALAR_SENSORS
from r2d2_viz.msgs.typestore import deserialize

BOUNDS: dict[str, tuple[float, float, bool]] = {
    "sensor_msgs/msg/Temperature": (0.0, 100.0, True),
    "sensor_msgs/msg/FluidPressure": (98000.0, 105000.0, False),
    "sensor_msgs/msg/Illuminance": (0.0, 1000.0, False),
    "sensor_msgs/msg/RelativeHumidity": (0.0, 1.0, False),
}
"""Per type: RViz's Min Intensity, Max Intensity and Invert Rainbow."""


def point_color(value: float, low: float, high: float, invert: bool) -> np.ndarray:
    """The RGBA8 colour ``(1, 4)`` RViz's Intensity transformer gives ``value`` over fixed bounds."""
    diff = high - low if high != low else 1e20
    level = 1.0 - (value - low) / diff
    return rainbow(np.array([1.0 - level if invert else level], dtype=np.float32))


def _decoder(msgtype: str) -> Callable[[bytes | memoryview, DecodeOptions], Decoded]:
    field = SCALAR_SENSORS[msgtype]
    low, high, invert = BOUNDS[msgtype]

    def decode(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
        msg = deserialize(data, msgtype)
        frame, stamp = header_of(msg)
        value = float(getattr(msg, field))
        lo, hi = options.value_range or (low, high)
        with np.errstate(all="ignore"):
            color = point_color(value, lo, hi, invert)
        point = Points(np.zeros((1, 3), dtype=np.float32), color, options.point_radius)
        # the plot on <topic>/<field>: the point's entity keeps its frame (a plain row beside it cleared it in 3D)
        return Decoded(frame, stamp, (point, Series(field, (field,), np.array([value]))))

    decode.__doc__ = f"A {msgtype.rsplit('/', 1)[-1]} as RViz's coloured point in its frame, and its {field} plotted."
    return decode


DECODERS = {msgtype: _decoder(msgtype) for msgtype in BOUNDS}
