"""The MCAP specification's conformance variants (tests/data/mcap_conformance: the 416 files of foxglove/mcap's
suite, with and without chunks, message indexes, chunk indexes, statistics, summary copies of schemas and channels,
summary offsets, padding) read through the Storage protocol. The golden values are each file's JSON, written by the
suite's own generator: its Message records (topic through their Channel record, log time, bytes) in log-time order,
ties in file order. Messages on a channel without a schema (MCAP schema id 0) are not a ROS topic and are not
expected."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from conftest import REPO, cli

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.bags.mcap_scan import McapScan
from r2d2_viz.sources.bags.storage import Storage

DATA = REPO / "tests" / "data" / "mcap_conformance"
VARIANTS = sorted(DATA.rglob("*.mcap"))
Message = tuple[int, str, bytes]


class Expected:
    """What a variant's JSON says the file holds."""

    def __init__(self, mcap: Path) -> None:
        records = json.loads(mcap.with_suffix(".json").read_text())["records"]
        fields: list[tuple[str, dict[str, Any]]] = [(r["type"], dict(r["fields"])) for r in records]
        schemas = {int(f["id"]): f["name"] for t, f in fields if t == "Schema"}
        channels = {int(f["id"]): (f["topic"], int(f["schema_id"])) for t, f in fields if t == "Channel"}
        found = []
        for t, f in fields:
            if t == "Message" and channels[int(f["channel_id"])][1] != 0:
                topic = channels[int(f["channel_id"])][0]
                found.append((int(f["log_time"]), topic, bytes(int(b) for b in f["data"])))
        self.messages: list[Message] = sorted(found, key=lambda m: m[0])  # stable: ties keep the file's order
        self.types = {topic: schemas[s] for topic, s in channels.values() if s != 0}
        self.counts = dict(Counter(m[1] for m in self.messages))
        self.span = (self.messages[0][0], self.messages[-1][0]) if self.messages else None


def _read(storage: Storage, **kw: int) -> list[Message]:
    return [(t, topic, bytes(d)) for b in storage.blocks(list(storage.topics), **kw) for t, topic, d in b.messages()]


def _differences(mcap: Path) -> list[str]:
    expected = Expected(mcap)
    storage: Storage = McapScan(mcap)
    try:
        out = []
        if (got := _read(storage)) != expected.messages:
            out.append(f"messages {got[:3]}… != {expected.messages[:3]}…")
        counts = {t: info.count for t, info in storage.topics.items() if info.count}
        if counts != expected.counts:
            out.append(f"counts {counts} != {expected.counts}")
        types = {t: info.msgtype for t, info in storage.topics.items()}
        if types != expected.types:
            out.append(f"types {types} != {expected.types}")
        if expected.span is not None and storage.span != expected.span:
            out.append(f"span {storage.span} != {expected.span}")
        if storage.note or getattr(storage, "problems", None):
            out.append(f"warned: {storage.note} {getattr(storage, 'problems', None)}")
        for topic in expected.counts:
            last = [m for m in expected.messages if m[1] == topic][-1]
            if storage.last(topic) != (last[0], last[2]):
                out.append(f"last({topic}) {storage.last(topic)} != {last[0], last[2]}")
        if expected.span is not None:  # a stretch: from the second time on, up to (not including) the last one
            lo, hi = sorted({m[0] for m in expected.messages})[min(1, len(expected.messages) - 1)], expected.span[1]
            stretch = [m for m in expected.messages if lo <= m[0] < hi]
            if (got := _read(storage, start_ns=lo, stop_ns=hi)) != stretch:
                out.append(f"[{lo}, {hi}): {got} != {stretch}")
        return out
    finally:
        storage.close()


def test_the_variants_are_the_specifications_files() -> None:
    """Each file is byte for byte upstream's (sha256 and size from its Git LFS pointer at foxglove/mcap 95d067356,
    SHA256SUMS): the golden JSON and the file it describes come from the same generator run."""
    sums = {}
    for line in (DATA / "SHA256SUMS").read_text().splitlines():
        digest, size, name = line.split()
        sums[name] = (digest, int(size))
    assert len(VARIANTS) == len(sums) == 416
    for mcap in VARIANTS:
        data = mcap.read_bytes()
        assert (hashlib.sha256(data).hexdigest(), len(data)) == sums[str(mcap.relative_to(DATA))], mcap.name


def test_every_variant_reads_exactly() -> None:
    """All 416 variants in one loop: messages, counts, types, span, the last message of each topic and a stretch
    of time, no warning."""
    wrong = {mcap.name: d for mcap in VARIANTS if (d := _differences(mcap))}
    assert not wrong, f"{len(VARIANTS) - len(wrong)} of {len(VARIANTS)} read exactly; e.g. {list(wrong.items())[:3]}"


