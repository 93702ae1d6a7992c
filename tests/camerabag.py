"""A camera bag like a real sensor's, written by ``rosbags``: 640x480 rgb8 frames with texture (a sinusoid and
a checkerboard), hard edges (moving coloured blocks), motion (the background pans) and sensor noise (Gaussian,
sigma 2 levels), not flat colour; with its CameraInfo, so the images also show in 3D. The benchmarks write theirs
with it too."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from bagmaker import T0, TS, BagSpec, stamp, write_bag

WIDTH, HEIGHT, RATE = 640, 480, 30.0
Image = TS.types["sensor_msgs/msg/Image"]
CameraInfo = TS.types["sensor_msgs/msg/CameraInfo"]
Header = TS.types["std_msgs/msg/Header"]
RegionOfInterest = TS.types["sensor_msgs/msg/RegionOfInterest"]
CAMERA_TYPES = {"/camera/image_raw": "sensor_msgs/msg/Image", "/camera/camera_info": "sensor_msgs/msg/CameraInfo"}


class Frames:
    """Frame ``i`` of the scene (deterministic: the noise is seeded per frame)."""

    def __init__(self, width: int = WIDTH, height: int = HEIGHT, noise: float = 2.0) -> None:
        self.width, self.height, self.noise = width, height, noise
        yy, xx = np.mgrid[0 : height + 200, 0 : width + 200].astype(np.float32)
        grey = 128 + 50 * np.sin(xx / 7.0) * np.cos(yy / 11.0) + 40 * ((xx // 40 + yy // 40) % 2) - 20
        self.scene = np.stack([grey, np.roll(grey, 13, 1) * 0.8 + 30, 255 - grey * 0.7], -1).clip(0, 255)

    def __call__(self, i: int) -> np.ndarray:
        w, h = self.width, self.height
        ox, oy = (2 * i) % 200, i % 200
        img = self.scene[oy : oy + h, ox : ox + w].copy()
        x, y = int(w * 0.15 + w * 0.3 * np.sin(i / 20)), int(h * 0.4 + h * 0.2 * np.cos(i / 15))
        img[y : y + h // 6, x + w // 6 : x + w // 3] = (250, 30, 30)
        img[h // 5 : h // 5 + h // 12, (5 * i) % w : (5 * i) % w + w // 10] = (20, 200, 20)
        img += np.random.default_rng(i).normal(0, self.noise, img.shape).astype(np.float32)
        out: np.ndarray = img.clip(0, 255).astype(np.uint8)
        return out


def image(t: int, pixels: np.ndarray, encoding: str = "rgb8", frame: str = "camera_optical") -> bytes:
    h, w = pixels.shape[:2]
    step = pixels.strides[0]
    data = np.ascontiguousarray(pixels).view(np.uint8).reshape(-1)
    msg = Image(Header(stamp(t), frame), h, w, encoding, 0, step, data)
    return bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/Image"))


def camera_info(t: int, width: int = WIDTH, height: int = HEIGHT, frame: str = "camera_optical") -> bytes:
    k = np.array([500.0, 0, width / 2, 0, 500.0, height / 2, 0, 0, 1])
    p = np.array([500.0, 0, width / 2, 0, 0, 500.0, height / 2, 0, 0, 0, 1, 0])
    msg = CameraInfo(
        Header(stamp(t), frame), height, width, "plumb_bob", np.zeros(5), k, np.eye(3).reshape(-1), p, 0, 0,
        RegionOfInterest(0, 0, 0, 0, False),
    )  # fmt: skip
    return bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/CameraInfo"))


def write_camera_bag(path: Path, n: int, *, frames: Frames | None = None, rate: float = RATE) -> list[int]:
    """``n`` frames at ``rate`` on /camera/image_raw (and its CameraInfo each second); the receive times."""
    frames = frames or Frames()
    spec = BagSpec(types=dict(CAMERA_TYPES))
    times = [T0 + round(i * 1e9 / rate) for i in range(n)]
    for i, t in enumerate(times):
        if i % round(rate) == 0:
            spec.add("/camera/camera_info", t, camera_info(t, frames.width, frames.height))
        spec.add("/camera/image_raw", t + 1, image(t, frames(i)))
    write_bag(path, spec)
    return [t + 1 for t in times]


from msgs_build import FOXGLOVE_VIDEO  # noqa: E402


def write_video_bag(path: Path, samples: list[tuple[str, int, str, bytes]]) -> None:
    """(topic, receive ns, format, sample) as ``foxglove_msgs/msg/CompressedVideo`` (topics ending in
    ``/compressed``: ``sensor_msgs/msg/CompressedImage``), the definition carried in the MCAP's schema."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg(FOXGLOVE_VIDEO, "foxglove_msgs/msg/CompressedVideo"))
    video, compressed = store.types["foxglove_msgs/msg/CompressedVideo"], store.types["sensor_msgs/msg/CompressedImage"]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {}
        for topic, t, fmt, data in samples:
            as_image = topic.endswith("/compressed")
            msgtype = "sensor_msgs/msg/CompressedImage" if as_image else "foxglove_msgs/msg/CompressedVideo"
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=store)
            blob = np.frombuffer(data, np.uint8)
            msg = compressed(Header(stamp(t), "cam"), fmt, blob) if as_image else video(stamp(t), "cam", blob, fmt)
            writer.write(connections[topic], t, bytes(store.serialize_cdr(msg, msgtype)))


