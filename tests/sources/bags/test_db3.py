""".db3 bags read without writing a byte beside them: WAL-mode databases in read-only folders, a recorder's unfinished
write-ahead log, folder names that are special in an SQLite URI. The bags are rosbags' (its writer); the WAL mode and
the unfinished log are made with Python's own sqlite3, as rosbag2's ``resilient`` preset and a killed recorder leave
them."""

from __future__ import annotations

import os
import shutil
import sqlite3
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from bagmaker import T0, BagSpec, joint_state, storage_file, write_bag

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.bags.db3 import readonly_uri

TIMES = [T0 + k * 10**7 for k in range(20)]


def _wal_bag(path: Path) -> Path:
    """A rosbags .db3 bag of 20 joint states, switched to WAL mode (file format bytes 18-19 become 2, 2)."""
    spec = BagSpec()
    for t in TIMES:
        spec.add("/joint_states", t, joint_state(t, ["a"], [float(t - T0)]))
    write_bag(path, spec, storage="sqlite3")
    db = sqlite3.connect(storage_file(path))
    assert db.execute("PRAGMA journal_mode=WAL").fetchone() == ("wal",)
    db.close()
    assert storage_file(path).read_bytes()[18:20] == b"\x02\x02"
    return path


def _listing(folder: Path) -> dict[str, tuple[int, int]]:
    return {p.name: (p.stat().st_size, p.stat().st_mtime_ns) for p in folder.iterdir()}


READ = """
import sys
from r2d2_viz.sources.bags.bag import open_bag
with open_bag(sys.argv[1]) as bag:
    print(len(list(bag.raw("/joint_states"))))
"""
PLAIN_SQLITE = """
import sqlite3, sys
print(sqlite3.connect(f"file:{sys.argv[1]}?mode=ro", uri=True).execute("SELECT count(*) FROM messages").fetchone()[0])
"""


@pytest.fixture
def readonly_folder() -> Iterator[Path]:
    """A folder under /tmp that the reading process cannot write (mode 555; as root, the test reads as nobody)."""
    top = Path(tempfile.mkdtemp(prefix="r2d2-ro-"))
    top.chmod(0o755)
    try:
        yield top / "bag"
    finally:
        for p in [top, *top.rglob("*")]:
            p.chmod(0o755)
        shutil.rmtree(top)


def _as_reader(script: str, *args: str) -> subprocess.CompletedProcess[str]:
    prefix: list[str] = []
    if os.geteuid() == 0:
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            pytest.skip("running as root without setpriv: cannot read as a user who may not write the folder")
        prefix = [setpriv, "--reuid=65534", "--regid=65534", "--clear-groups"]
    return subprocess.run(
        [*prefix, sys.executable, "-c", script, *args], capture_output=True, text=True, timeout=60, cwd="/"
    )


def test_wal_bag_in_a_readonly_folder(readonly_folder: Path) -> None:
    bag = _wal_bag(readonly_folder)
    for p in bag.iterdir():
        p.chmod(0o444)
    bag.chmod(0o555)
    before = _listing(bag)
    # the counter-check: plain read-only SQLite wants to create the -shm file here, and cannot
    plain = _as_reader(PLAIN_SQLITE, str(storage_file(bag)))
    if plain.returncode == 0:
        pytest.skip(f"the folder is writable to the reader after all: {plain.stdout!r}")
    assert "readonly" in plain.stderr or "unable to open" in plain.stderr, plain.stderr
    for form in (bag, storage_file(bag)):
        result = _as_reader(READ, str(form))
        assert result.returncode == 0, result.stderr
        assert result.stdout.split() == ["20"] and result.stderr == ""
    assert _listing(bag) == before


def test_wal_bag_leaves_no_file_beside_it(tmp_path: Path) -> None:
    """In a writable folder too: no -wal, -shm or -journal file appears, and no file changes."""
    bag = _wal_bag(tmp_path / "b")
    before = _listing(bag)
    with open_bag(bag) as opened:
        assert [t for t, _ in opened.raw("/joint_states")] == TIMES
        assert _listing(bag) == before  # also while it is open
    assert _listing(bag) == before


