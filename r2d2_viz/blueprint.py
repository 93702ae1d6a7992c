"""``python -m r2d2_viz.blueprint`` — regenerate ``blueprints/r2d2.rbl`` (or convert ``--rviz CONFIG OUT.rbl``).

Kept at the top so the documented command stays; the layout lives in :mod:`r2d2_viz.viewer.layout.blueprint`.
"""

from __future__ import annotations

import sys

from r2d2_viz.viewer.layout.blueprint import main

if __name__ == "__main__":
    sys.exit(main())
