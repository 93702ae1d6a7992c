"""Robot descriptions as ROS users keep them: a URDF, or a xacro file expanded with the PyPI ``xacro`` package.

:func:`load_description` reads a file and, when it is xacro (``.xacro`` or a xacro namespace), expands it
in a child process (``python -m r2d2_viz.xacro_load``) with a wall-clock timeout, CPU and memory limits and
a bound on the output, so a hostile file can neither hang nor exhaust the app. In the child,
:func:`_hardened` makes xacro safe to run:

- ``${…}`` and ``$(eval …)`` are checked by :func:`r2d2_viz.xacro_guard.check_expression` first;
- ``$(eval …)`` runs without builtins (xacro's own gives it all of Python's); ``${…}`` sees xacro's
  symbols minus ``python.type`` and ``python.vars``;
- ``$(find pkg)`` and ``$(eval find('pkg'))`` use :class:`r2d2_viz.packages.PackageIndex` (no ROS needed);
- every file xacro parses (the description, includes) must be a regular file under the size limit and
  declare no entities.

xacro offers no public hook for these, so :func:`_hardened` swaps five module attributes of ``xacro``
and ``xacro.substitution_args`` — ``safe_eval``, ``_global_symbols``, ``parse``,
``substitution_args._eval``, ``substitution_args._eval_find`` — and restores them on exit. Tested with
xacro 2.1.

What a xacro file can still read: files it includes or loads (``xacro:include``, ``xacro.load_yaml``), by
any path the user can read, and environment variables (``$(env NAME)``, ``$(optenv NAME)``).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import stat
import subprocess
import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from .errors import PackageError, UrdfError, UsageError, XacroError
from .packages import PackageIndex
from .urdf_check import MAX_FILE_BYTES
from .xacro_guard import RefusedExpressionError, check_expression

if TYPE_CHECKING:
    from .model import Robot

TIMEOUT_S = 60.0
MEMORY_BYTES = 2 * 1024**3
RECURSION_LIMIT = 3000
MAX_WARNINGS = 20
_XACRO_NS = re.compile(
    rb"""xmlns:[A-Za-z_][\w.-]*\s*=\s*["']https?://(?:www\.|wiki\.)?ros\.org/(?:wiki/)?xacro/?["']"""
)


class Description(NamedTuple):
    """A robot description ready for :func:`r2d2_viz.model.parse_urdf`."""

    text: bytes
    """The URDF (expanded if the file was xacro), UTF-8."""
    source: str
    """The file's name, for messages."""
    base_dir: Path
    """Where relative mesh paths resolve: the file's folder."""
    warnings: tuple[str, ...] = ()
    """xacro's own warnings (one line each)."""


def load_description(
    path: str | Path, *, mappings: Mapping[str, str] | None = None, packages: PackageIndex | None = None
) -> Description:
    """Read ``path``; expand it if it is xacro (``NAME:=VALUE`` arguments in ``mappings``; ``$(find)``
    through ``packages``). Raises :class:`UrdfError` (:class:`XacroError` for xacro problems)."""
    path = Path(path)
    data = read_bounded(path)
    if not is_xacro(path, data):
        return Description(data, path.name, path.parent)
    packages = packages or PackageIndex.from_environ(description=path)
    text, notes = _expand(path, mappings or {}, packages)
    return Description(text.encode("utf-8"), path.name, path.parent, notes)


def load_robot(
    path: str | Path, *, mappings: Mapping[str, str] | None = None, packages: PackageIndex | None = None
) -> Robot:
    """A :class:`~r2d2_viz.model.Robot` from a URDF or xacro file (xacro's warnings first in its warnings).
    ``NAME:=VALUE`` ``mappings`` are for xacro files only (:class:`UsageError` otherwise)."""
    from .model import load_urdf, parse_urdf

    path = Path(path)
    packages = packages or PackageIndex.from_environ(description=path)
    if not is_xacro(path, _head(path)):
        if mappings:
            raise UsageError(f"{', '.join(f'{k}:={v}' for k, v in mappings.items())}: arguments for a xacro file, "
                             f"but {path.name} is not one")  # fmt: skip
        return load_urdf(path, packages=packages)  # its own one-line errors for unreadable files
    description = load_description(path, mappings=mappings, packages=packages)
    try:
        robot = parse_urdf(
            description.text, source=description.source, base_dir=description.base_dir, packages=packages
        )
    except UrdfError as exc:
        if str(exc).endswith("has no <link> elements"):  # e.g. a file of macros, meant to be included
            raise UrdfError(f"{exc} after xacro (does it only define macros that another file calls?)") from None
        raise
    return dataclasses.replace(robot, warnings=description.warnings + robot.warnings)


