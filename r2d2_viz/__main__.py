"""``python -m r2d2_viz`` — same as the ``r2d2-viz`` command."""

from __future__ import annotations

import sys

from r2d2_viz.cli import main

if __name__ == "__main__":
    sys.exit(main())
