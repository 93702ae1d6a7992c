"""The disk cache of converted meshes: location, staleness, failure to write (see also tests/test_meshes.py for
content keys, corruption and deletion on real meshes)."""

from __future__ import annotations

from pathlib import Path

import pytest
from meshdata import FINGER

from r2d2_viz.meshes.assets import MeshCache
from r2d2_viz.meshes.disk_cache import APP_DIR, DiskCache, default_cache_dir, sha256


def test_disk_cache_entry_is_stale_when_a_file_it_read_changed(tmp_path: Path) -> None:
    disk = DiskCache(tmp_path)
    key = "ab12"
    disk.put(key, b"payload", {"texture.png": sha256(b"old texture")})
    assert disk.get(key, lambda name: b"old texture") == b"payload"
    assert disk.get(key, lambda name: b"new texture") is None
    assert disk.get(key, lambda name: None) is None
    with pytest.raises(ValueError):
        disk.path("../escape")


def test_unwritable_cache_folder_is_not_an_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    assert MeshCache(DiskCache(blocker / "cache")).asset(FINGER).media_type == "model/gltf-binary"


def test_cache_folder_follows_xdg(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert default_cache_dir() == tmp_path / APP_DIR
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/not/allowed")
    assert default_cache_dir() == Path.home() / ".cache" / "r2d2-viz"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert default_cache_dir() == Path.home() / ".cache" / "r2d2-viz"
    assert MeshCache().disk is not None and MeshCache().disk.directory == default_cache_dir()  # type: ignore[union-attr]
