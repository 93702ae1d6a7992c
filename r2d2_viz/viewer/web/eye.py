"""The 3D view's eye as the viewer holds it, for the pose tools' rays (RViz's ``PoseTool`` takes the ground under the
pointer, whatever is drawn there). Rerun's web viewer keeps each 3D view's camera in its blueprint
(``EyeControls3D``, saved as the user orbits); its selection events give only the point picked. The page serves
rerun-notebook's module with one hook (:func:`hooked_widget`: the widget's ``WebViewer`` on ``globalThis``), so that
at a click it can send the blueprint (``WebViewer.save_blueprint``) and :class:`EyeReader` reads the eye's
position back, in the view's world (the fixed frame).

The blueprint is bytes from the page, and Rerun's reader aborts the whole process on some malformed ones (a panic
in its Arrow decoder: SIGABRT) and warns with a temporary file's path on others. So the framing is checked here
first (:func:`framing_problem`), and what passes is read by Rerun in a worker process of its own (started at the
first click, this module run as ``python -m``; its warnings go nowhere): a blueprint that ends the worker is refused,
and the next click starts a new one.
"""

from __future__ import annotations

import json
import os
import select
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import IO

from r2d2_viz.errors import DEBUG_ENV, ToolEventError

MAX_BLUEPRINT_BYTES = 4 << 20
"""A blueprint the page sends is some tens of kB (77 kB measured for the R2D2's layout)."""
WIDGET_VIEWER = "this.viewer = new WebViewer();"
WIDGET_HOOK = WIDGET_VIEWER + " globalThis.r2d2Viewer = this.viewer;"
"""rerun-notebook's widget keeps its ``WebViewer`` to itself: the page reaches it through ``globalThis``."""
POSITION = "EyeControls3D:position"
TIMELINE = "blueprint"
READ_TIMEOUT_S = 20.0
"""How long a blueprint may take Rerun's reader (a worker that takes longer is ended; the first read also waits for
the worker to import rerun)."""

MAGIC = b"RRF2"
HEADER_BYTES = 12
"""An RRD stream's header: ``RRF2``, the format version, the options (compression)."""
MESSAGE_HEAD = struct.Struct("<QQ")
"""Each message: its kind and its length in bytes."""
KINDS = (0, 1, 2, 3)
"""Rerun's message kinds: the end (its payload the footer), a store's info, an Arrow chunk, a blueprint's activation."""
LENGTH = struct.Struct("<Q")

Point = tuple[float, float, float]


def hooked_widget(js: bytes) -> bytes:
    """rerun-notebook's ``widget.js`` with its viewer on ``globalThis.r2d2Viewer`` (unchanged if the line is not
    there exactly once: the page then finds no viewer, and the pose tools take the point picked)."""
    text = js.decode("utf-8")
    if text.count(WIDGET_VIEWER) != 1:
        return js
    return text.replace(WIDGET_VIEWER, WIDGET_HOOK).encode("utf-8")


def framing_problem(blob: bytes) -> str | None:
    """Why ``blob`` is not an RRD stream as Rerun frames one (header, then messages of known kinds, each within the
    bytes, up to the end marker or the bytes' end); None when it is framed as one."""
    if not blob:
        return "empty"
    if len(blob) > MAX_BLUEPRINT_BYTES:
        return f"larger than {MAX_BLUEPRINT_BYTES >> 20} MiB"
    if len(blob) < HEADER_BYTES or blob[:4] != MAGIC:
        return "not an RRD stream (no RRF2 header)"
    offset, count = HEADER_BYTES, 0
    while offset < len(blob):
        if offset + MESSAGE_HEAD.size > len(blob):
            return f"message {count + 1} is cut short"
        kind, length = MESSAGE_HEAD.unpack_from(blob, offset)
        if kind not in KINDS:
            return f"message {count + 1} is of no known kind ({kind})"
        if length > len(blob) - offset - MESSAGE_HEAD.size:
            return f"message {count + 1} claims {length} bytes, more than are left"
        if kind == 0:
            break
        offset += MESSAGE_HEAD.size + length
        count += 1
    return None if count else "no messages"


