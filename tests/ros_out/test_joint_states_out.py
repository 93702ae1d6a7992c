"""``--ros --motion sliders``: the sliders' ``/joint_states`` — each message read back with rosbags' own CDR
deserializer (not r2d2-viz's), names and positions as the sliders hold them; 10 Hz, stopped on close."""

from __future__ import annotations

import threading

import pytest
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.errors import UsageError
from r2d2_viz.robot.model import default_urdf_path, load_urdf
from r2d2_viz.ros_out.joint_states_out import JOINT_STATE_TYPE, JointStatesOut, joint_state_cdr, live_sliders
from r2d2_viz.sources.sliders import SliderBoard

STORE = get_typestore(Stores.ROS2_HUMBLE)


class Graph:
    def __init__(self) -> None:
        self.sent: list[tuple[str, str, bytes]] = []
        self.third = threading.Event()

    def publish(self, topic: str, ros_type: str, data: bytes) -> None:
        self.sent.append((topic, ros_type, data))
        if len(self.sent) >= 3:
            self.third.set()


def test_a_joint_state_message_as_rosbags_reads_it() -> None:
    data = joint_state_cdr(("tilt", "swivel"), [-0.3, 1.25], 1_700_000_000_123_456_789)
    message = STORE.deserialize_cdr(data, JOINT_STATE_TYPE)
    assert message.name == ["tilt", "swivel"]
    assert message.position.tolist() == [-0.3, 1.25]
    assert len(message.velocity) == 0 and len(message.effort) == 0
    assert (message.header.stamp.sec, message.header.stamp.nanosec) == (1_700_000_000, 123_456_789)


def test_the_sliders_are_published_until_closed() -> None:
    board = SliderBoard(load_urdf(default_urdf_path()))
    board.set("tilt", -0.3)
    graph = Graph()
    out = JointStatesOut(board, graph, period=0.01, stamp=lambda: 5).start()
    assert graph.third.wait(10)
    out.close()
    count = len(graph.sent)
    assert out.sent == count >= 3
    topic, ros_type, data = graph.sent[-1]
    assert (topic, ros_type) == ("/joint_states", "sensor_msgs/msg/JointState")
    message = STORE.deserialize_cdr(data, ros_type)
    assert message.name == ["tilt", "swivel", "periscope"] and message.position.tolist() == [-0.3, 0.0, 0.0]
    threading.Event().wait(0.05)
    assert len(graph.sent) == count  # nothing after close


def test_live_sliders_need_a_robot() -> None:
    assert live_sliders("sweep", None) is None
    with pytest.raises(UsageError, match="--urdf"):
        live_sliders("sliders", None)
    motion = live_sliders("sliders", load_urdf(default_urdf_path()))
    assert motion is not None and [s.name for s in motion.board.sliders] == ["tilt", "swivel", "periscope"]


SCENARIO = """
import json, re, subprocess, sys, time, urllib.request
exe, out, urdf = sys.argv[1], sys.argv[2], sys.argv[3]
app = subprocess.Popen([exe, "--ros", "--urdf", urdf, "--motion", "sliders", "--serve", "--port", "19877",
                        "--web-port", "19091", "--save", out, "--duration", "8"], stderr=subprocess.PIPE, text=True)
line = app.stderr.readline()
page = re.search(r"http://localhost(:\\d+/[^/\\s]+/)", line).group(1)
page = "http://127.0.0.1" + page  # the page listens on 127.0.0.1
time.sleep(3)
event = json.dumps({"tool": "Joints", "joint": "tilt", "position": -0.3}).encode()
opener = urllib.request.build_opener(urllib.request.ProxyHandler({}))  # loopback: never through a proxy
print(opener.open(urllib.request.Request(page + "event", data=event), timeout=30).read().decode())
print(app.wait(timeout=60), app.stderr.read())
"""


def test_the_sliders_go_round_the_graph_and_into_the_recording(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """``r2d2-viz --ros --motion sliders --serve --save`` in a loopback-only network namespace: the sliders'
    /joint_states (the page's tilt of −0.3) come back through DDS to the app's own subscription, as any node's would,
    and into the recording. A real rclpy node: not here (see tests/ros_out/test_tools_to_node.py for how)."""
    import subprocess
    import sys
    from pathlib import Path

    from rrd import read_recording
    from sources.live import ros_node

    if subprocess.run(["unshare", "-n", "true"], capture_output=True).returncode != 0:
        pytest.skip("no network namespace (unshare -n) here")
    exe = Path(sys.executable).parent / "r2d2-viz"
    out = tmp_path / "ros.rrd"
    script = tmp_path / "scenario.py"
    script.write_text(SCENARIO)
    command = [sys.executable, str(script), str(exe), str(out), str(default_urdf_path())]
    done = ros_node.in_netns(command, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert '{"line": "tilt = -0.3"}' in done.stdout, done.stdout
    assert "received /joint_states" in done.stdout, done.stdout
    plot = read_recording(out)["/joints/limited"]
    names = plot.static["SeriesLines:names"][-1]
    tilt = [row[names.index("tilt")] for row in plot.temporal["Scalars:scalars"]]
    assert tilt[0] == 0.0 and tilt[-1] == -0.3 and len(tilt) >= 40  # 10 Hz for about 8 s
