"""How a run is shown: the RViz config it follows (``--rviz``, else the tutorial's), the camera and TF marker
scale fitted to the robot (:mod:`r2d2_viz.viewer.layout.fit`), which plots it needs, and the fixed frame — decided
once, before anything is logged."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from r2d2_viz.errors import listed
from r2d2_viz.kinematics.transforms import quat_to_matrix
from r2d2_viz.msgs.extent import extent_points
from r2d2_viz.msgs.registry import VIEWS, decode
from r2d2_viz.msgs.shapes import Decoded, DecodeOptions
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.robot.model import Robot
from r2d2_viz.rviz.config import load_rviz, tutorial_spec
from r2d2_viz.rviz.spec import Camera, TopicDisplay, ViewSpec, missing_fixed_frame, orbit_eye
from r2d2_viz.sources.bag_displays import IMAGES, camera_images, frames_of
from r2d2_viz.sources.base import JointState, SampleChunk, TfRecords, reachable
from r2d2_viz.sources.motion import GeneratedMotion, TutorialMotion
from r2d2_viz.sources.plan import RunPlan
from r2d2_viz.sources.tf_lookup import frame_pose, frame_positions
from r2d2_viz.viewer.blocks.odometry_keep import ANGLE_TOLERANCE, POSITION_TOLERANCE, Tolerance
from r2d2_viz.viewer.blocks.stack_styles import stack_options
from r2d2_viz.viewer.display_feed import DisplayStyle
from r2d2_viz.viewer.layout.blueprint import Layout, robot_display
from r2d2_viz.viewer.layout.fit import AXIS_LENGTH, ViewFit, fit_scene, fit_view
from r2d2_viz.viewer.layout.joined_styles import joined_options
from r2d2_viz.viewer.layout.joined_styles import joined_topics as joined_topics  # the runner's

PREVIEW_TIMES = 256
"""A bag's view follows its recorded TF at this many times spread over the whole bag…"""
PREVIEW_MESSAGES = 16
"""…and frames what its first this many display messages draw (a cloud is milliseconds to decode)."""
PREVIEW_SAMPLES = 3000
"""The stretch of a generated motion the view is fitted to (100 s at 30 Hz), sampled at 256 points."""


@dataclass(frozen=True)
class ViewPlan:
    spec: ViewSpec
    layout: Layout
    axis_length: float
    show_names: bool
    notes: tuple[str, ...]
    """Lines for the user: what the config has no counterpart for, a fixed frame that does not exist."""
    display_styles: dict[str, DisplayStyle] = field(default_factory=dict)
    """Display topic → how the config's display draws it (absent: RViz's defaults)."""


