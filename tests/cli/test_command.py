"""The command line, in a subprocess, as a user runs it."""

from __future__ import annotations

import re
import socket
from pathlib import Path

import pytest
from conftest import cli
from rrd import read_recording, tf_by_child

from r2d2_viz.cli import main


def test_python_dash_m_works_too(tmp_path: Path) -> None:
    import subprocess
    import sys

    out = tmp_path / "m.rrd"
    result = subprocess.run(
        [sys.executable, "-m", "r2d2_viz", "--save", str(out), "--duration", "1"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert len(tf_by_child(read_recording(out))["axis"].times) == 30


def test_duration_rate_and_motion_shape_the_recording(tmp_path: Path) -> None:
    out = tmp_path / "short.rrd"
    result = cli("--save", str(out), "--duration", "2", "--rate", "10", "--motion", "still")
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    moving = tf_by_child(recording)
    assert moving["body"].times == [k * 100_000_000 for k in range(20)]  # 2 s at 10 Hz
    assert "axis" not in moving  # still: odom → axis is static
    assert recording["/tf_static/axis"].static["Transform3D:parent_frame"][-1] == ["odom"]


def test_any_urdf_sweeps_by_default(tmp_path: Path) -> None:
    from r2d2_viz.robot.synth import random_urdf

    urdf = tmp_path / "arm.urdf"
    urdf.write_text(random_urdf(12, seed=9, joint_types=("revolute", "prismatic", "fixed")))
    out = tmp_path / "arm.rrd"
    result = cli("--urdf", str(urdf), "--save", str(out), "--duration", "1")
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    assert len(recording["/joints/limited"].times) == 30
    assert all(len(rows.times) == 30 for rows in tf_by_child(recording).values())


def test_headless_computes_and_writes_nothing(tmp_path: Path) -> None:
    result = cli("--headless", "--duration", "1", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "30 samples" in result.stderr and not list(tmp_path.iterdir())


BAD_INPUT = [
    (["--rate", "0"], "--rate must be a positive"),
    (["--rate", "-5"], "--rate must be a positive"),
    (["--rate", "nan"], "--rate must be a positive"),
    (["--duration", "0"], "--duration must be a positive"),
    (["--duration", "-1"], "--duration must be a positive"),
    (["--duration", "inf"], "--duration must be a positive"),
    (["--duration", "soon"], "not a number: 'soon'"),
    (["--motion", "dance"], "unknown motion 'dance'; expected one of tutorial, sweep, still"),
    (["--urdf", "/nonexistent/robot.urdf"], "robot.urdf"),
    (["--spawn", "--serve"], "choose one live sink"),
    (["--headless", "--save", "x.rrd"], "--headless"),
    (["--bogus"], "unrecognized arguments: --bogus"),
    (["--save", "out.txt"], "--save out.txt: unknown extension '.txt'; write a recording (.rrd) or a ROS 2 bag"),
    (["--save", "recording"], "--save recording: unknown extension"),
    (["--tool-topic", "select=/x"], "--tool-topic 'select=/x': expected TOOL=TOPIC, TOOL one of goal"),
    (["--tool-topic", "goal"], "--tool-topic 'goal': expected TOOL=TOPIC"),
    (["--tool-topic", "goal=move base"], "'move base' is not a ROS topic name"),
    # a name longer than the file system takes (255 bytes on ext4, Linux's NAME_MAX): the OS's words, the file named
    (["--save", "a" * 300 + ".rrd"], ".rrd: File name too long"),
    (["--save", "line\nbreak" + "c" * 300 + ".rrd"], "line\\x0abreak"),  # the name's line break shown, one line
    (["--render", "b" * 300 + ".mp4", "--duration", "1"], ".mp4: File name too long"),
]
CONSOLE_SCRIPT = {"--bogus", "--urdf"}
"""The cases run by the real console script, each in its own process: one the parser refuses, one the library does.
The others go through the same ``main`` in one fresh process (17 console-script starts cost 9.5 s of CPU)."""

_MAINS = """
import json, os, sys
from contextlib import redirect_stderr
from io import StringIO
from r2d2_viz.cli import main
results = []
for cwd, args in json.loads(sys.stdin.read()):
    os.chdir(cwd)
    err = StringIO()
    with redirect_stderr(err):
        try:
            code = main(args)
        except SystemExit as exc:  # the parser's refusals
            code = exc.code
    results.append([code, err.getvalue()])
print(json.dumps(results))
"""


def _with_save(args: list[str], folder: Path) -> list[str]:
    writes = {"--save", "--headless", "--render"} & set(args)
    return [*args, "--save", str(folder / "out.rrd")] if not writes else args


@pytest.fixture(scope="module")
def bad_input_runs(tmp_path_factory: pytest.TempPathFactory) -> dict[int, tuple[int, str, Path]]:
    """Exit code, stderr and working folder of each case of :data:`BAD_INPUT`, each in a folder of its own."""
    import json
    import subprocess
    import sys

    folders = {k: tmp_path_factory.mktemp(f"bad{k}") for k in range(len(BAD_INPUT))}
    runs: dict[int, tuple[int, str, Path]] = {}
    batch = [k for k, (args, _) in enumerate(BAD_INPUT) if not CONSOLE_SCRIPT & set(args)]
    payload = json.dumps([[str(folders[k]), _with_save(BAD_INPUT[k][0], folders[k])] for k in batch])
    done = subprocess.run([sys.executable, "-c", _MAINS], input=payload, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    for k, (code, err) in zip(batch, json.loads(done.stdout.strip().splitlines()[-1]), strict=True):
        runs[k] = (code, err, folders[k])
    for k, (args, _) in enumerate(BAD_INPUT):
        if k not in runs:
            result = cli(*_with_save(args, folders[k]), cwd=folders[k])
            runs[k] = (result.returncode, result.stderr, folders[k])
    return runs


@pytest.mark.parametrize("case", range(len(BAD_INPUT)), ids=[" ".join(args) for args, _ in BAD_INPUT])
def test_bad_input_is_one_line_exit_2_and_nothing_written(
    bad_input_runs: dict[int, tuple[int, str, Path]], case: int
) -> None:
    code, stderr, folder = bad_input_runs[case]
    fragment = BAD_INPUT[case][1]
    assert code == 2, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0], stderr
    assert "Traceback" not in stderr and not list(folder.iterdir())


def test_main_is_callable_in_process(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--rate", "-1", "--headless"]) == 2
    assert capsys.readouterr().err.startswith("error: --rate must be a positive")


def test_save_defaults_to_one_lap_whatever_the_rate(tmp_path: Path) -> None:
    out = tmp_path / "lap60.rrd"
    result = cli("--save", str(out), "--rate", "60")
    assert result.returncode == 0, result.stderr
    times = tf_by_child(read_recording(out))["axis"].times
    assert len(times) == 1440 and times[-1] == round(1439 * 1e9 / 60)  # 360° at ¼° a frame: 24 s at 60 Hz


def test_connect_without_a_url_leaves_xacro_arguments_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    # "--connect" takes an optional URL; "--connect ur_type:=ur5e" used to send the run to a viewer at
    # "ur_type:=ur5e". The run itself is replaced: only what the command line makes of its arguments is checked.
    from r2d2_viz import runner
    from r2d2_viz.cli import CONNECT_DEFAULT

    seen: list[runner.RunConfig] = []

    def fake_run(config: runner.RunConfig, **_: object) -> None:
        seen.append(config)
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "run", fake_run)
    assert main(["--urdf", "ur.urdf.xacro", "--connect", "ur_type:=ur5e", "name:=ur"]) == 130
    assert main(["--urdf", "ur.urdf.xacro", "--connect", "rerun+http://10.0.0.2:9876/proxy", "name:=ur"]) == 130
    first, second = seen
    assert (first.mappings, first.sink.connect) == ({"ur_type": "ur5e", "name": "ur"}, CONNECT_DEFAULT)
    assert (second.mappings, second.sink.connect) == ({"name": "ur"}, "rerun+http://10.0.0.2:9876/proxy")


def _free_ports(n: int) -> list[int]:
    """``n`` loopback ports nothing listens on (bound by the kernel's choice, then released)."""
    sockets = [socket.socket() for _ in range(n)]
    try:
        for s in sockets:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def test_connect_to_no_viewer_is_one_line_and_exit_2(tmp_path: Path) -> None:
    """Rerun's gRPC sink connects lazily and retries for ever (a run used to hang, deaf to Ctrl-C): the address
    is tried first. The subprocess's timeout ends a hang; no timing is asserted."""
    (port,) = _free_ports(1)
    url = f"rerun+http://127.0.0.1:{port}/proxy"
    result = cli("--connect", url, "--duration", "30", timeout=60, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"error: --connect {url}: no viewer at 127.0.0.1:{port}"), result.stderr
    assert f"rerun --port {port}" in lines[0]


def test_without_a_display_the_default_viewer_is_the_web_viewer_on_loopback(tmp_path: Path) -> None:
    """No sink flag on a machine without a display (a server, a container, SSH): the web viewer, served on
    127.0.0.1, and one line with its URL and the ``ssh -L`` that reaches it from another machine. (A typed
    ``--spawn`` still says it cannot: tests/test_bad_input.py.)"""
    [web] = _free_ports(1)
    env = {"DISPLAY": "", "WAYLAND_DISPLAY": ""}
    result = cli("--duration", "1", "--web-port", str(web), env=env, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    [line] = [line for line in result.stderr.splitlines() if "no display" in line]
    found = re.search(rf"open http://localhost:{web}/([A-Za-z0-9_-]{{32}})/ in a browser", line)  # with its token
    assert found, line
    assert f"or run: rerun http://localhost:{web}/{found.group(1)}/recording.rrd" in line, line
    assert f"ssh -L {web}:localhost:{web} THIS-HOST" in line, line  # one port: the recording comes through the page
    assert "error" not in result.stderr and "30 samples" in result.stderr
    assert not list(tmp_path.iterdir())


def test_rerun_log_lines_only_with_r2d2_viz_debug(tmp_path: Path) -> None:
    """``--headless`` disables the recording, and Rerun logs a WARN line (with colour codes) for every call it
    ignores: off by default; ``R2D2_VIZ_DEBUG=1`` turns them back on (so the check is not vacuous)."""
    quiet = cli("--headless", "--duration", "0.2", env={"RUST_LOG": "info"}, cwd=tmp_path)
    assert quiet.returncode == 0, quiet.stderr
    assert all(line.startswith(("warning: ", "r2d2-viz: ")) for line in quiet.stderr.splitlines()), quiet.stderr
    debug = cli("--headless", "--duration", "0.2", env={"R2D2_VIZ_DEBUG": "1"}, cwd=tmp_path)
    assert debug.returncode == 0, debug.stderr
    assert "re_sdk::recording_stream" in debug.stderr
    # --serve starts no Rerun process (the page's server carries the recording): only the app's own lines
    [web] = _free_ports(1)
    quiet = cli("--serve", "--duration", "0.5", "--web-port", str(web), env={"RUST_LOG": "info"}, cwd=tmp_path)
    assert quiet.returncode == 0, quiet.stderr
    assert all(line.startswith(("warning: ", "r2d2-viz: ", "serving: ")) for line in quiet.stderr.splitlines())


def _entry_points() -> list[str]:
    """Every ``python -m`` entry point of the installed package: the modules with a ``__main__`` block (found by
    reading the files, so a new one is covered without being listed here)."""
    import r2d2_viz

    root = Path(r2d2_viz.__file__).parent
    found = []
    for path in sorted(root.rglob("*.py")):
        if 'if __name__ == "__main__"' in path.read_text(encoding="utf-8"):
            parts = path.relative_to(root.parent).with_suffix("").parts
            found.append(".".join(parts[:-1] if parts[-1] == "__main__" else parts))
    return found


def test_the_entry_points_are_found() -> None:
    assert {"r2d2_viz", "r2d2_viz.blueprint", "r2d2_viz.msgs.registry", "r2d2_viz.robot.xacro_sandbox"} <= set(
        _entry_points()
    )


@pytest.mark.parametrize("module", _entry_points())
def test_every_python_dash_m_entry_point_takes_help(module: str, tmp_path: Path) -> None:
    """``python -m r2d2_viz.blueprint --help`` used to write a 74 kB blueprint named ``--help``."""
    import subprocess
    import sys

    result = subprocess.run(
        [sys.executable, "-m", module, "--help"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
        stdin=subprocess.DEVNULL,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage: "), result.stdout
    assert not list(tmp_path.iterdir()), "--help writes nothing"


def test_blueprint_entry_point_refuses_what_is_not_a_blueprint(tmp_path: Path) -> None:
    import subprocess
    import sys

    for args in (["out.txt"], ["--rviz", "x.rviz"], ["--bogus"]):
        run = [sys.executable, "-m", "r2d2_viz.blueprint", *args]
        result = subprocess.run(run, capture_output=True, text=True, cwd=tmp_path, timeout=120)
        assert result.returncode == 2, (args, result.stderr)
    assert not list(tmp_path.iterdir())
    result = subprocess.run(
        [sys.executable, "-m", "r2d2_viz.blueprint", "mine.rbl"], capture_output=True, text=True, cwd=tmp_path
    )
    assert result.returncode == 0 and (tmp_path / "mine.rbl").stat().st_size > 1000, result.stderr


def test_a_bag_with_78_undrawn_topics_says_so_in_one_short_line(tmp_path: Path) -> None:
    """A Gazebo bag's 78 topics nothing can decode used to be one 6,000-character line: now the count, the first
    few names and why, once (the bag written by rosbags; .db3, its types then renamed to one neither Humble nor the
    bag defines)."""
    from bagmaker import T0, BagSpec, unknown_type, write_bag
    from msgs_build import cdr, color

    topics = [f"/gazebo/link_{k:02d}/diagnostics_with_a_long_name" for k in range(78)]
    spec = BagSpec(types={t: "std_msgs/msg/ColorRGBA" for t in topics})
    for k, topic in enumerate(topics):
        spec.add(topic, T0 + k, cdr(color(1.0, 0.0, 0.0)))
    bag = write_bag(tmp_path / "gz", spec, storage="sqlite3")
    unknown_type(bag, "std_msgs/msg/ColorRGBA")
    result = cli("--bag", bag.name, "--save", "gz.rrd", cwd=tmp_path)  # from the bag's folder, as a user types it
    assert result.returncode == 0, result.stderr
    [line] = [line for line in result.stderr.splitlines() if "not shown" in line]
    assert "78 topics that cannot be decoded, not shown: " in line and "and 75 more (--list shows every topic)" in line
    assert f"{topics[0]}, {topics[1]}," in line and topics[-1] not in line
    assert line.endswith("topic); gz_msgs/msg/Link: no definition in the bag, not a Humble type"), line
    path_len = len(str(tmp_path))  # the line names the bag; its folder (longer under xdist) is not the list
    assert len(line) - path_len <= 300 and max(len(x) - path_len for x in result.stderr.splitlines()) < 450, line
    listed = cli("--bag", str(bag), "--list", cwd=tmp_path)  # all of them, like ros2 bag info
    assert listed.returncode == 0 and listed.stderr == "", listed.stderr
    assert listed.stdout.splitlines() == [f"{t} [gz_msgs/msg/Link] 1 message" for t in topics]


def test_the_summary_names_what_it_counted(tmp_path: Path, tutorial_urdf: Path) -> None:
    """'samples' meant joint states for one bag, clouds for another: the summary now says which. Seven joint
    states written (by rosbags) → '7 joint states'; a bag without joint states counts its transforms and display
    messages; a motion counts its samples."""
    from bagmaker import T0, BagSpec, joint_state, write_bag
    from displaybags import write_display_bag

    spec = BagSpec()
    for k in range(7):
        spec.add("/joint_states", T0 + k * 10**8, joint_state(T0 + k * 10**8, ["swivel", "tilt"], [0.1 * k, 0.0]))
    joints = write_bag(tmp_path / "joints", spec)
    result = cli("--bag", str(joints), "--urdf", str(tutorial_urdf), "--headless", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert f"r2d2-viz: 7 joint states from {joints}" in result.stderr, result.stderr
    displays = write_display_bag(tmp_path / "displays")
    result = cli("--bag", str(displays), "--headless", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "transforms and display messages from" in result.stderr.splitlines()[-1], result.stderr
    result = cli("--headless", "--duration", "1", cwd=tmp_path)
    assert result.stderr.splitlines()[-1] == "r2d2-viz: 30 samples at 30 Hz", result.stderr


def test_the_web_viewer_fallback_says_why_when_it_fails(tmp_path: Path) -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        env = {"DISPLAY": "", "WAYLAND_DISPLAY": ""}
        result = cli("--duration", "1", "--web-port", str(port), env=env, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    [line] = result.stderr.strip().splitlines()
    assert line.startswith("error: no display for a viewer window, and the web viewer instead failed: "), line
    assert f"cannot listen on 127.0.0.1:{port}" in line


@pytest.mark.parametrize("args", [["--bag", "talker_mcap", "--list"], ["--help"]], ids=["bag-list", "help"])
def test_a_reader_that_stops_early_ends_it_quietly(args: list[str]) -> None:
    """``r2d2-viz --bag b --list | head`` sometimes ended in "unexpected BrokenPipeError", exit 1 (issue 36): the
    reader had gone before the output was flushed. A real pipe whose reading end is closed before the program
    writes (the worst case of ``| head``): nothing on stderr, and 141, what a shell reports for ``seq 1 100000 | head``
    (killed by SIGPIPE, 128 + 13), so ``set -o pipefail`` sees it as it sees coreutils'."""
    import os
    import subprocess
    import sys

    from conftest import REPO

    exe = Path(sys.executable).parent / "r2d2-viz"
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader is gone before the first byte
    try:
        done = subprocess.run(
            [str(exe), *args],
            stdout=write_end,
            stderr=subprocess.PIPE,
            text=True,
            timeout=120,
            cwd=REPO / "tests" / "data" / "bags",
        )
    finally:
        os.close(write_end)
    # --help is argparse's, which drops a write error itself: exit 0 (checked, so that it stays quiet)
    assert done.stderr == "" and done.returncode == (0 if args == ["--help"] else 141), (done.returncode, done.stderr)


def test_start_up_imports_run_without_the_cyclic_collector_then_it_runs_again(monkeypatch, capsys) -> None:
    """Issue 38: Python's cyclic collector walked every object the imports made at each full collection and again
    at exit (~0.2 s of CPU in a run of a few seconds). The imports run with it paused; then what they made is frozen
    out of it and it runs again — also when the command fails before or after that point."""
    import gc

    from r2d2_viz.cli import command

    seen: list[bool] = []
    started = command._started
    monkeypatch.setattr(command, "_started", lambda: (seen.append(gc.isenabled()), started()))
    frozen = gc.get_freeze_count()
    assert main(["--tree"]) == 0  # the R2D2's tree: past the imports
    assert seen[0] is False  # the imports ran with the collector paused
    assert gc.isenabled()
    assert gc.get_freeze_count() > frozen
    assert "robot name is: r2d2" in capsys.readouterr().out
    assert main(["--save", "x.txt"]) == 2  # refused before the imports
    assert gc.isenabled()


def test_a_busy_web_port_names_the_flag_that_sets_it() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        served = cli("--serve", "--web-port", str(port), "--duration", "0.2")
        fallback = cli("--web-port", str(port), "--duration", "0.2", env={"DISPLAY": "", "WAYLAND_DISPLAY": ""})
    for result in (served, fallback):
        assert result.returncode == 2, result.stderr
        (line,) = result.stderr.splitlines()
        assert f"cannot listen on 127.0.0.1:{port} for the web page: Address already in use" in line
        assert line.endswith("; choose another port with --web-port PORT"), line
