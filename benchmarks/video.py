"""Cameras as video (issues 32 and 38), side by side in one run, on issue 38's camera bag written by rosbags
(tests/camerabag.py's ``write_camera_video_bag``: 900 frames, 60 s, of 640x480 rgb8 at 15 Hz with texture, hard
edges, motion and sensor noise, and an H.264 ``CompressedVideo`` topic passed through, written after the camera as a
converting tool writes topic by topic — its chunks span the bag and overlap every camera chunk in time):

* **size and fidelity**: ``r2d2-viz --bag cam --save out.rrd --video`` — the camera's samples against its raw bytes,
  and their luma PSNR against the bag's frames (samples decoded back with PyAV's dav1d; goals ≤ 2 %, ≥ 38 dB mean,
  ≥ 34 dB every frame);
* **time and memory**: the whole ``--save --video`` run against the least converter that does the same — a process
  that reads the frames with rosbags and encodes them with PyAV's SVT-AV1 at preset 12 with the same keyframe
  interval, nothing else (goal ≤ 1.2×), wall and CPU (user + sys of the process tree); peak RssAnon of the process
  tree (goal ≤ 500 MB); the lossless ``--save`` beside them for reference;
* **live**: frames handed to the live path's display feed (``--ros --video``: decode, encode, log to a recording)
  at 30 Hz as they arrive; latency from a frame's arrival to its sample being logged (goal p99 ≤ 50 ms) and the
  bitrate (goal ≤ 2 Mbit/s). DDS transport is not in it (benchmarks/live_app.py measures that).

``--smoke`` (CI): a short bag, one round, no verdicts.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
TESTS = HERE.parent / "tests"
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(TESTS))

import bigbag  # noqa: E402

CONVERTER = """
import sys, av
from fractions import Fraction
from pathlib import Path
from rosbags.highlevel import AnyReader
av.logging.set_level(av.logging.PANIC)
context, total = None, 0
with AnyReader([Path(sys.argv[1])]) as reader:
    connections = [c for c in reader.connections if c.topic == "/camera/image_raw"]
    for connection, _, raw in reader.messages(connections=connections):
        msg = reader.deserialize(raw, connection.msgtype)
        if context is None:
            context = av.CodecContext.create("libsvtav1", "w")
            context.width, context.height, context.pix_fmt = msg.width, msg.height, "yuv420p"
            context.time_base, context.framerate, context.max_b_frames = Fraction(1, 30), Fraction(30), 0
            context.gop_size = int(sys.argv[3])  # r2d2-viz: a keyframe every 2 s of message time
            context.options = {"preset": "12", "crf": sys.argv[2], "svtav1-params": "pred-struct=1"}
        pixels = msg.data.reshape(msg.height, msg.width, 3)
        total += sum(p.size for p in context.encode(av.VideoFrame.from_ndarray(pixels, format="rgb24")))
    total += sum(p.size for p in context.encode(None))
