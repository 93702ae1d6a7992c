"""``--watch``'s poller and the files a description is made of: the poller driven by an injected clock and stat
(no sleeping), the files by a xacro tree written here (what it includes and loads is known by construction)."""

from __future__ import annotations

from pathlib import Path

import pytest

from r2d2_viz.errors import XacroError
from r2d2_viz.robot.watch import FileWatcher, Signature, robot_files, stat_signature
from r2d2_viz.robot.xacro_load import load_robot


class Disk:
    """Files' signatures as the test sets them, and a clock the test moves."""

    def __init__(self) -> None:
        self.sig: dict[Path, Signature] = {}
        self.now = 0.0

    def stat(self, path: Path) -> Signature:
        return self.sig.get(path)

    def clock(self) -> float:
        return self.now


def _watcher(disk: Disk, *files: Path) -> FileWatcher:
    return FileWatcher(files, stat=disk.stat, clock=disk.clock, period=0.25, settle=0.2)


def _polls(watcher: FileWatcher, disk: Disk, n: int) -> list[bool]:
    seen = []
    for _ in range(n):
        disk.now += 0.25
        seen.append(watcher.changed())
    return seen


def test_a_change_is_reported_once_after_it_settles() -> None:
    disk, a = Disk(), Path("/a.urdf")
    disk.sig[a] = (1, 10)
    watcher = _watcher(disk, a)
    assert _polls(watcher, disk, 3) == [False, False, False]
    disk.sig[a] = (2, 12)
    # seen at the first poll, unchanged at the second (0.25 s ≥ 0.2 s settle): reported then, and only then
    assert _polls(watcher, disk, 4) == [False, True, False, False]


def test_a_file_changed_after_the_robot_was_read_but_before_the_watch_began_is_a_change() -> None:
    """Issue 44, item 13: a live run's watch begins after its recording opens; a description replaced by a FIFO in
    between was the watch's reference, so nothing was ever said (by hand: mtimes either side of ``since_ns``)."""
    disk, edited, kept = Disk(), Path("/edited.urdf"), Path("/kept.stl")
    disk.sig[edited], disk.sig[kept] = (2_000, 0), (500, 10)
    watcher = FileWatcher([edited, kept], stat=disk.stat, clock=disk.clock, period=0.25, settle=0.2, since_ns=1_000)
    assert _polls(watcher, disk, 4) == [False, True, False, False]  # seen, settled, reported once
    quiet = FileWatcher([kept], stat=disk.stat, clock=disk.clock, period=0.25, settle=0.2, since_ns=1_000)
    assert _polls(quiet, disk, 4) == [False] * 4


def test_a_half_written_file_is_not_loaded_until_it_stops_changing() -> None:
    disk, a = Disk(), Path("/a.urdf")
    disk.sig[a] = (1, 10)
    watcher = _watcher(disk, a)
    reports = []
    for size in (3, 7, 11, 15):  # an editor writing in four pieces, one a poll
        disk.sig[a] = (size, size)
        reports += _polls(watcher, disk, 1)
    reports += _polls(watcher, disk, 3)
    assert reports == [False] * 4 + [True, False, False]  # once, when it stayed the same


def test_polls_are_at_most_every_period_and_a_deleted_file_is_a_change() -> None:
    disk, a = Disk(), Path("/a.urdf")
    disk.sig[a] = (1, 10)
    calls: list[Path] = []

    def stat(path: Path) -> Signature:
        calls.append(path)
        return disk.stat(path)

    watcher = FileWatcher([a], stat=stat, clock=disk.clock, period=0.25, settle=0.2)
    calls.clear()
    for _ in range(10):  # the run asks before every sample: the disk is looked at once
        watcher.changed()
    assert len(calls) == 1
    del disk.sig[a]
    assert _polls(watcher, disk, 2) == [False, True]


