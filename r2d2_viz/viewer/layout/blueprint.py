"""The viewer layout: an RViz config (:mod:`r2d2_viz.rviz.config`) as a Rerun blueprint.

The built-in layout *is* the conversion of the tutorial's ``r2d2.rviz`` (shipped as ``assets/r2d2.rviz``): one
3D view in the fixed frame with its Grid, TF and RobotModel displays and camera, plus plots of the joint values
(what ``ros2 topic echo /joint_states`` would print) and a log of warnings. :func:`generate_blueprint` is a pure
function of the config and of the run (:class:`Layout`: which plots the robot needs, a camera fitted to it).

Save it with ``python -m r2d2_viz.blueprint [PATH]`` (default ``blueprints/r2d2.rbl``), or convert a config with
``python -m r2d2_viz.blueprint --rviz CONFIG.rviz OUT.rbl``.
"""

from __future__ import annotations

import os
import sys
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import rerun as rr
import rerun.blueprint as rrb

from r2d2_viz.errors import stderr_line
from r2d2_viz.rviz.config import load_rviz, tutorial_spec
from r2d2_viz.rviz.spec import Camera, RobotModel, TopicDisplay, ViewSpec
from r2d2_viz.viewer.entities import (
    APP_ID,
    JOINTS_CONTINUOUS,
    JOINTS_LIMITED,
    LIMITS,
    TF,
    TIMELINE,
    WARNINGS,
    joints_root,
    path,
    robot_root,
)
from r2d2_viz.viewer.layout.frustum import frustums

DEFAULT_BLUEPRINT_PATH = Path("blueprints/r2d2.rbl")
_ID_NAMESPACE = uuid.UUID("5f1b7a52-3c1e-4d0e-9a43-6b2f3f2d2d20")
MANY_JOINTS = 12
"""Above this many joints in a plot its legend would cover it: the legend is hidden (hover a line for its
name) and the limit lines are left out (a joint that leaves its limits is reported in the warnings)."""
_PLANES = {"XY": (0.0, 0.0, 1.0), "XZ": (0.0, 1.0, 0.0), "YZ": (1.0, 0.0, 0.0)}


@dataclass(frozen=True)
class Layout:
    """What the layout needs to know about a run (None everywhere: the tutorial's)."""

    limited: int | None = None
    """Joints with limits (None: unknown, show the plot)."""
    continuous: int | None = None
    camera: Camera | None = None
    """A camera fitted to the robot, used instead of the config's (see :mod:`r2d2_viz.viewer.layout.fit`)."""
    show_arrows: bool = True
    """False hides the TF arrows (robots with many frames)."""
    fixed_frame: str | None = None
    """The run's fixed frame, instead of the config's (a bag's TF root)."""
    flat_images: tuple[str, ...] = ()
    """Image topics without a camera (no CameraInfo, so no pinhole): kept out of the 3D view, which cannot place
    them (RViz's 3D view draws none either; each has its 2D view)."""
    robots: tuple[str, ...] = ()
    """Several robots: their namespaces (shapes under ``/robots/<namespace>``, plots under ``/joints/<namespace>``)."""
    logs: tuple[str, ...] = ()
    """Log topics (``/rosout``, strings): a log view of them, rqt_console's."""
    states: tuple[str, ...] = ()
    """Diagnostics topics: a state timeline of their statuses, rqt_robot_monitor's."""
    maps: tuple[str, ...] = ()
    """NavSatFix topics: a map of their fixes."""
    plots: tuple[str, ...] = ()
    """Topics plotted (IMUs, batteries, scalar sensors, std_msgs numbers): a time-series view each, as tabs."""
    field_plots: tuple[tuple[str, ...], ...] = ()
    """``--plot`` paths: a time-series view per flag, of its paths (``/plot/<n>``)."""
    tf_graph: bool = False
    """``--tf-tree``: the TF tree as a graph view (``/tf_tree``) beside the 3D view."""
    node_graph: bool = False
    """``--ros --tf-tree``: the graph of nodes and topics (``/node_graph``), a tab beside the TF tree."""


