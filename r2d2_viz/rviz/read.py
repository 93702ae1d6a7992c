"""Reading an RViz config's displays, tools, panels and view into a :class:`~r2d2_viz.rviz.spec.ViewSpec` (see
:mod:`r2d2_viz.rviz.spec` for the mapping and the formulas). Every value is type-checked; a wrong one is an
:class:`~r2d2_viz.rviz.spec.RvizError` naming the file and the key. Pure: no rerun import."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from typing import Any

from r2d2_viz.rviz.spec import (
    ASSUMED_VIEW_HEIGHT_PX,
    FIXED,
    FOV_Y,
    SCENE_ROBOT_DISPLAYS,
    TOPIC_DISPLAYS,
    TOPIC_KEYS,
    XY_ORBIT_LIFT,
    Camera,
    DisplayStyleSpec,
    Grid,
    RobotModel,
    RvizError,
    Tf,
    TopicDisplay,
    ViewSpec,
    orbit_eye,
    orbit_view,
    short_class,
)
from r2d2_viz.rviz.tools import RVIZ_CLASSES

PAGE_TOOLS = frozenset({*RVIZ_CLASSES, "Measure"})
"""RViz's tool classes that r2d2-viz's page has (``--serve``): not noted as missing."""


class Reader:
    def __init__(self, source: str) -> None:
        self.source = source
        self.notes: list[str] = []

    def note(self, text: str) -> None:
        line = f"{self.source}: {text}"
        if line not in self.notes:
            self.notes.append(line)

    def number(self, node: Mapping[str, Any], key: str, default: float, where: str) -> float:
        value = node.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise RvizError(f"{self.source}: {where} / {key}: expected a number, got {type(value).__name__}")
        try:
            out = float(value)
        except ValueError:
            raise RvizError(f"{self.source}: {where} / {key}: expected a number, got {value!r}") from None
        if not math.isfinite(out):
            raise RvizError(f"{self.source}: {where} / {key}: not a finite number ({value!r})")
        return out

    def flag(self, node: Mapping[str, Any], key: str, default: bool, where: str) -> bool:
        value = node.get(key, default)
        if not isinstance(value, bool):
            raise RvizError(f"{self.source}: {where} / {key}: expected true or false, got {value!r}")
        return value

    def enabled(self, display: Mapping[str, Any], where: str) -> bool:
        """A display's checkbox: ``Enabled`` (ROS 2 and newer ROS 1 configs), else ``Value`` (older ROS 1)."""
        if "Enabled" in display:
            return self.flag(display, "Enabled", True, where)
        return self.flag(display, "Value", True, where)

    def text(self, node: Mapping[str, Any], key: str, default: str, where: str) -> str:
        value = node.get(key, default)
        if value is None:
            return default
        if isinstance(value, dict):  # ROS 2 topics: {Value: /scan, Depth: 5, ...}
            value = value.get("Value", default)
        if not isinstance(value, (str, int, float)) or isinstance(value, bool):
            raise RvizError(f"{self.source}: {where} / {key}: expected text, got {type(value).__name__}")
        return str(value)

    def color(
        self, node: Mapping[str, Any], key: str, default: tuple[int, int, int], where: str
    ) -> tuple[int, int, int]:
        value = node.get(key)
        if value is None:
            return default
        parts = str(value).split(";")
        try:
            r, g, b = (max(0, min(255, round(float(p)))) for p in parts)
        except ValueError:
            raise RvizError(f"{self.source}: {where} / {key}: expected 'R; G; B', got {value!r}") from None
        return (r, g, b)

    def vector(self, node: Mapping[str, Any], key: str, where: str) -> tuple[float, float, float]:
        value = node.get(key) or {}
        if not isinstance(value, dict):
            raise RvizError(f"{self.source}: {where} / {key}: expected X, Y, Z")
        x, y, z = (self.number(value, axis, 0.0, f"{where} / {key}") for axis in ("X", "Y", "Z"))
        return (x, y, z)

    # --- the whole file ----------------------------------------------------------------------------

    def spec(self, data: Mapping[str, Any], manager: Mapping[str, Any]) -> ViewSpec:
        options = manager.get("Global Options") or {}
        if not isinstance(options, dict):
            raise RvizError(f"{self.source}: Global Options: expected a mapping")
        fixed = self.text(options, "Fixed Frame", "map", "Global Options")
        background = self.color(options, "Background Color", (48, 48, 48), "Global Options")
        grid: Grid | None = None
        tf: Tf | None = None
        robot: RobotModel | None = None
        more_robots: list[RobotModel] = []
        topics: list[TopicDisplay] = []
        for display, where in self.displays(manager.get("Displays") or [], "Displays"):
            kind = short_class(display.get("Class"))
            if kind == "Grid" and grid is None:
                grid = self.grid(display, where, fixed)
            elif kind == "TF" and tf is None:
                tf = self.tf(display, where)
            elif kind == "RobotModel" and robot is None:
                robot = self.robot(display, where)
            elif kind == "RobotModel":
                more_robots.append(self.robot(display, where))
            elif kind in SCENE_ROBOT_DISPLAYS and isinstance(display.get("Scene Robot"), dict):
                # MoveIt's planning displays draw the robot themselves (their "Scene Robot")
                if robot is None and self.enabled(display, where):
                    robot = self.robot(display["Scene Robot"], f"{where} / Scene Robot", scene=True)
                    self.note(
                        f"display {display.get('Class')}: its Scene Robot is shown as a RobotModel; "
                        "planning scene, goal state and trajectories have no counterpart"
                    )
                else:
                    self.note(f"display {display.get('Class')}: no counterpart in Rerun; skipped")
            elif kind in TOPIC_DISPLAYS or kind == "Axes":  # Axes: no topic, a frame
                topic = next((t for key in TOPIC_KEYS if (t := self.text(display, key, "", where))), "")
                if kind == "InteractiveMarkers" and "Interactive Markers Namespace" in display and topic:
                    topic = topic.rstrip("/") + "/update"  # ROS 2: the server's update topic in its namespace
                enabled = self.enabled(display, where)
                style = display_style(self, display, where)
                topics.append(TopicDisplay(kind, str(display.get("Name", kind)), topic, enabled, style))
            else:
                self.note(f"display {display.get('Class')}: no counterpart in Rerun; skipped")
        if note := tools_and_panels(manager.get("Tools"), data.get("Panels")):
            self.note(note)
        views = manager.get("Views") or {}
        current = views.get("Current") if isinstance(views, dict) else None
        camera = read_camera(self, current, fixed) if isinstance(current, dict) else None
        shown, notes = tuple(topics), tuple(self.notes)
        return ViewSpec(self.source, fixed, background, grid, tf, robot, camera, shown, notes, tuple(more_robots))

    def displays(self, items: Any, where: str) -> Iterator[tuple[Mapping[str, Any], str]]:
        """Every display, those inside Groups included (a disabled group disables what it holds)."""
        if not isinstance(items, list):
            raise RvizError(f"{self.source}: {where}: expected a list of displays")
        for item in items:
            if not isinstance(item, dict):
                raise RvizError(f"{self.source}: {where}: a display is not a mapping")
            here = f"{where} / {item.get('Name', item.get('Class', '?'))}"
            if short_class(item.get("Class")) == "Group":
                enabled = self.enabled(item, here)
                for inner, inner_where in self.displays(item.get("Displays") or [], here):
                    yield ({**inner, "Enabled": False} if not enabled else inner), inner_where
            else:
                yield item, here

    def grid(self, d: Mapping[str, Any], where: str, fixed: str) -> Grid:
        reference = self.text(d, "Reference Frame", FIXED, where)
        plane = self.text(d, "Plane", "XY", where)
        if plane not in ("XY", "XZ", "YZ"):
            raise RvizError(f"{self.source}: {where} / Plane: {plane!r}; expected XY, XZ or YZ")
        count = self.number(d, "Plane Cell Count", 10, where)
        self.note(f"Grid / Plane Cell Count {count:g}: Rerun's grid is unbounded (it fades with distance)")
        style = d.get("Line Style") or {}
        if isinstance(style, dict) and style.get("Value") == "Billboards":
            self.note("Grid / Line Style Billboards: Rerun draws thin lines (stroke width in UI points)")
        if reference not in (FIXED, fixed):
            self.note(f"Grid / Reference Frame {reference}: Rerun's grid lies in the view's frame ({fixed})")
        return Grid(
            enabled=self.enabled(d, where),
            cell_size=self.number(d, "Cell Size", 1.0, where),
            color=self.color(d, "Color", (160, 160, 164), where),
            alpha=min(1.0, max(0.0, self.number(d, "Alpha", 0.5, where))),
            plane=plane,
            offset=self.vector(d, "Offset", where),
            reference_frame=None if reference in (FIXED, fixed) else reference,
        )

    def tf(self, d: Mapping[str, Any], where: str) -> Tf:
        frames = d.get("Frames") or {}
        hidden = ()
        if isinstance(frames, dict):
            hidden = tuple(sorted(k for k, v in frames.items() if isinstance(v, dict) and v.get("Value") is False))
        return Tf(
            enabled=self.enabled(d, where),
            show_axes=self.flag(d, "Show Axes", True, where),
            show_arrows=self.flag(d, "Show Arrows", True, where),
            show_names=self.flag(d, "Show Names", False, where),
            marker_scale=self.number(d, "Marker Scale", 1.0, where),
            hidden_frames=hidden,
        )

    def robot(self, d: Mapping[str, Any], where: str, *, scene: bool = False) -> RobotModel:
        """A RobotModel display, or (``scene``) the Scene Robot of MoveIt's planning displays."""
        visual_key, collision_key, alpha_key = (
            ("Show Robot Visual", "Show Robot Collision", "Robot Alpha")
            if scene
            else ("Visual Enabled", "Collision Enabled", "Alpha")
        )
        links = d.get("Links") or {}
        hidden: tuple[str, ...] = ()
        axes: tuple[str, ...] = ()  # the links whose "Show Axes" is ticked
        if isinstance(links, dict):
            hidden = tuple(sorted(k for k, v in links.items() if isinstance(v, dict) and v.get("Value") is False))
            axes = tuple(sorted(k for k, v in links.items() if isinstance(v, dict) and v.get("Show Axes") is True))
        found = d.get("Mass Properties")
        masses: Mapping[str, Any] = found if isinstance(found, dict) else {}
        alpha = self.number(d, alpha_key, 1.0, where)
        if alpha < 1:
            self.note(f"RobotModel / Alpha {alpha:g}: shown opaque (the URDF colours' alpha applies)")
        return RobotModel(
            enabled=True if scene else self.enabled(d, where),
            visual=self.flag(d, visual_key, True, where),
            collision=self.flag(d, collision_key, False, where),
            alpha=alpha,
            hidden_links=hidden,
            description_topic=self.text(d, "Description Topic", "", where) or "/robot_description",
            tf_prefix=self.text(d, "TF Prefix", "", where).strip("/"),
            mass=self.flag(masses, "Mass", False, where),
            inertia=self.flag(masses, "Inertia", False, where),
            axes=axes,
        )


