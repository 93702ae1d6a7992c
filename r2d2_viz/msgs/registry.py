"""The one table from ROS type names to decoders, and ``decode`` that fails only with ``MsgError``."""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence

import numpy as np

from r2d2_viz.errors import one_line
from r2d2_viz.msgs import images, markers, nav, pointcloud, poses, scan, telemetry
from r2d2_viz.msgs.blocks import markers as marker_arrays
from r2d2_viz.msgs.blocks.telemetry_blocks import decode_imu_block
from r2d2_viz.msgs.rviz2 import accel, interactive, scalar_points
from r2d2_viz.msgs.shapes import Decoded, DecodeOptions, MarkerOp
from r2d2_viz.msgs.stacks import detections, particles, voxels
from r2d2_viz.msgs.typestore import MsgError

Decoder = Callable[[bytes | memoryview, DecodeOptions], Decoded | list[MarkerOp]]

DECODERS: dict[str, Decoder] = {
    "sensor_msgs/msg/LaserScan": scan.decode_laserscan,
    "sensor_msgs/msg/Range": scan.decode_range,
    "sensor_msgs/msg/PointCloud2": pointcloud.decode_pointcloud2,
    "sensor_msgs/msg/PointCloud": pointcloud.decode_pointcloud,
    "sensor_msgs/msg/Image": images.decode_image,
    "sensor_msgs/msg/CompressedImage": images.decode_compressed_image,
    "sensor_msgs/msg/CameraInfo": images.decode_camera_info,
    "foxglove_msgs/msg/CompressedVideo": images.decode_compressed_video,
    "visualization_msgs/msg/Marker": markers.decode_marker,
    "visualization_msgs/msg/MarkerArray": markers.decode_marker_array,
    "nav_msgs/msg/Path": nav.decode_path,
    "nav_msgs/msg/Odometry": poses.decode_odometry,
    "nav_msgs/msg/OccupancyGrid": nav.decode_occupancy_grid,
    "nav_msgs/msg/GridCells": nav.decode_grid_cells,
    "geometry_msgs/msg/PoseStamped": poses.decode_pose_stamped,
    "geometry_msgs/msg/PoseArray": poses.decode_pose_array,
    "geometry_msgs/msg/PoseWithCovarianceStamped": poses.decode_pose_with_covariance,
    "geometry_msgs/msg/PointStamped": poses.decode_point_stamped,
    "geometry_msgs/msg/PolygonStamped": poses.decode_polygon_stamped,
    "geometry_msgs/msg/WrenchStamped": poses.decode_wrench_stamped,
    "geometry_msgs/msg/TwistStamped": poses.decode_twist_stamped,
    "geometry_msgs/msg/AccelStamped": accel.decode_accel_stamped,
    "visualization_msgs/msg/InteractiveMarkerUpdate": interactive.decode_interactive_update,
    "rcl_interfaces/msg/Log": telemetry.decode_log,
    "rosgraph_msgs/msg/Log": telemetry.decode_ros1_log,
    "diagnostic_msgs/msg/DiagnosticArray": telemetry.decode_diagnostics,
    "std_msgs/msg/String": telemetry.decode_string,
    "sensor_msgs/msg/Imu": telemetry.decode_imu,
    "sensor_msgs/msg/NavSatFix": telemetry.decode_navsatfix,
    "sensor_msgs/msg/BatteryState": telemetry.decode_battery,
    **scalar_points.DECODERS,
    **telemetry.NUMBER_DECODERS,
    # the navigation and perception stacks' displays (issue 46)
    "nav2_msgs/msg/ParticleCloud": particles.decode_particle_cloud,
    "nav2_msgs/msg/VoxelGrid": voxels.decode_voxel_grid,
    "vision_msgs/msg/Detection2DArray": detections.decode_detection2d_array,
    "vision_msgs/msg/Detection3DArray": detections.decode_detection3d_array,
}

BlockDecoder = Callable[[Sequence[bytes | memoryview], DecodeOptions], object]
"""One topic's messages of a window (CDR) → a block of their own type, decoded together (issue 46, item 3)."""

BLOCK_DECODERS: dict[str, BlockDecoder] = {
    # block decoders (issue 46): a window's messages of one topic at once, columns over their CDR bytes
    "visualization_msgs/msg/MarkerArray": marker_arrays.decode_marker_arrays,  # in the feed, when logged
    "sensor_msgs/msg/Imu": decode_imu_block,  # in the bag's reader thread (viewer/blocks/block_feed.py)
}
"""Types a batch run decodes a window's worth at a time (no decay, no ``--video``, no header time); what a block
does not read exactly (None from an Imu block, a MarkerArray block's ``bad``) goes through :data:`DECODERS`, with
their errors."""