def _stable_id(part: rrb.View | rrb.Container, key: str) -> None:
    """Name-derived ids instead of random ones, so the saved blueprint is the same on every save."""
    part.id = uuid.uuid5(_ID_NAMESPACE, key)


def generate_blueprint(
    spec: ViewSpec | None = None, *, layout: Layout | None = None, hidden_links: Sequence[str] = ()
) -> rrb.Blueprint:
    """The RViz-like layout of ``spec`` (default: the tutorial's) for a run described by ``layout``.

    ``hidden_links`` hides those links' visuals, like unticking them under RobotModel / Links in RViz.
    """
    spec = spec or tutorial_spec()
    layout = layout or Layout()
    fixed = layout.fixed_frame or spec.fixed_frame
    overrides: dict[str, object] = {**_hidden(spec, layout, hidden_links), **_decay(spec), **frustums(spec)}
    scene = rrb.Spatial3DView(
        name=f"3D: {fixed} (Grid · TF · RobotModel)",
        origin="/",
        contents=["+ /**", "- /joints/**", f"- {WARNINGS}", *(f"- {topic}/**" for topic in layout.flat_images)]
        + (["- /tf_tree/**", "- /health/**", "- /node_graph/**"] if layout.tf_graph or layout.node_graph else []),
        background=rrb.Background(color=spec.background),
        line_grid=_grid(spec),
        spatial_information=rrb.SpatialInformation(target_frame=fixed, show_axes=False, show_bounding_box=False),
        eye_controls=_eye(layout.camera or spec.camera),
        overrides=overrides,  # type: ignore[arg-type]  # str keys are entity paths
    )
    parts: dict[str, rrb.View | rrb.Container] = {"scene": scene}
    side: list[rrb.View] = []
    shares: list[float] = []
    # /joint_states as plots: joints with limits (and the limits), and continuous joints, which grow without
    # bound (the tutorial's swivel) and would flatten the others on a shared axis. No empty panels.
    for ns in layout.robots:  # several robots: a plot each
        plots = rrb.TimeSeriesView(name=f"Joint states {ns or '/'}", origin=joints_root(ns))
        parts[f"joints {ns}"] = plots
        side.append(plots)
        shares.append(2)
    if not layout.robots and (layout.limited is None or layout.limited > 0):
        many = layout.limited is not None and layout.limited > MANY_JOINTS
        limited = rrb.TimeSeriesView(
            name="Joint states",
            origin=JOINTS_LIMITED,
            contents=[f"+ {JOINTS_LIMITED}/**", f"- {LIMITS}"] if many else "$origin/**",
            plot_legend=rrb.PlotLegend(visible=False) if many else None,
        )
        parts["limited"] = limited
        side.append(limited)
        shares.append(3)
    if not layout.robots and (layout.continuous is None or layout.continuous > 0):
        many = layout.continuous is not None and layout.continuous > MANY_JOINTS
        continuous = rrb.TimeSeriesView(
            name="Continuous joints",
            origin=JOINTS_CONTINUOUS,
            plot_legend=rrb.PlotLegend(visible=False) if many else None,
        )
        parts["continuous"] = continuous
        side.append(continuous)
        shares.append(2)
    for topic in spec.topics:
        if topic.kind in ("Image", "Camera") and topic.enabled and topic.topic:
            side.append(rrb.Spatial2DView(name=f"{topic.kind}: {topic.topic}", origin=topic.topic))
            shares.append(2)
    for n, texts in enumerate(layout.field_plots):
        plot = rrb.TimeSeriesView(name=f"Plot: {', '.join(texts)}"[:120], origin=f"/plot/{n}")
        parts[f"plot {n}"] = plot
        side.append(plot)
        shares.append(2)
    log = rrb.TextLogView(name="Warnings", origin=WARNINGS)
    parts["log"] = log
    side.append(log)
    shares.append(1)
    parts["side"] = rrb.Vertical(*side, row_shares=shares)
    parts["root"] = rrb.Horizontal(scene, parts["side"], column_shares=[2, 1])
    if layout.tf_graph:  # view_frames beside the 3D view
        graph = rrb.GraphView(name="TF tree (rate · age)", origin="/tf_tree")
        rates = rrb.TimeSeriesView(name="Topic rates (Hz)", origin="/health", contents="+ /health/**/rate")
        _stable_id(graph, "tf graph")
        _stable_id(rates, "topic rates")
        if layout.node_graph:  # rqt_graph's, a third tab
            parts["node graph"] = rrb.GraphView(name="Nodes and topics", origin="/node_graph")
        parts["tf tree"] = rrb.Tabs(graph, rates, *([parts["node graph"]] if layout.node_graph else []))
        parts["root"] = rrb.Horizontal(scene, parts["tf tree"], parts["side"], column_shares=[2, 1.5, 1])
    below = _telemetry_views(layout)
    if below:  # a row under the 3D view and plots; none without such topics (the tutorial's layout unchanged)
        parts.update(below)
        parts["main"] = parts["root"]
        shares = [BELOW_SHARES[key] for key in below]
        parts["below"] = rrb.Horizontal(*below.values(), column_shares=shares)
        parts["root"] = rrb.Vertical(parts["main"], parts["below"], row_shares=[3, 2])
    for key, part in parts.items():
        _stable_id(part, key)
    return rrb.Blueprint(
        parts["root"],
        rrb.BlueprintPanel(state=rrb.components.PanelState.Expanded),
        rrb.SelectionPanel(state=rrb.components.PanelState.Collapsed),
        # Play state left to the viewer: a recording plays once from the start and stays on its last
        # sample; a live stream is followed as it arrives — RViz always shows the latest state.
        rrb.TimePanel(state=rrb.components.PanelState.Collapsed, timeline=TIMELINE),
        auto_views=False,
    )


