"""The ``r2d2-viz`` command run in a process forked from a warm interpreter: the suite's CLI runs without the
second of start-up each (Python, numpy, pyarrow, the app's own modules imported once per xdist worker).

A *zygote* (one per worker, started on the first call) imports what every run imports and waits on a Unix
socket. Each call sends it the command's arguments, environment and working directory with the two pipes of its
stdout and stderr; the zygote forks, and the child sets ``sys.argv``, ``os.environ`` and the cwd, makes the pipes
its fds 1 and 2 (``/dev/null`` its stdin) and runs exactly what the console script runs (``sys.exit(main())``),
ending as any interpreter does (atexit handlers, Rerun's shutdown, flushed streams). The zygote reports its exit
status and CPU. So each run is still a process of its own, with its own fds, signals, exit code and children:
only the imports are shared, and ``tests/test_startup.py`` (a fresh interpreter) holds what a run imports.

Not forked (a fresh ``subprocess.run`` instead): an environment that changes how Python or Rerun start
(``PYTHON*``, ``RUST_*``, ``RERUN_*``, the locale, the loader) or a caller asking ``fresh=True``.
"""

from __future__ import annotations

import atexit
import contextlib
import json
import locale
import os
import selectors
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

# What the zygote imports: the console script's module, and what runs import (the app's run, Rerun, a bag's
# readers and type store, the YAML of --rviz). Rerun is imported as the CLI imports it (``cli/command.py``'s
# ``_quiet_rerun``: ``RUST_LOG=off`` around it, its log filter is read then; not under ``R2D2_VIZ_DEBUG``). Rerun
# supports fork (``os.register_at_fork``: a child drops the parent's recordings); numpy's OpenBLAS and Arrow's
# jemalloc too. The app's modules read no environment when imported. What a run would not have imported is there
# all the same: ``tests/test_startup.py`` (a fresh interpreter) holds what a run imports.
PRELOAD = (
    "r2d2_viz.cli",
    "r2d2_viz.viewer.sinks",
    "r2d2_viz.runner",
    "r2d2_viz.cli.run_args",
    "rosbags.typesys",
    "ruamel.yaml",
    "PIL.Image",
    "lxml.etree",
    "psutil",
    "ssl",
    "uuid",
)
# Flags whose runs are gRPC clients (of a viewer: ``--render``'s ViewerClient, ``--spawn``/``--connect``'s GrpcSink;
# of a catalog server: ``--dataset``): a forked child's client never gets its tokio tasks run (a ``--render`` hung
# in ``ViewerClient.connect``), though its server side (``--serve``) answers. These run fresh.
FRESH_FLAGS = ("--render", "--spawn", "--connect", "--dataset")
FRESH_PREFIXES = ("PYTHON", "RUST_", "RERUN_", "R2D2_VIZ_DEBUG", "LC_", "LANG", "LD_", "MALLOC", "JE_", "ARROW_")

