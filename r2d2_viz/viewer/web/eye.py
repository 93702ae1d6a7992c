"""The 3D view's eye as the viewer holds it, for the pose tools' rays (RViz's ``PoseTool`` takes the ground under the
pointer, whatever is drawn there). Rerun's web viewer keeps each 3D view's camera in its blueprint
(``EyeControls3D``, saved as the user orbits); its selection events give only the point picked. The page serves
rerun-notebook's module with one hook (:func:`hooked_widget`: the widget's ``WebViewer`` on ``globalThis``), so that
at a click it can send the blueprint (``WebViewer.save_blueprint``) and :func:`blueprint_eye` reads the eye's
position back, in the view's world (the fixed frame).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

MAX_BLUEPRINT_BYTES = 4 << 20
"""A blueprint the page sends is some tens of kB (77 kB measured for the R2D2's layout)."""
WIDGET_VIEWER = "this.viewer = new WebViewer();"
WIDGET_HOOK = WIDGET_VIEWER + " globalThis.r2d2Viewer = this.viewer;"
"""rerun-notebook's widget keeps its ``WebViewer`` to itself: the page reaches it through ``globalThis``."""
POSITION = "EyeControls3D:position"
TIMELINE = "blueprint"

Point = tuple[float, float, float]


def hooked_widget(js: bytes) -> bytes:
    """rerun-notebook's ``widget.js`` with its viewer on ``globalThis.r2d2Viewer`` (unchanged if the line is not
    there exactly once: the page then finds no viewer, and the pose tools take the point picked)."""
    text = js.decode("utf-8")
    if text.count(WIDGET_VIEWER) != 1:
        return js
    return text.replace(WIDGET_VIEWER, WIDGET_HOOK).encode("utf-8")


def blueprint_eye(blob: bytes) -> Point | None:
    """The eye position of the blueprint's one 3D view (the last one saved), from an ``.rbl`` stream; None when it
    holds none, several views with an eye, or cannot be read."""
    if not blob or len(blob) > MAX_BLUEPRINT_BYTES:
        return None
    with tempfile.TemporaryDirectory(prefix="r2d2-viz-eye-") as folder:
        path = Path(folder) / "blueprint.rbl"
        path.write_bytes(blob)
        try:
            return _eye(path)
        except Exception:  # Rerun's reader on bytes from the page: whatever it raises, there is no eye
            return None


def _eye(path: Path) -> Point | None:
    from rerun.chunk import RrdReader  # on the first pose tool's click, not when the page starts

    reader = RrdReader(path)
    eyes: dict[str, tuple[int, Point]] = {}  # view → the eye saved last (on the ``blueprint`` timeline)
    for store in reader.blueprints():
        for chunk in reader.stream(store=store):
            batch = chunk.to_record_batch()
            names = [f.name for f in batch.schema]
            if POSITION not in names:
                continue
            times = batch.column(names.index(TIMELINE)).to_pylist() if TIMELINE in names else [-1] * batch.num_rows
            for time, cell in zip(times, batch.column(names.index(POSITION)).to_pylist(), strict=True):
                if cell and (chunk.entity_path not in eyes or int(time) >= eyes[chunk.entity_path][0]):
                    x, y, z = (float(v) for v in cell[-1])
                    eyes[chunk.entity_path] = (int(time), (x, y, z))
    return next(iter(eyes.values()))[1] if len(eyes) == 1 else None
