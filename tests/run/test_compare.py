"""``r2d2-viz --compare A B``, driven as a user does (the installed CLI in a subprocess), on two runs of the
tutorial's R2D2 written by rosbags' own writer: run ``b`` starts 0.7 s later, samples every 25 ms instead of 20 ms,
its swivel 0.3 rad off, and it has a topic (``/extra``) that ``a`` has not. Expected values come from rosbags'
deserializer, yourdfpy's forward kinematics and numpy — never from the code under test."""

from __future__ import annotations

import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from bagmaker import T0, TS, BagSpec, joint_state, string, write_bag
from conftest import cli, made_once
from rosbags.rosbag2 import Reader
from rrd import blueprint_components, frame_edges_at, pose_in, read_recording

from r2d2_viz.robot.model import default_urdf_path

NAMES = ("swivel", "tilt", "periscope")
LATE_NS = 700_000_000
PLOT = "/joint_states.position[0]"
PLOT_ENTITY = r"plot/0/\/joint_states.position\[0\]"
GHOST_ALPHA = 100  # r2d2_viz.viewer.compare.scene.GHOST_ALPHA, as the docs say: 100 of 255


def _values(t_s: float, late: bool) -> list[float]:
    return [math.sin(2 * t_s) + (0.3 if late else 0.0), -0.25 - 0.2 * math.sin(3 * t_s), -0.1 - 0.05 * t_s]


def _bag(path: Path, *, late: bool) -> Path:
    start = T0 + (LATE_NS if late else 0)
    period = 25_000_000 if late else 20_000_000
    spec = BagSpec()
    spec.types["/go"] = spec.types["/extra"] = "std_msgs/msg/String"
    spec.add("/robot_description", start, string(default_urdf_path().read_text()))
    for k in range(40 if late else 50):
        t = start + k * period
        spec.add("/joint_states", t, joint_state(t, NAMES, _values((t - start) / 1e9, late)))
    spec.add("/go", start + (500_000_000 if late else 300_000_000) + 1, string("go"))
    if late:
        for k in range(5):
            spec.add("/extra", start + k * 100_000_000 + 2, string("x"))
    spec.messages.sort(key=lambda m: m[1])
    return write_bag(path, spec)


def _made(folder: Path) -> None:
    a, b = _bag(folder / "a", late=False), _bag(folder / "b", late=True)
    runs = {
        "compare": ["--plot", PLOT, "--save", str(folder / "compare.rrd")],
        "summary": ["--plot", PLOT, "--summary"],
        "align": ["--align", "/go", "--save", str(folder / "align.rrd")],
    }
    for name, args in runs.items():
        result = cli("--compare", str(a), str(b), *args)
        assert result.returncode == 0, result.stderr
        (folder / f"{name}.out").write_text(result.stdout)


