"""The display feed's blocks (issue 46): which runs take a topic's messages as a block, and a block logged in
the stretches :meth:`until` asks for is the same recording as logged at once."""

from __future__ import annotations

from typing import Any

import numpy as np
import rerun as rr
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.viewer.display_feed import DisplayFeed, DisplayStyle
from r2d2_viz.viewer.notices import Notices

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types
IMU, LOG = "sensor_msgs/msg/Imu", "rcl_interfaces/msg/Log"
T0 = 1_700_000_000 * 1_000_000_000


def _imu(rng: np.random.Generator, t_ns: int, frame: str) -> Any:
    v3, quat = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(t_ns, 1_000_000_000)), frame)
    cov = rng.normal(size=9)
    return T[IMU](header, quat(*rng.normal(size=4)), cov, v3(*rng.normal(size=3)), cov, v3(*rng.normal(size=3)), cov)


def _feed(**kwargs: Any) -> DisplayFeed:
    return DisplayFeed(Notices(rr.RecordingStream("blocks")), clock="timestamp", fixed_frame="odom", **kwargs)


def test_only_a_plain_batch_run_takes_blocks() -> None:
    """A batch run (``hold``) without decay or header time: blocks; a live run, ``--time header``, a decayed display,
    an empty frame id, one message alone or a type without a block decoder: one by one."""
    rng = np.random.default_rng(3)
    data = [bytes(STORE.serialize_cdr(_imu(rng, T0 + k, "imu_link"), IMU)) for k in range(3)]
    bare = [bytes(STORE.serialize_cdr(_imu(rng, T0 + k, ""), IMU)) for k in range(3)]
    times = np.arange(3, dtype=np.int64) + T0

    block = _feed(hold=True).decode_block("/imu", IMU, times, data)
    assert block is not None and len(block) == 3 and block.times_ns.tolist() == times.tolist()
    assert _feed(hold=True).decode_block("/imu", IMU, times, bare) is None
    assert _feed(hold=True).decode_block("/imu", IMU, times[:1], data[:1]) is None
    assert _feed(hold=True).decode_block("/rosout", LOG, times, data) is None
    assert _feed(hold=False).decode_block("/imu", IMU, times, data) is None
    assert _feed(hold=True, header_time=True).decode_block("/imu", IMU, times, data) is None
    decayed = {"/imu": DisplayStyle(decay=True)}
    assert _feed(hold=True, styles=decayed).decode_block("/imu", IMU, times, data) is None


def test_a_block_is_logged_as_far_as_until_asks() -> None:
    """Stretches of a block (receive times inclusive) count its messages and leave the rest pending."""
    rng = np.random.default_rng(5)
    data = [bytes(STORE.serialize_cdr(_imu(rng, T0 + k, "imu_link"), IMU)) for k in range(6)]
    feed = _feed(hold=True, topics={"/imu": IMU})
    block = feed.decode_block("/imu", IMU, np.arange(6, dtype=np.int64) * 10 + T0, data)
    assert block is not None
    feed.push([], [block])
    assert feed.next_time_ns == T0
    feed.until(T0 + 20)
    assert feed.topics["/imu"].messages == 3 and feed.next_time_ns == T0 + 30
    assert feed.rows.now == T0 + 20  # the recording's time where its last message logged left it
    assert feed.block_runs.runs["/imu/angular_velocity"].rows == 3  # held, not sent yet
    feed.until(None)
    assert feed.topics["/imu"].messages == 6 and feed.next_time_ns is None and not feed.block_runs.runs
