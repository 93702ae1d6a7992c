"""r2d2-viz: see a robot, and what it senses, in the Rerun viewer — without ROS.

Stages, each importing only from the ones before it: ``robot`` (descriptions → model) → ``meshes`` →
``kinematics`` (pure numpy) → ``msgs`` (ROS messages as numpy) → ``sources`` (motions, bags) → ``rviz`` (configs)
→ ``viewer`` (the only stage importing rerun) → ``ros_out`` (bags written) → ``runner``, ``api``, ``cli``, and
``fleet`` (many bags in parallel, one dataset).
The Python API (:class:`RobotLogger` and friends, listed in ``__all__``) is imported lazily, so
``import r2d2_viz`` stays light.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS = {
    "RobotLogger": "api",
    "on_pick": "api",
    "serve_tools": "api",
    "load_urdf": "robot.model",
    "load_robot": "robot.xacro_load",
    "parse_urdf": "robot.model",
    "default_urdf_path": "robot.model",
    "Robot": "robot.model",
    "make_motion": "sources.motion",
    "MOTIONS": "sources.motion",
    "Source": "sources.base",
    "SampleChunk": "sources.base",
    "FrameTrack": "sources.base",
    "ArraySource": "sources.base",
    "generate_blueprint": "viewer.layout.blueprint",
    "R2d2VizError": "errors",
    "UrdfError": "errors",
    "UsageError": "errors",
    "APP_ID": "viewer.entities",
    "TIMELINE": "viewer.entities",
    "fleet_summary": "fleet.dataset",
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
    "fleet_summary",
    "generate_blueprint",
    "load_robot",
    "load_urdf",
    "make_motion",
    "on_pick",
    "parse_urdf",
    "serve_tools",
]

if TYPE_CHECKING:
    from r2d2_viz.api import RobotLogger, on_pick, serve_tools
    from r2d2_viz.errors import R2d2VizError, UrdfError, UsageError
    from r2d2_viz.fleet.dataset import fleet_summary
    from r2d2_viz.robot.model import Robot, default_urdf_path, load_urdf, parse_urdf
    from r2d2_viz.robot.xacro_load import load_robot
    from r2d2_viz.sources.base import ArraySource, FrameTrack, SampleChunk, Source
    from r2d2_viz.sources.motion import MOTIONS, make_motion
    from r2d2_viz.viewer.entities import APP_ID, TIMELINE
    from r2d2_viz.viewer.layout.blueprint import generate_blueprint


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'r2d2_viz' has no attribute {name!r}")
    return getattr(import_module(f".{module}", __name__), name)
