"""One bag → one episode's parts, in a folder of its own (a worker's output, before the dataset takes it in):
``observation.state`` from ``/joint_states``, ``action`` from a command topic, an MP4 per camera topic, all sampled
at ``fps`` on the bag's time (receive or header stamps), from the first time every feature has had a message to the
last time every feature still has (no frame outside a topic's span).

Two passes over the bag: the joint states, the command and the cameras' times; then each camera's messages, decoded
only where a frame shows them (a video stream: every message) and encoded as they come: constant memory.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import I64
from r2d2_viz.errors import BagError, one_line
from r2d2_viz.export import lerobot_stats
from r2d2_viz.export.lerobot_columns import ACTION_TYPES, Series, add_message, frame_times, held_index, ordered
from r2d2_viz.export.lerobot_format import IMAGES
from r2d2_viz.export.lerobot_video import CAMERA_TYPES, CameraError, Codec, FrameReader, Mp4Writer
from r2d2_viz.msgs.typestore import MsgError, deserialize
from r2d2_viz.sources.bag_joints import read_robot_description
from r2d2_viz.sources.bags.bag import Bag, open_bag

JOINT_STATES = "/joint_states"


@dataclass(frozen=True)
class EpisodeSpec:
    bag: Path
    out: Path
    """A folder for this episode's videos (made by the caller)."""
    fps: int = 30
    action: str | None = None
    header_time: bool = False
    codec: Codec = "av1"
    robot_order: tuple[str, ...] | None = None
    """Joint order of a robot given by the caller (``--urdf``); else the bag's ``/robot_description``'s."""


@dataclass
class EpisodePart:
    frames: int
    start_ns: int
    state_names: list[str] = field(default_factory=list)
    state: npt.NDArray[np.float32] | None = None
    action_names: list[str] = field(default_factory=list)
    action: npt.NDArray[np.float32] | None = None
    cameras: dict[str, tuple[int, int]] = field(default_factory=dict)
    """Feature key → (height, width); its video is ``out/<key>.mp4``."""
    camera_stats: dict[str, lerobot_stats.Stats] = field(default_factory=dict)
    robot_type: str | None = None


def camera_key(topic: str) -> str:
    """``/camera/color/image_raw`` → ``observation.images.camera_color_image_raw``."""
    return IMAGES + "_".join(p for p in topic.split("/") if p)


def urdf_joint_order(xml: str) -> tuple[tuple[str, ...], str | None]:
    """The moving joints of a URDF in document order, and the robot's name."""
    from r2d2_viz.robot.urdf_xml import parse_urdf_xml

    root = parse_urdf_xml(xml, source="/robot_description", base_dir=Path.cwd())
    joints = tuple(str(j.get("name")) for j in root.iter("joint") if j.get("type") not in (None, "fixed"))
    return joints, root.get("name")


def export_episode(spec: EpisodeSpec, *, progress: Callable[[float], None] | None = None) -> EpisodePart:
    """Read ``spec.bag`` and write its cameras' videos in ``spec.out``; BagError (one line naming the bag and the
    topic) when it has no joint states and no camera, lacks the ``--action`` topic or holds nothing to sample."""
    with open_bag(spec.bag) as bag:
        return _export(bag, spec, progress or (lambda _: None))


