"""The project's error hierarchy: every expected failure is one of these.

The CLI turns an ``R2d2VizError`` into one line on stderr and exit code 2; anything
else is unexpected and exits 1.
"""

from __future__ import annotations


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


class BagError(R2d2VizError):
    """A ROS 2 bag cannot be read or holds the wrong thing: ``run.mcap: /joint_states is std_msgs/msg/String``."""


class PackageError(UrdfError):
    """A ROS package named by ``$(find pkg)`` or ``package://pkg`` cannot be found; says where it looked."""


class XacroError(UrdfError):
    """A xacro file cannot be expanded (bad XML, bad expression, refused expression, missing include or
    package); names the file and the include / macro chain."""


def one_line(exc: BaseException) -> str:
    """A third-party exception as part of one message line: whitespace collapsed, at most 200 characters."""
    return " ".join(str(exc).split())[:200] or type(exc).__name__