def plan_view(
    plan: RunPlan, *, rviz: Path | None, fixed_frame: str | None, show: frozenset[str] = frozenset()
) -> ViewPlan:
    """``show``: what the command line turns on of the RobotModel display (``mass``, ``inertia``, ``axes``), over
    the config's."""
    spec = load_rviz(rviz) if rviz is not None else tutorial_spec()
    if show and spec.robot is not None:
        robot = spec.robot
        spec = dataclasses.replace(spec, robot=dataclasses.replace(
            robot, mass=robot.mass or "mass" in show, inertia=robot.inertia or "inertia" in show,
            axes=("*",) if "axes" in show else robot.axes))  # fmt: skip
    if rviz is None:  # without a config, every image topic gets its 2D view, as an Image display would
        images = [TopicDisplay("Image", t, t, True) for t, m in sorted(plan.displays.items()) if m in IMAGES]
        spec = dataclasses.replace(spec, topics=(*spec.topics, *images))
    notes = list(spec.notes) if rviz is not None else []
    tree, source = plan.tree, plan.source
    limits = tree.limits if tree is not None else {}
    n_limited = len(limits)
    n_continuous = len(tree.moving) - n_limited if tree is not None else 0
    scale = spec.tf.marker_scale if spec.tf is not None else 1.0
    axis_length, camera, arrows = AXIS_LENGTH * scale, None, True
    recorded = plan.moving_tf is not None or plan.replay is not None
    fit = None
    if rviz is None and recorded:
        fit = _recorded_fit(plan)
    elif rviz is None and tree is not None and not isinstance(source, TutorialMotion):
        fit = fit_view(tree, _preview(plan))
    if fit is not None:
        axis_length, arrows = fit.axis_length(), fit.show_arrows
        yaw, pitch = _orbit_angles(spec)
        camera = Camera("Orbit", orbit_eye(fit.center, fit.distance(), yaw, pitch), fit.center)
    frame = fixed_frame or (plan.fixed_frame if rviz is None else spec.fixed_frame)
    known = {*(tree.links if tree is not None else ())}  # the frames the run has
    for records in (plan.static_tf, plan.moving_tf):
        if records is not None:
            known |= {*records.parents, *records.children}
    frames = {plan.fixed_frame, *known}
    missing = missing_fixed_frame(spec, frames) if rviz is not None and fixed_frame is None else None
    if fixed_frame is not None and plan.replay is not None:  # --fixed-frame on a bag: said once, as RViz says it
        known |= frames_of(plan.preview_messages)
        if fixed_frame not in known:
            missing = (
                f"--fixed-frame {fixed_frame}: Fixed Frame [{fixed_frame}] does not exist in the bag's first "
                f"transforms (its frames: {listed(sorted(known))}); the view opens on it all the same"
            )
    if missing:
        notes.append(missing)
    elif plan.preview_messages:  # (a fixed frame that does not exist is said already)
        notes.extend(unconnected_frames(plan, frame))
    if rviz is not None:
        notes += _prefix_notes(spec, plan)
    layout = Layout(
        limited=n_limited if tree is not None else 0,
        continuous=n_continuous,
        camera=camera,
        show_arrows=arrows,
        fixed_frame=frame,
        robots=tuple(r.namespace for r in plan.robots) if len(plan.robots) > 1 else (),
        flat_images=_flat_images(plan.displays),
    )
    layout = with_telemetry(layout, plan.displays)
    show_names = spec.tf.show_names if spec.tf is not None else False
    styles = _styles(spec, plan.tree.robot if plan.tree is not None else None) if rviz is not None else {}
    return ViewPlan(spec, layout, axis_length, show_names, tuple(notes), styles)


def _prefix_notes(spec: ViewSpec, plan: RunPlan) -> list[str]:
    """A RobotModel display whose TF Prefix is not the one the recording gives its robot's frames."""
    notes = []
    for robot in plan.robots:
        display = robot_display(spec, robot.namespace)
        if display is not None and display.tf_prefix and display.tf_prefix + "/" != robot.prefix:
            shown = robot.prefix.rstrip("/") or "none"
            notes.append(
                f"RobotModel ({display.description_topic}) / TF Prefix {display.tf_prefix!r}: the recording's frames "
                f"of robot {robot.name} carry the prefix {shown!r}; shown with that"
            )
    return notes


def unconnected_frames(plan: RunPlan, fixed: str) -> list[str]:
    """One line per display topic whose messages lie in a frame no recorded transform (nor the robot) joins to
    the fixed frame, in RViz's words: its display says "No transform from [person] to [laser]", and so does the
    viewer's 3D view (it cannot place them either)."""
    neighbours: dict[str, set[str]] = {}
    edges = [e for r in (plan.static_tf, plan.moving_tf) if r is not None for e in r.edges()]
    for tree in [r.tree for r in plan.robots] or ([plan.tree] if plan.tree is not None else []):
        edges += [(tree.robot.root, link) for link in tree.links]  # every robot's links, when there are several
    for parent, child in edges:
        neighbours.setdefault(parent, set()).add(child)
        neighbours.setdefault(child, set()).add(parent)
    reached = reachable(neighbours, fixed)
    lost: dict[str, set[str]] = {}
    checked: dict[str, int] = {}
    for message in plan.preview_messages:
        seen = lost.setdefault(message.topic, set())
        checked[message.topic] = checked.get(message.topic, 0) + 1
        if message.msgtype in IMAGES or checked[message.topic] > 2:
            continue  # images: drawn in their own 2D views
        try:
            decoded = decode(message.msgtype, message.data)
        except MsgError:
            continue
        parts = [decoded] if isinstance(decoded, Decoded) else [op.decoded for op in decoded if op.decoded]
        seen.update(d.frame_id for d in parts if d.frame_id not in reached)
    return [
        f"{topic}: No transform from [{'], ['.join(sorted(frames - {''}))}] to "
        f"[{fixed}]: nothing joins them in the bag's transforms; not shown (RViz says the same)"
        for topic, frames in sorted(lost.items())
        if frames - {""}
    ]