def _export(bag: Bag, spec: EpisodeSpec, progress: Callable[[float], None]) -> EpisodePart:
    where = str(spec.bag)
    cameras = sorted(t for t, info in bag.topics.items() if info.msgtype in CAMERA_TYPES)
    joints = bag.require_type(JOINT_STATES, "sensor_msgs/msg/JointState")
    if not joints and not cameras:
        raise BagError(f"{where}: no {JOINT_STATES} and no camera topic (Image, CompressedImage, CompressedVideo)")
    if spec.action is not None:
        action_type = bag.topic_type(spec.action)
        if action_type is None:
            raise BagError(f"{where}: no topic {spec.action} (--action)")
        if action_type not in ACTION_TYPES:
            kinds = ", ".join(t.rsplit("/", 1)[1] for t in ACTION_TYPES)
            raise BagError(f"{where}: --action {spec.action} is {action_type}, not a command ({kinds})")
    state, action = Series(), Series()
    series = {JOINT_STATES: state} if joints else {}
    if spec.action is not None:
        series[spec.action] = action
    for block in bag.blocks(list(series)):
        for time_ns, topic, data in block.messages():
            try:
                add_message(series[topic], bag.topics[topic].msgtype, data, time_ns, spec.header_time)
            except MsgError as exc:
                raise BagError(f"{where}: {topic}: {one_line(exc)}") from None
    for topic, values in series.items():
        if not values.times:
            raise BagError(f"{where}: {topic} has no message to take values from")
    camera_times = {topic: _times(bag, topic, spec.header_time) for topic in cameras}
    firsts = [s.first_ns() for s in series.values()] + [int(t.min()) for t in camera_times.values() if len(t)]
    lasts = [s.last_ns() for s in series.values()] + [int(t.max()) for t in camera_times.values() if len(t)]
    frames_ns = frame_times(max(firsts), min(lasts), spec.fps)
    if len(frames_ns) < 2:
        raise BagError(f"{where}: its topics overlap for less than two frames at {spec.fps} fps: nothing to export")
    robot_order, robot_type = spec.robot_order, None
    description = read_robot_description(bag)
    if description is not None:
        try:
            order, robot_type = urdf_joint_order(description)
        except Exception:  # a description that does not parse: the joint states' own order
            order = ()
        robot_order = robot_order or order
    part = EpisodePart(frames=len(frames_ns), start_ns=int(frames_ns[0]), robot_type=robot_type)
    if joints:
        part.state_names = ordered(state.names, robot_order or ())
        part.state = state.at(frames_ns, part.state_names)
    if spec.action is not None:
        part.action_names = ordered(action.names, robot_order or ())
        part.action = action.at(frames_ns, part.action_names)
    for k, topic in enumerate(cameras):
        key = camera_key(topic)
        try:
            size, stats = _encode(bag, topic, held_index(camera_times[topic], frames_ns), spec, key)
        except CameraError as exc:
            raise BagError(f"{where}: {topic}: {one_line(exc)}") from None
        part.cameras[key], part.camera_stats[key] = size, stats
        progress((k + 1) / len(cameras))
    return part


def _times(bag: Bag, topic: str, header: bool) -> I64:
    """Each message's time, in the topic's (receive) order: receive times, or header stamps."""
    times: list[int] = []
    for block in bag.blocks([topic]):
        if not header:
            times.extend(block.times_ns.tolist())
            continue
        for time_ns, data in block.pairs():
            try:
                msg = deserialize(data, bag.topics[topic].msgtype)
            except MsgError as exc:
                raise BagError(f"{bag.path}: {topic}: {one_line(exc)}") from None
            stamp = msg.timestamp if hasattr(msg, "timestamp") else msg.header.stamp
            times.append(int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec) or time_ns)
    return np.asarray(times, dtype=np.int64)


def _encode(
    bag: Bag, topic: str, shown: I64, spec: EpisodeSpec, key: str
) -> tuple[tuple[int, int], lerobot_stats.Stats]:
    """Encode the frames of ``topic`` (frame ``k`` shows message ``shown[k]``); its size and pixel stats."""
    reader = FrameReader(bag.topics[topic].msgtype)
    writer = Mp4Writer(spec.out / f"{key}.mp4", fps=spec.fps, codec=spec.codec)
    sampled = set(lerobot_stats.sample_indices(len(shown)).tolist())
    kept: list[np.ndarray] = []
    video = reader.msgtype != "sensor_msgs/msg/Image"  # a compressed image's format may be a video codec
    k, index = 0, 0
    try:
        for block in bag.blocks([topic]):
            for _, data in block.pairs():
                if k < len(shown) and (video or shown[k] == index):
                    try:
                        frame = reader.frame(data)
                    except MsgError as exc:
                        raise CameraError(one_line(exc)) from None
                    while k < len(shown) and shown[k] == index:
                        if frame is None:
                            raise CameraError("no frame decoded yet at the episode's start (a video without keyframe)")
                        writer.write(frame)
                        if k in sampled:
                            kept.append(lerobot_stats.thinned(frame))
                        k += 1
                index += 1
    finally:
        writer.close()
    if k < len(shown) or writer.size is None:
        raise CameraError(f"{k} of {len(shown)} frames read (the bag broke off?)")
    return writer.size, lerobot_stats.image_stats(kept)