def _head(path: Path) -> bytes:
    try:
        with path.open("rb") as fh:
            return fh.read(65536) if path.is_file() else b""
    except OSError:
        return b""


def expand_xacro(path: str | Path, *, mappings: Mapping[str, str], packages: PackageIndex) -> str:
    """The URDF a xacro file expands to (hardened, in a child process). Raises :class:`XacroError`."""
    return _expand(Path(path), mappings, packages)[0]


def is_xacro(path: Path, data: bytes) -> bool:
    """By extension, or a xacro namespace declaration (``xmlns:xacro="http://www.ros.org/wiki/xacro"``)."""
    return path.suffix.lower() == ".xacro" or _XACRO_NS.search(data[:65536]) is not None


def read_bounded(path: Path) -> bytes:
    """A regular file's bytes, refused (one line) when missing, special or over the size limit."""
    name = path.name or str(path)
    try:
        st = path.stat()
    except FileNotFoundError:
        raise UrdfError(f"{name}: file not found ({str(path)!r})") from None
    except OSError as exc:
        raise UrdfError(f"{name}: cannot access file: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise UrdfError(f"{name}: is a directory, not a URDF file")
    if not stat.S_ISREG(st.st_mode):
        raise UrdfError(f"{name}: is not a regular file")
    try:
        with path.open("rb") as fh:
            data = fh.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise UrdfError(f"{name}: cannot read file: {exc.strerror or exc}") from None
    if len(data) > MAX_FILE_BYTES:
        raise UrdfError(f"{name}: file is too large (more than {MAX_FILE_BYTES} bytes)")
    return data


# --------------------------------------------------------------------------- the parent side


def _expand(path: Path, mappings: Mapping[str, str], packages: PackageIndex) -> tuple[str, tuple[str, ...]]:
    job = {
        "path": str(path.absolute()),
        "mappings": dict(mappings),
        "pins": {k: str(v) for k, v in packages.pins.items()},
        "paths": [str(p) for p in packages.paths],
        "description": str(packages.description) if packages.description is not None else str(path.absolute()),
        "ros_package_path": [str(p) for p in packages.ros_package_path],
        "ament_prefix_path": [str(p) for p in packages.ament_prefix_path],
    }
    try:
        done = subprocess.run(
            [sys.executable, "-m", "r2d2_viz.xacro_load"],
            input=json.dumps(job),
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
        )
    except subprocess.TimeoutExpired:
        raise XacroError(f"{path.name}: xacro expansion took more than {TIMEOUT_S:g} s; stopped") from None
    try:
        answer = json.loads(done.stdout)
    except ValueError:
        why = _last_line(done.stderr) or f"exit status {done.returncode}"
        if done.returncode < 0 or "MemoryError" in done.stderr:
            why = f"xacro ran out of its limits (memory {MEMORY_BYTES >> 20} MiB, CPU {TIMEOUT_S:g} s)"
        raise XacroError(f"{path.name}: xacro expansion failed: {why}") from None
    if "error" in answer:
        raise XacroError(str(answer["error"]))
    return str(answer["urdf"]), tuple(str(w) for w in answer.get("warnings", ()))


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1][:300] if lines else ""


# --------------------------------------------------------------------------- the child side


def _child_main() -> int:
    _limit_resources()
    job = json.loads(sys.stdin.read())
    path = Path(job["path"])
    packages = PackageIndex(
        pins={k: Path(v) for k, v in job["pins"].items()},
        paths=[Path(p) for p in job["paths"]],
        description=Path(job["description"]),
        ros_package_path=[Path(p) for p in job["ros_package_path"]],
        ament_prefix_path=[Path(p) for p in job["ament_prefix_path"]],
    )
    captured = _Captured()
    try:
        with redirect_stdout(captured), redirect_stderr(captured):
            urdf = _expand_here(path, job["mappings"], packages)
        answer: dict[str, Any] = {"urdf": urdf, "warnings": captured.warnings()}
    except UrdfError as exc:
        answer = {"error": str(exc)}
    sys.stdout.write(json.dumps(answer))
    return 0