def test_ties_and_disorder_are_in_the_variants() -> None:
    """The loop above means something: TenMessages has log times out of order and equal ones."""
    times = [m[0] for m in Expected(DATA / "TenMessages" / "TenMessages-ch-chx-mx.mcap").messages]
    raw = json.loads((DATA / "TenMessages" / "TenMessages-ch-chx-mx.json").read_text())["records"]
    file_order = [int(dict(r["fields"])["log_time"]) for r in raw if r["type"] == "Message"]
    assert file_order != sorted(file_order) and len(set(times)) < len(times)


def test_a_bag_of_a_variant_says_nothing() -> None:
    """Through the bag (what the app opens): the topic's count, no warning, for variants without statistics,
    chunk index or channels in the summary. The bag names the topic ``/example``: ROS 2 names get their leading
    slash there, as rosbag2 records them (the variants' channel is ``example``)."""
    for name in ("TenMessages-ch-mx", "TenMessages-rch", "TenMessages-ch-chx-mx-rsh-st", "TenMessages"):
        warnings: list[str] = []
        with open_bag(DATA / "TenMessages" / f"{name}.mcap", warn=warnings.append) as bag:
            assert bag.topic_type("/example") == "Example"
            assert [len(b) for b in bag.blocks(["/example"])] and not warnings, name
            assert sum(len(b) for b in bag.blocks(["/example"])) == 10


CLI_VARIANTS = [
    "TenMessages/TenMessages-ch-chx-mx-rch-rsh-st-sum",
    "OneSchemalessMessage/OneSchemalessMessage-ch-chx-mx-rch-st-sum",
]
"""The console script itself on one file it records and one it refuses: every variant (each missing part of the
summary, padding, no messages) goes through the same ``main`` with the same checks in test_the_app_on_every_variant;
twelve console-script runs of them cost 10 s of CPU and 50 s of a loaded worker."""


_EVERY_VARIANT = """
import json, sys
from contextlib import redirect_stderr
from io import StringIO
from pathlib import Path
from r2d2_viz.cli import main
out = Path(sys.argv[1])
for mcap in json.loads(sys.stdin.read()):
    err = StringIO()
    with redirect_stderr(err):
        code = main(["--bag", mcap, "--save", str(out)])
    print(json.dumps([mcap, code, err.getvalue().strip().splitlines(), out.exists()]), flush=True)
    out.unlink(missing_ok=True)
"""


def test_the_app_on_every_variant(tmp_path: Path) -> None:
    """All 416 through the CLI's ``main`` in one process (``--bag X --save out.rrd``): exit 0 and a recording for
    every file with a message on a channel with a schema, else exit 2 with one line; no line over 300 characters.
    The process is a child of its own: Rerun keeps each recording stream (two threads, one of them ticking) for the
    life of the process, and 416 of them slowed every later test of this worker."""
    done = subprocess.run(
        [sys.executable, "-c", _EVERY_VARIANT, str(tmp_path / "out.rrd")],
        input=json.dumps([str(m) for m in VARIANTS]),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    wrong = []
    for row in done.stdout.splitlines():
        mcap, code, lines, written = json.loads(row)
        if Expected(Path(mcap)).messages:
            ok = code == 0 and written
        else:
            ok = code == 2 and lines == [f"error: {mcap}: empty bag (no messages)"] and not written
        if not ok or any(len(line) > 300 for line in lines):
            wrong.append((Path(mcap).name, code, lines[-2:]))
    assert len(done.stdout.splitlines()) == len(VARIANTS)
    assert not wrong, f"{len(VARIANTS) - len(wrong)} of {len(VARIANTS)} as expected; e.g. {wrong[:3]}"


@pytest.mark.slow
@pytest.mark.parametrize("name", CLI_VARIANTS)
def test_the_cli_saves_a_variant_or_says_it_holds_no_messages(tmp_path: Path, name: str) -> None:
    """The real console script in a subprocess, ``r2d2-viz --bag X --save out.rrd``, on :data:`CLI_VARIANTS`: exit 0
    and a recording, or exit 2 with one line for a file without a message the app can read (here: no schema); never
    a traceback, no line over 300 characters."""
    mcap = DATA / f"{name}.mcap"
    out = tmp_path / "out.rrd"
    run = cli("--bag", str(mcap), "--save", str(out))
    lines = run.stderr.strip().splitlines()
    assert "Traceback" not in run.stderr and all(len(line) <= 300 for line in lines), run.stderr
    if Expected(mcap).messages:
        assert run.returncode == 0 and out.exists(), run.stderr
    else:
        assert run.returncode == 2 and not out.exists(), run.stderr
        assert lines == [f"error: {mcap}: empty bag (no messages)"]