def write_camera_video_bag(path: Path, n: int, *, rate: float = 15.0, frames: Frames | None = None) -> None:
    """Issue 38's camera bag: ``n`` rgb8 frames at ``rate`` on /camera/image_raw (CameraInfo each second), and an
    H.264 topic ``/front/video`` (``foxglove_msgs/msg/CompressedVideo``, 320x240 by PyAV's x264, a keyframe every
    2 s) of the same scene, written after the camera, topic by topic as a converting tool writes — so its few
    chunks span the whole bag and overlap every camera chunk in time. Written as it goes (the frames are not held)."""
    from fractions import Fraction

    import av
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg(FOXGLOVE_VIDEO, "foxglove_msgs/msg/CompressedVideo"))
    video = store.types["foxglove_msgs/msg/CompressedVideo"]
    encoder = av.CodecContext.create("libx264", "w")
    encoder.width, encoder.height, encoder.pix_fmt = 320, 240, "yuv420p"
    encoder.time_base, encoder.gop_size, encoder.max_b_frames = Fraction(1, round(rate)), round(2 * rate), 0
    encoder.options = {"tune": "zerolatency", "preset": "ultrafast"}
    frames = frames or Frames()
    samples: list[tuple[int, bytes]] = []
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        info = writer.add_connection("/camera/camera_info", "sensor_msgs/msg/CameraInfo", typestore=store)
        camera = writer.add_connection("/camera/image_raw", "sensor_msgs/msg/Image", typestore=store)
        passed = writer.add_connection("/front/video", "foxglove_msgs/msg/CompressedVideo", typestore=store)
        for i in range(n):
            t = T0 + round(i * 1e9 / rate)
            pixels = frames(i)
            if i % round(rate) == 0:
                writer.write(info, t, camera_info(t, frames.width, frames.height))
            writer.write(camera, t + 1, image(t, pixels))
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(pixels[::2, ::2]), format="rgb24")
            frame.pts = i
            samples += [(t + 2, bytes(p)) for p in encoder.encode(frame)]
        samples += [(T0 + round(n * 1e9 / rate), bytes(p)) for p in encoder.encode(None)]
        for t, sample in samples:
            msg = video(stamp(t), "front", np.frombuffer(sample, np.uint8), "h264")
            writer.write(passed, t, bytes(store.serialize_cdr(msg, "foxglove_msgs/msg/CompressedVideo")))
