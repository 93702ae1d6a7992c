"""``--motion sliders`` (joint_state_publisher_gui without ROS): the sliders' ranges and starting values (worked out
by hand from the URDFs, by joint_state_publisher's rules), the page's events, and a slider moved in a live run
(POSTed as the page does, with the page's token) found in the recording."""

from __future__ import annotations

import json
import math
import re
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from rrd import read_recording

from r2d2_viz.errors import ToolEventError
from r2d2_viz.robot.model import default_urdf_path, load_urdf, parse_urdf
from r2d2_viz.sources.motion import SlidersMotion, make_motion
from r2d2_viz.sources.sliders import SliderBoard

MIMIC = """<robot name="g"><link name="a"/><link name="b"/><link name="c"/><link name="d"/>
<joint name="lift" type="prismatic"><parent link="a"/><child link="b"/><limit lower="0.1" upper="0.3" effort="1"
  velocity="1"/></joint>
<joint name="finger" type="revolute"><parent link="a"/><child link="c"/><limit lower="-1" upper="1" effort="1"
  velocity="1"/></joint>
<joint name="twin" type="revolute"><parent link="a"/><child link="d"/><mimic joint="finger" multiplier="-1"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""


def test_the_r2d2s_sliders_span_their_limits() -> None:
    """assets/r2d2.urdf: tilt [-0.5, 0] (revolute), swivel continuous (±π), periscope [-0.5, 0] m (prismatic)."""
    board = SliderBoard(load_urdf(default_urdf_path()))
    ranges = {s.name: (s.type, s.lower, s.upper, s.zero) for s in board.sliders}
    assert ranges == {
        "tilt": ("revolute", -0.5, 0.0, 0.0),
        "swivel": ("continuous", -math.pi, math.pi, 0.0),
        "periscope": ("prismatic", -0.5, 0.0, 0.0),
    }


def test_a_range_without_zero_starts_in_its_middle_and_mimics_have_no_slider() -> None:
    board = SliderBoard(parse_urdf(MIMIC), seed=1)
    assert [s.name for s in board.sliders] == ["lift", "finger"]  # twin follows finger in the kinematics
    assert board.values().tolist() == pytest.approx([0.2, 0.0])  # lift: (0.1 + 0.3) / 2
    assert board.handle({"tool": "Joints", "joint": "finger", "position": 0.5}) == "finger = 0.5"
    board.handle({"tool": "Joints", "action": "randomise"})
    lift, finger = board.values()
    assert 0.1 <= lift <= 0.3 and -1 <= finger <= 1
    board.handle({"tool": "Joints", "action": "centre"})
    assert board.values().tolist() == pytest.approx([0.2, 0.0])
    board.handle({"tool": "Joints", "positions": {"lift": 0.25, "finger": -0.75}})
    assert board.values().tolist() == pytest.approx([0.25, -0.75])


@pytest.mark.parametrize(
    "event",
    [
        {"tool": "Joints", "joint": "twin", "position": 0.1},  # a mimic: no slider
        {"tool": "Joints", "joint": "finger", "position": 1.5},  # outside its limits
        {"tool": "Joints", "joint": "finger", "position": float("nan")},
        {"tool": "Joints", "joint": "finger", "position": True},
        {"tool": "Joints", "joint": "finger"},
        {"tool": "Joints", "action": "dance"},
        {"tool": "Joints", "positions": {"lift": 0.2, "finger": 9.0}},  # one bad: none set
        {"tool": "Joints", "positions": [0.2]},
        {"tool": "Joints", "joint": "finger", "position": 10**400},  # JSON's ints have no limit; floats do
        {"tool": "Joints", "positions": {"lift": 0.2, "finger": -(10**400)}},
    ],
)
def test_bad_slider_events_are_refused_and_change_nothing(event: dict[str, object]) -> None:
    board = SliderBoard(parse_urdf(MIMIC))
    before = board.values()
    with pytest.raises(ToolEventError):
        board.handle(event)
    np.testing.assert_array_equal(board.values(), before)


def test_the_motion_takes_the_sliders_values_sample_by_sample() -> None:
    motion = make_motion(parse_urdf(MIMIC), "sliders", rate=10.0)
    assert isinstance(motion, SlidersMotion)
    chunks = motion.chunks(1000)
    first = next(chunks)
    assert len(first) == 1 and first.positions.tolist() == [[0.2, 0.0]]
    motion.board.set("finger", -0.5)
    second = next(chunks)
    assert second.times_ns.tolist() == [100_000_000] and second.positions.tolist() == [[0.2, -0.5]]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_a_slider_moved_in_the_page_is_in_the_recording(tmp_path: Path) -> None:
    """The issue's check: moving the slider named ``tilt`` to −0.3 puts a tilt sample of −0.3 in the recording."""
    pytest.importorskip("rerun_notebook")
    out = tmp_path / "sliders.rrd"
    exe = Path(sys.executable).parent / "r2d2-viz"
    command = [str(exe)] if exe.exists() else [sys.executable, "-m", "r2d2_viz"]
    port, web_port = _free_port(), _free_port()
    run = subprocess.Popen(
        [
            *command,
            "--motion",
            "sliders",
            "--serve",
            "--port",
            str(port),
            "--web-port",
            str(web_port),
            "--save",
            str(out),
            "--duration",
            "6",
            "--rate",
            "20",
        ],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert run.stderr is not None
        line = run.stderr.readline()
        found = re.search(r"(http://localhost:\d+/[^/\s]+/)", line)
        assert found, line
        page = found.group(1)
        deadline, config = time.monotonic() + 60, {}
        while "joints" not in config and time.monotonic() < deadline:  # the page tells its sliders once attached
            with urllib.request.urlopen(page, timeout=30) as answer:
                html = answer.read().decode()
            found_config = re.search(r'<script id="r2d2-config" type="application/json">(.*?)</script>', html)
            assert found_config is not None
            config = json.loads(found_config.group(1))
            time.sleep(0.1)
        assert [j["name"] for j in config["joints"]] == ["tilt", "swivel", "periscope"]
        assert 'src="sliders.js"' in html
        with urllib.request.urlopen(page + "sliders.js", timeout=30) as answer:
            assert b'tool: "Joints"' in answer.read()
        time.sleep(1.0)  # some samples at the starting value first
        for huge in (
            '{"tool": "Joints", "joint": "tilt", "position": 1%s}',
            '{"tool": "Joints", "positions": {"tilt": -1%s}}',
        ):
            # issue 44, item 16: a 400-digit number dropped the connection unanswered (float() of it overflows)
            request = urllib.request.Request(page + "event", data=(huge % ("0" * 400)).encode(),
                                             headers={"Content-Type": "application/json"})  # fmt: skip
            with pytest.raises(urllib.error.HTTPError) as refused:
                urllib.request.urlopen(request, timeout=30)
            assert refused.value.code == 400 and re.search(
                r"tilt: -?10+… is out of range", json.loads(refused.value.read())["error"]
            )
        event = json.dumps({"tool": "Joints", "joint": "tilt", "position": -0.3}).encode()
        request = urllib.request.Request(page + "event", data=event, headers={"Content-Type": "application/json"})
        with urllib.request.urlopen(request, timeout=30) as answer:
            assert json.loads(answer.read()) == {"line": "tilt = -0.3"}
        assert run.wait(timeout=60) == 0, run.stderr.read()
    finally:
        if run.poll() is None:  # SIGTERM: the app stops its gRPC server too (SIGKILL would orphan it)
            run.terminate()
            try:
                run.wait(timeout=30)
            except subprocess.TimeoutExpired:
                run.kill()
                run.wait()
    plot = read_recording(out)["/joints/limited"]
    names = plot.static["SeriesLines:names"][-1]
    tilt = [row[names.index("tilt")] for row in plot.temporal["Scalars:scalars"]]
    assert len(tilt) == 120  # 6 s at 20 Hz
    assert tilt[0] == 0.0 and tilt[-1] == -0.3
    changed = tilt.index(-0.3)
    assert 0 < changed and set(tilt[:changed]) == {0.0} and set(tilt[changed:]) == {-0.3}
