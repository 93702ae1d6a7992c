#!/usr/bin/env python3
"""Any message decoded (issue 30, item 8): every field of every topic of a bag of custom types, beside rosbags'
own deserializer, in one run.

    python benchmarks/anymsg.py                       # 20 custom-type topics at 100 Hz for 2 min (240,000 msgs)
    python benchmarks/anymsg.py --data /work/bigdata  # keep the bag there (reused when present)
    python benchmarks/anymsg.py --smoke               # 5 s of bag, one round: CI, no thresholds
    python benchmarks/anymsg.py --whole-only          # only the side-by-side subprocesses

The bag is written by ``rosbags`` (its serializer and MCAP writer) with its twenty types registered from ``.msg``
text (``bench_msgs/msg/Sensor00`` …), so their definitions are only in the bag: half of fixed size (a header,
scalars of every width, fixed arrays), half variable (with a ``float64[]`` of six joints, a ``string`` mode and
a ``bench_msgs/msg/Sample[]`` of three), as a robot's controllers and drivers publish them.

First, the whole run beside the user's alternative, each a subprocess, alternating, medians of ``--rounds``
(wall, CPU of the process tree — user+sys by ``os.wait4`` — and peak anonymous memory, RssAnon polled every 20 ms):

* **r2d2-viz**: ``r2d2-viz --bag BAG --save out.rrd`` (read, decode every field, log them to Rerun, write the file);
* **rosbags**: a Python process that reads the bag with ``rosbags.rosbag2.Reader``, registers the bag's own
  definitions and calls ``Typestore.deserialize_cdr`` on every message (the quickest way with rosbags);
* **AnyReader**: the same with ``rosbags.highlevel.AnyReader`` and its ``deserialize`` (the documented way).

Goal (issue 38): r2d2-viz ≤ 1.0× rosbags, wall and CPU. Then the decoding alone, in this process: the bag's
messages are read into memory once (our reader's blocks); alternating, medians of ``--rounds``:

* **rosbags**: ``Typestore.deserialize_cdr`` of every message, with each topic's own definition (the store
  ``r2d2_viz.msgs.definitions.own_store`` builds from the bag; it only deserialises — no flattening to columns);
* **ours**: :class:`r2d2_viz.sources.fields_pass.FieldsPass` ``.decode`` of every block: every field of every
  message as named numpy columns (what the recording gets).

Printed, never asserted; the machine may be shared (2 cores): the load is printed with each figure.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

PY = sys.executable
APP = str(Path(PY).parent / "r2d2-viz")
T0 = 1_700_000_000_000_000_000
TOPICS = 20
SAMPLE = "float64 value\nint32 id\n"
FIXED = """std_msgs/Header header
float64 position
float64 velocity
float32 current
int32 ticks
uint8 status
bool enabled
float32[4] temperatures
geometry_msgs/Vector3 force
"""
VARIABLE = """std_msgs/Header header
string mode
float64[] positions
float64[] velocities
bench_msgs/Sample[] samples
uint16 errors
"""


def _types() -> dict[str, str]:
    """Type name → .msg text of the twenty topics' types (and their sample type)."""
    out = {"bench_msgs/msg/Sample": SAMPLE}
    for k in range(TOPICS):
        out[f"bench_msgs/msg/Sensor{k:02d}"] = FIXED if k % 2 == 0 else VARIABLE
    return out


