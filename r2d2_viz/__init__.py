"""r2d2-viz: see a URDF robot move in the Rerun viewer, without ROS.

Layers (each knows only the ones before it): model (URDF → frozen dataclasses) → sources (generated motions,
recordings; pure numpy) → kinematics (pure numpy) → stream, sinks, blueprint (the only modules importing
rerun) → runner → cli. The Python API (:class:`RobotLogger` and friends, listed in ``__all__``) is imported
lazily, so ``import r2d2_viz`` stays light.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS = {
    "RobotLogger": "api",
    "load_urdf": "model",
    "load_robot": "xacro_load",
    "parse_urdf": "model",
    "default_urdf_path": "model",
    "Robot": "model",
    "make_motion": "motion",
    "MOTIONS": "motion",
    "Source": "sources",
    "SampleChunk": "sources",
    "FrameTrack": "sources",
    "ArraySource": "sources",
    "generate_blueprint": "blueprint",
    "R2d2VizError": "errors",
    "UrdfError": "errors",
    "UsageError": "errors",
    "APP_ID": "entities",
    "TIMELINE": "entities",
}
__all__ = [
    "APP_ID",
    "MOTIONS",
    "TIMELINE",
    "ArraySource",
    "FrameTrack",
    "R2d2VizError",
    "Robot",
    "RobotLogger",
    "SampleChunk",
    "Source",
    "UrdfError",
    "UsageError",
    "default_urdf_path",
    "generate_blueprint",
    "load_robot",
    "load_urdf",
    "make_motion",
    "parse_urdf",
]

if TYPE_CHECKING:
    from .api import RobotLogger
    from .blueprint import generate_blueprint
    from .entities import APP_ID, TIMELINE
    from .errors import R2d2VizError, UrdfError, UsageError
    from .model import Robot, default_urdf_path, load_urdf, parse_urdf
    from .motion import MOTIONS, make_motion
    from .sources import ArraySource, FrameTrack, SampleChunk, Source
    from .xacro_load import load_robot


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'r2d2_viz' has no attribute {name!r}")
    return getattr(import_module(f".{module}", __name__), name)