BELOW_SHARES = {"robot log": 3.0, "diagnostics": 2.0, "map": 1.0, "sensors": 2.0}
"""The widths of the views below the 3D one: the log's lines are long."""


def _telemetry_views(layout: Layout) -> dict[str, rrb.View | rrb.Container]:
    """The views of what a 3D view does not show: the log, diagnostics' states, fixes on a map, and sensor plots
    (a tab per topic)."""

    def contents(topics: tuple[str, ...]) -> list[str]:
        return [f"+ {t}/**" for t in topics]

    views: dict[str, rrb.View | rrb.Container] = {}
    if layout.logs:
        columns = [rrb.encodings.TextLogColumn(kind) for kind in ("LogLevel", "Body", "EntityPath")]  # text first
        views["robot log"] = rrb.TextLogView(
            name="Log: " + " · ".join(layout.logs),
            contents=contents(layout.logs),
            columns=rrb.archetypes.TextLogColumns(text_log_columns=columns),
        )
    if layout.states:
        views["diagnostics"] = rrb.StateTimelineView(
            name="Diagnostics: " + " · ".join(layout.states), contents=contents(layout.states)
        )
    if layout.maps:
        views["map"] = rrb.MapView(name="Map: " + " · ".join(layout.maps), contents=contents(layout.maps))
    plots = {f"plot {t}": rrb.TimeSeriesView(name=t, origin=t) for t in layout.plots}  # units differ: one each
    for key, plot in plots.items():
        _stable_id(plot, key)
    if len(plots) == 1:
        views["sensors"] = next(iter(plots.values()))
    elif plots:
        views["sensors"] = rrb.Tabs(*plots.values(), name="Sensors")
    return views


def _grid(spec: ViewSpec) -> rrb.LineGrid3D:
    grid = spec.grid
    if grid is None:
        return rrb.LineGrid3D(visible=False)
    normal = _PLANES[grid.plane]
    distance = sum(n * o for n, o in zip(normal, grid.offset, strict=True))
    plane = (
        rr.components.Plane3D.XY if (grid.plane, distance) == ("XY", 0.0) else rr.components.Plane3D(normal, distance)
    )
    return rrb.LineGrid3D(
        visible=grid.enabled,
        spacing=grid.cell_size,
        plane=plane,
        stroke_width=1.0,
        color=(*grid.color, round(255 * grid.alpha)),
    )


