"""Image (encodings, step padding, byte order), CompressedImage and CameraInfo."""

from __future__ import annotations

from pathlib import Path

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


# --- Bayer and YUV 4:2:2 (refused before: "unsupported image encoding") ------------------------------------------


def _mosaic(cfa: str, cells: np.ndarray, dtype: str = "u1") -> np.ndarray:
    """A Bayer mosaic ``(2h, 2w)`` from per-cell colours ``(h, w, 4)`` = (R, G of the first row, G of the second
    row, B), laid out by hand in the 2x2 ``cfa`` order."""
    h, w = cells.shape[:2]
    out = np.zeros((2 * h, 2 * w), dtype=dtype)
    greens = iter([1, 2])
    for k, channel in enumerate(cfa):
        y, x = divmod(k, 2)
        out[y::2, x::2] = cells[:, :, next(greens) if channel == "g" else {"r": 0, "b": 3}[channel]]
    return out


@pytest.mark.parametrize("cfa", ["rggb", "bggr", "gbrg", "grbg"])
def test_bayer_mosaics_show_in_colour_one_colour_a_cell(cfa: str) -> None:
    """Each 2x2 cell of the mosaic becomes its (red, mean of its greens rounded half up, blue) on all four pixels:
    cells worked out by hand, for each of the four colour filters, 8 and 16 bits."""
    cells = np.array([[[200, 100, 103, 30], [0, 255, 255, 255]], [[17, 1, 2, 90], [255, 0, 0, 0]]])
    expected = np.array([[[200, 102, 30], [0, 255, 255]], [[17, 2, 90], [255, 0, 0]]])
    expected = np.repeat(np.repeat(expected, 2, axis=0), 2, axis=1)
    mosaic = _mosaic(cfa, cells)
    (img,) = decode_image(image(mosaic.tobytes(), f"bayer_{cfa}8", 4, 4, 4), OPTIONS).items
    assert isinstance(img, shapes.Image) and img.color_model == "RGB"
    assert img.pixels.dtype == np.uint8 and img.pixels.tolist() == expected.tolist()
    wide = _mosaic(cfa, cells * 257, ">u2")
    (img16,) = decode_image(image(wide.tobytes(), f"bayer_{cfa}16", 4, 4, 8, bigendian=True), OPTIONS).items
    # greens (100 + 103) * 257 / 2 = 26085.5 -> 26086, (1 + 2) * 257 / 2 = 385.5 -> 386
    expected16 = np.array([[[51400, 26086, 7710], [0, 65535, 65535]], [[4369, 386, 23130], [65535, 0, 0]]])
    expected16 = np.repeat(np.repeat(expected16, 2, axis=0), 2, axis=1)
    assert isinstance(img16, shapes.Image) and img16.pixels.tolist() == expected16.tolist()


def test_an_odd_bayer_image_repeats_its_last_cell_and_padding_is_skipped() -> None:
    mosaic = np.array([[10, 20, 11, 77], [30, 40, 12, 77], [50, 60, 13, 77]], dtype=np.uint8)  # 3x3, step 4
    (img,) = decode_image(image(mosaic.tobytes(), "bayer_rggb8", 3, 3, 4), OPTIONS).items
    assert isinstance(img, shapes.Image)
    # cell 1: R 10, G (20 + 30) / 2 = 25, B 40; the third column and row take the colour of the cell beside them
    assert img.pixels.tolist() == [[[10, 25, 40]] * 3] * 3