def write_bag(path: Path, seconds: float, rate: float = 100.0) -> int:
    """The benchmark bag (MCAP, rosbags' writer); returns the number of messages."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    for name, text in _types().items():
        ts.register(get_types_from_msg(text, name))
    T = ts.types
    rng = np.random.default_rng(0)
    n = int(seconds * rate)
    count = 0
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = [
            writer.add_connection(f"/robot/sensor{k:02d}", f"bench_msgs/msg/Sensor{k:02d}", typestore=ts)
            for k in range(TOPICS)
        ]
        for i in range(n):
            t = T0 + int(i * 1e9 / rate)
            for k, connection in enumerate(connections):
                msg = custom_message(T, k, i, t, rng)
                writer.write(connection, t + k, bytes(ts.serialize_cdr(msg, f"bench_msgs/msg/Sensor{k:02d}")))
                count += 1
    return count


def custom_message(T: Any, k: int, i: int, t: int, rng: np.random.Generator) -> Any:
    """The ``i``-th message (at ``t``) of custom topic ``k`` (types ``T`` of a store with :func:`_types` in it)."""
    header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(t, 1_000_000_000)), "base_link")
    msgtype = f"bench_msgs/msg/Sensor{k:02d}"
    x = rng.standard_normal(6)
    if k % 2 == 0:
        force = T["geometry_msgs/msg/Vector3"](*x[:3])
        return T[msgtype](header, x[0], x[1], np.float32(x[2]), i, i % 4, bool(i % 2), x[:4].astype(np.float32), force)
    samples = [T["bench_msgs/msg/Sample"](float(x[j]), j) for j in range(3)]
    return T[msgtype](header, "position", x, x * 0.5, samples, i % 7)


def _rosbags(bag: object, blocks: list, stores: dict) -> float:  # type: ignore[type-arg]
    start = time.perf_counter()
    for block in blocks:
        for _, topic, data in block.messages():
            store, msgtype = stores[topic]
            store.deserialize_cdr(data, msgtype)
    return time.perf_counter() - start


def _ours(bag: object, blocks: list) -> tuple[float, int]:  # type: ignore[type-arg]
    from r2d2_viz.sources.fields_pass import FieldsPass

    start = time.perf_counter()
    fields = FieldsPass(bag, {t: i.msgtype for t, i in bag.topics.items()})  # type: ignore[attr-defined]
    rows = 0
    for block in blocks:
        rows += sum(len(c) for _, c in fields.decode(block))
    return time.perf_counter() - start, rows


NOTE = "std_msgs/Header header\nstring text\nfloat64 value\n"


def varying(n: int, rounds: int) -> tuple[float, float]:
    """The worst case, for the record: ``n`` messages whose every one has its own layout (a ``string`` of a new
    length each time, as in a log), which the numpy matching cannot share — each is walked on its own. Medians of
    ``rounds``: (rosbags, ours) seconds."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    from r2d2_viz.msgs.generic.decoder import FieldDecoder

    ts = get_typestore(Stores.ROS2_HUMBLE)
    ts.register(get_types_from_msg(NOTE, "bench_msgs/msg/Note"))
    T = ts.types
    data = []
    for i in range(n):
        header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](i, 0), "base_link")
        msg = T["bench_msgs/msg/Note"](header, "x" * (i % 1000), float(i))
        data.append(bytes(ts.serialize_cdr(msg, "bench_msgs/msg/Note")))
    buf = np.frombuffer(b"".join(data), dtype=np.uint8)
    lengths = np.array([len(d) for d in data], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    theirs, ours = [], []
    for _ in range(rounds):
        t = time.perf_counter()
        for d in data:
            ts.deserialize_cdr(d, "bench_msgs/msg/Note")
        theirs.append(time.perf_counter() - t)
        t = time.perf_counter()
        FieldDecoder(ts, "bench_msgs/msg/Note").decode(buf, starts, lengths, np.arange(n, dtype=np.int64))
        ours.append(time.perf_counter() - t)
    return statistics.median(theirs), statistics.median(ours)


ROSBAGS = """
import sys
from pathlib import Path
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
store = get_typestore(Stores.ROS2_HUMBLE)
with Reader(Path(sys.argv[1])) as reader:
    types = {}
    for c in reader.connections:
        types.update(get_types_from_msg(c.msgdef.data, c.msgtype))
    store.register(types)
    n = sum(1 for c, _, raw in reader.messages() if store.deserialize_cdr(raw, c.msgtype) is not None)
print(n)
"""
"""The user's alternative: read the bag, every message deserialised (rosbags' low-level reader)."""
ANYREADER = """
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader
with AnyReader([Path(sys.argv[1])]) as reader:
    n = sum(1 for c, _, raw in reader.messages() if reader.deserialize(raw, c.msgtype) is not None)
print(n)
"""


def measured(command: list[str]) -> tuple[float, float, float]:
    """Run ``command`` to its end: (wall s, CPU s of its tree — user+sys by ``os.wait4`` —, peak RssAnon MB)."""
    from bigbag import rss_anon_kb

    with tempfile.TemporaryFile() as err:  # a file, not a pipe: a chatty run never blocks on it
        start = time.perf_counter()
        proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=err)
        peak = 0
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            peak = max(peak, rss_anon_kb(proc.pid))
            time.sleep(0.02)
        wall = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here: Popen must not wait for it again
        if proc.returncode:
            err.seek(0)
            raise RuntimeError(f"{' '.join(command)} failed:\n{err.read().decode(errors='replace')[-2000:]}")
    return wall, usage.ru_utime + usage.ru_stime, peak / 1024