ZYGOTE = r"""
import json, os, selectors, signal, socket, struct, sys, tempfile

def _send(sock, message):
    data = json.dumps(message).encode()
    sock.sendall(struct.pack("!I", len(data)) + data)

def _serve(sock, preface):
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_w, False)
    signal.signal(signal.SIGCHLD, lambda *_: None)
    signal.set_wakeup_fd(wake_w)
    selector = selectors.DefaultSelector()
    selector.register(sock, selectors.EVENT_READ)
    selector.register(wake_r, selectors.EVENT_READ)
    while True:
        for key, _ in selector.select():
            if key.fileobj == wake_r:
                os.read(wake_r, 4096)
                while True:
                    try:
                        pid, status, usage = os.wait4(-1, os.WNOHANG)
                    except ChildProcessError:
                        break
                    if pid == 0:
                        break
                    _send(sock, {"exited": pid, "code": os.waitstatus_to_exitcode(status),
                                 "cpu": usage.ru_utime + usage.ru_stime})
                continue
            head = sock.recv(4)
            if not head:  # the worker closed its end: reap what is left (its CPU counts for the run), then end
                while True:
                    try:
                        os.wait()
                    except ChildProcessError:
                        return None
            size = struct.unpack("!I", head)[0]
            data, fds, _, _ = socket.recv_fds(sock, size, 2)
            while len(data) < size:
                data += sock.recv(size - len(data))
            request = json.loads(data)
            sys.stdout.flush(); sys.stderr.flush()
            pid = os.fork()
            if pid == 0:
                signal.set_wakeup_fd(-1)
                signal.signal(signal.SIGCHLD, signal.SIG_DFL)
                signal.signal(signal.SIGINT, signal.default_int_handler)  # as in any Python process
                selector.close(); sock.close(); os.close(wake_r); os.close(wake_w)
                null = os.open(os.devnull, os.O_RDONLY)
                os.dup2(null, 0); os.dup2(fds[0], 1); os.dup2(fds[1], 2)
                for fd in (null, *fds):
                    os.close(fd)
                os.environ.clear()
                os.environ.update(request["env"])
                if request["cwd"] is not None:
                    os.chdir(request["cwd"])
                if preface:
                    os.write(2, preface)
                return request["argv"]
            for fd in fds:
                os.close(fd)
            _send(sock, {"started": pid})

sock = socket.socket(fileno=int(sys.argv[1]))
signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C sent to the worker's process group is not the zygote's
with tempfile.TemporaryFile() as said:  # what importing prints (a warning) goes to every run's stderr
    saved = os.dup(2)
    os.dup2(said.fileno(), 2)
    try:
        import importlib
        saved_log = os.environ.get("RUST_LOG")
        if not os.environ.get("R2D2_VIZ_DEBUG"):
            os.environ["RUST_LOG"] = "off"
        for name in sys.argv[2].split(","):
            importlib.import_module(name)
        if saved_log is None:
            os.environ.pop("RUST_LOG", None)
        else:
            os.environ["RUST_LOG"] = saved_log
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)
    said.seek(0)
    preface = said.read()
argv = _serve(sock, preface)
if argv is None:
    sys.exit(0)
del sock, preface, _serve, _send
sys.argv = argv
from r2d2_viz.cli import main
sys.exit(main())
"""


