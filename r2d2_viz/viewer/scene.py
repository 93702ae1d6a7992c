"""The static scene of a robot: what RViz's RobotModel and TF displays draw that never changes.

* ``/tf_static/<child>`` — fixed (and planar) joints, and ``<fixed frame> → <root>`` when no source moves
  the root: one static ``Transform3D(parent_frame, child_frame)`` each (like /tf_static);
* ``/tf_arrows/<child>`` — an arrow from each child frame's origin to its parent's (RViz TF "Show Arrows"),
  static in the parent frame, for every joint that does not move its child's origin (all but prismatic);
* ``/tf_axes/<frame>`` — ``TransformAxes3D`` for every frame (RViz TF "Show Axes"; names off);
* ``/robot/visual/<link>/<i>``, ``/robot/collision/<link>/<i>`` — the link's shapes in its named frame
  (:mod:`r2d2_viz.viewer.visuals`: ``Mesh3D`` for boxes, cylinders and spheres, ``Asset3D`` for mesh files).
"""

from __future__ import annotations

import numpy as np
import rerun as rr

from r2d2_viz.arrays import F64
from r2d2_viz.kinematics.tree import PRISMATIC, KinematicTree
from r2d2_viz.meshes.assets import MeshCache
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.layout.fit import AXIS_LENGTH
from r2d2_viz.viewer.notices import Notices
from r2d2_viz.viewer.visuals import log_shape

ARROW_COLOR = (255, 0, 255)


def log_scene(
    rec: rr.RecordingStream,
    tree: KinematicTree,
    notices: Notices,
    *,
    fixed_frame: str,
    root_is_static: bool,
    axis_length: float = AXIS_LENGTH,
    show_names: bool = False,
    robot_name: str = "",
    frame_prefix: str = "",
) -> None:
    """Model warnings, fixed transforms and static arrows, TF axes and the robot's shapes, all static. Several robots:
    ``robot_name`` (its namespace) puts the shapes under ``/robots/<namespace>/``, named by link without the
    ``frame_prefix`` its frames carry."""
    robot = tree.robot
    for message in (*robot.warnings, *tree.warnings):
        notices.report(message)

    translation, quat = tree.static_translation_quat()
    for i, name in enumerate(tree.static):
        joint = robot.joint(name)
        rec.log(
            entities.tf_static(joint.child),
            rr.Transform3D(
                translation=translation[i],
                quaternion=rr.Quaternion(xyzw=quat[i]),
                parent_frame=joint.parent,
                child_frame=joint.child,
            ),
            static=True,
        )
        _log_arrow(rec, joint.parent, joint.child, translation[i])
    # Revolute/continuous joints never move their child's origin: their arrow is static too.
    for m, name in enumerate(tree.moving):
        if tree.moving_kind[m] != PRISMATIC:
            joint = robot.joint(name)
            _log_arrow(rec, joint.parent, joint.child, tree.moving_origin_t[m])
    if root_is_static:
        rec.log(
            entities.tf_static(robot.root),
            rr.Transform3D(translation=[0.0, 0.0, 0.0], parent_frame=fixed_frame, child_frame=robot.root),
            static=True,
        )

    for frame in (fixed_frame, *tree.links):
        rec.log(
            entities.tf_axes(frame),
            rr.CoordinateFrame(frame),
            rr.TransformAxes3D(axis_length, show_frame=show_names),
            static=True,
        )

    meshes = MeshCache()  # each mesh file read (and converted) once, however many links use it

    def warn(message: str) -> None:
        notices.report(f"{robot.source}: {message}")

    for link in robot.links:
        for kind, shapes in (("visual", link.visuals), ("collision", link.collisions)):
            for i, shape in enumerate(shapes):
                entity = entities.robot_shape(kind, link.name.removeprefix(frame_prefix), i, robot_name)
                log_shape(rec, entity, link.name, shape, visual=kind == "visual", cache=meshes, warn=warn)


def _log_arrow(rec: rr.RecordingStream, parent: str, child: str, t_parent_child: F64) -> None:
    if float(np.linalg.norm(t_parent_child)) == 0.0:
        return  # coincident frames: RViz draws no arrow either
    rec.log(
        entities.tf_arrow(child),
        rr.CoordinateFrame(parent),
        rr.Arrows3D(origins=[t_parent_child], vectors=[-np.asarray(t_parent_child)], colors=[ARROW_COLOR]),
        static=True,
    )
