"""A bag's display topics — what RViz's displays draw: scans, clouds, markers, maps, paths, poses, images
(the types of :data:`r2d2_viz.msgs.registry.DECODERS`): which of a bag's topics they are, their raw messages
(:class:`TopicMessage`), and the frames such messages are drawn in. Pure: no rerun.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from r2d2_viz.msgs.registry import DECODERS, decode, in_3d
from r2d2_viz.msgs.shapes import Decoded, MarkerOp, VideoSample
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bags.bag import Bag

GRID_UPDATE = "map_msgs/msg/OccupancyGridUpdate"
"""A map's partial update (nav2's costmaps): applied to the map of the topic it updates (``<map>_updates``)."""
OURS = ("/joint_states", "/tf", "/tf_static", "/robot_description")
"""Topics the robot pipeline itself reads."""
VIDEO_TYPES = ("foxglove_msgs/msg/CompressedVideo", "sensor_msgs/msg/CompressedImage")
"""Types whose messages may be video samples passed through (a CompressedImage when its format names a codec)."""
KEYFRAME_SEARCH_NS = 120 * 1_000_000_000
"""How far before a seek a passed-through video's keyframe is looked for (read twice as far each time, 2 s first)."""


@dataclass(frozen=True)
class TopicMessage:
    """One message of a display topic as it was recorded or received: raw CDR bytes."""

    time_ns: int
    """Receive time (a bag's log time, a live sample's source timestamp)."""
    topic: str
    msgtype: str
    data: bytes | memoryview
    decoded: Decoded | list[MarkerOp] | MsgError | None = None
    """What it draws, when decoded ahead (in the bag reader's thread); None: not yet decoded."""
    prepared: object = None
    """What the viewer built ahead from ``decoded`` to log it (opaque here; None: nothing built)."""


def display_topics(bag: Bag, joined: Iterable[str] = ()) -> tuple[dict[str, str], dict[str, str]]:
    """``(topic → type)`` of the bag's topics a display draws, and of the others (not ours, no display);
    ``joined``: topics drawn with others' help (an RViz Effort display's JointState topic), ours or not."""
    shown: dict[str, str] = {t: bag.topics[t].msgtype for t in joined if t in bag.topics}
    other: dict[str, str] = {}
    for topic, info in sorted(bag.topics.items()):
        if topic in OURS or topic.endswith("/robot_description") or topic in shown:
            continue  # a robot's description (any namespace's) is its model, not a String to show
        (shown if info.msgtype in DECODERS or info.msgtype == GRID_UPDATE else other)[topic] = info.msgtype
    return shown, other


IMAGES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")


def camera_images(topics: Mapping[str, str]) -> dict[str, tuple[str, ...]]:
    """Each CameraInfo topic's image topics: those under its namespace (``/cam/camera_info`` →
    ``/cam/image_raw``, ``/cam/image_raw/compressed``), as RViz's Camera display pairs them."""
    out = {}
    for info, msgtype in topics.items():
        if msgtype != "sensor_msgs/msg/CameraInfo":
            continue
        namespace = info.rsplit("/", 1)[0] + "/"
        images = tuple(t for t, m in sorted(topics.items()) if m in IMAGES and t.startswith(namespace))
        if images:
            out[info] = images
    return out


DETECTIONS_2D = "vision_msgs/msg/Detection2DArray"


def detection_images(topics: Mapping[str, str]) -> dict[str, str]:
    """Each Detection2DArray topic's image: the first image topic under its namespace (``/cam/detections`` →
    ``/cam/image_raw``; a namespace up when there is none: ``/cam/yolo/detections`` → ``/cam/image_raw``), one
    with a CameraInfo (:func:`camera_images`) first, then the shallowest. Its boxes are drawn on that image."""
    with_camera = {t for images in camera_images(topics).values() for t in images}
    out = {}
    for topic, msgtype in topics.items():
        namespace = topic.rsplit("/", 1)[0]
        while msgtype == DETECTIONS_2D and topic not in out:
            found = sorted(
                (t not in with_camera, t.count("/"), t)
                for t, m in topics.items()
                if m in IMAGES and t.startswith(namespace + "/")
            )
            if found:
                out[topic] = found[0][2]
            elif not namespace:
                break
            namespace = namespace.rsplit("/", 1)[0]
    return out


def frames_of(messages: Iterable[TopicMessage]) -> set[str]:
    """The frames these display messages are drawn in (empty ids and undecodable messages left out)."""
    frames: set[str] = set()
    for message in messages:
        try:
            decoded = decode(message.msgtype, message.data)
        except MsgError:
            continue
        parts = [decoded] if isinstance(decoded, Decoded) else [op.decoded for op in decoded if op.decoded]
        frames.update(d.frame_id for d in parts if d.frame_id)
    return frames


def first_messages(
    bag: Bag, shown: dict[str, str], start: int, stop: int, wanted: int, max_bytes: int = 64 << 20
) -> tuple[TopicMessage, ...]:
    """The first ``wanted`` messages of the display topics ``shown`` that draw in 3D (:func:`in_3d`) in ``[start,
    stop)``, reading no more than about ``max_bytes`` of them (a bag whose displays start late: what the view is
    fitted to)."""
    found: list[TopicMessage] = []
    seen = 0
    drawn = tuple(topic for topic, msgtype in shown.items() if in_3d(msgtype))
    for block in bag.blocks(drawn, start_ns=start, stop_ns=stop) if drawn else ():
        for t, topic, data in block.messages():
            found.append(TopicMessage(t, topic, shown[topic], bytes(data)))
            if len(found) >= wanted:
                return tuple(found)
        seen += block.nbytes
        if seen > max_bytes:
            break
    return tuple(found)


def _video_sample(msgtype: str, data: bytes | memoryview) -> VideoSample | None:
    try:
        decoded = decode(msgtype, data)
    except MsgError:
        return None
    item = decoded.items[0] if isinstance(decoded, Decoded) and decoded.items else None
    return item if isinstance(item, VideoSample) else None


def _keyframe(msgtype: str, data: bytes | memoryview) -> bool:
    sample = _video_sample(msgtype, data)
    return sample is not None and sample.keyframe


def video_preroll(bag: Bag, shown: dict[str, str], start_ns: int) -> tuple[TopicMessage, ...]:
    """For a seek to ``start_ns``: each passed-through video topic's samples from its last keyframe before the
    seek (found by parsing the samples' bitstreams, up to :data:`KEYFRAME_SEARCH_NS` back) up to the seek, at their
    own times — without them the frames after the seek cannot be decoded until the next keyframe."""
    first = bag.span[0] if bag.span is not None else start_ns
    out: list[TopicMessage] = []
    for topic, msgtype in shown.items():
        last = bag.last(topic, before_ns=start_ns) if msgtype in VIDEO_TYPES else None
        if last is None or _video_sample(msgtype, last[1]) is None:  # no video there (JPEG images, say)
            continue
        back, key = 2 * 1_000_000_000, None
        while key is None:
            low = max(first, start_ns - back)
            for block in bag.blocks([topic], start_ns=low, stop_ns=start_ns):
                key = next((t for t, data in reversed(block.pairs()) if _keyframe(msgtype, data)), key)
            if low == first or back >= KEYFRAME_SEARCH_NS:
                break
            back *= 2
        if key is not None:
            for block in bag.blocks([topic], start_ns=key, stop_ns=start_ns):
                out += [TopicMessage(t, topic, msgtype, bytes(data)) for t, data in block.pairs()]
    return tuple(sorted(out, key=lambda m: m.time_ns))