def _limit_resources() -> None:
    sys.setrecursionlimit(RECURSION_LIMIT)
    try:
        import resource
    except ImportError:  # not on POSIX: the parent's timeout still applies
        return
    for limit, value in ((resource.RLIMIT_AS, MEMORY_BYTES), (resource.RLIMIT_CPU, math.ceil(TIMEOUT_S))):
        hard = resource.getrlimit(limit)[1]
        bound = value if hard == resource.RLIM_INFINITY else min(hard, value)
        resource.setrlimit(limit, (bound, bound))


class _Captured:
    """xacro's warnings (it prints them); kept as one-line strings."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def write(self, text: str) -> int:
        self.lines.extend(line.strip() for line in text.splitlines() if line.strip())
        return len(text)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False

    def warnings(self) -> list[str]:
        kept = [line for line in self.lines if line.lower().startswith("warning")]
        return kept[:MAX_WARNINGS]


def _expand_here(path: Path, mappings: Mapping[str, str], packages: PackageIndex) -> str:
    """Expand in this process (the child), hardened; raise :class:`XacroError` with the include/macro chain."""
    import xml.parsers.expat

    import xacro

    with _hardened(packages):
        try:
            doc = xacro.process_file(str(path), mappings=dict(mappings), verbosity=0)
        except xml.parsers.expat.ExpatError as exc:
            raise XacroError(_located(path, f"not well-formed XML: {exc}")) from None
        except Exception as exc:
            raise XacroError(_located(path, _reason(exc))) from None
        text = str(doc.documentElement.toxml())
    if len(text) > MAX_FILE_BYTES:
        raise XacroError(f"{path.name}: expands to more than {MAX_FILE_BYTES} bytes; refused")
    return '<?xml version="1.0" encoding="utf-8"?>\n' + text


def _reason(exc: BaseException) -> str:
    """The innermost cause, in words: ours (package, refused expression) as they are, xacro's with context."""
    inner: BaseException = exc
    while getattr(inner, "exc", None) is not None and isinstance(inner.exc, BaseException):  # type: ignore[attr-defined]
        inner = inner.exc  # type: ignore[attr-defined]
    if isinstance(inner, (PackageError, XacroError)):
        return str(inner)
    if isinstance(inner, MemoryError):
        return f"xacro ran out of memory (limit {MEMORY_BYTES >> 20} MiB)"
    if isinstance(inner, RecursionError):
        return "macros or includes nest too deeply (recursion)"
    if isinstance(inner, RefusedExpressionError):
        return f"expression refused for safety: {inner}"
    from xacro.substitution_args import ArgException

    if isinstance(inner, ArgException):
        return f"xacro argument {str(inner)!r} is not set (pass {inner}:=VALUE)"
    if inner is exc:
        text = str(exc)
    else:  # xacro wraps the cause: "<class 'X'>: cause cause" or "cause\nwhen evaluating expression '…'"
        if isinstance(inner, SyntaxError):
            text = f"syntax error: {inner.msg}"
        elif isinstance(inner, OSError) and inner.strerror:
            text = f"{inner.strerror}: {inner.filename}" if inner.filename else inner.strerror
        else:
            text = str(inner)
        suffix = getattr(exc, "suffix", None)
        text = f"{text} {suffix}" if suffix else text
    return " ".join(text.split()) or type(inner).__name__


def _located(path: Path, problem: str) -> str:
    """``<file>: <problem> (in macro 'm' of a.xacro, included from b.xacro < c.xacro)``, one line."""
    import xacro

    files = [Path(f).name for f in reversed(xacro.filestack or []) if f]
    macros = [str(m.body.getAttribute("name")) for m in reversed(xacro.macrostack or []) if m.body is not None]
    where = files[0] if files else path.name
    chain: list[str] = []
    if macros:
        chain.append("in macro " + " < ".join(repr(m) for m in macros[:6]))
    if len(files) > 1:
        chain.append("included from " + " < ".join(files[1:7]))
    suffix = f" ({'; '.join(chain)})" if chain else ""
    return " ".join(f"{where}: {problem}{suffix}".split())