def test_stat_signature_is_mtime_and_size(tmp_path: Path) -> None:
    f = tmp_path / "x"
    f.write_bytes(b"12345")
    st = f.stat()
    assert stat_signature(f) == (st.st_mtime_ns, 5)
    assert stat_signature(tmp_path / "missing") is None


XACRO = """<robot name="w" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:include filename="parts/arm.xacro"/>
  <xacro:property name="dims" value="${xacro.load_yaml('dims.yaml')}"/>
  <link name="base"><visual><geometry><box size="${dims['side']} 1 1"/></geometry></visual></link>
  <xacro:arm parent="base"/>
</robot>"""
ARM = """<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="arm" params="parent">
    <link name="arm"><visual><geometry><mesh filename="meshes/arm.stl"/></geometry></visual></link>
    <joint name="j" type="fixed"><parent link="${parent}"/><child link="arm"/></joint>
  </xacro:macro>
</robot>"""
STL = (
    "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n"
)


def write_xacro_tree(root: Path) -> Path:
    """robot.xacro, which includes parts/arm.xacro and loads dims.yaml; the arm's mesh meshes/arm.stl."""
    (root / "parts").mkdir()
    (root / "meshes").mkdir()
    (root / "parts" / "arm.xacro").write_text(ARM)
    (root / "dims.yaml").write_text("side: 0.5\n")
    (root / "meshes" / "arm.stl").write_text(STL)
    path = root / "robot.xacro"
    path.write_text(XACRO)
    return path


def test_the_files_of_a_xacro_robot_are_its_includes_yaml_and_meshes(tmp_path: Path) -> None:
    path = write_xacro_tree(tmp_path)
    read: list[Path] = []
    robot = load_robot(path, read=read)
    assert {p.resolve() for p in read} == {tmp_path / "parts" / "arm.xacro", tmp_path / "dims.yaml"}
    files = {p.resolve() for p in robot_files(path, robot, read)}  # a relative mesh: from the description's folder
    assert files == {tmp_path / f for f in ("robot.xacro", "parts/arm.xacro", "dims.yaml", "meshes/arm.stl")}


def test_a_mesh_the_robot_uses_is_watched(tmp_path: Path) -> None:
    (tmp_path / "arm.stl").write_text(STL)
    urdf = tmp_path / "r.urdf"
    urdf.write_text('<robot name="r"><link name="a"><visual><geometry><mesh filename="arm.stl"/></geometry>'
                    "</visual></link></robot>")  # fmt: skip
    files = robot_files(urdf, load_robot(urdf))
    assert {p.resolve() for p in files} == {urdf, tmp_path / "arm.stl"}


def test_a_broken_include_is_among_the_files_read(tmp_path: Path) -> None:
    path = write_xacro_tree(tmp_path)
    (tmp_path / "parts" / "arm.xacro").write_text(ARM.replace("</xacro:macro>", ""))  # not well-formed
    read: list[Path] = []
    with pytest.raises(XacroError, match=r"arm\.xacro"):
        load_robot(path, read=read)
    assert tmp_path / "parts" / "arm.xacro" in {p.resolve() for p in read}


def test_an_edit_made_while_the_robot_loads_is_seen_after_the_files_are_watched_again(tmp_path: Path) -> None:
    """Issue 44, item 13: a live run loads an edit in a thread; the files watched again afterwards keep what they were
    when the change was reported, so an edit made during the load is seen (not taken as the new reference)."""
    path = tmp_path / "r.urdf"
    path.write_text("a")
    now = [0.0]
    watcher = FileWatcher([path], clock=lambda: now[0], period=0.25, settle=0.2)
    path.write_text("bb")
    for t in (0.3, 0.6):
        now[0] = t
        reported = watcher.changed()
    assert reported  # the first edit, settled
    path.write_text("ccc")  # edited again while the robot loads
    watcher.watch([path, tmp_path / "missing.stl"])  # the load is done: its files watched from now on
    for t in (0.9, 1.2):
        now[0] = t
        reported = watcher.changed()
    assert reported
