"""2D detections drawn on their camera's image: paired by namespace, below the image's entity, in the frame that
image is drawn in (its pinhole's image plane, or the fixed frame of a flat image)."""

from __future__ import annotations

import numpy as np
import pytest
from rrd import read_recording
from stackbags import DETECTIONS_2D_CORNERS, DETECTIONS_2D_ENTITY, stack_recordings

from r2d2_viz.msgs.shapes import Decoded
from r2d2_viz.viewer.blocks.image_overlays import on_image, overlay_frames

D, IMG, C = "vision_msgs/msg/Detection2DArray", "sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo"


def test_paired_with_the_image_of_its_camera() -> None:
    topics = {
        "/cam/detections": D,
        "/cam/image_raw": IMG,
        "/cam/camera_info": C,
        "/flat/yolo/boxes": D,
        "/flat/img": IMG,
    }
    assert overlay_frames(topics, "map") == {
        "/cam/detections": ("/cam/image_raw/detections/cam/detections", "/cam/image_raw#image"),  # its pinhole's plane
        "/flat/yolo/boxes": ("/flat/img/detections/flat/yolo/boxes", "map"),  # a namespace up; no pinhole: fixed
    }
    assert overlay_frames({"/detections": D}, "map") == {}  # no image: drawn in its own frame


def test_on_image_moves_only_what_has_an_image() -> None:
    decoded = Decoded("cam_optical", 1)
    assert on_image(decoded, None) is decoded
    assert on_image(decoded, "/cam/image_raw#image") == Decoded("/cam/image_raw#image", 1)


def test_recorded_on_the_image(tmp_path_factory: pytest.TempPathFactory) -> None:
    recording = read_recording(stack_recordings(tmp_path_factory)["plain"])
    rows = recording[DETECTIONS_2D_ENTITY]
    (i,) = [k for k, v in enumerate(rows.temporal["LineStrips2D:strips"]) if v is not None]
    assert rows.temporal["CoordinateFrame:frame"][i] == ["/cam/image_raw#image"]
    closed = [[*c, c[0]] for c in DETECTIONS_2D_CORNERS]  # each outline closed: its first corner again
    np.testing.assert_allclose(rows.temporal["LineStrips2D:strips"][i], closed, atol=1e-5)
    assert rows.temporal["LineStrips2D:labels"][i] == ["person 0.90", ""]
    assert rows.temporal["LineStrips2D:colors"][i] == [0x0000FFFF, 0xFF1650FF]
    # the image's pinhole names the same plane: the outlines show on the image, in 2D and in 3D
    pinholes = recording["/cam/image_raw"].temporal["Pinhole:child_frame"]
    assert ["/cam/image_raw#image"] in pinholes
