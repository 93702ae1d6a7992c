"""The default recording, read back with Rerun's reader, against an independent reference.

Reference: the tutorial's state_publisher.py ported line by line (tests/reference.py) for the joint
states and odom → axis, and yourdfpy's forward kinematics for robot_state_publisher. Every link's pose
is composed through the recording's *named frames* (Transform3D parent_frame / child_frame), from odom.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from conftest import cli
from reference import state_publisher
from rrd import Rows, pose, read_recording, static_edges, tf_by_child

LINKS = ("axis", "leg1", "leg2", "body", "head", "rod", "box")
N_FRAMES = 1440  # one lap: 360° / (¼° per frame)


@pytest.fixture(scope="module")
def recording(lap_recording: tuple[Path, object]) -> dict[str, Rows]:
    return read_recording(lap_recording[0])


@pytest.fixture(scope="module")
def round_trip(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Rows]:
    """``r2d2-viz --save lap.mcap`` (a ROS 2 bag), then ``r2d2-viz --bag lap.mcap --save lap.rrd``: the robot from
    the bag's /robot_description, its joints from /joint_states, odom → axis from /tf."""
    tmp = tmp_path_factory.mktemp("round_trip")
    for args in (["--save", str(tmp / "lap.mcap")], ["--bag", str(tmp / "lap.mcap"), "--save", str(tmp / "lap.rrd")]):
        result = cli(*args)
        assert result.returncode == 0, result.stderr
    return read_recording(tmp / "lap.rrd")


def test_one_lap_is_1440_frames_on_the_time_timeline(recording: dict[str, Rows]) -> None:
    times = tf_by_child(recording)["axis"].times
    assert len(times) == N_FRAMES
    expected = np.rint(np.arange(N_FRAMES) * 1e9 / 30).astype(np.int64)
    assert np.array_equal(times, expected)  # frame k at t = k / 30 s


def test_fixed_joints_are_static_and_moving_ones_are_not(recording: dict[str, Rows]) -> None:
    static = static_edges(recording)
    for child, parent in (("leg1", "axis"), ("leg2", "axis"), ("box", "rod")):
        assert static[child][0] == parent
    temporal_children = {
        child[0] for rows in recording.values() for child in rows.temporal.get("Transform3D:child_frame", [])
    }
    assert temporal_children == {"axis", "body", "head", "rod"}  # odom→axis, tilt, swivel, periscope
    assert set(tf_by_child(recording)) == temporal_children  # all on /tf, as on the /tf topic


@pytest.mark.parametrize("made", ["recording", "round_trip"])
def test_every_link_pose_matches_state_publisher_and_robot_state_publisher(
    made: str, tutorial_urdf: Path, request: pytest.FixtureRequest
) -> None:
    recording: dict[str, Rows] = request.getfixturevalue(made)
    static = static_edges(recording)
    moving = tf_by_child(recording)
    for child, rows in moving.items():
        assert len(rows.times) == N_FRAMES, child

    reference = state_publisher(N_FRAMES)
    urdf = yourdfpy.URDF.load(str(tutorial_urdf), load_meshes=False)
    worst_m = worst_rad = 0.0
    for k in range(N_FRAMES):
        edges = dict(static)
        for child, rows in moving.items():
            edges[child] = (
                rows.temporal["Transform3D:parent_frame"][k][0],
                pose(rows.temporal["Transform3D:translation"][k][0], rows.temporal["Transform3D:quaternion"][k][0]),
            )

        def in_odom(frame: str, edges: dict[str, tuple[str, np.ndarray]] = edges) -> np.ndarray:
            T = np.eye(4)
            while frame != "odom":
                parent, T_parent_frame = edges[frame]
                T = T_parent_frame @ T
                frame = parent
            return T

        ref = reference[k]
        T_odom_axis = pose(list(ref["odom_translation"]), list(ref["odom_rotation_xyzw"]))  # type: ignore[arg-type]
        urdf.update_cfg(ref["joint_state"])
        for link in LINKS:
            expected = T_odom_axis @ urdf.get_transform(frame_to=link, frame_from="axis")
            got = in_odom(link)
            worst_m = max(worst_m, float(np.abs(got[:3, 3] - expected[:3, 3]).max()))
            cos_angle = (np.trace(got[:3, :3].T @ expected[:3, :3]) - 1) / 2
            worst_rad = max(worst_rad, float(np.arccos(np.clip(cos_angle, -1, 1))))
    assert worst_m < 1e-5
    assert worst_rad < 1e-5


