"""Broken and hostile input through the real command line: one clear line, exit 2, nothing written."""

from __future__ import annotations

import os
import socket
from pathlib import Path

import pytest
from conftest import cli
from rrd import read_recording
from urdfdata import BAD, BAD_MANIFEST, GOOD

from r2d2_viz.cli import main


def _assert_refused(stderr: str, fragment: str, tmp_path: Path) -> None:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith("error: ") and fragment in lines[0], stderr
    assert "Traceback" not in stderr
    assert not [p for p in tmp_path.iterdir() if p.name != "keep.rrd"], "nothing may be written"


@pytest.mark.parametrize("name", sorted(BAD_MANIFEST))
def test_every_bad_urdf_is_refused_by_main(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--urdf", str(BAD / name), "--save", str(tmp_path / "out.rrd")]) == 2
    _assert_refused(capsys.readouterr().err, f"{name}: ", tmp_path)


@pytest.mark.parametrize(
    "name", ["billion_laughs.urdf", "xxe_file.urdf", "truncated.urdf", "not_utf8.urdf", "cycle.urdf"]
)
def test_bad_urdf_in_a_subprocess_keeps_the_existing_recording(name: str, tmp_path: Path) -> None:
    assert (BAD / name).exists(), name
    keep = tmp_path / "keep.rrd"
    keep.write_bytes(b"previous")
    result = cli("--urdf", str(BAD / name), "--save", str(keep))
    assert result.returncode == 2
    _assert_refused(result.stderr, BAD_MANIFEST[name], tmp_path)
    assert keep.read_bytes() == b"previous"


def test_urdf_path_problems(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for target, fragment in ((tmp_path / "nope.urdf", "nope.urdf: "), (tmp_path, f"{tmp_path.name}: ")):
        assert main(["--urdf", str(target), "--headless"]) == 2
        _assert_refused(capsys.readouterr().err, fragment, tmp_path)


@pytest.mark.parametrize(
    ("save", "fragment"),
    [("missing/dir/out.rrd", "does not exist"), (".", "is a directory")],
)
def test_save_target_problems(tmp_path: Path, save: str, fragment: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--save", str(tmp_path / save)]) == 2
    _assert_refused(capsys.readouterr().err, fragment, tmp_path)


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write into any directory")
def test_save_into_an_unwritable_directory(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    assert main(["--save", str(locked / "out.rrd")]) == 2
    assert "is not writable" in capsys.readouterr().err


def test_spawn_without_a_display_says_what_to_do_instead(tmp_path: Path) -> None:
    result = cli("--spawn", "--duration", "1", env={"DISPLAY": "", "WAYLAND_DISPLAY": ""}, cwd=tmp_path)
    assert result.returncode == 2
    _assert_refused(result.stderr, "--spawn: no display", tmp_path)
    assert "--save" in result.stderr and "--serve" in result.stderr


def test_serve_on_a_port_in_use_is_a_clear_error(tmp_path: Path) -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        result = cli("--serve", "--web-port", str(port), "--duration", "1", cwd=tmp_path)  # the one port it opens
    assert result.returncode == 2
    _assert_refused(result.stderr, f"cannot listen on 127.0.0.1:{port}", tmp_path)


def test_odd_names_keep_their_frames_exactly(tmp_path: Path) -> None:
    out = tmp_path / "odd.rrd"
    result = cli("--urdf", str(GOOD / "names_unicode_spaces.urdf"), "--save", str(out), "--duration", "1")
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    child_frames = {
        child[0]
        for rows in recording.values()
        for child in (
            *rows.static.get("Transform3D:child_frame", []),
            *rows.temporal.get("Transform3D:child_frame", []),
        )
    }
    assert child_frames == {"base link", "arm/upper", "Gelenk-ä", "手首 🤖"}
    axes_frames = {
        rows.static["CoordinateFrame:frame"][-1][0] for path, rows in recording.items() if path.startswith("/tf_axes/")
    }
    assert axes_frames == {"odom", "base link", "arm/upper", "Gelenk-ä", "手首 🤖"}


def test_good_corpus_runs_headless(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for urdf in sorted(GOOD.glob("*.urdf")):
        assert main(["--urdf", str(urdf), "--headless", "--duration", "0.5"]) == 0, capsys.readouterr().err


def test_lying_display_messages_warn_grouped_and_leak_nothing(tmp_path: Path) -> None:
    """NaN, infinite and 1e300 marker poses, scales and points, zero quaternions, a 1e300 transform, clouds and
    images whose sizes do not match their data: grouped warnings, exit 0, and nothing from inside numpy or
    rerun (``RuntimeWarning: overflow encountered in cast`` and its source line) — every warning shown
    (``PYTHONWARNINGS=always``), none may be there."""
    from liarbag import write_liar_bag

    bag = write_liar_bag(tmp_path / "liar")
    out = tmp_path / "liar.rrd"
    result = cli("--bag", str(bag), "--save", str(out), env={"PYTHONWARNINGS": "always"}, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "Warning" not in result.stderr, result.stderr
    lines = result.stderr.splitlines()
    assert all(line.startswith(("warning: ", "r2d2-viz: ")) for line in lines), result.stderr
    for topic in ("/markers", "/cloud", "/image", "/map"):
        assert sum(f"{topic}: " in line and "could not be shown" in line for line in lines) == 1, result.stderr
    assert out.stat().st_size < 100_000_000


def test_no_stderr_line_is_longer_than_300_characters(tmp_path: Path, tutorial_urdf: Path) -> None:
    """Names are input too (issue 29: a Gazebo bag's undrawn topics made a 486-character line): 400-character topic
    names, a scan on such a topic that cannot be decoded, 40 unknown 80-character joint names, 70 undrawn topics —
    every line the run prints stays within 300 characters, and still names what it is about."""
    from bagmaker import T0, BagSpec, joint_state, unknown_type, write_bag
    from msgs_build import T, cdr

    undrawn = [f"/{'u' * 390}_{k:02d}" for k in range(70)]
    scan = f"/{'s' * 400}/scan"
    unknown = [f"{'j' * 76}_{k:02d}" for k in range(40)]
    types = {**{t: "std_msgs/msg/ColorRGBA" for t in undrawn}, scan: "sensor_msgs/msg/LaserScan"}
    spec = BagSpec(types={**types, "/joint_states": "sensor_msgs/msg/JointState"})
    for k, topic in enumerate(undrawn):
        spec.add(topic, T0 + k, cdr(T("std_msgs/msg/ColorRGBA")(r=1.0, g=0.0, b=0.0, a=1.0)))
    spec.add(scan, T0 + 100, b"\x00\x01\x00\x00" + b"\x07" * 3)  # a CDR header and 3 bytes: truncated
    spec.add("/joint_states", T0 + 200, joint_state(T0 + 200, ["swivel", *unknown], [0.1] * 41))
    bag = write_bag(tmp_path / "names", spec, storage="sqlite3")
    # the undrawn topics' type made unknown (no definition in the bag, not a Humble type), so nothing decodes them
    unknown_type(bag, "std_msgs/msg/ColorRGBA")
    for args in (["--save", str(tmp_path / "n.rrd")], ["--list"]):  # the bag's full path (xdist makes it longer)
        result = cli("--bag", str(bag), "--urdf", str(tutorial_urdf), *args, cwd=tmp_path)
        assert result.returncode == 0, result.stderr
        # stderr only: --list's stdout is the data asked for, full names as ros2 bag info prints them
        assert max((len(line) for line in result.stderr.splitlines()), default=0) <= 300, result.stderr
    # as a user types it, from the bag's folder: what each line says, whole
    saved = cli("--bag", bag.name, "--urdf", str(tutorial_urdf), "--save", "m.rrd", cwd=tmp_path)
    err = saved.stderr
    assert "70 topics that cannot be decoded, not shown: /uuu" in err and " and " in err and " more " in err, err
    # the scan's problem: its topic cut short, its type, and the end of what went wrong
    assert "/sss" in err and "a sensor_msgs/msg/LaserScan message" in err and "(actual buffer size is 3)" in err, err
    assert "ignored joints" in err and f"{'j' * 76}_00" in err, err