def display_style(self: Reader, display: Mapping[str, Any], where: str) -> DisplayStyleSpec:
    """A topic display's style properties (RViz's names; absent ones keep the display's default)."""

    def number(key: str) -> float | None:
        return self.number(display, key, 0.0, where) if display.get(key) is not None else None

    covariance = display.get("Covariance")
    keep = number("Keep")
    return DisplayStyleSpec(
        color=self.color(display, "Color", (0, 0, 0), where) if display.get("Color") is not None else None,
        alpha=number("Alpha"),
        size=number("Size (m)") if display.get("Size (m)") is not None else number("Line Width"),
        color_transformer=str(display["Color Transformer"]) if display.get("Color Transformer") else None,
        decay_time=number("Decay Time"),
        keep=int(keep) if keep is not None and keep >= 0 else None,
        color_scheme=str(display["Color Scheme"]) if display.get("Color Scheme") else None,
        covariance=self.flag(covariance, "Value", False, where) if isinstance(covariance, dict) else None,
        position_tolerance=number("Position Tolerance"),
        angle_tolerance=number("Angle Tolerance"),
        shape=str(display["Shape"]) if display.get("Shape") is not None else None,
        arrow_lengths=(number("Min Arrow Length"), number("Max Arrow Length")),
        only_edge=self.flag(display, "Only Edge", False, where) if display.get("Only Edge") is not None else None,
        length=number("Length") if display.get("Length") is not None else number("Far clip"),
        radius=number("Radius"),
        scale=number("Scale"),
        width=number("Width"),
        value_range=_range(number("Min Intensity"), number("Max Intensity")),
        color_topic=self.text(display, "Color Image Topic", "", where) or None,
        frame=_frame(self.text(display, "Reference Frame", "", where)),
    )


