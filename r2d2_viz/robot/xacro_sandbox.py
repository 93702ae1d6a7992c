"""The child process that expands a xacro file (``python -m r2d2_viz.robot.xacro_sandbox``), made safe to run.

:mod:`r2d2_viz.robot.xacro_load` sends a job (file, arguments, where packages are) as JSON on stdin and reads
``{"urdf": …, "warnings": […]}`` or ``{"error": "one line"}`` on stdout. Here, bounded in memory
(:data:`MEMORY_BYTES`), CPU time and recursion, :func:`_hardened` makes xacro safe to run:

- ``${…}`` and ``$(eval …)`` are checked by :func:`r2d2_viz.robot.xacro_guard.check_expression` first;
- ``$(eval …)`` runs without builtins (xacro's own gives it all of Python's); ``${…}`` sees xacro's
  symbols minus ``python.type`` and ``python.vars``;
- ``$(find pkg)`` and ``$(eval find('pkg'))`` use :class:`r2d2_viz.robot.packages.PackageIndex` (no ROS needed);
- every file xacro parses (the description, includes) must be a regular file under the size limit and
  declare no entities.

xacro offers no public hook for these, so :func:`_hardened` swaps five module attributes of ``xacro``
and ``xacro.substitution_args`` — ``safe_eval``, ``_global_symbols``, ``parse``,
``substitution_args._eval``, ``substitution_args._eval_find`` — and restores them on exit. Tested with
xacro 2.1 (pinned in pyproject.toml).
"""

from __future__ import annotations

import json
import math
import os
import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from pathlib import Path
from typing import Any

from r2d2_viz.errors import PackageError, UrdfError, XacroError
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.regular_file import NotRegularFileError, read_regular
from r2d2_viz.robot.urdf_xml import MAX_FILE_BYTES
from r2d2_viz.robot.xacro_guard import RefusedExpressionError, check_expression

MEMORY_BYTES = 2 * 1024**3
RECURSION_LIMIT = 3000
MAX_WARNINGS = 20


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m r2d2_viz.robot.xacro_sandbox",
        usage="%(prog)s < JOB.json",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.parse_args(argv)  # the job comes on stdin: only --help is an argument
    job = json.loads(sys.stdin.read())
    _limit_resources(float(job["cpu_seconds"]))
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
    answer["files"] = _files_read()
    sys.stdout.write(json.dumps(answer))
    return 0


def _files_read() -> list[str]:
    """Every file xacro read besides the description (includes, ``load_yaml`` files), for ``--watch``."""
    import xacro

    return sorted({str(Path(f).absolute()) for f in (*xacro.all_includes, *(xacro.filestack or ())) if f})


def _limit_resources(cpu_seconds: float) -> None:
    sys.setrecursionlimit(RECURSION_LIMIT)
    try:
        import resource
    except ImportError:  # not on POSIX: the parent's timeout still applies
        return
    for limit, value in ((resource.RLIMIT_AS, MEMORY_BYTES), (resource.RLIMIT_CPU, math.ceil(cpu_seconds))):
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
    try:
        data = read_regular(path, MAX_FILE_BYTES)
    except NotRegularFileError:
        raise XacroError("is not a regular file; refused") from None
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
    sys.exit(main())
