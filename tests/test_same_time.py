"""Joint states that share a receive time (a real PR2 ROS 1 bag has 552 of 1,598 such): the robot, its transforms
and its plots at that time all come from one message, the last one in the file, as if each had been applied in
turn (a joint the last one leaves out keeps the value the one before it gave). Bags written by rosbags; the
recording read back with Rerun's reader (tests/rrd.py); the golden poses from yourdfpy's forward kinematics of
the values written, picked by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from bagmaker import T0, BagSpec, joint_state, string, write_bag
from conftest import cli
from rrd import frame_edges_at, pose_in, read_recording

MS = 1_000_000
N = 30


def _bag(tmp_path: Path, urdf: Path, storage: str) -> tuple[Path, dict[int, dict[str, float]]]:
    """Pairs of joint states received at one time: the first gives every joint, the second (later in the file)
    tilt and swivel only. Returns each receive time → the joint values applying both in turn leaves."""
    spec = BagSpec().add("/robot_description", T0, string(urdf.read_text()))
    expected: dict[int, dict[str, float]] = {}
    for k in range(N):
        t = T0 + (k + 1) * 10 * MS
        first = {"tilt": -0.01 * k, "swivel": 0.1 * k, "periscope": -0.005 * k}
        second = {"tilt": -0.01 * k - 0.2, "swivel": 0.1 * k + 1.0}
        spec.add("/joint_states", t, joint_state(t, list(first), list(first.values())))
        spec.add("/joint_states", t, joint_state(t + MS, list(second), list(second.values())))
        expected[t] = {**first, **second}
    return write_bag(tmp_path / storage, spec, storage=storage), expected


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_the_robot_and_its_plots_at_a_shared_time_come_from_the_last_message(
    tmp_path: Path, tutorial_urdf: Path, storage: str
) -> None:
    bag, expected = _bag(tmp_path, tutorial_urdf, storage)
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--urdf", str(tutorial_urdf), "--save", str(out))
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    urdf = yourdfpy.URDF.load(str(tutorial_urdf), load_meshes=False)
    plots = {
        entity: (recording[entity].static["SeriesLines:names"][-1], recording[entity])
        for entity in ("/joints/limited", "/joints/continuous")
    }
    for t, values in expected.items():
        # every plot row at that time holds the last message's values (one row: one message)
        for names, rows in plots.values():
            at = [i for i, time in enumerate(rows.times) if time == t]
            assert len(at) == 1, (t, names)
            got = dict(zip(names, rows.temporal["Scalars:scalars"][at[0]], strict=True))
            assert got == pytest.approx({n: values[n] for n in names}, abs=1e-12)
        # the robot as a viewer resolves its frames at that time: the same values, through yourdfpy
        edges = frame_edges_at(recording, t)
        urdf.update_cfg(values)
        for link in ("body", "head", "rod", "box"):
            want = urdf.get_transform(frame_to=link, frame_from="axis")
            got_T = pose_in(edges, link, "axis")
            np.testing.assert_allclose(got_T, want, atol=1e-6, err_msg=f"{link} at {t}")
