"""Several robots in one bag, one of each convention: (A) ``/robot1/robot_description`` with its frames prefixed on the
shared ``/tf`` (robot_state_publisher's ``frame_prefix``), (B) ``/robot2/robot_description`` with its own ``/robot2/tf``
and ``/robot2/tf_static`` and bare frames. Bags written by rosbags (tests/bagmaker.py), replayed by the real CLI, link
poses read back from the recording and checked against yourdfpy's forward kinematics of each robot's own joint
states (an independent library); plus the pure helpers of :mod:`r2d2_viz.sources.robots`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from bagmaker import T0, TYPES, BagSpec, joint_state, string, tf_message, write_bag
from conftest import REPO, cli
from rrd import frame_edges_at, pose_in, read_recording

from r2d2_viz.robot.model import parse_urdf
from r2d2_viz.sources.base import TfRecords
from r2d2_viz.sources.robots import (
    choose_prefix,
    description_namespaces,
    prefixed_robot,
    renamed,
)

ARM = REPO / "examples" / "arm6.urdf"
# robot2 is another arm: a longer upper arm, so each robot must be drawn from its own description
ARM2_TEXT = ARM.read_text().replace(
    '<child link="forearm"/><origin xyz="0 0 0.4"/>', '<child link="forearm"/><origin xyz="0 0 0.55"/>'
)
JOINTS = ("base_yaw", "shoulder_pitch", "elbow", "wrist_pitch", "wrist_roll", "tool_slide")
MS = 1_000_000
ID = (0, 0, 0, 1)


def _two_robot_bag(path: Path, *, n: int = 40, third: bool = False) -> dict[str, list[tuple[int, dict[str, float]]]]:
    """robot1 (A): base at x = 1 + 0.01 k in map on /tf as ``map → robot1/base_link``, and the fixed
    ``robot1/base_link → robot1/shoulder`` its robot_state_publisher would publish; robot2 (B): ``map → odom`` on
    /robot2/tf_static, ``odom → base_link`` at y = -1 - 0.02 k on /robot2/tf. Each at 50 Hz, its own joint
    states."""
    assert ARM2_TEXT != ARM.read_text()
    spec = BagSpec(types={**TYPES})
    for ns in ("/robot1", "/robot2", "/robot3"):
        spec.types[f"{ns}/robot_description"] = TYPES["/robot_description"]
        spec.types[f"{ns}/joint_states"] = TYPES["/joint_states"]
    spec.types["/robot2/tf"] = spec.types["/robot2/tf_static"] = TYPES["/tf"]
    spec.add("/robot1/robot_description", T0, string(ARM.read_text()))
    spec.add("/robot2/robot_description", T0, string(ARM2_TEXT))
    if third:  # a robot nothing places
        spec.add("/robot3/robot_description", T0, string(ARM.read_text()))
    spec.add("/robot2/tf_static", T0, tf_message([(T0, "map", "odom", (0, 0, 0), ID)]))
    rng = np.random.default_rng(7)
    states: dict[str, list[tuple[int, dict[str, float]]]] = {"robot1": [], "robot2": []}
    for k in range(n):
        t = T0 + (k + 1) * 20 * MS
        yaw = 0.0
        for ns in ("robot1", "robot2"):
            q = rng.uniform(-1, 1, len(JOINTS))
            q[-1] = 0.02 * (k % 3)
            ts = t + (MS if ns == "robot2" else 0)
            spec.add(f"/{ns}/joint_states", ts, joint_state(ts, JOINTS, q))
            states[ns].append((ts, dict(zip(JOINTS, q, strict=True))))
            yaw = q[0] if ns == "robot1" else yaw
        spec.add(
            "/tf",
            t,
            tf_message(
                [
                    (t, "map", "robot1/base_link", (1 + 0.01 * k, 0, 0), ID),
                    # as robot1's robot_state_publisher says it (base_yaw about z, 0.1 m up): drawn by the kinematics
                    (t, "robot1/base_link", "robot1/shoulder", (0, 0, 0.1), (0, 0, np.sin(yaw / 2), np.cos(yaw / 2))),
                ]
            ),
        )
        spec.add("/robot2/tf", t, tf_message([(t, "odom", "base_link", (0, -1 - 0.02 * k, 0), ID)]))
    write_bag(path, spec)
    return states


def test_two_robots_of_both_conventions_stand_in_one_view(tmp_path: Path) -> None:
    bag = tmp_path / "two_robots"
    states = _two_robot_bag(bag)
    out = tmp_path / "two.rrd"
    result = cli("--bag", str(bag), "--save", str(out))
    assert result.returncode == 0, result.stderr
    assert "no /robot_description" not in result.stderr and "disagrees" not in result.stderr, result.stderr
    recording = read_recording(out)
    worst = {}
    for ns, text, base in (
        ("robot1", ARM.read_text(), lambda k: (1 + 0.01 * k, 0.0)),
        ("robot2", ARM2_TEXT, lambda k: (0.0, -1 - 0.02 * k)),
    ):
        urdf_file = tmp_path / f"{ns}.urdf"
        urdf_file.write_text(text)
        urdf = yourdfpy.URDF.load(str(urdf_file), load_meshes=False)
        held = dict.fromkeys(JOINTS, 0.0)
        worst[ns] = 0.0
        for i, (t, values) in enumerate(states[ns]):
            held.update(values)
            urdf.update_cfg(held)
            edges = frame_edges_at(recording, t)
            T_map_base = np.eye(4)
            T_map_base[:2, 3] = base(i)  # the latest base transform: sent at T0 + (i + 1) · 20 ms
            for link in ("shoulder", "forearm", "tool"):
                expected = T_map_base @ urdf.get_transform(frame_to=link, frame_from="base_link")
                got = pose_in(edges, f"{ns}/{link}", "map")
                worst[ns] = max(worst[ns], float(np.abs(got - expected).max()))
    assert worst["robot1"] < 1e-5 and worst["robot2"] < 1e-5, worst
    # both robots' shapes, each under its namespace; the shared frame stays bare, robot2's frames are prefixed
    assert "/robots/robot1/visual/forearm/0" in recording and "/robots/robot2/visual/forearm/0" in recording
    assert "/joints/robot1/limited" in recording and "/joints/robot2/limited" in recording
    assert "/tf_axes/robot2\\/odom" in recording and "/tf_axes/map" in recording
    assert "/tf_axes/odom" not in recording and "/robot/visual/forearm/0" not in recording
    # the robots' own topics are read by the robot pipeline, not left to Rerun's MCAP decoders
    assert not [k for k in recording if k.startswith(("/robot1/", "/robot2/"))]


def test_a_robot_that_does_not_reach_the_fixed_frame_is_named_once(tmp_path: Path) -> None:
    bag = tmp_path / "three_robots"
    _two_robot_bag(bag, n=5, third=True)
    result = cli("--bag", str(bag), "--save", str(tmp_path / "three.rrd"))
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if "robot /robot3" in line]
    assert len(lines) == 1 and "'robot3/base_link'" in lines[0] and "'map'" in lines[0], result.stderr
    assert "robot /robot1" not in result.stderr and "robot /robot2" not in result.stderr


def test_description_namespaces() -> None:
    topics = ["/robot_description", "/a/robot_description", "/a/joint_states", "/b/c/robot_description", "/tf"]
    assert description_namespaces(topics) == ["", "/a", "/b/c"]


def test_renamed_prefixes_all_but_the_shared_frames() -> None:
    records = TfRecords(
        np.zeros(3, dtype=np.int64),
        ("map", "odom", "/base_link"),
        ("odom", "base_link", "r2/laser"),
        np.zeros((3, 3)),
        np.tile([0.0, 0, 0, 1], (3, 1)),
    )
    out = renamed(records, "r2/", ("map",))
    assert out.parents == ("map", "r2/odom", "r2/base_link")
    assert out.children == ("r2/odom", "r2/base_link", "r2/laser")
    assert renamed(records, "", ("map",)) is records


@pytest.mark.parametrize(
    ("namespace", "own_tf", "frames", "several", "expected"),
    [
        ("", False, {"base_link"}, True, ""),  # the root namespace: bare
        ("/r1", False, {"map", "r1/base_link"}, True, "r1/"),  # (A) prefixed on /tf
        ("/r2", True, {"map"}, True, "r2/"),  # (B) its own TF topics
        ("/r1", False, {"odom", "base_link"}, False, ""),  # a lone robot, only its description namespaced
        ("/r1", False, {"odom", "base_link"}, True, "r1/"),  # never two robots on one name
        ("/r1", False, set(), False, "r1/"),  # nothing places it: prefixed anyway
    ],
)
def test_choose_prefix(namespace: str, own_tf: bool, frames: set[str], several: bool, expected: str) -> None:
    assert choose_prefix(namespace, "base_link", own_tf=own_tf, frames=frames, several=several) == expected


def test_prefixed_robot_renames_links_not_joints() -> None:
    robot = parse_urdf(ARM.read_text())
    renamed_robot = prefixed_robot(robot, "r1/")
    assert renamed_robot.root == "r1/base_link"
    assert [link.name for link in renamed_robot.links] == [f"r1/{link.name}" for link in robot.links]
    assert [j.name for j in renamed_robot.joints] == [j.name for j in robot.joints]
    assert renamed_robot.joint("elbow").parent == "r1/upper_arm"
    assert prefixed_robot(robot, "") is robot


def test_shared_frames_are_configurable(tmp_path: Path) -> None:
    bag = tmp_path / "two_robots"
    _two_robot_bag(bag, n=5)
    out = tmp_path / "two.rrd"
    # with only `world` shared, robot2's `map` is its own (robot2/map): its tree no longer reaches robot1's map
    result = cli("--bag", str(bag), "--save", str(out), "--shared-frames", "world", "--fixed-frame", "map")
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if "robot /robot2" in line]
    assert len(lines) == 1 and "'robot2/map'" in lines[0], result.stderr
    assert "robot /robot1" not in result.stderr
    recording = read_recording(out)
    assert "/tf_axes/robot2\\/map" in recording
    bad = cli("--bag", str(bag), "--save", str(out), "--shared-frames", " , ")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--shared-frames" in bad.stderr


RVIZ_TWO_ROBOTS = """Visualization Manager:
  Displays:
    - Class: rviz_default_plugins/RobotModel
      Name: robot1
      Enabled: true
      Collision Enabled: true
      Description Topic:
        Depth: 5
        Value: /robot1/robot_description
      TF Prefix: robot1
      Links:
        tool:
          Value: false
    - Class: rviz_default_plugins/RobotModel
      Name: robot2
      Enabled: false
      Description Topic:
        Value: /robot2/robot_description
      TF Prefix: robot_two
  Global Options:
    Fixed Frame: map
