"""Shared by the xacro tests: writing xacro files, expecting refusals, running plain xacro as the reference."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from lxml import etree

from r2d2_viz.errors import UrdfError, XacroError
from r2d2_viz.robot.xacro_load import load_description

FAKE_AMENT = """import json, os
def get_package_share_directory(name):
    return json.loads(os.environ["R2D2_TEST_PACKAGES"])[name]
"""


def canonical(xml: str | bytes) -> bytes:
    parser = etree.XMLParser(remove_blank_text=True, remove_comments=True, resolve_entities=False)
    data = xml.encode() if isinstance(xml, str) else xml
    return etree.tostring(etree.fromstring(data, parser), method="c14n")


def plain_xacro(tmp_path: Path, path: Path, args: dict[str, str], packages: dict[str, Path]) -> subprocess.Popen[str]:
    """Run the unmodified ``xacro`` command (the reference), with a stand-in ament index for $(find)."""
    exe = Path(sys.executable).parent / "xacro"
    if not exe.exists():
        pytest.skip("the xacro command is not installed beside python")
    (tmp_path / "ament_index_python").mkdir(exist_ok=True)
    (tmp_path / "ament_index_python" / "__init__.py").write_text("")
    (tmp_path / "ament_index_python" / "packages.py").write_text(FAKE_AMENT)
    env = {
        **os.environ,
        "PYTHONPATH": str(tmp_path),
        "R2D2_TEST_PACKAGES": json.dumps({k: str(v) for k, v in packages.items()}),
    }
    command = [str(exe), str(path), *(f"{k}:={v}" for k, v in args.items())]
    return subprocess.Popen(command, env=env, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def write(tmp_path: Path, body: str, name: str = "robot.urdf.xacro") -> Path:
    path = tmp_path / name
    head = '<?xml version="1.0"?>\n<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r">'
    path.write_text(f"{head}\n{body}\n</robot>\n")
    return path


def refusal(path: Path, **kwargs: object) -> str:
    with pytest.raises(XacroError) as info:
        load_description(path, **kwargs)  # type: ignore[arg-type]
    message = str(info.value)
    assert isinstance(info.value, UrdfError)
    assert "\n" not in message and len(message) < 1200
    return message