def _eye(camera: Camera | None) -> rrb.EyeControls3D | None:
    if camera is None:
        return None
    return rrb.EyeControls3D(
        kind=rrb.Eye3DKind.Orbital if camera.orbit else rrb.Eye3DKind.FirstPerson,
        position=camera.eye,
        look_target=camera.target,
        eye_up=camera.up,
        tracking_entity=path("tf_axes", camera.target_frame) if camera.target_frame else None,
    )


def robot_display(spec: ViewSpec, namespace: str) -> RobotModel | None:
    """The RobotModel display drawing the robot of ``namespace``: the one naming its description topic, else the
    one naming ``/robot_description`` (a config for one robot shows them all); None: no display draws it."""
    displays = [d for d in (spec.robot, *spec.more_robots) if d is not None]
    own = [d for d in displays if d.description_topic == f"{namespace}/robot_description"]
    default = [d for d in displays if d.description_topic == "/robot_description"]
    found = own or default
    return found[0] if found else None


def _robot_hidden(robot: RobotModel | None, root: str) -> list[str]:
    """What a RobotModel display (None: none) hides of the robot whose shapes are under ``root``."""
    if robot is None or not robot.enabled:
        return [root]
    hidden = [f"{root}/collision"] if not robot.collision else []
    if not robot.visual:
        hidden.append(f"{root}/visual")
    return hidden + [root + path("visual", link) for link in robot.hidden_links]


def _hidden(spec: ViewSpec, layout: Layout, hidden_links: Sequence[str]) -> dict[str, rrb.EntityBehavior]:
    """What RViz's unticked displays, frames and links hide."""
    hidden: list[str] = []
    tf = spec.tf
    if not layout.robots:
        hidden += _robot_hidden(spec.robot, "/robot")
    for ns in layout.robots:  # each robot as the RobotModel display of its description topic says
        hidden += _robot_hidden(robot_display(spec, ns), robot_root(ns))
    hidden.extend(path("robot", "visual", link) for link in hidden_links)
    if tf is None or not tf.enabled or not tf.show_axes:
        hidden.append("/tf_axes")
    elif tf.hidden_frames:
        hidden.extend(path("tf_axes", frame) for frame in tf.hidden_frames)
    if tf is None or not tf.enabled or not tf.show_arrows or not layout.show_arrows:
        hidden.extend(["/tf_arrows", TF])  # the arrows on /tf; its transforms still place every frame
    hidden.extend(topic.topic for topic in spec.topics if not topic.enabled and topic.topic.startswith("/"))
    return {entity: rrb.EntityBehavior(visible=False) for entity in dict.fromkeys(hidden)}


ODOMETRY_KEEP = 100
"""RViz's Odometry Keep by default (:data:`r2d2_viz.viewer.display_feed.KEEP`)."""
TWO_ITEMS = ("PoseWithCovariance", "Wrench", "Twist", "TwistStamped", "AccelStamped")
"""Displays whose message draws two things, logged on ``<topic>/0`` and ``<topic>/1``."""


def decay_entities(display: TopicDisplay) -> tuple[str, ...]:
    """The entities a topic display's messages are drawn on (:mod:`r2d2_viz.viewer.display_feed`): the topic's
    own, ``<topic>/<i>`` for a message drawn as several things, ``<topic>/<k>`` for Odometry's Keep slots.
    Markers go on ``<topic>/<ns>/<id>``, known only from the data: none here."""
    topic, style = display.topic, display.style
    if display.kind in ("Marker", "MarkerArray", "Image", "Camera", "InteractiveMarkers", "Effort", "DepthCloud"):
        return ()
    if display.kind == "Odometry":
        keep = style.keep if style.keep and style.keep > 0 else ODOMETRY_KEEP
        slots = [f"{topic}/{k}" for k in range(keep)] if keep > 1 else [topic]
        return tuple(f"{s}/{i}" for s in slots for i in (0, 1)) if style.covariance else tuple(slots)
    if display.kind in TWO_ITEMS:
        return (f"{topic}/0", f"{topic}/1")
    return (topic,)