@pytest.fixture(scope="module")
def made(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return made_once(tmp_path_factory, "compare-two-runs", _made)


def _decoded(bag: Path, topic: str) -> list[tuple[int, object]]:
    """(receive ns, message) of ``topic``, by rosbags."""
    with Reader(bag) as reader:
        connections = [c for c in reader.connections if c.topic == topic]
        return [(t, TS.deserialize_cdr(raw, c.msgtype)) for c, t, raw in reader.messages(connections=connections)]


def test_both_robots_are_each_bags_own_forward_kinematics_at_the_aligned_times(made: Path) -> None:
    recording = read_recording(made / "compare.rrd")
    model = yourdfpy.URDF.load(str(default_urdf_path()), load_meshes=False)
    worst = 0.0
    for name, start in (("a", T0), ("b", T0 + LATE_NS)):
        states = _decoded(made / name, "/joint_states")
        for t, msg in states[::9]:
            model.update_cfg(dict(zip(msg.name, msg.position, strict=True)))  # type: ignore[attr-defined]
            edges = frame_edges_at(recording, t - start)  # aligned at their starts: time since each one's start
            for link in model.link_map:
                expected = model.get_transform(frame_to=link, frame_from=model.base_link)
                worst = max(worst, float(np.abs(pose_in(edges, f"{name}/{link}", "compare") - expected).max()))
    assert worst <= 1e-6


def test_the_second_robot_is_a_translucent_tinted_ghost_the_first_as_it_is(made: Path) -> None:
    recording = read_recording(made / "compare.rrd")
    first = recording["/runs/a/robot/visual/body/0"].static["Mesh3D:albedo_factor"][-1][0]
    ghost = recording["/runs/b/robot/visual/body/0"].static["Mesh3D:albedo_factor"][-1][0]
    assert first == 0xFFFFFFFF  # the URDF's "white" material: rgba 1 1 1 1
    assert ghost & 0xFF == GHOST_ALPHA and ghost >> 8 != 0xFFFFFF
    assert recording["/runs/b/robot/visual/body/0"].static["CoordinateFrame:frame"][-1] == ["b/body"]


def test_both_series_of_the_plot_are_in_one_view_with_rosbags_values(made: Path) -> None:
    recording = read_recording(made / "compare.rrd")
    for name, start in (("a", T0), ("b", T0 + LATE_NS)):
        rows = recording[f"/runs/{name}/{PLOT_ENTITY}"]
        expected = _decoded(made / name, "/joint_states")
        assert rows.times == [t - start for t, _ in expected]
        assert np.allclose([v[0] for v in rows.temporal["Scalars:scalars"]], [m.position[0] for _, m in expected])  # type: ignore[attr-defined]
        assert rows.static["SeriesLines:names"][-1] == [f"{PLOT} ({name})"]
    views = blueprint_components(made / "compare.rrd")
    queries = [c.get("ViewContents:query") for c in views.values() if c.get("ViewContents:query")]
    plot = [q for q in queries if any("plot/0" in line for line in q)]
    assert len(plot) == 1 and {f"+ /runs/{n}/plot/0/**" for n in "ab"} <= set(plot[0])


def test_align_lines_up_the_topics_first_messages(made: Path) -> None:
    recording = read_recording(made / "align.rrd")
    go, first_state = {}, {}
    for name in "ab":
        rows = recording[f"/runs/{name}/go"]  # the String topic, a log (TextLog rows: its text)
        go[name] = rows.times[rows.temporal["TextLog:text"].index(["go"])]
        (t_go, _), *_ = _decoded(made / name, "/go")
        (t_state, _), *_ = _decoded(made / name, "/joint_states")
        first_state[name] = recording[f"/runs/{name}/joints/continuous"].times[0] - (t_state - t_go)
    assert abs(go["a"] - go["b"]) <= 20_000_000  # within one message period
    assert go == first_state == {"a": 0, "b": 0}  # the time shown: since the alignment point


def test_the_summary_names_the_extra_topic_the_counts_and_the_largest_difference(made: Path) -> None:
    lines = (made / "summary.out").read_text().splitlines()
    assert "topics only in b: /extra" in lines
    counts = {
        m.group(1): m.group(2) for line in lines if (m := re.match(r"(/\S+): .*\(count difference: (.*)\)", line))
    }
    assert counts["/extra"] == "b +5" and counts["/joint_states"] == "b -10" and counts["/go"] == "b +0"
    (line,) = [line for line in lines if line.startswith(f"series {PLOT}:")]
    shown = float(re.search(r"largest difference from a: b (\S+) at", line).group(1))  # type: ignore[union-attr]
    a, b = (_decoded(made / n, "/joint_states") for n in "ab")
    ta = np.array([t - T0 for t, _ in a], float)
    tb = np.array([t - T0 - LATE_NS for t, _ in b], float)
    va = np.array([m.position[0] for _, m in a])  # type: ignore[attr-defined]
    vb = np.array([m.position[0] for _, m in b])  # type: ignore[attr-defined]
    inside = ta <= tb[-1]
    expected = np.abs(np.interp(ta[inside], tb, vb) - va[inside]).max()
    assert abs(shown - expected) <= 1e-9


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["one"], "--compare needs two runs or more, got 1"),
        (["a", "b", "--align", "/nope"], "--align /nope: no run has that topic"),
        (["a", "b", "--align", "/extra"], "--align /extra: run a has no message on that topic"),
        (["a", "b", "--offset", "c=1"], "--offset 'c=1': no run named 'c' (runs: a, b)"),
        (["a", "b", "--offset", "b=soon"], "--offset 'b=soon': 'soon' is not a number of seconds"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(made: Path, args: list[str], says: str) -> None:
    paths = [str(made / a) if a in ("a", "b") else a for a in args]
    if paths[0] == "one":
        paths[0] = str(made / "a")
    result: subprocess.CompletedProcess[str] = cli("--compare", *paths, "--summary", timeout=60)
    assert result.returncode == 2
    assert result.stderr.splitlines() == [f"error: {says}"]
    assert result.stdout == ""


def test_side_by_side_spaces_the_runs_by_the_first_runs_camera_distance() -> None:
    from r2d2_viz.run.compare import _spacing

    eye = {"position": [3.0, 4.0, 0.0], "look_target": [0.0, 0.0, 0.0], "eye_up": [0.0, 0.0, 1.0]}
    assert _spacing(eye) == pytest.approx(0.6 * 5.0)  # |(3, 4, 0)| = 5 m, by hand
    assert _spacing({"position": [0.1, 0.0, 0.0], "look_target": [0.0, 0.0, 0.0]}) == 1.0  # at least 1 m
    assert _spacing({}) == 1.0


def test_a_recording_the_app_wrote_is_a_run_too(made: Path, tmp_path: Path) -> None:
    """``a`` as the ``.rrd`` that ``--bag a --plot …`` wrote: the same plotted series, hence the same figures as
    the bag itself gave (its "topics" are then its entities)."""
    rrd = tmp_path / "a.rrd"
    assert cli("--bag", str(made / "a"), "--plot", PLOT, "--save", str(rrd)).returncode == 0
    result = cli("--compare", str(rrd), str(made / "b"), "--plot", PLOT, "--summary")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[1] == "duration: a 0.98 s · b 0.975 s"  # 49 × 20 ms; 39 × 25 ms
    bag_lines = (made / "summary.out").read_text().splitlines()
    for name in (PLOT, "swivel", "tilt"):
        (mine,) = [line for line in lines if line.startswith(f"series {name}:")]
        assert mine in bag_lines
