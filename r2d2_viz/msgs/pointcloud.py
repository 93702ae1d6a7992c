"""sensor_msgs PointCloud2 (numpy views over the CDR ``data``) and the older PointCloud (channels)."""

from __future__ import annotations

from typing import Any

import numpy as np

from r2d2_viz.msgs.colormaps import intensity_colors, packed_rgb
from r2d2_viz.msgs.geometry import header_of, one_color, points3
from r2d2_viz.msgs.shapes import F32, U8, Decoded, DecodeOptions, Points
from r2d2_viz.msgs.typestore import MsgError, deserialize

# sensor_msgs/PointField datatypes
FIELD_TYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}
MAX_POINTS = 1 << 28


def _field_dtype(msg: Any, names: list[str]) -> tuple[np.dtype[Any], dict[str, int]]:
    """A structured dtype of ``point_step`` bytes with the wanted fields (colour words read as uint32)."""
    order = ">" if msg.is_bigendian else "<"
    fields = {f.name: f for f in msg.fields}
    chosen: dict[str, str] = {}
    offsets: dict[str, int] = {}
    for name in names:
        f = fields.get(name)
        if f is None:
            continue
        code = FIELD_TYPES.get(int(f.datatype))
        if code is None:
            raise MsgError(f"field {name!r} has unknown datatype {f.datatype}")
        if name in ("rgb", "rgba"):
            if code not in ("i4", "u4", "f4"):
                continue
            code = "u4"
        if int(f.offset) + int(code[1]) > int(msg.point_step):
            raise MsgError(f"field {name!r} at offset {f.offset} does not fit point_step {msg.point_step}")
        chosen[name] = order + code
        offsets[name] = int(f.offset)
    dtype = np.dtype(
        {
            "names": list(chosen),
            "formats": list(chosen.values()),
            "offsets": [offsets[n] for n in chosen],
            "itemsize": int(msg.point_step),
        }
    )
    return dtype, offsets


def cloud_view(msg: Any) -> np.ndarray:
    """The points of a deserialised PointCloud2 as a flat structured view (no copy of the point data)."""
    width, height, step, row_step = int(msg.width), int(msg.height), int(msg.point_step), int(msg.row_step)
    data: np.ndarray = msg.data
    if width * height == 0:
        dtype, _ = _field_dtype(msg, ["x", "y", "z"]) if step > 0 else (np.dtype([]), {})
        return np.zeros(0, dtype=dtype)
    if step <= 0:
        raise MsgError(f"point_step {step} with {width * height} points")
    if width * height > MAX_POINTS:
        raise MsgError(f"{width}x{height} points is too many")
    if height > 1 and row_step < width * step:
        raise MsgError(f"row_step {row_step} < width {width} x point_step {step}")
    row_step = row_step if height > 1 else width * step
    need = (height - 1) * row_step + width * step
    if need > len(data):
        raise MsgError(f"{width}x{height} points of {step} bytes need {need} bytes, data has {len(data)}")
    dtype, _ = _field_dtype(msg, ["x", "y", "z", "rgb", "rgba", "intensity", "intensities"])
    if not {"x", "y", "z"} <= set(dtype.names or ()):
        raise MsgError("no x, y, z fields")
    view = np.ndarray(shape=(height, width), dtype=dtype, buffer=data, strides=(row_step, step))
    return view.reshape(-1)


def cloud_colors(points: np.ndarray, flat: tuple[int, int, int, int]) -> U8:
    """RViz's colour choice: packed ``rgb``/``rgba`` (RGB8), else ``intensity`` / ``intensities``, else flat."""
    names = set(points.dtype.names or ())
    for name in ("rgb", "rgba"):
        if name in names:
            return packed_rgb(points[name], alpha=name == "rgba")
    for name in ("intensity", "intensities"):
        if name in names:
            return intensity_colors(points[name].astype(np.float64))
    return one_color(flat)


def decode_pointcloud2(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """Points of a PointCloud2, NaN / inf points dropped, coloured as RViz's default transformers do."""
    msg = deserialize(data, "sensor_msgs/msg/PointCloud2")
    frame, stamp = header_of(msg)
    points = cloud_view(msg)
    if points.shape[0] == 0:
        empty = Points(np.zeros((0, 3), np.float32), one_color(options.flat_color), options.point_radius)
        return Decoded(frame, stamp, (empty,))
    xyz = _xyz(points)
    finite = np.isfinite(xyz)
    everything = bool(finite.all())  # (the whole array at once: a reduction along rows of 3 is slow)
    flat = options.color_transformer == "FlatColor"
    colors = one_color(options.flat_color) if flat else cloud_colors(points, options.flat_color)
    if everything:  # the common case: no mask built (issue 48)
        return Decoded(frame, stamp, (Points(xyz, colors, options.point_radius),))
    keep = finite[:, 0] & finite[:, 1] & finite[:, 2]
    if colors.shape[0] > 1:
        colors = colors[keep]
    return Decoded(frame, stamp, (Points(xyz[keep], colors, options.point_radius),))


def _xyz(points: np.ndarray) -> F32:
    """``(N, 3)`` float32 positions: one strided copy when x, y, z are consecutive little-endian float32 (the
    common layout), else field by field."""
    fields: dict[str, Any] = dict(points.dtype.fields or {})
    x, y, z = (fields[name] for name in ("x", "y", "z"))
    consecutive = y[1] == x[1] + 4 and z[1] == x[1] + 8
    if consecutive and all(f[0] == np.dtype("<f4") for f in (x, y, z)) and points.strides[0] > 0:
        view = np.ndarray((points.shape[0], 3), "<f4", buffer=points, offset=x[1], strides=(points.strides[0], 4))
        return np.ascontiguousarray(view)
    with np.errstate(over="ignore", invalid="ignore"):
        return np.stack([points["x"], points["y"], points["z"]], axis=1).astype(np.float32)


def decode_pointcloud(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """The ROS 1 style PointCloud: ``rgb`` (packed float) or ``r``/``g``/``b`` or ``intensity`` channels."""
    msg = deserialize(data, "sensor_msgs/msg/PointCloud")
    frame, stamp = header_of(msg)
    xyz = points3(msg.points)
    n = xyz.shape[0]
    channels = {c.name: np.asarray(c.values, dtype=np.float32) for c in msg.channels}
    for name, values in channels.items():
        if values.shape[0] != n:
            raise MsgError(f"channel {name!r} has {values.shape[0]} values for {n} points")
    colors = one_color(options.flat_color)
    if "rgb" in channels:
        colors = packed_rgb(channels["rgb"].view(np.uint32), alpha=False)
    elif {"r", "g", "b"} <= set(channels):
        rgb = np.stack([channels[c] for c in "rgb"], axis=1).astype(np.float64)
        colors = np.empty((n, 4), dtype=np.uint8)
        colors[:, :3] = np.round(np.clip(np.nan_to_num(rgb), 0.0, 1.0) * 255)
        colors[:, 3] = 255
    elif "intensity" in channels or "intensities" in channels:
        colors = intensity_colors(channels["intensity" if "intensity" in channels else "intensities"])
    keep = np.isfinite(xyz).all(axis=1)
    if colors.shape[0] > 1:
        colors = colors[keep]
    return Decoded(frame, stamp, (Points(xyz[keep], colors, options.point_radius),))
