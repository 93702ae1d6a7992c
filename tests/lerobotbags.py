"""Bags for the LeRobot export, written by ``rosbags``: a two-joint arm's ``/joint_states`` at 50 Hz (names in
the opposite order to its URDF's, published on ``/robot_description``), a command topic at 10 Hz
(``/arm_controller/joint_trajectory``, JointTrajectory, or ``/cmd_vel``, Twist), and a 320x240 rgb8 camera at 15 Hz
with texture, motion and noise (:class:`camerabag.Frames`). Each bag's motion differs by ``seed``.

``expected`` gives, from the messages as written (decoded back with rosbags' own deserializer), what the dataset's
frames must hold: the state and command held at each frame's time, the camera's image shown at it."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from bagmaker import T0, TS, BagSpec, Header, joint_state, stamp, string, write_bag
from camerabag import Frames, image

URDF = """<robot name="two_joint_arm">
  <link name="base"/><link name="upper"/><link name="lower"/><link name="tool"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="lower"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="tool_mount" type="fixed"><parent link="lower"/><child link="tool"/></joint>
</robot>"""
JOINTS_URDF_ORDER = ["shoulder", "elbow"]
WIDTH, HEIGHT = 320, 240
TYPES = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/robot_description": "std_msgs/msg/String",
    "/arm_controller/joint_trajectory": "trajectory_msgs/msg/JointTrajectory",
    "/cmd_vel": "geometry_msgs/msg/Twist",
    "/camera/image_raw": "sensor_msgs/msg/Image",
}
JointTrajectory = TS.types["trajectory_msgs/msg/JointTrajectory"]
JointTrajectoryPoint = TS.types["trajectory_msgs/msg/JointTrajectoryPoint"]
Duration = TS.types["builtin_interfaces/msg/Duration"]
Twist = TS.types["geometry_msgs/msg/Twist"]
Vector3 = TS.types["geometry_msgs/msg/Vector3"]


def trajectory(t: int, positions: list[float]) -> bytes:
    point = JointTrajectoryPoint(np.asarray(positions), np.zeros(0), np.zeros(0), np.zeros(0), Duration(0, 100_000_000))
    later = JointTrajectoryPoint(np.asarray(positions) + 5, np.zeros(0), np.zeros(0), np.zeros(0), Duration(1, 0))
    msg = JointTrajectory(Header(stamp(t), ""), list(JOINTS_URDF_ORDER), [point, later])
    return bytes(TS.serialize_cdr(msg, "trajectory_msgs/msg/JointTrajectory"))


def twist(vx: float, wz: float) -> bytes:
    return bytes(TS.serialize_cdr(Twist(Vector3(vx, 0.0, 0.0), Vector3(0.0, 0.0, wz)), "geometry_msgs/msg/Twist"))


@dataclass(frozen=True)
class ArmBag:
    path: Path
    seed: int
    seconds: float
    command: str


def write_arm_bag(
    path: Path, *, seed: int = 0, seconds: float = 2.0, command: str = "trajectory", camera: bool = True,
    joints: bool = True, camera_lag_ns: int = 0,
) -> ArmBag:  # fmt: skip
    """The bag (camera from 0.04 s, joint states from 0, commands from 0.02 s: the episode starts at 0.04 s; its
    frames every 1/30 s fall on a joint state every 0.1 s and on some images: "at or before" is tested).
    ``camera_lag_ns``: the images' header stamps that much before their receive times."""
    spec = BagSpec(types=dict(TYPES))
    spec.add("/robot_description", T0 - 1, string(URDF))
    frames = Frames(WIDTH, HEIGHT)
    for i in range(int(seconds * 50) + 1):
        t = T0 + i * 20_000_000
        if joints:
            q = _joints(seed, t)
            spec.add("/joint_states", t, joint_state(t, ["elbow", "shoulder"], [q[1], q[0]]))
        if i % 5 == 1:
            if command == "trajectory":
                spec.add("/arm_controller/joint_trajectory", t, trajectory(t, list(_command(seed, t))))
            else:
                c = _command(seed, t)
                spec.add("/cmd_vel", t, twist(c[0], c[1]))
        if (camera and i % 10 == 2) or (camera and i % 10 == 5 and i > 0):  # 15 Hz-ish, irregular
            spec.add(
                "/camera/image_raw", t, image(t - camera_lag_ns, frames(seed * 100 + i))
            )  # frames fall on some messages
    write_bag(path, spec)
    return ArmBag(path, seed, seconds, command)


def _joints(seed: int, t: int) -> tuple[float, float]:
    s = (t - T0) / 1e9
    return (0.5 * np.sin(2 * s + seed), -0.3 + 0.2 * np.cos(3 * s + 2 * seed))


def _command(seed: int, t: int) -> tuple[float, float]:
    s = (t - T0) / 1e9
    return (0.1 * seed + np.sin(s), 0.25 * np.cos(s + seed))


def messages(path: Path, topic: str) -> list[tuple[int, object]]:
    """``(receive ns, message)`` of a topic, as rosbags' own reader and deserializer give them."""
    from rosbags.rosbag2 import Reader

    with Reader(path) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        return [(t, TS.deserialize_cdr(raw, c.msgtype)) for c, t, raw in reader.messages(connections=conns)]


def held(times: list[int], at: np.ndarray) -> np.ndarray:
    """For each time in ``at``, the index of the last of ``times`` at or before it (a plain Python loop)."""
    out = []
    for t in at.tolist():
        out.append(max(k for k, m in enumerate(times) if m <= t))
    return np.asarray(out)


def expected(bag: ArmBag, fps: int = 30) -> dict[str, np.ndarray]:
    """The frames' times and what each must hold, from the bag's messages (rosbags) and numpy."""
    states = messages(bag.path, "/joint_states")
    cameras = messages(bag.path, "/camera/image_raw")
    command_topic = "/arm_controller/joint_trajectory" if bag.command == "trajectory" else "/cmd_vel"
    commands = messages(bag.path, command_topic)
    start = max(states[0][0], cameras[0][0], commands[0][0])
    end = min(states[-1][0], cameras[-1][0], commands[-1][0])
    count = int((end - start) * fps // 1_000_000_000) + 1
    frames = np.asarray([start + k * 1_000_000_000 // fps for k in range(count)], dtype=np.int64)
    js = [dict(zip(m.name, m.position, strict=True)) for _, m in states]  # type: ignore[attr-defined]
    state = np.array([[js[k][j] for j in JOINTS_URDF_ORDER] for k in held([t for t, _ in states], frames)])
    if bag.command == "trajectory":
        values = [list(m.points[0].positions) for _, m in commands]  # type: ignore[attr-defined]
    else:
        values = [
            [m.linear.x, m.linear.y, m.linear.z, m.angular.x, m.angular.y, m.angular.z]  # type: ignore[attr-defined]
            for _, m in commands
        ]
    action = np.array([values[k] for k in held([t for t, _ in commands], frames)])
    images = [m.data.reshape(m.height, m.width, 3) for _, m in cameras]  # type: ignore[attr-defined]
    shown = held([t for t, _ in cameras], frames)
    return {
        "frames_ns": frames,
        "state": state.astype(np.float32),
        "action": action.astype(np.float32),
        "images": np.stack([images[k] for k in shown]),
    }
