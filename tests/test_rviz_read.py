"""Hostile or broken .rviz files: one line naming the file and the key, nothing run, nothing half-read."""

from __future__ import annotations

from pathlib import Path

import pytest

from r2d2_viz.rviz import RvizError, load_rviz, parse_rviz


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
