"""Hostile or broken .rviz files: one line naming the file and the key, nothing run, nothing half-read."""

from __future__ import annotations

from pathlib import Path

import pytest

from r2d2_viz.rviz.config import load_rviz, parse_rviz
from r2d2_viz.rviz.spec import RvizError


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("Panels: [\n  - {", "not YAML"),
        ("- just\n- a list\n", "not an RViz config"),
        ("Visualization Manager: 3\n", "no 'Visualization Manager'"),
        ("Visualization Manager:\n  Views:\n    Current:\n      Class: rviz/Orbit\n      Distance: far\n", "Distance"),
        ("Visualization Manager:\n  Displays:\n    - Class: rviz/Grid\n      Enabled: maybe\n", "Enabled"),
        ("Visualization Manager:\n  Displays: 7\n", "list of displays"),
        ("Visualization Manager:\n  Global Options:\n    Background Color: red\n", "Background Color"),
        ("!!python/object/apply:os.system ['touch PWNED']\n", "not YAML"),
    ],
)
def test_bad_configs_are_one_line(text: str, problem: str, tmp_path: Path) -> None:
    with pytest.raises(RvizError) as info:
        parse_rviz(text, source="bad.rviz")
    message = str(info.value)
    assert message.startswith("bad.rviz: ") and problem in message and "\n" not in message
    assert not (tmp_path / "PWNED").exists() and not Path("PWNED").exists()


def test_a_huge_config_is_refused_before_it_is_read(tmp_path: Path) -> None:
    big = tmp_path / "big.rviz"
    with big.open("wb") as f:
        f.truncate(5 * 1024 * 1024)
    with pytest.raises(RvizError, match="too large"):
        load_rviz(big)


def _view(body: str):
    spec = parse_rviz("Visualization Manager:\n  Views:\n    Current:\n" + body, source="v.rviz")
    assert spec.camera is not None
    return spec.camera, spec.notes


def test_orbit_with_invert_z_axis_negates_yaw_and_pitch() -> None:
    # OrbitViewController::updateCamera: inverted, yaw → −yaw and pitch → −pitch, camera yaw axis −Z.
    # Distance 2, Yaw 0, Pitch 0.5 about the origin: eye (2 cos 0.5, 0, −2 sin 0.5) = (1.7552, 0, −0.9589)
    camera, _ = _view(
        "      Class: rviz_default_plugins/Orbit\n      Distance: 2\n      Yaw: 0\n      Pitch: 0.5\n"
        "      Invert Z Axis: true\n"
    )
    assert camera.eye == pytest.approx((1.7551651, 0.0, -0.9588511)) and camera.up == (0.0, 0.0, -1.0)


def test_third_person_follower_is_lifted_and_follows_its_frame() -> None:
    # Distance 10, Yaw 0, Pitch 0 around (1, 2, 0): the orbit eye (11, 2, 0), the camera's up +Z, lifted by
    # 0.2 × 10 = 2: eye (11, 2, 2), target (1, 2, 2)
    camera, notes = _view(
        "      Class: rviz_default_plugins/ThirdPersonFollower\n      Distance: 10\n      Yaw: 0\n"
        "      Pitch: 0\n      Focal Point: {X: 1, Y: 2, Z: 0}\n      Target Frame: base_link\n"
    )
    assert camera.eye == pytest.approx((11, 2, 2)) and camera.target == pytest.approx((1, 2, 2))
    assert camera.target_frame == "base_link" and any("not its yaw" in n for n in notes)


def test_fps_looks_along_yaw_and_pitch_with_roll() -> None:
    # FPSViewController: yaw about Z, then pitch about Y (tipped downward), then roll about X. Yaw π/2, Pitch
    # π/6, Roll 0 from (1, 1, 1): forward (0, cos 30°, −sin 30°) = (0, 0.866, −0.5), up (0, sin 30°, cos 30°)
    camera, _ = _view(
        "      Class: rviz/FPS\n      Position: {X: 1, Y: 1, Z: 1}\n      Yaw: 1.5707963267948966\n"
        "      Pitch: 0.5235987755982988\n"
    )
    assert camera.eye == (1, 1, 1) and not camera.orbit
    assert camera.target == pytest.approx((1, 1.8660254, 0.5)) and camera.up == pytest.approx((0, 0.5, 0.8660254))
    # Roll π/2 with yaw and pitch 0: looking along +X, the camera's up turned from +Z to −Y
    rolled, _ = _view("      Class: rviz/FPS\n      Yaw: 0\n      Pitch: 0\n      Roll: 1.5707963267948966\n")
    assert rolled.up == pytest.approx((0, -1, 0), abs=1e-12)


def test_top_down_ortho_is_marked_orthographic() -> None:
    camera, notes = _view("      Class: rviz_default_plugins/TopDownOrtho\n      Scale: 100\n      X: 3\n      Y: 4\n")
    assert camera.orthographic and camera.target == (3, 4, 0) and any("no orthographic" in n for n in notes)


@pytest.mark.parametrize(
    ("body", "key"),
    [
        ("      Class: rviz/Orbit\n      Invert Z Axis: 1\n", "Invert Z Axis"),
        ("      Class: rviz/FPS\n      Position: [1, 2, 3]\n", "Position"),
        ("      Class: rviz/Orbit\n      Field of View: .nan\n", "Field of View"),
    ],
)
def test_wrong_types_in_a_view_name_the_key(body: str, key: str) -> None:
    with pytest.raises(RvizError, match=f"v.rviz: Views / Current .*{key}"):
        _view(body)