def whole(path: Path, out: Path, rounds: int, smoke: bool) -> None:
    """The whole ``--save`` beside rosbags' read and deserialise of every message, each a subprocess, alternating;
    medians of ``rounds`` printed with their ratio."""
    commands = {
        "r2d2-viz --save": [APP, "--bag", str(path), "--save", str(out)],
        "rosbags Reader + deserialize_cdr": [PY, "-c", ROSBAGS, str(path)],
        "rosbags AnyReader + deserialize": [PY, "-c", ANYREADER, str(path)],
    }
    got: dict[str, list[tuple[float, float, float]]] = {k: [] for k in commands}
    loads = []
    for _ in range(rounds):
        for name, command in commands.items():
            loads.append(os.getloadavg()[0])
            got[name].append(measured(command))
    med = {k: tuple(statistics.median(r[j] for r in runs) for j in range(3)) for k, runs in got.items()}
    print(f"whole runs, medians of {rounds} alternating (load {min(loads):.1f}–{max(loads):.1f}):")
    ours = med["r2d2-viz --save"]
    for name, (wall, cpu, peak) in med.items():
        print(f"  {name:34s} wall {wall:5.2f} s  CPU {cpu:5.2f} s  peak {peak:4.0f} MB")
    for name in list(commands)[1:]:
        wall, cpu = ours[0] / med[name][0], ours[1] / med[name][1]
        goal = "" if smoke else (" met" if max(wall, cpu) <= 1.0 else " NOT met")
        print(f"  r2d2-viz / {name}: wall {wall:.2f}x, CPU {cpu:.2f}x (goal ≤ 1.0x){goal}")
    print(f"  the recording: {out.stat().st_size / 1e6:.0f} MB")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="seconds of bag (default 120)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--data", type=Path, default=None, help="keep the bag in this folder (reused when present)")
    parser.add_argument("--smoke", action="store_true", help="5 s of bag, one round, no thresholds")
    parser.add_argument("--whole-only", action="store_true", help="only the whole runs side by side")
    args = parser.parse_args()
    if args.smoke:
        args.seconds, args.rounds = 5.0, 1
    from r2d2_viz.sources.bags.bag import open_bag
    from r2d2_viz.sources.fields_pass import store_of

    tmp = Path(tempfile.mkdtemp(prefix="anymsg-"))
    try:
        folder = args.data if args.data is not None else tmp
        path = folder / f"anymsg_{args.seconds:g}s"
        if not path.exists():
            t = time.perf_counter()
            n = write_bag(path, args.seconds)
            print(f"wrote {path}: {n:,} messages in {time.perf_counter() - t:.0f} s", file=sys.stderr)
        print(
            f"bag: {TOPICS} custom-type topics, {args.seconds:g} s at 100 Hz "
            f"({int(args.seconds * 100 * TOPICS):,} messages)"
        )
        whole(path, tmp / "out.rrd", args.rounds, args.smoke)
        if args.whole_only:
            return 0
        with open_bag(path) as bag:
            blocks = list(bag.blocks(list(bag.topics)))
            stores = {t: (store_of(bag, t), i.msgtype) for t, i in bag.topics.items()}
            n = sum(len(b) for b in blocks)
            theirs, ours = [], []
            for _ in range(args.rounds):
                theirs.append(_rosbags(bag, blocks, stores))
                took, rows = _ours(bag, blocks)
                ours.append(took)
                assert rows == n, (rows, n)
        a, b = statistics.median(theirs), statistics.median(ours)
        load = os.getloadavg()[0]
        print(f"decoding alone, in this process, medians of {args.rounds} (load {load:.1f}):")
        print(f"  rosbags deserialize_cdr, every message: {a:.2f} s ({a / n * 1e6:.1f} µs/message)")
        print(f"  r2d2-viz fields, every field as columns: {b:.2f} s ({b / n * 1e6:.1f} µs/message)")
        print(f"  ratio ours / rosbags: {b / a:.2f}x")
        va, vb = varying(2_000 if args.smoke else 20_000, args.rounds)
        worst = "worst case, a new layout every message (a string of a new length each, 1,000 lengths)"
        print(f"  {worst}: {vb / va:.2f}x rosbags (not a goal)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
