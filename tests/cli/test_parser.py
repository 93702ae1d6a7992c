"""The command line's flags (``r2d2_viz.cli.parser``): ``--help`` as a user reads it, in a subprocess, and argparse's
errors as one line and exit 2."""

from __future__ import annotations

import pytest
from conftest import cli

from r2d2_viz.cli.parser import EXIT_BAD_INPUT, build_parser


def test_help_lists_the_flags() -> None:
    result = cli("--help")
    assert result.returncode == 0
    for flag in (
        "--urdf",
        "--motion",
        "--duration",
        "--rate",
        "--spawn",
        "--save",
        "--connect",
        "--serve",
        "--headless",
    ):
        assert flag in result.stdout


def test_help_says_what_happens_without_a_sink_flag_and_keeps_list_out_of_the_ros_group() -> None:
    out = cli("--help", env={"COLUMNS": "200"}).stdout
    blocks = out.split("\n\n")
    assert "--spawn is used" not in out  # untrue on a machine without a display (issue 29)
    assert " ".join(blocks[-1].split()).startswith(
        "Without a sink flag: the native viewer (--spawn), or on a machine without a display a web viewer on "
        "127.0.0.1 (--serve)."
    )
    # --list serves bags (like ros2 bag info) and the graph alike: it sits with the general options
    [group] = [block for block in blocks if "\n  --list " in block]
    assert group.startswith("options:"), group


def test_a_bad_flag_is_one_line_and_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(["--rate", "fast"])
    assert exc.value.code == EXIT_BAD_INPUT == 2
    [line] = capsys.readouterr().err.strip().splitlines()
    assert line == "error: argument --rate: not a number: 'fast' (see r2d2-viz --help)", line


def test_flags_parse_to_what_the_command_reads() -> None:
    args = build_parser().parse_args(["--bag", "a.mcap", "--plot", "/odom.x", "/odom.y", "--plot", "/j.effort[2]"])
    assert [str(b) for b in args.bag] == ["a.mcap"]
    assert args.plot == [["/odom.x", "/odom.y"], ["/j.effort[2]"]]  # one view per flag
    assert build_parser().parse_args(["--video"]).video == "av1"  # AV1 by default
    assert build_parser().parse_args(["--serve"]).bind == "127.0.0.1"  # loopback unless --bind
