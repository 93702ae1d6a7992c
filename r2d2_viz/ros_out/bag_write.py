"""Write a run as a ROS 2 bag: a rosbag2 directory (MCAP storage and ``metadata.yaml``, written by ``rosbags``)
that ``rosbags`` and ``ros2 bag info`` / ``ros2 bag play`` read, with the topics a robot_state_publisher setup
records: ``/joint_states`` and ``/tf`` at every sample, ``/tf_static`` and ``/robot_description`` once (both
offered transient-local, as robot_state_publisher does). Header stamps are the recording times.

Messages are built in bulk: one message serialized by ``rosbags`` is the template of all that share its names
(:mod:`r2d2_viz.msgs.layouts` says where the stamps and numbers go), and numpy fills in the rest.

Atomic: the bag is written into a temporary directory beside the target and renamed when complete; on any
failure it is removed and an existing bag at the target is left as it was. Pure: no rerun import.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType
from typing import Literal, NamedTuple, Protocol

import numpy as np
import numpy.typing as npt
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag2 import StoragePlugin, Writer, WriterError

from r2d2_viz.arrays import F64
from r2d2_viz.errors import BagError
from r2d2_viz.msgs.layouts import joint_state_layout, tf_layout
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.sources.base import Clock

JOINT_STATE = "sensor_msgs/msg/JointState"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
STRING = "std_msgs/msg/String"


def qos_profile(depth: int, durability: QosDurability) -> Qos:
    zero = QosTime(0, 0)
    return Qos(
        QosHistory.KEEP_LAST,
        depth,
        QosReliability.RELIABLE,
        durability,
        zero,
        zero,
        QosLiveliness.AUTOMATIC,
        zero,
        False,
    )


LATCHED = qos_profile(1, QosDurability.TRANSIENT_LOCAL)
"""What robot_state_publisher offers on /robot_description and /tf_static: reliable, transient local, depth 1."""
STREAM = {"/joint_states": qos_profile(10, QosDurability.VOLATILE), "/tf": qos_profile(100, QosDurability.VOLATILE)}


class StaticTransform(NamedTuple):
    parent: str
    child: str
    translation: Sequence[float]  # (3,)  T_parent_child
    quat_xyzw: Sequence[float]  # (4,)


class Track(Protocol):
    """A moving named-frame edge (:class:`r2d2_viz.sources.base.FrameTrack` is one)."""

    @property
    def parent(self) -> str: ...
    @property
    def child(self) -> str: ...
    @property
    def translation(self) -> F64: ...  # (n, 3)
    @property
    def quat_xyzw(self) -> F64: ...  # (n, 4)


def _stamps(times_ns: npt.NDArray[np.int64]) -> npt.NDArray[np.uint8]:
    sec, nsec = np.divmod(times_ns, 1_000_000_000)
    out = np.empty((len(times_ns), 2), dtype="<i4")
    out[:, 0], out[:, 1] = sec, nsec
    return out.view(np.uint8).reshape(len(times_ns), 8)


def _doubles(values: F64) -> npt.NDArray[np.uint8]:
    v = np.ascontiguousarray(values, dtype="<f8")
    return v.view(np.uint8).reshape(len(v), -1)


class BagWriter:
    """Use as a context manager: the bag appears at ``path`` when the block ends without an exception."""

    def __init__(
        self,
        path: str | Path,
        *,
        robot_description: str,
        static_transforms: Sequence[StaticTransform] = (),
        clock: Clock = "timestamp",
        start_ns: int | None = None,
        version: Literal[8, 9] = 8,
    ) -> None:
        self.path = Path(path)
        self.clock = clock
        self.start_ns = (time.time_ns() if start_ns is None else start_ns) if clock == "duration" else 0
        self._description, self._static = robot_description, tuple(static_transforms)
        if self.path.exists() and not (self.path.is_dir() and (self.path / "metadata.yaml").is_file()):
            raise BagError(f"{self.path}: exists and is not a rosbag2 directory; not overwriting it")
        if not self.path.parent.is_dir():
            raise BagError(f"{self.path}: directory {self.path.parent} does not exist")
        try:
            self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.", dir=self.path.parent))
            name = self.path.name[: -len(".mcap")] if self.path.name.endswith(".mcap") else self.path.name
            self._writer = Writer(self._tmp / (name or "bag"), version=version, storage_plugin=StoragePlugin.MCAP)
            self._writer.set_custom_data("recorded_by", "r2d2-viz")
            self._writer.open()
            add = self._writer.add_connection
            ts = typestore()
            self._conn = {
                "/robot_description": add("/robot_description", STRING, typestore=ts, offered_qos_profiles=[LATCHED]),
                "/tf_static": add("/tf_static", TF_MESSAGE, typestore=ts, offered_qos_profiles=[LATCHED]),
                "/joint_states": add(
                    "/joint_states", JOINT_STATE, typestore=ts, offered_qos_profiles=[STREAM["/joint_states"]]
                ),
                "/tf": add("/tf", TF_MESSAGE, typestore=ts, offered_qos_profiles=[STREAM["/tf"]]),
            }
        except OSError as exc:
            self.abort()
            raise BagError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
        self._started = False
        self._templates: dict[tuple[str, ...], tuple[npt.NDArray[np.uint8], int]] = {}
        self.samples = 0

    def _bag_times(self, times_ns: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
        return np.asarray(times_ns, dtype=np.int64) + self.start_ns

    def _start(self, first_ns: int) -> None:
        ts, self._started = typestore(), True
        description = ts.types[STRING](self._description)
        self._write("/robot_description", [first_ns], [bytes(ts.serialize_cdr(description, STRING))])
        if self._static:
            items = [(first_ns, s.parent, s.child, s.translation, s.quat_xyzw) for s in self._static]
            self._write("/tf_static", [first_ns], [_tf_message(items)])

    def write_samples(
        self,
        times_ns: npt.NDArray[np.int64],
        joint_names: Sequence[str],
        positions: F64,
        frames: Sequence[Track] = (),
    ) -> None:
        """Samples on the writer's clock: a JointState per sample (naming the joints whose position is not
        NaN) and, with ``frames``, a TFMessage per sample holding one transform per track."""
        n = len(times_ns)
        positions = np.asarray(positions, dtype=np.float64).reshape(n, len(joint_names))
        if n == 0:
            return
        t = self._bag_times(times_ns)
        if not self._started:
            self._start(int(t[0]))
        messages = np.empty(n, dtype=object)
        given = ~np.isnan(positions)
        patterns, which = np.unique(given, axis=0, return_inverse=True)
        for k, pattern in enumerate(patterns):
            rows = np.flatnonzero(which.reshape(-1) == k)
            names = tuple(name for name, g in zip(joint_names, pattern, strict=True) if g)
            template, offset = self._joint_template(names)
            buf = np.repeat(template[None, :], len(rows), axis=0)
            buf[:, 4:12] = _stamps(t[rows])
            buf[:, offset : offset + 8 * len(names)] = _doubles(positions[np.ix_(rows, np.flatnonzero(pattern))])
            messages[rows] = [row.tobytes() for row in buf]
        self._write("/joint_states", t, messages.tolist())
        if frames:
            self._write("/tf", t, _tf_messages(t, frames))
        self.samples += n

    def _joint_template(self, names: tuple[str, ...]) -> tuple[npt.NDArray[np.uint8], int]:
        if names not in self._templates:
            ts = typestore()
            msg = ts.types[JOINT_STATE](
                ts.types["std_msgs/msg/Header"](ts.types["builtin_interfaces/msg/Time"](0, 0), ""),
                list(names),
                np.zeros(len(names)),
                np.zeros(0),
                np.zeros(0),
            )
            data = bytes(ts.serialize_cdr(msg, JOINT_STATE))
            self._templates[names] = (np.frombuffer(data, dtype=np.uint8), joint_state_layout(data).positions)
        return self._templates[names]

    def _write(self, topic: str, times: Sequence[int] | npt.NDArray[np.int64], messages: Sequence[bytes]) -> None:
        conn, write = self._conn[topic], self._writer.write
        try:
            for t, data in zip(np.asarray(times).tolist(), messages, strict=True):
                write(conn, t, data)
        except OSError as exc:
            self.abort()
            raise BagError(f"{self.path}: cannot write: {exc.strerror or exc}") from None

    def close(self) -> Path:
        """Finish the bag and move it to ``path`` (replacing a bag there); returns ``path``."""
        try:
            if not self._started:
                self._start(self.start_ns or time.time_ns())
            self._writer.close()
            bag_dir = next(p for p in self._tmp.iterdir() if p.is_dir())
            move_into_place(bag_dir, self.path, aside=self._tmp / "replaced")
        except (OSError, WriterError) as exc:
            self.abort()
            raise BagError(f"{self.path}: not saved: {cause(exc)}") from None
        shutil.rmtree(self._tmp, ignore_errors=True)
        return self.path

    def abort(self) -> None:
        """Drop everything written; the target is untouched."""
        writer = getattr(self, "_writer", None)
        try:
            if writer is not None:
                writer.abort()  # rosbags closes the file again: on a full disk that raises again
        except (OSError, WriterError):
            pass  # the error being handled says more; the temporary bag goes all the same
        finally:
            tmp = getattr(self, "_tmp", None)
            if tmp is not None:
                shutil.rmtree(tmp, ignore_errors=True)

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


def move_into_place(bag_dir: Path, path: Path, *, aside: Path) -> None:
    """``bag_dir`` renamed to ``path``; a bag already there is moved ``aside`` first, and back if the new one
    cannot take its place."""
    if not path.exists():
        os.replace(bag_dir, path)
        return
    os.replace(path, aside)
    try:
        os.replace(bag_dir, path)
    except OSError:
        os.replace(aside, path)
        raise


MARKS = ("recorded_by", "converted_by")
"""The custom data every bag r2d2-viz writes carries (``r2d2-viz`` or ``r2d2-viz --ros``) in its metadata."""


def written_by_us(path: Path) -> bool:
    """Whether ``path`` is a rosbag2 bag that r2d2-viz wrote (``--save X.mcap`` run again replaces it)."""
    try:
        text = (path / "metadata.yaml").read_text(errors="replace")
    except OSError:
        return False
    return any(re.search(rf"^\s+{mark}:\s*['\"]?r2d2-viz", text, re.MULTILINE) for mark in MARKS)


def cause(exc: BaseException) -> str:
    """What the file system said ("no space left on device"), found under rosbags' own errors."""
    seen: BaseException | None = exc
    while seen is not None:
        if isinstance(seen, OSError) and seen.strerror:
            return seen.strerror.lower()
        seen = seen.__cause__ or seen.__context__
    return str(exc) or type(exc).__name__