class _Zygote:
    def __init__(self) -> None:
        self.sock, theirs = socket.socketpair()
        self.env = dict(os.environ)
        self.proc = subprocess.Popen(
            [sys.executable, "-c", ZYGOTE, str(theirs.fileno()), ",".join(PRELOAD)],
            pass_fds=[theirs.fileno()],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        theirs.close()
        self.lock = threading.Lock()
        self.exits: dict[int, tuple[int, float]] = {}
        self.started: list[int] = []
        self.reported = 0.0  # its runs' CPU, counted in child_cpu and again in RUSAGE_CHILDREN once it is reaped

    def _read_one(self) -> None:
        head = self._recv_exact(4)
        message = json.loads(self._recv_exact(struct.unpack("!I", head)[0]))
        if "started" in message:
            self.started.append(message["started"])
        else:
            self.exits[message["exited"]] = (message["code"], message["cpu"])

    def _recv_exact(self, size: int) -> bytes:
        data = b""
        while len(data) < size:
            part = self.sock.recv(size - len(data))
            if not part:
                raise RuntimeError("the CLI zygote died")
            data += part
        return data

    def start(self, argv: list[str], env: dict[str, str], cwd: str | None, out: int, err: int) -> int:
        data = json.dumps({"argv": argv, "env": env, "cwd": cwd}).encode()
        with self.lock:
            self.sock.sendall(struct.pack("!I", len(data)))
            socket.send_fds(self.sock, [data], [out, err])
            while not self.started:
                self._read_one()
            return self.started.pop()

    def wait(self, pid: int, deadline: float = float("inf")) -> tuple[int, float] | None:
        while time.monotonic() < deadline:
            with self.lock:
                if pid in self.exits:
                    return self.exits.pop(pid)
                self.sock.settimeout(0.05)  # another thread may hold the exit we wait for: take turns
                try:
                    self._read_one()
                except TimeoutError:
                    pass
                finally:
                    self.sock.settimeout(None)
        return None


_zygote: _Zygote | None = None
_zygote_lock = threading.Lock()
child_cpu = 0.0  # the forked runs' CPU (user + system), which RUSAGE_CHILDREN of the worker does not see


def _the_zygote() -> _Zygote:
    global _zygote, child_cpu
    with _zygote_lock:
        if _zygote is None or _zygote.proc.poll() is not None:
            if _zygote is None:
                atexit.register(_stop)
            else:  # reaped just now: its runs' CPU came into RUSAGE_CHILDREN with it
                child_cpu -= _zygote.reported
            _zygote = _Zygote()
        return _zygote


def _stop() -> None:
    """At the worker's exit: the zygote ends once its last run is reaped, and is waited for (its CPU counted)."""
    if _zygote is not None:
        _zygote.sock.close()
        with contextlib.suppress(subprocess.TimeoutExpired):
            _zygote.proc.wait(timeout=60)


def forks(env: dict[str, str], args: tuple[str, ...] = ()) -> bool:
    """Whether a run with these arguments and this environment may be forked from the zygote (made with the
    worker's environment)."""
    if os.environ.get("R2D2_TEST_FRESH_CLI") or any(a.split("=")[0] in FRESH_FLAGS for a in args):
        return False
    base = _zygote.env if _zygote is not None else dict(os.environ)
    changed = {k for k in set(env) | set(base) if env.get(k) != base.get(k)}
    return not any(k.startswith(FRESH_PREFIXES) for k in changed)


def _decode(data: bytes) -> str:
    # as subprocess.run(text=True) does: the locale's encoding, universal newlines
    return data.decode(locale.getpreferredencoding(False)).replace("\r\n", "\n").replace("\r", "\n")


def _kill(zygote: _Zygote, pid: int) -> None:
    global child_cpu
    os.kill(pid, signal.SIGKILL)  # as subprocess.run does on a timeout; the zygote still has it unwaited
    ended = zygote.wait(pid)
    child_cpu += ended[1] if ended else 0.0
    zygote.reported += ended[1] if ended else 0.0


def run(
    command: list[str], args: tuple[str, ...], env: dict[str, str], cwd: Path | None, timeout: float
) -> subprocess.CompletedProcess[str]:
    """``subprocess.run(command + args, capture_output=True, text=True, timeout=…)``, forked from the zygote."""
    global child_cpu
    zygote = _the_zygote()
    out_r, out_w = os.pipe()
    err_r, err_w = os.pipe()
    try:
        pid = zygote.start([command[0], *args], env, None if cwd is None else str(cwd), out_w, err_w)
    finally:
        os.close(out_w)
        os.close(err_w)
    chunks: dict[int, list[bytes]] = {out_r: [], err_r: []}
    deadline = time.monotonic() + timeout
    with selectors.DefaultSelector() as selector:
        for fd in chunks:
            selector.register(fd, selectors.EVENT_READ)
        while selector.get_map():
            left = deadline - time.monotonic()
            ready = selector.select(max(left, 0)) if left > 0 else []
            if not ready:
                for key in list(selector.get_map().values()):
                    os.close(key.fd)
                _kill(zygote, pid)
                raise subprocess.TimeoutExpired([*command, *args], timeout)
            for key, _ in ready:
                part = os.read(key.fd, 65536)
                if part:
                    chunks[key.fd].append(part)
                else:
                    selector.unregister(key.fd)
                    os.close(key.fd)
    ended = zygote.wait(pid, deadline)
    if ended is None:
        _kill(zygote, pid)
        raise subprocess.TimeoutExpired([*command, *args], timeout)
    code, cpu = ended
    child_cpu += cpu
    zygote.reported += cpu
    return subprocess.CompletedProcess(
        [*command, *args], code, _decode(b"".join(chunks[out_r])), _decode(b"".join(chunks[err_r]))
    )
