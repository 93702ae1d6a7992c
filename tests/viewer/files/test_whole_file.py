"""A small output file written whole: a hidden partial renamed over the target, never written through a symlink,
and a failed write (here the disk's ENOSPC, injected into ``os.write``; a real full tmpfs in
tests/cli/test_system_hostile.py) leaves nothing but the older file."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from r2d2_viz.viewer.files import whole_file
from r2d2_viz.viewer.files.whole_file import NotWrittenError, check_target, partial_of, write_whole


def test_written_whole_and_replacing(tmp_path: Path) -> None:
    target = tmp_path / "t.dot"
    write_whole(target, b"one")
    write_whole(target, b"two")
    assert target.read_bytes() == b"two" and [p.name for p in tmp_path.iterdir()] == ["t.dot"]


def test_a_symlink_is_replaced_and_its_file_untouched(tmp_path: Path) -> None:
    victim, target = tmp_path / "victim", tmp_path / "t.dot"
    victim.write_text("keep")
    target.symlink_to(victim)
    write_whole(target, b"graph")
    assert victim.read_text() == "keep" and not target.is_symlink() and target.read_bytes() == b"graph"


def test_a_planted_partial_is_not_followed(tmp_path: Path) -> None:
    victim, target = tmp_path / "victim", tmp_path / "t.dot"
    victim.write_text("keep")
    partial_of(target).symlink_to(victim)
    with pytest.raises(NotWrittenError, match=r"t\.dot: not written: file exists"):
        write_whole(target, b"graph")
    assert victim.read_text() == "keep" and not target.exists()


def test_a_failed_write_leaves_the_older_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "t.dot"
    target.write_text("older")

    def full(fd: int, data: object) -> int:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(whole_file.os, "write", full)
    with pytest.raises(NotWrittenError, match=r"t\.dot: not written: no space left on device$"):
        write_whole(target, b"x" * 100)
    assert target.read_text() == "older" and [p.name for p in tmp_path.iterdir()] == ["t.dot"]


def test_bad_targets(tmp_path: Path) -> None:
    with pytest.raises(NotWrittenError, match="no such directory"):
        check_target(tmp_path / "none" / "t.dot")
    (tmp_path / "d.dot").mkdir()
    with pytest.raises(NotWrittenError, match=r"d\.dot: not written: is a directory"):
        check_target(tmp_path / "d.dot")
    check_target(tmp_path / "t.dot")
    assert [p.name for p in tmp_path.iterdir()] == ["d.dot"]  # the probe's partial removed
