"""r2d2-viz: the ROS 2 "URDF with robot_state_publisher" tutorial, in the Rerun viewer, without ROS.

Layers (each knows only the ones before it):
model (URDF → frozen dataclasses) → motion / kinematics (pure numpy) → stream + sinks + blueprint
(the only modules importing rerun) → runner → cli.
"""

from __future__ import annotations

__version__ = "0.1.0"