def _flat_images(displays: dict[str, str]) -> tuple[str, ...]:
    """Image topics no CameraInfo gives a pinhole (:func:`camera_images` pairs them like RViz's Camera display)."""
    with_camera = {t for images in camera_images(displays).values() for t in images}
    return tuple(t for t, m in sorted(displays.items()) if m in IMAGES and t not in with_camera)


def with_telemetry(layout: Layout, displays: Mapping[str, str]) -> Layout:
    """``layout`` with the log, state, map and plot topics (:data:`r2d2_viz.msgs.registry.VIEWS`) among
    ``displays`` (topic → type: a bag's display topics, or those a live graph offered when its view was planned);
    a NavSatFix's altitude is plotted too."""

    def of(view: str) -> tuple[str, ...]:
        return tuple(t for t, m in sorted(displays.items()) if VIEWS.get(m) == view or (view, m) == ("plot", NAVSAT))

    return dataclasses.replace(layout, logs=of("log"), states=of("state"), maps=of("map"), plots=of("plot"))


NAVSAT = "sensor_msgs/msg/NavSatFix"


MAP_SCHEMES = ("map", "costmap", "raw")


def _styles(spec: ViewSpec, robot: Robot | None = None) -> dict[str, DisplayStyle]:
    """How the config's topic displays draw: colour and alpha, point size, the flat-colour transformer, a
    map's colour scheme, Odometry's Keep, Covariance, Position and Angle Tolerance, the scalar displays' bounds,
    DepthCloud's camera and colour topics, Effort's joints (``robot``'s), Width and Scale (what a display leaves
    unset keeps RViz's default)."""
    styles = {}
    for display in spec.topics:
        s = display.style
        changes: dict[str, Any] = joined_options(display, robot)
        if s.color is not None:
            alpha = 1.0 if s.alpha is None else min(max(s.alpha, 0.0), 1.0)
            changes["flat_color"] = (*s.color, round(255 * alpha))
        if s.size is not None and s.size > 0:
            changes["point_radius"] = s.size / 2  # RViz's Size (m) is a diameter
        if s.color_transformer == "FlatColor":
            changes["color_transformer"] = "FlatColor"
        if s.color_scheme in MAP_SCHEMES:
            changes["map_scheme"] = s.color_scheme
        if s.covariance is not None:
            changes["odometry_covariance"] = s.covariance
        changes.update(stack_options(s))
        keep = s.keep if s.keep and s.keep > 0 else None
        decay = s.decay_time is not None and s.decay_time > 0 and display.enabled
        options = dataclasses.replace(DecodeOptions(), **changes)
        tolerance = Tolerance(  # RViz's FloatProperty has a minimum of 0
            max(s.position_tolerance, 0.0) if s.position_tolerance is not None else POSITION_TOLERANCE,
            max(s.angle_tolerance, 0.0) if s.angle_tolerance is not None else ANGLE_TOLERANCE,
        )
        styles[display.topic] = DisplayStyle(options, keep=keep, decay=decay, tolerance=tolerance)
    return styles


def _orbit_angles(spec: ViewSpec) -> tuple[float, float]:
    """Yaw and pitch of the config's orbit camera (r2d2.rviz: 4.6186, 0.4598)."""
    camera = spec.camera
    if camera is None:
        return 0.785398, 0.785398
    dx, dy, dz = (e - t for e, t in zip(camera.eye, camera.target, strict=True))
    distance = float(np.sqrt(dx * dx + dy * dy + dz * dz)) or 1.0
    return float(np.arctan2(dy, dx)), float(np.arcsin(dz / distance))