def _decay(spec: ViewSpec) -> dict[str, rrb.VisibleTimeRanges]:
    """RViz's Decay Time (seconds; 0: only the latest message) as each drawn entity's visible time range: the
    messages of the last N seconds before the time cursor, both ends included (``PointCloudCommon``: a cloud is
    dropped once ``now - received > decay``). An override on a topic's entity does not reach the entities below
    it, so each entity gets its own."""
    out: dict[str, rrb.VisibleTimeRanges] = {}
    for display in spec.topics:
        seconds = display.style.decay_time
        if not display.enabled or not display.topic.startswith("/") or seconds is None or seconds <= 0:
            continue
        ranges = rrb.VisibleTimeRanges(
            timeline=TIMELINE,
            start=rrb.TimeRangeBoundary.cursor_relative(seconds=-seconds),
            end=rrb.TimeRangeBoundary.cursor_relative(),
        )
        out.update(dict.fromkeys(decay_entities(display), ranges))
    return out


def save_blueprint(path: Path = DEFAULT_BLUEPRINT_PATH, spec: ViewSpec | None = None) -> Path:
    """Write :func:`generate_blueprint` as an ``.rbl`` file for ``rerun FILE.rrd PATH.rbl``.

    Rerun mints a new store id, chunk ids and row ids and stamps ``log_time`` on every save (0.41's API lets none
    be chosen), so two saves of one layout never match byte for byte: a file already holding the same layout is
    left untouched, and the committed ``blueprints/r2d2.rbl`` stays unmodified until the layout changes."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fresh = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        generate_blueprint(spec).save(APP_ID, fresh)
        if not path.is_file() or (old := _layout(path)) is None or old != _layout(fresh):
            os.replace(fresh, path)
    finally:
        fresh.unlink(missing_ok=True)
    return path


def _layout(rbl: Path) -> dict[str, list[object]] | None:
    """What a blueprint file lays out, per entity, without the ids and log times of the save (None: unreadable)."""
    from rerun.chunk import RrdReader

    try:
        reader = RrdReader(rbl)
        out: dict[str, list[object]] = {}
        for store in reader.blueprints():
            for chunk in reader.store(store=store).stream().to_chunks():
                batch = chunk.to_record_batch()
                keep = [name for name in batch.schema.names if name not in ("log_time", "rerun.controls.RowId")]
                out.setdefault(chunk.entity_path, []).extend(batch.select(keep).to_pylist())
        return out
    except Exception:  # not a blueprint Rerun can read: written anew
        return None


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m r2d2_viz.blueprint [OUT.rbl]`` or ``python -m r2d2_viz.blueprint --rviz CONFIG.rviz OUT.rbl``."""
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m r2d2_viz.blueprint",
        description="Write the viewer layout as a Rerun blueprint (.rbl), for: rerun FILE.rrd OUT.rbl",
    )
    parser.add_argument(
        "out", nargs="?", type=Path, default=None, metavar="OUT.rbl", help=f"default: {DEFAULT_BLUEPRINT_PATH}"
    )
    parser.add_argument(
        "--rviz", type=Path, default=None, metavar="CONFIG.rviz", help="convert this RViz config (then OUT is needed)"
    )
    args = parser.parse_args(argv)
    if args.rviz is not None and args.out is None:
        parser.error("--rviz CONFIG.rviz needs OUT.rbl")
    out: Path = args.out if args.out is not None else DEFAULT_BLUEPRINT_PATH
    if out.suffix != ".rbl":
        parser.error(f"{out}: a blueprint is written as NAME.rbl")
    spec = None
    if args.rviz is not None:
        from r2d2_viz.errors import R2d2VizError

        try:
            spec = load_rviz(args.rviz)
        except R2d2VizError as exc:
            print(stderr_line(f"error: {exc}"), file=sys.stderr)
            return 2
        for note in spec.notes:
            print(f"note: {note}", file=sys.stderr)
    print(save_blueprint(out, spec))
    return 0


if __name__ == "__main__":
    sys.exit(main())