@contextmanager
def _hardened(packages: PackageIndex) -> Iterator[None]:
    """Swap xacro's evaluation, ``$(find)`` and file parsing for guarded ones; restore them on exit."""
    import xacro
    from xacro import substitution_args

    def find(name: str) -> str:
        near = Path(xacro.filestack[-1]).parent if xacro.filestack and xacro.filestack[-1] else None
        return str(packages.find(str(name), near=near))

    original = {
        (xacro, "safe_eval"): xacro.safe_eval,
        (xacro, "_global_symbols"): xacro._global_symbols,
        (xacro, "parse"): xacro.parse,
        (substitution_args, "_eval"): substitution_args._eval,
        (substitution_args, "_eval_find"): substitution_args._eval_find,
    }
    safe_eval, parse = xacro.safe_eval, xacro.parse

    def checked_safe_eval(expr: str, globals: dict[str, Any], locals: Any = None) -> Any:
        check_expression(expr)
        return safe_eval(expr, globals, locals)

    def guarded_parse(inp: Any, filename: str | None = None) -> Any:
        if inp is None and filename is not None:
            try:
                inp = _read_xacro_file(Path(os.path.join(xacro.root_dir, filename)))
            except OSError as exc:  # as xacro does: lets <xacro:include optional="true"> skip the file
                xacro.filestack.pop()
                raise xacro.XacroException(f"{exc.strerror or exc}: {filename}", exc=exc) from None
        return parse(inp, filename)

    def eval_without_builtins(expr: str, context: dict[str, Any]) -> str:
        check_expression(expr)
        names = _EvalNames(context.setdefault("arg", {}), find)
        return str(eval(compile(expr.strip(), "<$(eval)>", "eval"), {"__builtins__": {}}, names))

    replacement = {
        (xacro, "safe_eval"): checked_safe_eval,
        (xacro, "_global_symbols"): _shrunk_symbols(xacro),
        (xacro, "parse"): guarded_parse,
        (substitution_args, "_eval"): eval_without_builtins,
        (substitution_args, "_eval_find"): find,
    }
    try:
        for (module, attr), value in replacement.items():
            setattr(module, attr, value)
        yield
    finally:
        for (module, attr), value in original.items():
            setattr(module, attr, value)


def _read_xacro_file(path: Path) -> str:
    st = path.stat()
    if not stat.S_ISREG(st.st_mode):
        raise XacroError("is not a regular file; refused")
    with path.open("rb") as fh:
        data = fh.read(MAX_FILE_BYTES + 1)
    if len(data) > MAX_FILE_BYTES:
        raise XacroError(f"file is too large (more than {MAX_FILE_BYTES} bytes)")
    if b"<!DOCTYPE" in data and b"<!ENTITY" in data:
        raise XacroError("DOCTYPE declares entities (<!ENTITY ...>); refused for safety")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise XacroError(f"not valid UTF-8 (offset {exc.start})") from None


def _shrunk_symbols(xacro: Any) -> dict[str, Any]:
    """xacro's global symbols without ``python.type`` and ``python.vars`` (reflection)."""
    symbols = dict(xacro._global_symbols)
    python = xacro.NameSpace()
    python.update({k: v for k, v in symbols["python"].items() if k not in ("type", "vars")})
    symbols["python"] = python
    return symbols


class _EvalNames(Mapping[str, Any]):
    """The names ``$(eval …)`` sees: xacro's functions, math, a few constructors, then the arguments."""

    def __init__(self, args: Mapping[str, str], find: Any) -> None:
        from xacro.substitution_args import convert_value

        self._args, self._convert = args, convert_value
        self._functions: dict[str, Any] = {k: v for k, v in vars(math).items() if not k.startswith("_")}
        self._functions.update(
            {"true": True, "false": False, "True": True, "False": False, "find": find},
            list=list, dict=dict, map=map, str=str, float=float, int=int,
            arg=lambda name: convert_value(args[name], "auto"),
            env=lambda name: os.environ[name],
            optenv=lambda name, default="": os.environ.get(name, default),
        )  # fmt: skip

    def __getitem__(self, key: str) -> Any:
        if key in self._functions:
            return self._functions[key]
        return self._convert(self._args[key], "auto")

    def __iter__(self) -> Iterator[str]:
        return iter({**self._functions, **self._args})

    def __len__(self) -> int:
        return len(self._functions) + len(self._args)


if __name__ == "__main__":
    sys.exit(_child_main())
