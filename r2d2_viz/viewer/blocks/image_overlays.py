"""What is drawn on a camera's image rather than in a TF frame: vision_msgs' 2D detections
(:func:`r2d2_viz.sources.bag_displays.detection_images` pairs each with the image of its camera). Their outlines
go below the image's entity, on ``<image>/detections<topic>`` (``/cam/image_raw/detections/cam/detections``), so
the image's 2D view shows them and a flat image's exclusion from the 3D view excludes them, in the frame that image
is in: its image plane when a CameraInfo gives it a pinhole (so they also show on the image in 3D), else the fixed
frame every flat image sits in."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from r2d2_viz.msgs.shapes import Decoded, MarkerOp
from r2d2_viz.sources.bag_displays import camera_images, detection_images
from r2d2_viz.viewer.displays import image_plane


def overlay_frames(topics: Mapping[str, str], fixed_frame: str) -> dict[str, tuple[str, str]]:
    """Each Detection2DArray topic → (the entity it is drawn on, the frame its image is drawn in)."""
    with_camera = {t for images in camera_images(topics).values() for t in images}
    return {
        topic: (f"{image}/detections{topic}", image_plane(image) if image in with_camera else fixed_frame)
        for topic, image in detection_images(topics).items()
    }


def on_image(decoded: Decoded | list[MarkerOp], frame: str | None) -> Decoded | list[MarkerOp]:
    """``decoded`` in its image's ``frame`` (as it is when its topic has no image)."""
    if frame is None or not isinstance(decoded, Decoded):
        return decoded
    return dataclasses.replace(decoded, frame_id=frame)
