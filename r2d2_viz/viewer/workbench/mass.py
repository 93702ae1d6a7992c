"""RViz's RobotModel "Mass Properties" and "Show Axes", logged static in each link's named frame:

* ``/robot/mass/<link>`` — a red ball of lead of the link's mass at its centre of mass (``Ellipsoids3D``);
* ``/robot/inertia/<link>`` — the red box of equal inertia on the tensor's principal axes (``Boxes3D``,
  quaternion xyzw);
* ``/robot/axes/<link>`` — the link's axes (``TransformAxes3D``).

The maths is :mod:`r2d2_viz.robot.inertial`'s. An impossible inertia (RViz draws no box for it either) is one
notice line, said when the inertia is asked for; so is a robot with no ``<inertial>`` at all when mass or inertia
is asked for (nothing would show, and nothing would say why).
"""

from __future__ import annotations

import rerun as rr

from r2d2_viz.kinematics.transforms import matrix_to_quat
from r2d2_viz.robot.inertial import equivalent_box, inertia_problems, lead_sphere_radius
from r2d2_viz.robot.model import Robot
from r2d2_viz.rviz.spec import RobotModel
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.notices import Notices

MASS_COLOR = (255, 0, 0, 255)
"""RViz: ``setColor(1, 0, 0, 1)`` for both shapes."""
ALL_LINKS = "*"
"""In :attr:`RobotModel.axes`: every link's axes (``--link-axes``)."""


def wants_mass_properties(display: RobotModel | None) -> bool:
    return display is not None and display.enabled and (display.mass or display.inertia or bool(display.axes))


def log_mass_properties(
    rec: rr.RecordingStream,
    robot: Robot,
    display: RobotModel | None,
    notices: Notices,
    *,
    axis_length: float,
    robot_name: str = "",
    frame_prefix: str = "",
) -> int:
    """What ``display`` asks for of ``robot``, static; returns how many entities were logged."""
    if display is None or not wants_mass_properties(display):
        return 0
    if display.inertia:
        for line in inertia_problems(robot):
            notices.report(line)
    if (display.mass or display.inertia) and all(link.inertial is None for link in robot.links):
        notices.report(f"{robot.source}: no link has an inertial: nothing to show")
    root, logged = entities.robot_root(robot_name), 0
    every_axis = ALL_LINKS in display.axes
    for link in robot.links:
        name = link.name.removeprefix(frame_prefix)
        inertial = link.inertial
        if display.mass and inertial is not None and inertial.mass > 0:
            radius = lead_sphere_radius(inertial.mass)
            rec.log(
                root + entities.path("mass", name),
                rr.CoordinateFrame(link.name),
                rr.Ellipsoids3D(
                    centers=[inertial.T_link_inertial[:3, 3]],
                    half_sizes=[[radius, radius, radius]],
                    colors=[MASS_COLOR],
                    fill_mode="Solid",
                ),
                static=True,
            )
            logged += 1
        box = equivalent_box(inertial) if display.inertia and inertial is not None else None
        if box is not None:
            rec.log(
                root + entities.path("inertia", name),
                rr.CoordinateFrame(link.name),
                rr.Boxes3D(
                    centers=[box.T_link_box[:3, 3]],
                    sizes=[box.size],
                    quaternions=matrix_to_quat(box.T_link_box[:3, :3]),  # xyzw
                    colors=[MASS_COLOR],
                    fill_mode="Solid",
                ),
                static=True,
            )
            logged += 1
        if every_axis or link.name in display.axes or name in display.axes:
            rec.log(
                root + entities.path("axes", name),
                rr.CoordinateFrame(link.name),
                rr.TransformAxes3D(axis_length),
                static=True,
            )
            logged += 1
    return logged
