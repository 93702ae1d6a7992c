"""Image (encodings, step padding, byte order), CompressedImage and CameraInfo."""

from __future__ import annotations

import numpy as np
import pytest
from msgs_build import T, cdr, header

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.images import decode_camera_info, decode_compressed_image, decode_image
from r2d2_viz.msgs.shapes import DecodeOptions
from r2d2_viz.msgs.typestore import MsgError

OPTIONS = DecodeOptions()


def image(pixels: bytes, encoding: str, width: int, height: int, step: int, bigendian: bool = False) -> bytes:
    msg = T("sensor_msgs/msg/Image")(
        header=header("/camera_optical"),
        height=height,
        width=width,
        encoding=encoding,
        is_bigendian=bigendian,
        step=step,
        data=np.frombuffer(pixels, dtype=np.uint8),
    )
    return cdr(msg)


def test_rgb8_with_row_padding() -> None:
    rows = [bytes([1, 2, 3, 4, 5, 6]) + b"\xaa\xbb", bytes([7, 8, 9, 10, 11, 12]) + b"\xcc\xdd"]  # step 8 > 6
    decoded = decode_image(image(b"".join(rows), "rgb8", 2, 2, 8), OPTIONS)
    assert decoded.frame_id == "camera_optical"
    (img,) = decoded.items
    assert isinstance(img, shapes.Image) and img.color_model == "RGB"
    assert img.pixels.tolist() == [[[1, 2, 3], [4, 5, 6]], [[7, 8, 9], [10, 11, 12]]]


def test_mono16_both_byte_orders_and_bgr8() -> None:
    (little,) = decode_image(image(b"\x01\x02\x03\x04", "mono16", 2, 1, 4), OPTIONS).items
    (big,) = decode_image(image(b"\x01\x02\x03\x04", "16UC1", 2, 1, 4, bigendian=True), OPTIONS).items
    assert isinstance(little, shapes.Image) and isinstance(big, shapes.Image)
    assert little.pixels.tolist() == [[0x0201, 0x0403]] and big.pixels.tolist() == [[0x0102, 0x0304]]
    assert big.pixels.dtype.isnative
    (bgr,) = decode_image(image(bytes([9, 8, 7]), "bgr8", 1, 1, 3), OPTIONS).items
    assert isinstance(bgr, shapes.Image) and bgr.color_model == "BGR" and bgr.pixels.tolist() == [[[9, 8, 7]]]


def test_bad_images() -> None:
    with pytest.raises(MsgError, match="encoding"):
        decode_image(image(b"\x00" * 4, "yuv422_weird", 1, 1, 4), OPTIONS)
    with pytest.raises(MsgError, match="need"):
        decode_image(image(b"\x00" * 6, "rgb8", 2, 100_000, 6), OPTIONS)
    with pytest.raises(MsgError, match="step"):
        decode_image(image(b"\x00" * 6, "rgb8", 2, 1, 5), OPTIONS)


def test_compressed_image_by_magic_bytes() -> None:
    def compressed(blob: bytes, fmt: str) -> bytes:
        msg = T("sensor_msgs/msg/CompressedImage")(
            header=header("cam"), format=fmt, data=np.frombuffer(blob, dtype=np.uint8)
        )
        return cdr(msg)

    (jpeg,) = decode_compressed_image(compressed(b"\xff\xd8\xff\xe0rest", "jpeg"), OPTIONS).items
    assert isinstance(jpeg, shapes.CompressedImage) and jpeg.media_type == "image/jpeg"
    assert jpeg.data == b"\xff\xd8\xff\xe0rest"
    (png,) = decode_compressed_image(compressed(b"\x89PNG\r\n\x1a\n....", "png"), OPTIONS).items
    assert isinstance(png, shapes.CompressedImage) and png.media_type == "image/png"
    with pytest.raises(MsgError, match="neither"):
        decode_compressed_image(compressed(b"\x00\x00\x00\x0cPNG", "16UC1; compressedDepth"), OPTIONS)


def test_camera_info_pinhole() -> None:
    def info(k: list[float]) -> bytes:
        roi = T("sensor_msgs/msg/RegionOfInterest")(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
        msg = T("sensor_msgs/msg/CameraInfo")(
            header=header("cam"),
            height=480,
            width=640,
            distortion_model="plumb_bob",
            d=np.zeros(5),
            k=np.array(k, dtype=np.float64),
            r=np.eye(3).reshape(-1),
            p=np.zeros(12),
            binning_x=0,
            binning_y=0,
            roi=roi,
        )
        return cdr(msg)

    (pinhole,) = decode_camera_info(info([500, 0, 320, 0, 510, 240, 0, 0, 1]), OPTIONS).items
    assert isinstance(pinhole, shapes.Pinhole) and (pinhole.width, pinhole.height) == (640, 480)
    assert pinhole.K.tolist() == [[500, 0, 320], [0, 510, 240], [0, 0, 1]]
    assert decode_camera_info(info([0.0] * 9), OPTIONS).items == ()  # uncalibrated: nothing to draw
