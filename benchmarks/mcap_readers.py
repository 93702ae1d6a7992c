#!/usr/bin/env python3
"""Which MCAP reader (issue 23): the project's own scan beside the ``mcap`` library, on the big sensor bag.

    python benchmarks/mcap_readers.py --data /work/bigdata        # the 150 s bag of bigbag.py (written if absent)
    python benchmarks/mcap_readers.py --bag some.mcap --topic /scan
    python benchmarks/mcap_readers.py --smoke                     # a 3 s bag, one round

Each reader runs in its own subprocess and touches every message it yields (counts it, adds up its length, and
reads one byte in every 4 kB of it, so that a reader handing out views of a mapped file pays for the pages it
maps as the others pay for the bytes they copy), for
every message of the bag and for one topic (``/scan``: 20 Hz, 2.9 kB a message, in every chunk of the file):

* ours: ``r2d2_viz.sources.bags.mcap_scan.McapScan``: since issue 23 ``blocks(topics)``, one pass through the
  summary's chunk index and the chunks' message indexes (each message touched through ``Block.data``); before it,
  ``messages(topic)``, a record scan from byte 0 per topic (so "every message" was one scan per topic);
* ``mcap`` (PyPI ``mcap``, the format's reference reader; not a dependency: ``pip install mcap``, else its rows are
  left out): ``make_reader(f).iter_messages(topics=…)`` — with a
  seekable file this is its ``SeekingReader``, which reads the summary, then only the chunks the chunk index says
  hold the topics, in log-time order — and ``NonSeekingReader`` (no index: every record from byte 0);
* rosbags' ``Reader.messages(connections)`` (its MCAP backend, index-driven), for reference.

Figures: wall time of the whole child (imports included, ~0.1–0.3 s) and its peak RssAnon (anonymous memory;
file pages of a read or mmapped bag are the page cache's), polled every 20 ms. Medians of ``--rounds``; the bag
is in the page cache after the first read (every reader sees it warm). The machine may be shared: say so.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bigbag

OURS = """
import sys
from pathlib import Path
from r2d2_viz.sources.bags.mcap_scan import McapScan
scan = McapScan(Path(sys.argv[1]))
n = size = touched = 0
if hasattr(scan, "blocks"):  # issue 23: several topics in one pass, through the chunk and message indexes
    for block in scan.blocks(sys.argv[2:] or list(scan.topics)):
        for i in range(len(block)):
            data = block.data(i); n += 1; size += len(data); touched += len(bytes(data[::4096]))
else:  # before: one scan from byte 0 per topic
    for topic in sys.argv[2:] or list(scan.topics()):
        for _, data in scan.messages(topic):
            n += 1; size += len(data); touched += len(bytes(data[::4096]))
print(n, size)
"""

MCAP = """
import sys
from mcap.reader import NonSeekingReader, make_reader
topics = sys.argv[3:] or None
with open(sys.argv[1], "rb") as f:
    reader = make_reader(f) if sys.argv[2] == "index" else NonSeekingReader(f)
    n = size = touched = 0
    for _, _, message in reader.iter_messages(topics=topics):
        n += 1; size += len(message.data); touched += len(bytes(message.data[::4096]))
print(n, size)
"""

ROSBAGS = """
import sys
from rosbags.rosbag2 import Reader
with Reader(sys.argv[1]) as reader:
    wanted = set(sys.argv[2:])
    connections = [c for c in reader.connections if not wanted or c.topic in wanted]
    n = size = touched = 0
    for _, _, data in reader.messages(connections=connections):
        n += 1; size += len(data); touched += len(bytes(data[::4096]))
print(n, size)
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bag", type=Path, help="an .mcap file (default: bigbag.py's sensor bag)")
    parser.add_argument("--data", type=Path, help="where bigbag.py keeps its bags")
    parser.add_argument("--seconds", type=float, default=150.0, help="length of bigbag.py's bag")
    parser.add_argument("--topic", default="/scan")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--smoke", action="store_true", help="a 3 s bag, one round")
    args = parser.parse_args()
    if args.smoke:
        args.seconds, args.rounds = 3.0, 1
    with tempfile.TemporaryDirectory(prefix="r2d2-readers-") as tmp:
        bag = args.bag or bigbag.sensor_bag(args.data or Path(tmp), args.seconds)
        py = bigbag.PY
        readers = {
            "ours: McapScan": ([py, "-c", OURS, str(bag)], []),
            "mcap: make_reader (index)": ([py, "-c", MCAP, str(bag), "index"], []),
            "mcap: NonSeekingReader (no index)": ([py, "-c", MCAP, str(bag), "scan"], []),
            "rosbags: Reader.messages": ([py, "-c", ROSBAGS, str(bag.parent)], []),
        }
        if importlib.util.find_spec("mcap") is None:
            readers = {name: how for name, how in readers.items() if not name.startswith("mcap")}
            print("the mcap library is not installed (pip install mcap): its rows are left out")
        print(f"bag: {bag} ({bag.stat().st_size / 1e9:.2f} GB); medians of {args.rounds} rounds\n")
        print("| reader | what | messages | wall s | peak RssAnon MB |\n|---|---|---:|---:|---:|")
        for what, extra in (("every message", []), (f"only {args.topic}", [args.topic])):
            counts: set[str] = set()
            for name, (command, _) in readers.items():
                if name.startswith("rosbags") and not (bag.parent / "metadata.yaml").exists():
                    continue
                runs = []
                for _ in range(args.rounds):
                    run = bigbag.run_watched([*command, *extra])
                    if run.returncode != 0:
                        raise RuntimeError(f"{name} failed:\n{run.stderr[-2000:]}")
                    runs.append(run)
                wall = statistics.median(r.wall for r in runs)
                mem = statistics.median(r.peak_anon_mb for r in runs)
                n = f"{int(runs[0].stdout.split()[0]):,}"
                counts.add(n)
                print(f"| {name} | {what} | {n} | {wall:.2f} | {mem:,.0f} |")
            if len(counts) > 1:
                print(f"\nreaders disagree on the number of messages ({what}): {sorted(counts)}")


if __name__ == "__main__":
    main()
