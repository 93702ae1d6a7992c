"""Decoding that needs more than one message: RViz displays that join topics or remember earlier messages.

- DepthCloud: a depth image (16UC1 / 32FC1) becomes points with its camera's latest CameraInfo (the depth topic's
  ``<namespace>/camera_info``, as image_transport names it) and the latest image of the Color Image Topic
  (:mod:`r2d2_viz.msgs.rviz2.depth_cloud`); drawn as the op ``("depth_cloud", 0)`` (on ``<topic>/depth_cloud/0``: the
  topic's own entity may carry its camera's pinhole). Nothing is drawn before the first CameraInfo (RViz waits too).
- InteractiveMarkers: pose updates move the markers of earlier updates (:mod:`r2d2_viz.msgs.rviz2.interactive`).
- Effort: a JointState's efforts at the robot's joints (:mod:`r2d2_viz.msgs.rviz2.effort`), when its topic's options
  name the joints.

Everything else is :func:`r2d2_viz.msgs.registry.decode`. Messages must come in receive order, each once. Pure: no
rerun.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping

from r2d2_viz.errors import one_line
from r2d2_viz.msgs.geometry import header_of
from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.rviz2.depth_cloud import Projection, depth_points, projection_of
from r2d2_viz.msgs.rviz2.effort import effort_ops
from r2d2_viz.msgs.rviz2.interactive import UPDATE, InteractiveMarkers
from r2d2_viz.msgs.shapes import Decoded, DecodeOptions, Image, MarkerOp
from r2d2_viz.msgs.typestore import MsgError, deserialize

JOINT_STATE = "sensor_msgs/msg/JointState"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"


def info_topic(image_topic: str) -> str:
    """image_transport's ``getCameraInfoTopic``: ``/cam/depth/image_raw`` → ``/cam/depth/camera_info``."""
    return image_topic.rsplit("/", 1)[0] + "/camera_info"


class Joins:
    """The state the joining displays keep; ``options``: each topic's decode options (its display's)."""

    def __init__(self, options: Mapping[str, DecodeOptions]) -> None:
        clouds = {topic: o.depth_cloud for topic, o in options.items() if o.depth_cloud is not None}
        self.infos = {info: depth for depth, (info, _) in clouds.items()}
        """CameraInfo topic → the depth topic it projects."""
        self.colors = {color: depth for depth, (_, color) in clouds.items() if color}
        self.projections: dict[str, Projection] = {}
        self.color_images: dict[str, Image] = {}
        self.interactive: dict[str, InteractiveMarkers] = {}

    @property
    def topics(self) -> set[str]:
        """The topics a join reads beside the depth topics: their cameras' infos and colour images."""
        return {*self.infos, *self.colors}

    def decode(
        self, topic: str, msgtype: str, data: bytes | memoryview, options: DecodeOptions
    ) -> Decoded | list[MarkerOp]:
        """What the message draws; fails only with ``MsgError`` (as :func:`r2d2_viz.msgs.registry.decode`)."""
        try:
            return self._decode(topic, msgtype, data, options)
        except MsgError:
            raise
        except (IndexError, KeyError, TypeError, OverflowError, AttributeError, ValueError, struct.error) as exc:
            raise MsgError(f"{msgtype}: {one_line(exc)}") from None

    def _decode(
        self, topic: str, msgtype: str, data: bytes | memoryview, options: DecodeOptions
    ) -> Decoded | list[MarkerOp]:
        if msgtype == UPDATE:
            return self.interactive.setdefault(topic, InteractiveMarkers()).decode(data)
        if msgtype == JOINT_STATE and options.effort:
            msg = deserialize(data, JOINT_STATE)
            width, scale = options.effort_size
            joints = {j.name: j for j in options.effort}
            stamp = header_of(msg)[1]
            return effort_ops(list(msg.name), list(msg.effort), joints, stamp, width=width, scale=scale)
        if msgtype == CAMERA_INFO and topic in self.infos:
            depth = self.infos[topic]
            try:
                self.projections[depth] = projection_of(deserialize(data, CAMERA_INFO))
            except MsgError:
                self.projections.pop(depth, None)  # an uncalibrated camera: no cloud (RViz: an error)
        decoded = decode(msgtype, data, options)
        if topic in self.colors and isinstance(decoded, Decoded) and decoded.items:
            image = decoded.items[0]
            if isinstance(image, Image):
                self.color_images[self.colors[topic]] = image
        if options.depth_cloud is None or not isinstance(decoded, Decoded) or not decoded.items:
            return decoded
        image, projection = decoded.items[0], self.projections.get(topic)
        if not isinstance(image, Image) or projection is None:
            return []
        points = depth_points(image, projection, self.color_images.get(topic), options.point_radius)  # Size (m) / 2
        return [MarkerOp("add", "depth_cloud", 0, Decoded(decoded.frame_id, decoded.stamp_ns, (points,)))]
