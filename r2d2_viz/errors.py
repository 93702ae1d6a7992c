"""The project's error hierarchy: every expected failure is one of these.

The CLI turns an ``R2d2VizError`` into one line on stderr and exit code 2; anything
else is unexpected and exits 1.
"""

from __future__ import annotations

import re
import sys
import threading
from collections.abc import Iterable

DEBUG_ENV = "R2D2_VIZ_DEBUG"
"""Set (to anything): tracebacks of unexpected errors, and the log lines of Rerun itself and of the Rerun processes
the app starts (off otherwise: our own lines say what went wrong)."""
SHOWN = 5
"""How many names a message line shows of a long list before counting the rest."""
NAMES_WIDTH = 140
"""At most this many characters of names in a message line (Gazebo's topic names are long)."""
NAME_WIDTH = 100
"""A single name longer than this (a hostile topic, say) is cut, ending in '…'."""
LINE_LIMIT = 300
"""No line the app prints to stderr is longer: :func:`stderr_line` cuts the middle of a longer one."""


class R2d2VizError(Exception):
    """Base class: a problem with the user's input that deserves one clear line."""


class UrdfError(R2d2VizError):
    """The URDF file cannot be read or describes an invalid robot.

    The message starts with the file name and names the element at fault, e.g.
    ``robot.urdf: joint 'tilt': parent link 'axs' does not exist``.
    """


class UsageError(R2d2VizError):
    """A command-line value is invalid (bad duration, rate, motion, output path, ...)."""


class SinkError(R2d2VizError):
    """A sink cannot be opened: no viewer possible, port in use, unwritable output."""


class ListenError(SinkError):
    """A port cannot be listened on (in use, not allowed): ``port`` says which, so the CLI can name the flag that
    sets it (None: not known)."""

    def __init__(self, message: str, port: int | None = None) -> None:
        super().__init__(message)
        self.port = port


class ToolEventError(R2d2VizError):
    """A tool event from the web page that is not one of the tools' messages (refused, nothing sent)."""


class BagError(R2d2VizError):
    """A ROS 2 bag cannot be read or holds the wrong thing: ``run.mcap: /joint_states is std_msgs/msg/String``."""


class PackageError(UrdfError):
    """A ROS package named by ``$(find pkg)`` or ``package://pkg`` cannot be found; says where it looked."""


class XacroError(UrdfError):
    """A xacro file cannot be expanded (bad XML, bad expression, refused expression, missing include or
    package); names the file and the include / macro chain."""


def listed(names: Iterable[object], *, first: int = SHOWN, width: int = NAMES_WIDTH) -> str:
    """Names in a message line: all of a short list (``a, b, c``), the first few of a long one and a count of
    the rest (``a, b, c, d, e and 73 more``) — a Gazebo bag's 78 undrawn topics are not a 6,000-character line.
    At most ``width`` characters of names (at least one name, itself cut to ``NAME_WIDTH``). Callers say the total
    where it matters (``78 topics …: a, b, …``)."""
    items = [short(n) for n in names]
    if len(items) <= first + 1 and len(", ".join(items)) <= width:  # "and 1 more" says no less than the name would
        return ", ".join(items)
    shown: list[str] = []
    for item in items[:first]:
        if shown and len(", ".join([*shown, item])) > width:
            break
        shown.append(item)
    return f"{', '.join(shown)} and {len(items) - len(shown)} more"


def short(name: object, width: int = NAME_WIDTH) -> str:
    """A name for a message line: cut at ``width`` characters, ending in '…' (a hostile topic name)."""
    text = str(name)
    return text if len(text) <= width else text[: width - 1] + "…"


CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")
"""Control characters but tab and newline: a frame or topic name from a bag that carries them would move the
cursor, rewrite the lines above or set the terminal's title."""


def shown(text: str) -> str:
    """``text`` with its control characters shown as escapes (``\\x1b``), never sent to the terminal."""
    return CONTROL.sub(lambda m: f"\\x{ord(m.group()):02x}", text)


def shown_in_line(text: str) -> str:
    """``text`` as one line of a listing: :func:`shown`, and its line breaks and tabs shown too (``\\x0a``), so
    that a name that holds them (a hostile frame or node name) cannot print lines of its own."""
    return shown(text).replace("\n", "\\x0a").replace("\t", "\\x09")


def stderr_line(text: str, limit: int = LINE_LIMIT) -> str:
    """``text`` with its control characters shown (:func:`shown`) and each of its lines at most ``limit``
    characters: a longer one keeps its start and its last 80 characters (where "(further problems … are
    counted)" and the like are) around a '…'."""
    text = shown(text)
    return "\n".join(line if len(line) <= limit else f"{line[: limit - 81]}…{line[-80:]}" for line in text.split("\n"))


def one_line(exc: BaseException) -> str:
    """A third-party exception as part of one message line: whitespace collapsed, at most 200 characters."""
    return " ".join(str(exc).split())[:200] or type(exc).__name__


_STDERR = threading.Lock()


def warn(message: str) -> None:
    """``warning: message`` as one whole line on stderr (at most :data:`LINE_LIMIT` characters): a bag's reader
    thread and the run warn at once, and ``print`` writes a line and its newline apart, so two lines could run
    into one."""
    line = stderr_line(f"warning: {message}") + "\n"
    with _STDERR:
        sys.stderr.write(line)
        sys.stderr.flush()
