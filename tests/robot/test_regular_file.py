"""Files the user names are read only when regular: a FIFO is refused at once, never opened to wait for a writer
(issue 44, item 13: a description replaced by a FIFO under ``--watch`` held the app for good)."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

from r2d2_viz.errors import UrdfError
from r2d2_viz.meshes.assets import MeshCache
from r2d2_viz.robot.regular_file import NotRegularFileError, read_regular
from r2d2_viz.robot.urdf_xml import read_urdf_xml
from r2d2_viz.robot.xacro_load import load_robot, read_bounded


def _returns_soon(call: Callable[[], object], fifo: Path) -> BaseException | None:
    """``call()`` in a thread: what it raised, asserting it returned within 10 s (a blocked open is then released by
    opening the FIFO's other end, so the test does not leave a thread behind)."""
    caught: list[BaseException | None] = [None]

    def run() -> None:
        try:
            call()
        except BaseException as exc:
            caught[0] = exc

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(10)
    blocked = thread.is_alive()
    if blocked:
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        thread.join(10)
    assert not blocked, "the FIFO was opened (it waits for a writer)"
    return caught[0]


def test_a_regular_file_is_read_up_to_one_byte_over_its_limit(tmp_path: Path) -> None:
    path = tmp_path / "r.urdf"
    path.write_bytes(b"x" * 100)
    assert read_regular(path, 1000) == b"x" * 100
    assert read_regular(path, 10) == b"x" * 11  # one more than the limit: it is larger


def test_a_fifo_and_a_directory_are_refused_without_opening_them_to_wait(tmp_path: Path) -> None:
    fifo = tmp_path / "r.urdf"
    os.mkfifo(fifo)
    assert isinstance(_returns_soon(lambda: read_regular(fifo, 10), fifo), NotRegularFileError)
    with pytest.raises(IsADirectoryError):
        read_regular(tmp_path, 10)


@pytest.mark.parametrize(
    "load",
    [read_bounded, read_urdf_xml, load_robot, lambda p: MeshCache(disk=None).read(p)],
    ids=["read_bounded", "read_urdf_xml", "load_robot", "mesh"],
)
def test_the_readers_of_descriptions_and_meshes_refuse_a_fifo(tmp_path: Path, load: Callable[[Path], object]) -> None:
    fifo = tmp_path / "r.urdf"
    os.mkfifo(fifo)
    error = _returns_soon(lambda: load(fifo), fifo)
    assert isinstance(error, (UrdfError, ValueError)) and "not a regular file" in str(error)