def test_unfinished_write_ahead_log_is_one_warning(tmp_path: Path) -> None:
    """A recorder killed in WAL mode: its last 5 messages are only in the -wal file, which is left alone."""
    bag = _wal_bag(tmp_path / "b")
    db3 = storage_file(bag)
    child = os.fork()
    if child == 0:  # pragma: no cover - the child writes 5 messages and dies without checkpointing
        db = sqlite3.connect(db3)
        db.execute("PRAGMA wal_autocheckpoint=0")
        for k in range(20, 25):
            t = T0 + k * 10**7
            db.execute(
                "INSERT INTO messages(topic_id, timestamp, data) VALUES (1, ?, ?)", (t, joint_state(t, ["a"], [k]))
            )
        db.commit()
        os._exit(0)
    os.waitpid(child, 0)
    assert (bag / f"{db3.name}-wal").stat().st_size > 0
    before = _listing(bag)
    warnings: list[str] = []
    with open_bag(bag, warn=warnings.append) as opened:
        assert [t for t, _ in opened.raw("/joint_states")] == TIMES  # what the database file itself holds
    assert len(warnings) == 1 and f"{db3.name}-wal" in warnings[0] and "not read" in warnings[0]
    assert "\n" not in warnings[0]
    assert _listing(bag) == before


@pytest.mark.parametrize("name", ["run#2", "what?", "100%", "100%25", "a b", "ünï"])
def test_folder_names_special_in_an_sqlite_uri(tmp_path: Path, name: str) -> None:
    """rosbags' writer and reader put the path into the URI unquoted ('#' and '?' end it, '%' escapes)."""
    bag = _wal_bag(tmp_path / "b").rename(tmp_path / name)
    for form in (bag, storage_file(bag)):
        with open_bag(form) as opened:
            assert [t for t, _ in opened.raw("/joint_states")] == TIMES


def test_readonly_uri_quotes_the_path() -> None:
    assert readonly_uri(Path("/a#b/c?d/e%f g.db3")) == "file:/a%23b/c%3Fd/e%25f%20g.db3?mode=ro&immutable=1"


def test_blocks_are_bounded_in_rows_and_bytes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import r2d2_viz.sources.bags.db3 as db3

    path = storage_file(_wal_bag(tmp_path / "b"))
    with open_bag(path) as bag:
        whole = [(t, bytes(d)) for t, d in bag.raw("/joint_states")]
        monkeypatch.setattr(db3, "BLOCK_ROWS", 6)
        blocks = list(bag.blocks(["/joint_states"]))
        assert [len(b) for b in blocks] == [6, 6, 6, 2]
        monkeypatch.setattr(db3, "BLOCK_ROWS", 1000)
        monkeypatch.setattr(db3, "BLOCK_BYTES", 3 * len(whole[0][1]))  # every message has the same length
        by_bytes = list(bag.blocks(["/joint_states"]))
        assert [len(b) for b in by_bytes] == [3] * 6 + [2]
    for parts in (blocks, by_bytes):
        assert [(t, bytes(d)) for b in parts for t, d in b.pairs()] == whole
    assert [t for t, _ in whole] == TIMES


def test_a_block_holds_its_rows_bytes_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 38: a .db3 block's bytes are the program's own memory (not a file's pages, as an mmapped MCAP's are), so
    gathering one must not hold its rows and their joined copy at once. 24 strings of 200 kB by rosbags' writer, read
    in blocks of about 1 MB: while one is read, Python allocates (tracemalloc) the block being gathered and the one
    before it (still held by the generators' frames until the next is handed out), not also the new block's rows
    beside their joined copy (three blocks, as before); the messages are rosbags' reader's."""
    import tracemalloc

    from bagmaker import string
    from rosbags.rosbag2 import Reader

    import r2d2_viz.sources.bags.db3 as db3

    spec = BagSpec(types={"/pad": "std_msgs/msg/String"})
    for k in range(24):
        spec.add("/pad", T0 + k, string(chr(65 + k) * 200_000))
    bag_dir = write_bag(tmp_path / "b", spec, storage="sqlite3")
    with Reader(bag_dir) as reader:
        expected = [(t, bytes(d)) for _, t, d in reader.messages()]
    monkeypatch.setattr(db3, "BLOCK_BYTES", 1_000_000)
    with open_bag(storage_file(bag_dir)) as bag:
        peaks, got = [], []
        tracemalloc.start()
        try:
            for block in bag.blocks(["/pad"]):  # each block dropped before the next is read
                peaks.append(tracemalloc.get_traced_memory()[1] - sum(len(d) for _, d in got))
                got += [(t, bytes(d)) for t, d in block.pairs()]
                del block
                tracemalloc.reset_peak()
        finally:
            tracemalloc.stop()
    assert got == expected and len(peaks) == 5  # 200,008-byte messages: 5 a block
    sizes = [5 * 200_008] * 4 + [4 * 200_008]
    # the previous block and this one (its buffer's growth: up to an eighth more) and the row being read; not three
    assert all(p < 2.3 * s + 250_000 for p, s in zip(peaks, sizes, strict=True)), peaks
