"""``--render``'s flags through the real CLI (a subprocess): bad ones are one line and exit 2 before anything is
run or written; ``--save-dir`` names one video per bag as it names their recordings."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest
from conftest import cli
from fleetbags import still_bag

import r2d2_viz.run.render as render_module
from r2d2_viz.cli.command import main
from r2d2_viz.cli.parser import build_parser
from r2d2_viz.cli.render import render_main
from r2d2_viz.run.render import RenderResult


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (["--render", "{tmp}/out.avi"], "unknown extension '.avi'; write a .mp4 or a .gif"),
        (["--render", "{tmp}/out.mp4", "--size", "640x481"], "--size '640x481': each side must be an even number"),
        (["--render", "{tmp}/out.mp4", "--size", "big"], "expected WIDTHxHEIGHT"),
        (["--render", "{tmp}/missing/out.mp4"], "does not exist"),
        (["--render", "{tmp}/out.mp4", "--fps", "0"], "--fps must be a number of frames per second"),
        (["--render", "{tmp}/out.mp4", "--save", "{tmp}/x.rrd"], "does not combine with --save"),
        (["--render", "{tmp}/out.mp4", "--serve"], "does not combine with --serve"),
        (["--view", "Warnings"], "--view chooses the view --render draws"),
        (["--render", "{tmp}/out.mp4", "--export-lerobot", "{tmp}/ds"], "choose one of --export-lerobot and --render"),
        (["--bag", "{tmp}/a", "--save-dir", "{tmp}/v", "--render", "mp4", "--jobs", "2"], "combine with --jobs"),
        (["--bag", "{tmp}/a", "{tmp}/b", "--render", "{tmp}/out.mp4"], "2 bags: give --save-dir DIR"),
        (["--bag", "{tmp}/nope", "--save-dir", "{tmp}/v", "--render", "avi"], "unknown extension"),
    ],
)
def test_bad_render_flags_are_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], said: str
) -> None:
    assert main([*(a.format(tmp=tmp_path) for a in args), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert said in err and len(err.splitlines()) == 1 and "Traceback" not in err
    assert not any(p.suffix in (".mp4", ".gif", ".partial") for p in tmp_path.rglob("*"))


def test_the_real_cli_says_a_bad_suffix_in_one_line(tmp_path: Path) -> None:
    result = cli("--render", str(tmp_path / "out.avi"))
    assert result.returncode == 2 and result.stdout == ""
    assert (
        result.stderr == f"error: --render {tmp_path / 'out.avi'}: unknown extension '.avi'; write a .mp4 or a .gif\n"
    )


def test_help_lists_the_flags() -> None:
    text = build_parser().format_help()
    for flag in ("--render OUT", "--view NAME", "--size WxH", "--fps N"):
        assert flag in text
    assert "frames per second of --export-lerobot and --render" in " ".join(text.split())


def test_save_dir_renders_one_video_per_bag_named_as_its_recording(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    bags = [still_bag(tmp_path / "first"), still_bag(tmp_path / "second.mcap.d")]
    made: list[tuple[Path | None, Path]] = []

    def render(config, video, *, say, said_software):  # type: ignore[no-untyped-def]
        made.append((config.bag, video.out))
        return RenderResult(video.out, 3, 0.6, "3D", False)

    monkeypatch.setattr(render_module, "render", render)
    args = build_parser().parse_args(["--bag", *map(str, bags), "--save-dir", str(tmp_path / "v"), "--render", ".gif"])
    assert isinstance(args, argparse.Namespace)
    assert render_main(args) == 0
    assert made == [(bags[0], tmp_path / "v" / "first.gif"), (bags[1], tmp_path / "v" / "second.mcap.d.gif")]