"""


def test_rviz_robot_model_displays_map_to_their_robots(tmp_path: Path) -> None:
    from rrd import blueprint_components

    bag = tmp_path / "two_robots"
    _two_robot_bag(bag, n=5)
    rviz = tmp_path / "two.rviz"
    rviz.write_text(RVIZ_TWO_ROBOTS)
    out = tmp_path / "two.rrd"
    result = cli("--bag", str(bag), "--save", str(out), "--rviz", str(rviz))
    assert result.returncode == 0, result.stderr
    # robot2's display names TF Prefix robot_two; its frames carry robot2/: said once
    assert result.stderr.count("TF Prefix 'robot_two'") == 1, result.stderr
    hidden = {
        key.split("/ViewContents/overrides", 1)[1].removesuffix("/visualizers")
        for key, values in blueprint_components(out).items()
        if "/ViewContents/overrides/" in key and values.get("EntityBehavior:visible") == [False]
    }
    # robot1: collision shown, its tool unticked; robot2: its display is disabled
    assert "/robots/robot1/visual/tool" in hidden and "/robots/robot2" in hidden
    assert "/robots/robot1/collision" not in hidden and "/robots/robot1" not in hidden


@pytest.mark.slow
def test_two_live_robots_of_both_conventions(tmp_path: Path) -> None:
    """Two real Kilted rclpy nodes, ``/robot1/…`` and ``/robot2/…`` (positions shifted by 0.5), robot1's base on /tf
    with prefixed frames, robot2's on /robot2/tf with bare ones (cyclonedds peers), robot3 with no TF (one line);
    ``--ros --save`` a late joiner.
    Link poses at recorded header stamps against yourdfpy's FK of what each node published."""
    import json
    import sys

    from rrd import tf_by_child
    from sources.live import ros_node
    from sources.live.nodes.publish_robot import joint_names, joint_state_values

    python = ros_node.require_live("kilted")
    urdfs = [tmp_path / "robot1.urdf", tmp_path / "robot2.urdf", tmp_path / "robot3.urdf"]
    urdfs[0].write_text(ARM.read_text())
    urdfs[1].write_text(ARM2_TEXT)
    urdfs[2].write_text(ARM.read_text())  # robot3: no transform places it
    out = tmp_path / "live.rrd"
    script = Path(ros_node.__file__).with_name("robots_scenario.py")
    exe = Path(sys.executable).parent / "r2d2-viz"
    run = ["--save", str(out), "--duration", "9", "--time", "header"]
    command = [sys.executable, str(script), "--ros-python", str(python), "--urdf", *map(str, urdfs), "--cli", str(exe)]
    done = ros_node.in_netns([*command, "--run", json.dumps(run)], timeout=150)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["rc"] == 0, result["stderr"][-3000:]
    # robot1's and robot2's trees reach map; robot3's is one line
    lines = [line for line in result["stderr"].splitlines() if "robot /robot" in line]
    assert len(lines) == 1 and "robot /robot3" in lines[0] and "'robot3/base_link'" in lines[0], result["stderr"]
    recording = read_recording(out)
    for ns, urdf_file, shift, base in (("robot1", urdfs[0], 0.0, (1.0, 0.0)), ("robot2", urdfs[1], 0.5, (0.0, -1.0))):
        names = joint_names(urdf_file.read_text(), 0)
        urdf = yourdfpy.URDF.load(str(urdf_file), load_meshes=False)
        times = sorted(t for t in set(tf_by_child(recording)[f"{ns}/shoulder"].times) if t >= 1000 * 10**9)
        assert len(times) >= 0.9 * 150, (ns, len(times))
        for t in (times[0], times[len(times) // 2], times[-1]):
            k = (t - 1000 * 10**9) // 1_000_000
            _, _, position, _ = joint_state_values(int(k), len(names), shift)
            urdf.update_cfg(dict(zip(names, position, strict=True)))
            T_map_base = np.eye(4)
            T_map_base[:2, 3] = base
            edges = frame_edges_at(recording, t)
            for link in ("forearm", "tool"):
                expected = T_map_base @ urdf.get_transform(frame_to=link, frame_from="base_link")
                np.testing.assert_allclose(pose_in(edges, f"{ns}/{link}", "map"), expected, atol=2e-6)
    assert "/robots/robot1/visual/forearm/0" in recording and "/robots/robot2/visual/forearm/0" in recording