class EyeReader:
    """Reads the eye of blueprints (:meth:`read`) through a worker process, one blueprint at a time."""

    def __init__(self, timeout: float = READ_TIMEOUT_S) -> None:
        self.timeout = timeout
        self._lock = threading.Lock()
        self._worker: subprocess.Popen[bytes] | None = None

    def read(self, blob: bytes) -> Point | None:
        """The eye position of the blueprint's one 3D view (the last one saved); None when it holds none or several
        views with an eye. ToolEventError when ``blob`` is not a blueprint Rerun can read."""
        problem = framing_problem(blob)
        if problem is not None:
            raise ToolEventError(f"eye: not a blueprint: {problem}")
        if not self._lock.acquire(timeout=self.timeout):
            raise ToolEventError("eye: busy reading another blueprint")
        try:
            return self._ask(blob)
        finally:
            self._lock.release()

    def _ask(self, blob: bytes) -> Point | None:
        worker = self._worker
        if worker is None or worker.poll() is not None:
            worker = self._worker = _start_worker()
        assert worker.stdin is not None and worker.stdout is not None
        try:
            worker.stdin.write(LENGTH.pack(len(blob)) + blob)
            worker.stdin.flush()
            line = _read_line(worker.stdout, time.monotonic() + self.timeout)
        except OSError:  # (a pipe broken by a worker that died)
            line = None
        if line is None:
            self._stop(worker)
            raise ToolEventError("eye: not a blueprint Rerun can read")
        answer = json.loads(line)
        if answer.get("error"):
            raise ToolEventError("eye: not a blueprint Rerun can read")
        eye = answer.get("eye")
        return None if eye is None else (float(eye[0]), float(eye[1]), float(eye[2]))

    def _stop(self, worker: subprocess.Popen[bytes]) -> None:
        if worker.poll() is None:
            worker.kill()
        worker.wait()
        self._worker = None

    def close(self) -> None:
        with self._lock:
            if self._worker is not None:
                if self._worker.stdin is not None:
                    self._worker.stdin.close()
                try:
                    self._worker.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    pass
                self._stop(self._worker)


def _start_worker() -> subprocess.Popen[bytes]:
    """The worker: it ends when its input does, so with the app, however the app ends (its pipe closes)."""
    return subprocess.Popen(
        [sys.executable, "-W", "ignore", "-m", __name__],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=None if os.environ.get(DEBUG_ENV) else subprocess.DEVNULL,
    )


def _read_line(stream: IO[bytes], deadline: float) -> bytes | None:
    """One line from the worker by ``deadline``; None if it ended (or took longer)."""
    fd, got = stream.fileno(), b""
    while not got.endswith(b"\n"):
        remaining = deadline - time.monotonic()
        if remaining <= 0 or not select.select([fd], [], [], remaining)[0]:
            return None
        more = os.read(fd, 1 << 16)
        if not more:
            return None
        got += more
    return got


def _eye(path: Path) -> Point | None:
    from rerun.chunk import RrdReader  # in the worker only

    reader = RrdReader(path)
    eyes: dict[str, tuple[int, Point]] = {}  # view → the eye saved last (on the ``blueprint`` timeline)
    for store in reader.blueprints():
        for chunk in reader.stream(store=store):
            batch = chunk.to_record_batch()
            names = [f.name for f in batch.schema]
            if POSITION not in names:
                continue
            times = batch.column(names.index(TIMELINE)).to_pylist() if TIMELINE in names else [-1] * batch.num_rows
            for time_, cell in zip(times, batch.column(names.index(POSITION)).to_pylist(), strict=True):
                if cell and (chunk.entity_path not in eyes or int(time_) >= eyes[chunk.entity_path][0]):
                    x, y, z = (float(v) for v in cell[-1])
                    eyes[chunk.entity_path] = (int(time_), (x, y, z))
    return next(iter(eyes.values()))[1] if len(eyes) == 1 else None


def _serve(source: IO[bytes], sink: IO[bytes]) -> None:
    """The worker: each blueprint from ``source`` (its length, then its bytes) → one JSON line on ``sink``."""
    with tempfile.TemporaryDirectory(prefix="r2d2-viz-eye-") as folder:
        path = Path(folder) / "blueprint.rbl"
        while len(head := source.read(LENGTH.size)) == LENGTH.size:
            (length,) = LENGTH.unpack(head)
            if length > MAX_BLUEPRINT_BYTES:
                return
            path.write_bytes(source.read(length))
            try:
                answer: dict[str, object] = {"eye": _eye(path)}
            except Exception as exc:  # Rerun's reader on bytes from the page: whatever it raises, there is no eye
                answer = {"error": type(exc).__name__}
            sink.write(json.dumps(answer).encode() + b"\n")
            sink.flush()


if __name__ == "__main__":
    import argparse

    argparse.ArgumentParser(
        prog="python -m r2d2_viz.viewer.web.eye",
        description="The page's eye reader: blueprints on standard input (each its length, then its bytes), one JSON "
        "line each on standard output. Started by r2d2-viz --serve; not for use by hand.",
    ).parse_args()
    _serve(sys.stdin.buffer, sys.stdout.buffer)
