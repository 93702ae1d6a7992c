"""The project's error hierarchy: every expected failure is one of these.

The CLI turns an ``R2d2VizError`` into one line on stderr and exit code 2; anything
else is unexpected and exits 1.
"""

from __future__ import annotations

from collections.abc import Iterable

DEBUG_ENV = "R2D2_VIZ_DEBUG"
"""Set (to anything): tracebacks of unexpected errors, and the log lines of Rerun itself and of the Rerun processes
the app starts (off otherwise: our own lines say what went wrong)."""
SHOWN = 5
"""How many names a message line shows of a long list before counting the rest."""


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


class ToolEventError(R2d2VizError):
    """A tool event from the web page that is not one of the tools' messages (refused, nothing sent)."""


class BagError(R2d2VizError):
    """A ROS 2 bag cannot be read or holds the wrong thing: ``run.mcap: /joint_states is std_msgs/msg/String``."""


class PackageError(UrdfError):
    """A ROS package named by ``$(find pkg)`` or ``package://pkg`` cannot be found; says where it looked."""


class XacroError(UrdfError):
    """A xacro file cannot be expanded (bad XML, bad expression, refused expression, missing include or
    package); names the file and the include / macro chain."""


def listed(names: Iterable[object], *, first: int = SHOWN) -> str:
    """Names in a message line: all of a short list (``a, b, c``), the first few of a long one and a count of
    the rest (``a, b, c, d, e and 73 more``) — a Gazebo bag's 78 undrawn topics are not a 6,000-character line.
    Callers say the total where it matters (``78 topics …: a, b, …``)."""
    items = [str(n) for n in names]
    if len(items) <= first + 1:  # "and 1 more" says no less than the name would
        return ", ".join(items)
    return f"{', '.join(items[:first])} and {len(items) - first} more"


def one_line(exc: BaseException) -> str:
    """A third-party exception as part of one message line: whitespace collapsed, at most 200 characters."""
    return " ".join(str(exc).split())[:200] or type(exc).__name__