def _pyav_rgb(fmt: str, packed: np.ndarray) -> np.ndarray:
    """FFmpeg's own conversion (swscale through PyAV) of packed 4:2:2 rows to RGB: the golden reference."""
    av = pytest.importorskip("av")
    height, row = packed.shape
    frame = av.VideoFrame(row // 2, height, fmt)
    plane = frame.planes[0]
    buffer = np.zeros((height, plane.line_size), np.uint8)
    buffer[:, :row] = packed
    plane.update(buffer.tobytes())
    rgb: np.ndarray = frame.to_ndarray(format="rgb24")
    return rgb


@pytest.mark.parametrize(
    ("encoding", "ffmpeg"),
    [("yuv422_yuy2", "yuyv422"), ("yuyv", "yuyv422"), ("yuv422", "uyvy422"), ("uyvy", "uyvy422")],
)
def test_yuv422_shows_in_colour_as_ffmpeg_converts_it(encoding: str, ffmpeg: str) -> None:
    """Packed YUV 4:2:2 (ROS's ``yuv422`` is UYVY, ``yuv422_yuy2`` is YUYV) against FFmpeg's BT.601 conversion,
    within 3 levels (its fast fixed-point path rounds down: 0 to 3 below exact, measured); and by hand: Y 235
    with neutral chroma is white, Y 16 black."""
    packed = np.random.default_rng(3).integers(16, 241, (6, 16), dtype=np.uint8)  # 8x6 pixels
    (img,) = decode_image(image(packed.tobytes(), encoding, 8, 6, 16), OPTIONS).items
    assert isinstance(img, shapes.Image) and img.color_model == "RGB" and img.pixels.shape == (6, 8, 3)
    assert np.abs(img.pixels.astype(int) - _pyav_rgb(ffmpeg, packed)).max() <= 3
    white_black = bytes([235, 128, 16, 128]) if ffmpeg == "yuyv422" else bytes([128, 235, 128, 16])
    (wb,) = decode_image(image(white_black, encoding, 2, 1, 4), OPTIONS).items
    assert isinstance(wb, shapes.Image) and wb.pixels.tolist() == [[[255, 255, 255], [0, 0, 0]]]


def test_yuv422_of_an_odd_width_is_refused() -> None:
    with pytest.raises(MsgError, match="even width"):
        decode_image(image(b"\x00" * 6, "yuv422", 3, 1, 6), OPTIONS)


def test_a_bags_bayer_and_yuv_cameras_are_recorded_in_colour(tmp_path: Path) -> None:
    """As found: a bag (written by rosbags) of a ``bayer_rggb8`` camera and a ``yuv422_yuy2`` one replayed
    through the CLI: both refused before ("unsupported image encoding"); read back, each is an RGB image with the
    colours worked out by hand (Bayer) and by FFmpeg (YUV)."""
    from bagmaker import T0, BagSpec, write_bag
    from conftest import cli
    from rrd import read_recording

    cells = np.array([[[200, 100, 103, 30], [5, 6, 7, 8]]])  # one row of two cells: 4x2 pixels
    bayer = image(_mosaic("rggb", cells).tobytes(), "bayer_rggb8", 4, 2, 4)
    packed = np.array([[81, 90, 81, 240, 235, 128, 16, 128]], dtype=np.uint8)  # BT.601 red, then white and black
    yuyv = image(packed.tobytes(), "yuv422_yuy2", 4, 1, 8)
    types = {"/bayer/image_raw": "sensor_msgs/msg/Image", "/yuyv/image_raw": "sensor_msgs/msg/Image"}
    spec = BagSpec(types=types).add("/bayer/image_raw", T0, bayer).add("/yuyv/image_raw", T0 + 1, yuyv)
    bag = write_bag(tmp_path / "cams", spec)
    out = tmp_path / "cams.rrd"
    result = cli("--bag", str(bag), "--save", str(out))
    assert result.returncode == 0, result.stderr
    assert "encoding" not in result.stderr, result.stderr
    recording = read_recording(out)

    def pixels(entity: str, width: int, height: int) -> np.ndarray:
        (buffer,) = [b for b in recording[entity].temporal["Image:buffer"] if b is not None]
        return np.array(buffer, dtype=np.uint8).reshape(height, width, 3)

    cell_colours = [[200, 102, 30], [5, 7, 8]]  # (R, mean of the greens rounded half up, B) of each cell
    assert pixels("/bayer/image_raw", 4, 2).tolist() == [[c for c in cell_colours for _ in range(2)]] * 2
    assert np.abs(pixels("/yuyv/image_raw", 4, 1).astype(int) - _pyav_rgb("yuyv422", packed)).max() <= 3
    assert pixels("/yuyv/image_raw", 4, 1)[0, 2:].tolist() == [[255, 255, 255], [0, 0, 0]]