VIEWS: dict[str, str] = {
    "rcl_interfaces/msg/Log": "log",
    "rosgraph_msgs/msg/Log": "log",
    "std_msgs/msg/String": "log",
    "diagnostic_msgs/msg/DiagnosticArray": "state",
    "sensor_msgs/msg/NavSatFix": "map",
    "sensor_msgs/msg/Imu": "plot",
    "sensor_msgs/msg/BatteryState": "plot",
    **dict.fromkeys([*telemetry.SCALAR_DECODERS, *telemetry.NUMBER_DECODERS], "plot"),
}
"""The view beside the 3D one that a type needs: a log, a state timeline, a map, a plot (NavSatFix's altitude is
plotted too; the scalar sensors' points are drawn in 3D too)."""


def in_3d(msgtype: str) -> bool:
    """Whether a display type draws in the 3D view, in a frame: not a log line, a state or a plot (an Imu's axes
    are drawn in its frame beside its plots)."""
    return msgtype not in VIEWS or msgtype == "sensor_msgs/msg/Imu" or msgtype in scalar_points.BOUNDS


SHOWN_AS: dict[str, tuple[str, str]] = {
    "sensor_msgs/msg/LaserScan": (
        "LaserScan",
        "`Points3D` in the scan's frame; kept as laser_geometry keeps them: range_min ≤ range < range_max (NaN, inf "
        "and range_max itself dropped); intensity rainbow (min/max of each scan), else the flat colour",
    ),
    "sensor_msgs/msg/PointCloud2": (
        "PointCloud2",
        "`Points3D`, any field layout (padding, big-endian, organised with NaN); packed rgb/rgba, else intensity, "
        "else flat",
    ),
    "sensor_msgs/msg/PointCloud": ("PointCloud", "`Points3D`; its `intensity` channel as the rainbow"),
    "sensor_msgs/msg/Range": ("Range", "`LineStrips3D` cone of its field of view; nothing outside its limits"),
    "sensor_msgs/msg/Image": (
        "Image",
        "`Image` in a 2D view (mono, rgb, bgr, 16-bit, with row padding; Bayer and YUV 4:2:2 as RGB); 8-bit ones as "
        "`VideoStream` with `--video`",
    ),
    "sensor_msgs/msg/CompressedImage": ("Image", "`EncodedImage` (JPEG, PNG); `VideoStream` (h264, h265, av1, vp9)"),
    "foxglove_msgs/msg/CompressedVideo": ("Image", "`VideoStream` samples as they are (h264, h265, av1, vp9)"),
    "sensor_msgs/msg/CameraInfo": ("Camera", "`Pinhole` from K, so images also show in 3D"),
    "visualization_msgs/msg/Marker": (
        "Marker",
        "all eleven types on `<topic>/<ns>/<id>` (arrows, boxes, spheres, cylinders, lines, points, text, "
        "meshes through the package resolver, triangle lists); DELETE, DELETEALL and lifetime as `Clear`",
    ),
    "visualization_msgs/msg/MarkerArray": ("MarkerArray", "as Marker, each marker on its own entity"),
    "nav_msgs/msg/Path": ("Path", "`LineStrips3D` through the poses"),
    "nav_msgs/msg/Odometry": (
        "Odometry",
        "`Arrows3D` along the pose's x; a pose kept when it moved 0.1 m or turned 0.1 rad from the last one kept "
        "(RViz's Position / Angle Tolerance), the last Keep (100) of those drawn; covariance ellipsoid when asked",
    ),
    "nav_msgs/msg/OccupancyGrid": (
        "Map",
        "a textured `Mesh3D` quad at its origin and resolution; RViz's map, costmap or raw palette",
    ),
    "nav_msgs/msg/GridCells": ("GridCells", "`Boxes3D`, one per cell"),
    "geometry_msgs/msg/PoseStamped": ("Pose", "`Arrows3D` along the pose's x"),
    "geometry_msgs/msg/PoseArray": ("PoseArray", "`Arrows3D`, one per pose"),
    "geometry_msgs/msg/PoseWithCovarianceStamped": (
        "PoseWithCovariance",
        "`Arrows3D` and the 1-sigma `Ellipsoids3D` of the position covariance",
    ),
    "geometry_msgs/msg/PointStamped": ("PointStamped", "a small `Ellipsoids3D` sphere"),
    "geometry_msgs/msg/PolygonStamped": ("Polygon", "a closed `LineStrips3D`"),
    "geometry_msgs/msg/WrenchStamped": ("Wrench", "`Arrows3D`: force, and torque"),
    **dict.fromkeys(
        ("geometry_msgs/msg/TwistStamped", "geometry_msgs/msg/AccelStamped"),
        ("Twist, TwistStamped, AccelStamped", "`Arrows3D`: linear and angular velocity (acceleration)"),
    ),
    "visualization_msgs/msg/InteractiveMarkerUpdate": (
        "InteractiveMarkers",
        "its controls' markers as Marker draws them (on `<topic>/<name>/<key>`), moved by pose updates, "
        "erases as `Clear`; display only",
    ),
    "rcl_interfaces/msg/Log": (
        "rqt_console",
        "`TextLog` with its level (FATAL as Rerun's CRITICAL), `[node] text (file:function:line)`, in a log view",
    ),
    "rosgraph_msgs/msg/Log": ("rqt_console", "as above, ROS 1's levels 1-16 mapped to the same names"),
    "diagnostic_msgs/msg/DiagnosticArray": (
        "rqt_robot_monitor",
        "`StateChange` per status on `<topic>/<name>` (OK, WARN, ERROR, STALE and its message) in a state view; "
        "its key/values as fields (numbers plottable)",
    ),
    "std_msgs/msg/String": ("rqt_console", "`TextLog` without a level, in the log view"),
    "sensor_msgs/msg/Imu": (
        "(rviz_imu_plugin)",
        "orientation as x/y/z `Arrows3D` in its frame; angular velocity and linear acceleration `Scalars`",
    ),
    "sensor_msgs/msg/NavSatFix": (
        "(Foxglove's Map)",
        "`GeoPoints` on a map view (none without a fix); altitude plotted",
    ),
    "sensor_msgs/msg/BatteryState": ("(rqt_plot)", "voltage, current, charge, percentage, temperature `Scalars`"),
    **{
        t: (
            "Temperature, FluidPressure, Illuminance, RelativeHumidity",
            "a `Points3D` point in its frame, RViz's rainbow over the display's Min/Max Intensity; `Scalars` of its "
            "value (not its variance)",
        )
        for t in telemetry.SCALAR_SENSORS
    },
    **dict.fromkeys(telemetry.NUMBERS, ("(rqt_plot)", "`Scalars` of its data (a Bool as 0/1)")),
    **dict.fromkeys(
        [
            "nav2_msgs/msg/ParticleCloud",
            "nav2_msgs/msg/VoxelGrid",
            *(f"vision_msgs/msg/Detection{d}DArray" for d in "23"),
        ],
        (
            "ParticleCloud, Detection3DArray (nav2's, vision_msgs' plugins)",
            "an arrow a particle, its length by weight; a VoxelGrid's occupied voxels and 3D detections as `Boxes3D`; "
            "2D detections outlined on their camera's image ([docs/bags.md](docs/bags.md#display-topics))",
        ),
    ),
}
"""What each decoded type becomes: the RViz display that draws it, and the Rerun archetypes r2d2-viz logs."""