def _tf_message(items: Sequence[tuple[int, str, str, Sequence[float], Sequence[float]]]) -> bytes:
    ts = typestore()
    T = ts.types
    transforms = [
        T["geometry_msgs/msg/TransformStamped"](
            T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(int(t), 1_000_000_000)), parent),
            child,
            T["geometry_msgs/msg/Transform"](
                T["geometry_msgs/msg/Vector3"](*map(float, xyz)), T["geometry_msgs/msg/Quaternion"](*map(float, q))
            ),
        )
        for t, parent, child, xyz, q in items
    ]
    return bytes(ts.serialize_cdr(T[TF_MESSAGE](transforms), TF_MESSAGE))


def _tf_messages(t: npt.NDArray[np.int64], frames: Sequence[Track]) -> list[bytes]:
    """One TFMessage per sample, built from a template."""
    template = _tf_message([(0, f.parent, f.child, (0, 0, 0), (0, 0, 0, 1)) for f in frames])
    layout = tf_layout(template)
    buf = np.repeat(np.frombuffer(template, dtype=np.uint8)[None, :], len(t), axis=0)
    stamps = _stamps(t)
    for f, stamp, offset in zip(frames, layout.stamps, layout.translations, strict=True):
        buf[:, stamp : stamp + 8] = stamps
        buf[:, offset : offset + 56] = _doubles(np.hstack([f.translation, f.quat_xyzw]))
    return [row.tobytes() for row in buf]