print(total)
"""


def r2d2_viz() -> list[str]:
    exe = Path(sys.executable).parent / "r2d2-viz"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "r2d2_viz"]


def fidelity(rrd: Path, n: int) -> tuple[int, float, float]:
    """(sample bytes, mean and min luma PSNR) of the camera's samples in ``rrd`` against the bag's frames."""
    import av
    from camerabag import Frames
    from rrd import read_recording

    recording = read_recording(rrd)
    rows = recording["/camera/image_raw"]
    samples = [bytes(s[0]) for s in rows.temporal["VideoStream:sample"] if s is not None]
    passed = [s for s in recording["/front/video"].temporal["VideoStream:sample"] if s is not None]
    assert len(passed) == n, (len(passed), n)  # the H.264 topic passed through, a sample a frame
    decoder = av.CodecContext.create("libdav1d", "r")
    lumas = []
    for sample in [*samples, None]:
        lumas += [f.to_ndarray(format="gray").astype(np.float64) for f in decoder.decode(
            av.Packet(sample) if sample is not None else None)]  # fmt: skip
    frames = Frames()
    scores = []
    for i, decoded in enumerate(lumas[:n]):
        reference = av.VideoFrame.from_ndarray(frames(i), format="rgb24").reformat(format="yuv420p")
        error = np.mean((decoded - reference.to_ndarray(format="gray").astype(np.float64)) ** 2)
        scores.append(float(10 * np.log10(255**2 / error)))
    assert len(lumas) == n, (len(lumas), n)
    return sum(map(len, samples)), float(np.mean(scores)), float(min(scores))


def live_latency(n: int) -> tuple[float, float, float]:
    """(p50 ms, p99 ms, Mbit/s): frames at 30 Hz through the live path's display feed (``--ros --video``)."""
    import rerun as rr
    from camerabag import Frames, image

    from r2d2_viz.sources.bag_displays import TopicMessage
    from r2d2_viz.viewer.display_feed import DisplayFeed, VideoFeed
    from r2d2_viz.viewer.notices import Notices

    frames = Frames()
    data = [image(i, frames(i % 60)) for i in range(min(n, 60))]
    with tempfile.TemporaryDirectory() as scratch:
        rec = rr.RecordingStream("video_live_bench")
        rec.save(Path(scratch) / "live.rrd")
        feed = DisplayFeed(Notices(rec), clock="timestamp", fixed_frame="map", video=VideoFeed("av1", live=True))
        latencies, sizes = [], 0
        start = time.perf_counter()
        for i in range(n):
            due = start + i / 30
            time.sleep(max(0.0, due - time.perf_counter()))
            arrived = time.perf_counter()
            message = TopicMessage(time.time_ns(), "/camera/image_raw", "sensor_msgs/msg/Image", data[i % len(data)])
            decoded = feed.decode(message)
            feed.log(decoded)
            latencies.append((time.perf_counter() - arrived) * 1000)
            sizes += sum(len(item.data) for item in getattr(decoded.decoded, "items", ()) if hasattr(item, "data"))
        feed.finish()
        rec.flush()
        rec.disconnect()
    return float(np.percentile(latencies, 50)), float(np.percentile(latencies, 99)), sizes * 8 / (n / 30) / 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=900, help="camera frames in the bag (default 900: 60 s)")
    parser.add_argument("--rate", type=float, default=15.0, help="camera rate, Hz (default 15)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--smoke", action="store_true", help="a short bag, one round, no verdicts (CI)")
    args = parser.parse_args()
    if args.smoke:
        args.frames, args.rounds = 45, 1
    from camerabag import write_camera_video_bag

    from r2d2_viz.msgs.images import CRF

    with tempfile.TemporaryDirectory() as scratch:
        bag = Path(scratch) / "cam"
        write_camera_video_bag(bag, args.frames, rate=args.rate)
        raw = args.frames * 640 * 480 * 3
        runs: dict[str, list[bigbag.Run]] = {"video": [], "converter": [], "lossless": []}
        cpu: dict[str, list[float]] = {name: [] for name in runs}
        out = Path(scratch) / "out.rrd"
        commands = {
            "video": [*r2d2_viz(), "--bag", str(bag), "--save", str(out), "--video"],
            "converter": [sys.executable, "-c", CONVERTER, str(bag), str(CRF["av1"]), str(round(2 * args.rate))],
            "lossless": [*r2d2_viz(), "--bag", str(bag), "--save", str(Path(scratch) / "raw.rrd")],
        }
        for _ in range(args.rounds):  # alternating, so the machine's load falls on all alike
            for name, command in commands.items():
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                runs[name].append(bigbag._checked(bigbag.run_watched(command), command))
                after = resource.getrusage(resource.RUSAGE_CHILDREN)  # the process tree, reaped
                cpu[name].append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
        size, mean_db, min_db = fidelity(out, args.frames)
        lossless_mb = (Path(scratch) / "raw.rrd").stat().st_size / 1e6
        video_mb = out.stat().st_size / 1e6
        p50, p99, mbits = live_latency(90 if args.smoke else 900)
    wall = {name: statistics.median(r.wall for r in rs) for name, rs in runs.items()}
    cpus = {name: statistics.median(c) for name, c in cpu.items()}
    peak = max(r.peak_anon_mb for r in runs["video"])
    ratio = wall["video"] / wall["converter"]
    load = os.getloadavg()[0]
    verdict = (lambda ok: "") if args.smoke else (lambda ok: " (met)" if ok else " (NOT met)")
    print(
        f"camera bag: {args.frames} frames 640x480 rgb8 at {args.rate:g} Hz ({raw / 1e6:.0f} MB raw) and an H.264 "
        f"topic written after it; load {load:.1f}"
    )
    print("| measure | value | goal |\n|---|---:|---|")
    print(f"| samples / raw bytes | {size / raw * 100:.2f} %{verdict(size <= 0.02 * raw)} | ≤ 2 % |")
    print(f"| luma PSNR mean / min | {mean_db:.1f} / {min_db:.1f} dB{verdict(mean_db >= 38 and min_db >= 34)} "
          "| ≥ 38 / ≥ 34 dB |")  # fmt: skip
    print(f"| `--save --video` wall / CPU (median of {args.rounds}) | {wall['video']:.2f} / {cpus['video']:.2f} s | |")
    floor = f"{wall['converter']:.2f} / {cpus['converter']:.2f} s"
    print(f"| converter (rosbags + SVT-AV1 preset 12) wall / CPU | {floor} | |")
    print(f"| ratio, wall | {ratio:.2f}×{verdict(ratio <= 1.2)} | ≤ 1.2× |")
    print(f"| ratio, CPU | {cpus['video'] / cpus['converter']:.2f}× | |")
    print(f"| lossless `--save` wall, .rrd | {wall['lossless']:.2f} s, {lossless_mb:.0f} MB | (reference) |")
    print(f"| `--video` .rrd | {video_mb:.1f} MB | |")
    print(f"| peak RssAnon `--save --video` | {peak:.0f} MB{verdict(peak <= 500)} | ≤ 500 MB |")
    print(f"| live: arrival → sample logged p50 / p99 | {p50:.1f} / {p99:.1f} ms{verdict(p99 <= 50)} | p99 ≤ 50 ms |")
    print(f"| live: bitrate | {mbits:.2f} Mbit/s{verdict(mbits <= 2)} | ≤ 2 Mbit/s |")


if __name__ == "__main__":
    main()
