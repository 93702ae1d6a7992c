"""The one table from ROS type names to decoders, and ``decode`` that fails only with ``MsgError``."""

from __future__ import annotations

import struct
from collections.abc import Callable

import numpy as np

from r2d2_viz.errors import one_line
from r2d2_viz.msgs import images, markers, nav, pointcloud, poses, scan
from r2d2_viz.msgs.shapes import Decoded, DecodeOptions, MarkerOp
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
}


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
