"""The command line on top of everything: ``r2d2-viz`` parses its flags (``parser``), runs the app or a fleet, and
alone speaks of flags and exit codes (``command``)."""

from r2d2_viz.cli.command import main
from r2d2_viz.cli.parser import CONNECT_DEFAULT, EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_OK, EXIT_UNEXPECTED

__all__ = ["CONNECT_DEFAULT", "EXIT_BAD_INPUT", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_UNEXPECTED", "main"]