def _range(low: float | None, high: float | None) -> tuple[float, float] | None:
    return (low, high) if low is not None and high is not None else None


def _frame(name: str) -> str | None:
    """A display's Reference Frame (None: RViz's ``<Fixed Frame>``, or unset)."""
    return None if name in ("", FIXED) else name


def read_camera(self: Reader, v: Mapping[str, Any], fixed: str) -> Camera:
    """The Current view, with RViz's formulas (see :mod:`r2d2_viz.rviz.spec`)."""
    kind = short_class(v.get("Class")) or "Orbit"
    where = f"Views / Current ({kind})"
    target_frame = self.text(v, "Target Frame", FIXED, where)
    follow = None if target_frame in (FIXED, fixed) else target_frame
    if kind in ("Orbit", "XYOrbit", "ThirdPersonFollower"):
        focal = self.vector(v, "Focal Point", where)
        d = self.number(v, "Distance", 10.0, where)
        yaw = self.number(v, "Yaw", 0.785398, where)
        pitch = self.number(v, "Pitch", 0.785398, where)
        lift = XY_ORBIT_LIFT if kind != "Orbit" else 0.0
        invert = self.flag(v, "Invert Z Axis", False, where)
        fov = self.number(v, "Field of View", FOV_Y, where)  # ROS 1 only
        if abs(fov - FOV_Y) > 1e-3:
            self.note(f"Views / Field of View {fov:.3g} rad: Rerun's 3D view has its own (45 degrees)")
        if kind == "ThirdPersonFollower" and follow is not None:
            self.note(f"Views / ThirdPersonFollower: Rerun follows {follow}'s position, not its yaw")
        eye, target, up = orbit_view(focal, d, yaw, pitch, invert_z=invert, lift=lift)
        return Camera(kind, eye, target, up, orbit=True, target_frame=follow)
    if kind == "FPS":
        eye = self.vector(v, "Position", where)
        yaw = self.number(v, "Yaw", 0.0, where)
        pitch = self.number(v, "Pitch", 0.0, where)
        roll = self.number(v, "Roll", 0.0, where)  # ROS 1 only
        forward = (math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), -math.sin(pitch))
        # up: Rz(yaw) · Ry(pitch) · Rx(roll) applied to +Z
        ux, uy, uz = math.cos(roll) * math.sin(pitch), -math.sin(roll), math.cos(roll) * math.cos(pitch)
        up = (ux * math.cos(yaw) - uy * math.sin(yaw), ux * math.sin(yaw) + uy * math.cos(yaw), uz)
        target = (eye[0] + forward[0], eye[1] + forward[1], eye[2] + forward[2])
        return Camera(kind, eye, target, up, orbit=False, target_frame=follow)
    if kind == "TopDownOrtho":
        x, y = self.number(v, "X", 0.0, where), self.number(v, "Y", 0.0, where)
        scale = self.number(v, "Scale", 10.0, where)
        angle = self.number(v, "Angle", 0.0, where)
        height = (ASSUMED_VIEW_HEIGHT_PX / max(scale, 1e-6) / 2) / math.tan(FOV_Y / 2)
        self.note(
            f"Views / TopDownOrtho: Rerun has no orthographic 3D view; a perspective eye {height:.3g} m "
            "above looks straight down instead"
        )
        up = (-math.sin(angle), math.cos(angle), 0.0)
        return Camera(kind, (x, y, height), (x, y, 0.0), up, orthographic=True, target_frame=follow)
    self.note(f"Views / Current {v.get('Class')}: no counterpart; the default orbit is used")
    return Camera(kind, orbit_eye((0.0, 0.0, 0.0), 10.0, 0.785398, 0.785398), (0.0, 0.0, 0.0))


def tools_and_panels(tools: Any, panels: Any) -> str | None:
    """One note naming every tool and panel without a counterpart (Rerun's viewer has its own camera,
    selection, blueprint and selection panels), rather than a line each. The tools that talk back (pose
    estimate, goal, point) and Measure have theirs on ``--serve``'s page (:mod:`r2d2_viz.rviz.tools`)."""
    named: dict[str, list[str]] = {"tools": [], "panels": []}
    for kind, items in (("tools", tools), ("panels", panels)):
        for item in items if isinstance(items, list) else []:
            if not isinstance(item, dict) or not item.get("Class") or str(item["Class"]) in named[kind]:
                continue
            if kind == "tools" and str(item["Class"]).rsplit("/", 1)[-1] in PAGE_TOOLS:
                continue
            named[kind].append(str(item["Class"]))
    parts = [f"{len(names)} {kind} ({', '.join(names)})" for kind, names in named.items() if names]
    if not parts:
        return None
    return (
        f"{' and '.join(parts)}: no counterpart (Rerun's viewer has its own camera and selection tools, "
        "blueprint and selection panels)"
    )