def displays_markdown() -> str:
    """The README's table of display types (in its "Bags" section)."""
    rows: dict[tuple[str, str], list[str]] = {}  # types shown alike share a row
    for msgtype, how in SHOWN_AS.items():
        rows.setdefault(how, []).append(msgtype)
    lines = ["| message type | RViz display | in Rerun |", "|---|---|---|"]
    lines += [f"| {', '.join(f'`{t}`' for t in types)} | {d} | {shown} |" for (d, shown), types in rows.items()]
    return "\n".join(lines)


def decode(typename: str, data: bytes | memoryview, options: DecodeOptions | None = None) -> Decoded | list[MarkerOp]:
    """Decode one message of ``typename``; unknown types and every failure raise ``MsgError``. Hostile values
    (huge doubles cast to float32 and the like) turn into inf / NaN silently: numpy prints nothing."""
    decoder = DECODERS.get(typename)
    if decoder is None:
        raise MsgError(f"no display for {typename}")
    try:
        with np.errstate(all="ignore"):
            return decoder(data, options or DecodeOptions())
    except ValueError:
        raise
    except (IndexError, KeyError, TypeError, OverflowError, AttributeError, struct.error) as exc:
        raise MsgError(f"{typename}: {one_line(exc)}") from None


if __name__ == "__main__":  # python -m r2d2_viz.msgs.registry: the README's table of display types
    import argparse

    argparse.ArgumentParser(
        prog="python -m r2d2_viz.msgs.registry", description="Print the README's table of display types (Markdown)."
    ).parse_args()
    print(displays_markdown())
