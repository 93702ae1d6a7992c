"""``--render``'s orchestration without a viewer: the frames' times, the output checks, and that an interrupted
render leaves no file (the viewer replaced by a stand-in that draws a gradient; the real one:
tests/e2e/test_render_e2e.py)."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

import av
import numpy as np
import pytest
from bagmaker import T0
from fleetbags import still_bag

import r2d2_viz.run.render as render_module
from r2d2_viz.errors import UsageError
from r2d2_viz.run.render import RenderConfig, check_out, frame_times, render
from r2d2_viz.runner import RunConfig
from r2d2_viz.viewer.files.render import ChosenView, Span

S = 1_000_000_000


def test_frame_times_are_start_plus_k_over_fps_before_the_end() -> None:
    # by hand: 60 s at 2 fps is 120 frames, 0, 0.5, …, 59.5 s
    times = frame_times(10 * S, 70 * S, 2.0)
    assert len(times) == 120 and times[0] == 10 * S and times[-1] == 10 * S + 59_500_000_000
    assert frame_times(0, 250_000_000, 30.0) == [round(k * S / 30) for k in range(8)]  # 7.5 frames: 8
    assert frame_times(5, 5, 30.0) == [5]  # a recording of one instant: one frame
    assert len(frame_times(0, 60 * S, 29.97)) == 1799  # 59.94 × 30 = 1798.2: 1799


def test_the_output_is_checked_before_anything_runs(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="unknown extension"):
        check_out(tmp_path / "a.avi")
    with pytest.raises(UsageError, match="does not exist"):
        check_out(tmp_path / "missing" / "a.mp4")
    with pytest.raises(UsageError, match="is a directory"):
        (tmp_path / "d.mp4").mkdir()
        check_out(tmp_path / "d.mp4")
    if os.geteuid() != 0:  # root writes anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        with pytest.raises(UsageError, match="not writable"):
            check_out(locked / "a.mp4")


class _StandIn:
    """A renderer whose frame k is a flat grey of level 10·k, that raises KeyboardInterrupt at ``stop_at``."""

    def __init__(self, stop_at: int | None, span: tuple[int, int]) -> None:
        self.view, self.software, self.stop_at, self.drawn = ChosenView("v", "3D", "3D"), True, stop_at, 0
        self.span = Span("time", "timestamp", *span)
        self.times: list[int] = []

    def frame(self, t_ns: int) -> np.ndarray:
        if self.drawn == self.stop_at:
            raise KeyboardInterrupt
        self.drawn += 1
        self.times.append(t_ns)
        return np.full((48, 64, 3), 10 * (self.drawn - 1), np.uint8)


def _stand_in(
    monkeypatch: pytest.MonkeyPatch, stop_at: int | None, span: tuple[int, int] = (0, 2 * S), drawn: list | None = None
) -> list[RunConfig]:
    runs: list[RunConfig] = []

    @contextlib.contextmanager
    def rendering(rrd: Path, size: tuple[int, int], wanted: str | None) -> Iterator[_StandIn]:
        renderer = _StandIn(stop_at, span)
        yield renderer
        if drawn is not None:
            drawn.append(renderer.times)

    monkeypatch.setattr(render_module, "run", runs.append)
    monkeypatch.setattr(render_module, "rendering", rendering)
    return runs


def test_a_render_writes_each_frame_and_says_the_cpu_fallback_once(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    runs = _stand_in(monkeypatch, None)
    said: list[str] = []
    once = [False]
    for name in ("a.mp4", "b.mp4"):
        result = render(RunConfig(), RenderConfig(tmp_path / name, (64, 48), 5.0), say=said.append, said_software=once)
        assert result.frames == 10 and result.seconds == 2.0  # 2 s at 5 fps
    assert len(said) == 1 and "lavapipe" in said[0]
    assert runs[0].sink.save is not None and runs[0].sink.save.suffix == ".rrd" and not runs[0].sink.live
    with av.open(str(tmp_path / "a.mp4")) as container:
        levels = [f.to_ndarray(format="gray").mean() for f in container.decode(video=0)]
    assert np.allclose(levels, [10 * k for k in range(10)], atol=3)  # in order, one each
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "b.mp4"]


def test_an_interrupted_render_leaves_no_file_and_keeps_the_old_one(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    _stand_in(monkeypatch, 4)
    out = tmp_path / "a.mp4"
    out.write_bytes(b"an older video")
    with pytest.raises(KeyboardInterrupt):
        render(RunConfig(), RenderConfig(out, (64, 48), 5.0))
    assert [p.name for p in tmp_path.iterdir()] == ["a.mp4"] and out.read_bytes() == b"an older video"


def test_with_a_start_offset_the_video_starts_at_the_offset_not_at_the_preroll(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    bag = still_bag(tmp_path / "still", samples=9)  # receive times T0 … T0 + 0.8 s (tests/fleetbags.py)
    drawn: list[list[int]] = []
    _stand_in(monkeypatch, None, span=(T0, T0 + 800_000_000), drawn=drawn)  # the preroll: from the bag's start
    render(RunConfig(bag=bag, start_offset=0.5), RenderConfig(tmp_path / "a.mp4", (64, 48), 10.0))
    assert drawn == [[T0 + 500_000_000, T0 + 600_000_000, T0 + 700_000_000]]  # 0.5, 0.6, 0.7 s: before 0.8 s
    render(RunConfig(bag=bag), RenderConfig(tmp_path / "b.mp4", (64, 48), 10.0))
    assert len(drawn[1]) == 8 and drawn[1][0] == T0