def test_periscope_is_not_clamped_and_the_excursion_is_reported_once(lap_recording, recording) -> None:
    names = recording["/joints/limited"].static["SeriesLines:names"][-1]
    column = names.index("periscope")
    values = np.array([v[column] for v in recording["/joints/limited"].temporal["Scalars:scalars"]])
    assert values.max() == pytest.approx(0.2, abs=1e-9)  # URDF upper limit is 0: not clamped
    assert values.min() == pytest.approx(0.0, abs=1e-9)
    limits = recording["/joints/limited/limits"]  # every limit line, two series per limited joint
    line_names = limits.static["SeriesLines:names"][-1]
    assert line_names == [f"{j} {b} limit" for j in ("tilt", "periscope") for b in ("lower", "upper")]
    rows = limits.temporal["Scalars:scalars"]
    lower, upper = line_names.index("periscope lower limit"), line_names.index("periscope upper limit")
    assert {row[lower] for row in rows} == {-0.5} and {row[upper] for row in rows} == {0.0}
    # the lines span the plot: from the first frame to the last
    assert limits.times[0] == 0 and limits.times[-1] == recording["/joints/limited"].times[-1]
    texts = [t[0] for t in recording["/warnings"].temporal["TextLog:text"]]
    assert sum("'periscope'" in t for t in texts) == 1
    stderr = lap_recording[1].stderr
    assert stderr.count("'periscope' left its URDF limits") == 1
    rod_translations = np.array([t[0] for t in tf_by_child(recording)["rod"].temporal["Transform3D:translation"]])
    assert rod_translations[:, 2].max() == pytest.approx(0.15 + 0.2, abs=1e-6)  # origin z + unclamped 0.2


def test_visuals_are_meshes_with_normals_colours_and_link_frames(recording: dict[str, Rows]) -> None:
    colours = {}
    for link in LINKS:
        rows = recording[f"/robot/visual/{link}/0"].static
        assert rows["CoordinateFrame:frame"][-1] == [link]
        positions = np.array(rows["Mesh3D:vertex_positions"][-1])
        normals = np.array(rows["Mesh3D:vertex_normals"][-1])
        assert positions.shape == normals.shape and len(positions) >= 24
        assert np.allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-5)
        colours[link] = rows["Mesh3D:albedo_factor"][-1][0]
    white, gray, blue = 0xFFFFFFFF, 0x333333FF, 0x0000FFFF  # rgba "1 1 1 1", ".2 .2 .2 1", "0 0 1 1"
    assert colours == {
        "axis": gray,
        "leg1": white,
        "leg2": white,
        "body": white,
        "head": white,
        "rod": gray,
        "box": blue,
    }
    # body's visual sits 0.2 m below its frame, its collision 0.2 m above (as the tutorial's URDF says)
    body_visual = np.array(recording["/robot/visual/body/0"].static["Mesh3D:vertex_positions"][-1])
    body_collision = np.array(recording["/robot/collision/body/0"].static["Mesh3D:vertex_positions"][-1])
    assert body_visual[:, 2].min() == pytest.approx(-0.5, abs=1e-6) and body_visual[:, 2].max() == pytest.approx(0.1)
    assert body_collision[:, 2].min() == pytest.approx(-0.1, abs=1e-6)


def test_tf_display_axes_on_every_frame_names_off_and_arrows_to_parents(recording: dict[str, Rows]) -> None:
    for frame in ("odom", *LINKS):
        rows = recording[f"/tf_axes/{frame}"].static
        assert rows["CoordinateFrame:frame"][-1] == [frame]
        assert rows["TransformAxes3D:show_frame"][-1] == [False]
    # leg1 hangs 0.3 m to the side of axis: its arrow points from leg1's origin back to axis's.
    leg1 = recording["/tf_arrows/leg1"].static
    assert leg1["CoordinateFrame:frame"][-1] == ["axis"]
    assert np.allclose(leg1["Arrows3D:origins"][-1][0], [0, 0.3, 0], atol=1e-6)
    assert np.allclose(leg1["Arrows3D:vectors"][-1][0], [0, -0.3, 0], atol=1e-6)
    # odom → axis and head → rod (prismatic) move every frame: their arrows are drawn per frame in odom, on
    # /tf (one chunk a frame), in the first of each frame's rows; the other rows hold no arrows (null).
    moving = recording["/tf"]
    assert moving.static["CoordinateFrame:frame"][-1] == ["odom"]
    cells = moving.temporal["Arrows3D:origins"]
    with_arrows = [i for i, cell in enumerate(cells) if cell is not None]
    rows = 4  # swivel, tilt, periscope and odom → axis
    assert len(cells) == rows * N_FRAMES and with_arrows == list(range(0, rows * N_FRAMES, rows))
    assert [moving.times[i] for i in with_arrows] == sorted(set(moving.times))  # one set of arrows per frame
    origins = np.array([cells[i] for i in with_arrows])  # (frames, 2 arrows, 3)
    vectors = np.array([moving.temporal["Arrows3D:vectors"][i] for i in with_arrows])
    assert origins.shape == (N_FRAMES, 2, 3)
    reference = state_publisher(N_FRAMES)
    odom_t = np.array([r["odom_translation"] for r in reference])
    root = [i for i in range(2) if np.allclose(origins[:, i], odom_t, atol=1e-5)]  # axis's origin, in odom
    assert len(root) == 1 and np.allclose(vectors[:, root[0]], -odom_t, atol=1e-5)
    rod = 1 - root[0]
    periscope = np.array([r["joint_state"]["periscope"] for r in reference])
    expected = np.hypot(0.12, 0.15 + periscope)  # |t_head_rod|: origin (.12, 0, .15) + periscope along z
    assert np.allclose(np.linalg.norm(vectors[:, rod], axis=1), expected, atol=1e-5)
