"""``r2d2-viz --ros --save out.mcap``: ``ros2 bag record`` without ROS — every message received from a live graph,
its bytes as they came, written to a rosbag2 (MCAP storage, ``metadata.yaml``) with its topic's type and that type's
message definition (rosbags' typestore of the graph's distro). Latched topics are offered transient-local, as
their publishers do. The receive time of a message is its writer's source timestamp.

Atomic like :class:`~r2d2_viz.ros_out.bag_write.BagWriter`: written into a temporary directory beside the target,
renamed into place by :meth:`LiveBagRecorder.close`; :meth:`LiveBagRecorder.abort` removes it. Pure: no rerun.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from rosbags.interfaces import QosDurability
from rosbags.rosbag2 import StoragePlugin, Writer

from r2d2_viz.errors import BagError
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.ros_out.bag_write import LATCHED, STREAM, qos_profile
from r2d2_viz.sources.live.dds import LATCHED_BY_NAME, Sample

VOLATILE = qos_profile(10, QosDurability.VOLATILE)


class LiveBagRecorder:
    """Use as a context manager, or :meth:`write` then :meth:`close` (or :meth:`abort`)."""

    def __init__(self, path: str | Path, *, distro: str = "jazzy", latched: Iterable[str] = LATCHED_BY_NAME) -> None:
        self.path = Path(path)
        self.latched = set(latched)
        self._store = typestore(distro)
        if self.path.exists() and not (self.path.is_dir() and (self.path / "metadata.yaml").is_file()):
            raise BagError(f"{self.path}: exists and is not a rosbag2 directory; not overwriting it")
        self._tmp: Path | None = None
        try:
            self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.", dir=self.path.parent))
            name = self.path.name[: -len(".mcap")] if self.path.name.endswith(".mcap") else self.path.name
            self._writer = Writer(self._tmp / (name or "bag"), version=8, storage_plugin=StoragePlugin.MCAP)
            self._writer.set_custom_data("recorded_by", "r2d2-viz --ros")
            self._writer.open()
        except OSError as exc:
            self.abort()
            raise BagError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
        self._connections: dict[tuple[str, str], Any] = {}
        self.messages = 0

    def write(self, samples: Iterable[Sample]) -> None:
        """Append received samples (their CDR bytes unchanged)."""
        try:
            for s in samples:
                conn = self._connections.get((s.topic, s.ros_type))
                if conn is None:
                    conn = self._connect(s.topic, s.ros_type)
                self._writer.write(conn, s.source_timestamp_ns, s.data)
                self.messages += 1
        except OSError as exc:
            self.abort()
            raise BagError(f"{self.path}: cannot write: {exc.strerror or exc}") from None

    def _connect(self, topic: str, ros_type: str) -> Any:
        qos = LATCHED if topic in self.latched else STREAM.get(topic, VOLATILE)
        conn = self._writer.add_connection(topic, ros_type, typestore=self._store, offered_qos_profiles=[qos])
        self._connections[(topic, ros_type)] = conn
        return conn

    def close(self) -> Path:
        """Finish the bag and move it to ``path`` (replacing a bag there); returns ``path``."""
        assert self._tmp is not None
        try:
            self._writer.close()
            bag_dir = next(p for p in self._tmp.iterdir() if p.is_dir())
            if self.path.exists():
                shutil.rmtree(self.path)
            os.replace(bag_dir, self.path)
        except OSError as exc:
            raise BagError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
        finally:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None
        return self.path

    def abort(self) -> None:
        """Leave nothing behind (an existing bag at ``path`` stays as it was)."""
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    def __enter__(self) -> LiveBagRecorder:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *rest: object) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()