def _recorded_fit(plan: RunPlan) -> ViewFit | None:
    """A bag's view: the robot (its size) along the trajectory its recorded TF gives its root (every robot's, when
    there are several), the TF frames of
    a replay without a robot, and what the first display messages draw, all in the fixed frame."""
    records = [r for r in (plan.static_tf, plan.moving_tf) if r is not None]
    moving = plan.moving_tf.times_ns if plan.moving_tf is not None else np.zeros(0, dtype=np.int64)
    times = np.sort(moving)[np.linspace(0, len(moving) - 1, PREVIEW_TIMES).astype(np.int64)] if len(moving) else None
    times = times if times is not None else np.zeros(1, dtype=np.int64)
    points: list[np.ndarray] = []
    robot_radius, frames = 0.0, 1 + len({c for r in records for c in r.children})
    if plan.tree is not None:
        own = fit_view(plan.tree, _preview(plan))
        robot_radius, frames = own.radius, max(frames, own.frames)
        roots = [r.tree.robot.root for r in plan.robots] or [plan.tree.robot.root]  # several robots: all of them
        placed = frame_positions(records, plan.fixed_frame, roots, times)
        points += [placed.get(root, np.zeros((1, 3))) for root in roots]
    else:
        children = sorted({c for r in records for c in r.children})
        points += list(frame_positions(records, plan.fixed_frame, children, times).values())
    backgrounds: list[np.ndarray] = []
    for message in plan.preview_messages[:PREVIEW_MESSAGES]:
        drawn, background = _drawn(message.msgtype, message.data, message.time_ns, records, plan.fixed_frame)
        points.append(drawn)
        backgrounds.append(background)
    if not any(len(p) for p in points):  # only maps (RViz does not frame a map; here it is all there is)
        points = backgrounds
    if not any(len(p) for p in points):
        return None
    return fit_scene(points, robot_radius=robot_radius, frames=frames)


def _drawn(
    msgtype: str, data: bytes | memoryview, t_ns: int, records: list[TfRecords], fixed: str
) -> tuple[np.ndarray, np.ndarray]:
    """What one display message draws, as points in the fixed frame (none when it cannot be placed): without
    and with maps' corners."""
    nothing = np.zeros((0, 3))
    try:
        decoded = decode(msgtype, data)
    except MsgError:
        return nothing, nothing
    parts = [decoded] if isinstance(decoded, Decoded) else [op.decoded for op in decoded if op.decoded is not None]
    frame = parts[0].frame_id if parts else ""
    out = []
    for local in (extent_points(decoded, maps=False), extent_points(decoded, maps=True)):
        if not frame or frame == fixed or len(local) == 0:
            out.append(local)
            continue
        pose = frame_pose(records, fixed, frame, np.array([t_ns], dtype=np.int64))
        if pose is None:
            out.append(nothing)
            continue
        translation, quat = pose
        placed: np.ndarray = local @ quat_to_matrix(quat[0]).T + translation[0]
        out.append(placed)
    return out[0], out[1]


def _preview(plan: RunPlan) -> np.ndarray:
    """Joint positions over a stretch of the motion, full rows for the kinematics."""
    tree, source = plan.tree, plan.source
    assert tree is not None
    state = JointState(tree.actuated)
    if isinstance(source, GeneratedMotion):
        k = np.unique(np.linspace(0, PREVIEW_SAMPLES, 256).astype(np.int64))
        positions, _ = source.at(k)
        return state.update(SampleChunk(k, source.joints, positions))
    chunk = plan.preview_joints
    if chunk is None and source is not None:
        chunk = next(iter(source.chunks(2000)), None)
    if chunk is not None and len(chunk):
        return state.update(chunk)
    return np.zeros((1, len(tree.actuated)))
