"""URDF → an immutable robot model.

The file is read and validated by :mod:`r2d2_viz.robot.urdf_check` (safe XML, one-line errors), then read element by
element into frozen dataclasses that the rest of the app uses (no second parser: yourdfpy, which the tests
compare against, costs a second of imports).
Nothing here is specific to the R2D2: any URDF with box, cylinder, sphere (and mesh) geometry loads.

Poses are 4×4 homogeneous matrices named after the frames they map between:
``Joint.T_parent_joint`` maps joint-frame coordinates into the parent link's frame (the URDF
``<origin>`` of the joint), ``Shape.T_link_shape`` maps shape coordinates into its link's frame.
"""

from __future__ import annotations

import gc
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import cached_property
from importlib import resources
from pathlib import Path

import numpy as np
import numpy.typing as npt
from lxml import etree

from r2d2_viz.errors import listed
from r2d2_viz.robot.inertial import Inertial, read_inertial
from r2d2_viz.robot.packages import PackageIndex, missing_files
from r2d2_viz.robot.urdf_check import JOINT_TYPES, check_robot, parse_urdf_xml, read_urdf_xml

JointType = str
"""One of :data:`r2d2_viz.robot.urdf_check.JOINT_TYPES` (checked before a model is built)."""
MOVABLE_TYPES: tuple[str, ...] = JOINT_TYPES[:3]
"""revolute, continuous, prismatic: the joints a joint state moves."""

Mat4 = npt.NDArray[np.float64]
Rgba = tuple[float, float, float, float]


def asset_path(name: str) -> Path:
    """A file shipped as package data (``r2d2_viz/assets/NAME``), or from the checkout's ``assets/`` when the
    package runs from a source tree (``python -m r2d2_viz`` in a clone)."""
    installed = Path(str(resources.files("r2d2_viz") / "assets" / name))
    checkout = Path(__file__).resolve().parents[2] / "assets" / name
    return installed if installed.is_file() or not checkout.is_file() else checkout


def default_urdf_path() -> Path:
    """The tutorial's R2D2 (``assets/r2d2.urdf``)."""
    return asset_path("r2d2.urdf")


def _frozen(matrix: npt.ArrayLike | None) -> Mat4:
    out = np.array(np.eye(4) if matrix is None else matrix, dtype=np.float64)
    out.flags.writeable = False
    return out


# --- geometry -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Box:
    size: tuple[float, float, float]


@dataclass(frozen=True)
class Cylinder:
    """Along the shape frame's z axis, centred on its origin (URDF convention)."""

    radius: float
    length: float


@dataclass(frozen=True)
class Sphere:
    radius: float


@dataclass(frozen=True)
class MeshFile:
    filename: str
    """As written in the URDF."""
    path: Path | None
    """Resolved local file, or None when it cannot be found (the shape is then skipped)."""
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)


Geometry = Box | Cylinder | Sphere | MeshFile


@dataclass(frozen=True, eq=False)
class Shape:
    """One ``<visual>`` or ``<collision>`` element of a link."""

    geometry: Geometry
    T_link_shape: Mat4 = field(default_factory=lambda: _frozen(None))
    rgba: Rgba | None = None
    """Resolved colour (named materials looked up); None for collisions or uncoloured visuals."""
    material: str | None = None
    name: str | None = None


# --- links and joints -----------------------------------------------------------------------------


@dataclass(frozen=True)
class Limit:
    lower: float
    upper: float
    effort: float | None = None
    velocity: float | None = None


@dataclass(frozen=True)
class Mimic:
    """``value = multiplier * value(joint) + offset``."""

    joint: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True, eq=False)
class Joint:
    name: str
    type: JointType
    parent: str
    child: str
    T_parent_joint: Mat4
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    """Unit vector in the joint frame."""
    limit: Limit | None = None
    mimic: Mimic | None = None

    @property
    def movable(self) -> bool:
        return self.type in MOVABLE_TYPES


@dataclass(frozen=True)
class Link:
    name: str
    visuals: tuple[Shape, ...] = ()
    collisions: tuple[Shape, ...] = ()
    inertial: Inertial | None = None


@dataclass(frozen=True)
class Robot:
    """A validated robot: one root link, every other link the child of exactly one joint.

    ``joints`` are in topological order (a joint's parent link is the root or the child of an
    earlier joint); ``links`` start with the root and follow the same order."""

    name: str
    source: str
    """File name, used in messages."""
    root: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    warnings: tuple[str, ...] = ()
    missing_meshes: tuple[Path, ...] = ()  # where the mesh files not found would be (--watch watches them)

    def joint(self, name: str) -> Joint:
        try:
            return self._joints_by_name[name]
        except KeyError:
            raise KeyError(f"no joint {name!r}; joints are {listed(j.name for j in self.joints)}") from None

    @cached_property
    def _joints_by_name(self) -> dict[str, Joint]:
        """Built on first use (a dictionary: looking every joint up stays linear for thousands of joints)."""
        return {joint.name: joint for joint in self.joints}

    @property
    def movable_joints(self) -> tuple[Joint, ...]:
        """Revolute, continuous and prismatic joints, in topological order (mimic joints included)."""
        return tuple(j for j in self.joints if j.movable)

    @property
    def actuated_joints(self) -> tuple[Joint, ...]:
        """Movable joints that are not mimics: the ones a joint state sets."""
        return tuple(j for j in self.joints if j.movable and j.mimic is None)


# --- loading ------------------------------------------------------------------------------------


def load_urdf(path: str | Path, *, packages: PackageIndex | None = None) -> Robot:
    """Read, validate and convert a URDF file. Raises :class:`UrdfError` with a one-line message.
    ``package://`` meshes are found through ``packages`` (default: above the file, then the ROS environment)."""
    path = Path(path)
    with _cyclic_gc_paused():
        root = read_urdf_xml(path)
        return _validated(root, source=path.name, base_dir=path.parent, packages=packages)


def parse_urdf(
    text: str | bytes,
    *,
    source: str = "robot_description",
    base_dir: str | Path | None = None,
    packages: PackageIndex | None = None,
) -> Robot:
    """Validate and convert a robot description given as text (e.g. a bag's ``/robot_description``), through
    the same checks and one-line errors as :func:`load_urdf`; ``source`` names it in messages, relative mesh
    paths resolve against ``base_dir`` (the current directory by default)."""
    base = Path(base_dir) if base_dir is not None else Path.cwd()
    with _cyclic_gc_paused():
        root = parse_urdf_xml(text, source=source, base_dir=base)
        return _validated(root, source=source, base_dir=base, packages=packages)


def _validated(root: etree._Element, *, source: str, base_dir: Path, packages: PackageIndex | None) -> Robot:
    packages = packages or PackageIndex.from_environ()
    notes = check_robot(root, source=source, base_dir=base_dir, packages=packages)
    robot = build_robot(root, source=source, base_dir=base_dir, packages=packages)
    meshes = (str(m.get("filename")) for m in root.iter("mesh"))
    return replace(robot, warnings=tuple(notes), missing_meshes=missing_files(packages, meshes, base_dir=base_dir))


@contextmanager
def _cyclic_gc_paused() -> Iterator[None]:
    """Parsing allocates tens of thousands of objects; each few hundred trigger Python's cyclic collector,
    whose full passes walk every live object (numpy, rerun, trimesh: ~10^5 at start-up), so loading
    grew faster than the file: a 3,000-link URDF took 1.2 s in a process with 3·10^5 objects and 0.8 s
    with the collector paused, like a 1,000-link one times 2. Nothing here makes cycles that must go early."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def build_robot(root: etree._Element, *, source: str, base_dir: Path, packages: PackageIndex | None = None) -> Robot:
    """Convert a validated ``<robot>`` element into a :class:`Robot`, element by element (urdfdom's reading:
    origins ``xyz`` then ``rpy`` as fixed-axis roll, pitch, yaw; axes default to x; materials by name).

    Shapes whose mesh file cannot be found are left out (:func:`check_robot` warns about them).
    """
    named_colors = _named_colors(root)
    index = packages or PackageIndex.from_environ()
    links: dict[str, Link] = {}
    for link in root.iterchildren("link"):
        visuals = (_shape(v, v.find("material"), named_colors, base_dir, index) for v in link.iterchildren("visual"))
        collisions = (_shape(c, None, named_colors, base_dir, index) for c in link.iterchildren("collision"))
        name, inertial = str(link.get("name")), link.find("inertial")
        origin = _origin(inertial.find("origin")) if inertial is not None else _frozen(None)
        links[name] = Link(name, tuple(s for s in visuals if s is not None),
                           tuple(s for s in collisions if s is not None), read_inertial(inertial, origin))  # fmt: skip
    joint_elements = list(root.iterchildren("joint"))
    joint_names = {str(j.get("name")) for j in joint_elements}
    joints = [_joint(j, joint_names) for j in joint_elements]
    root_name, ordered = _topological(links, joints, source)
    return Robot(
        name=root.get("name") or Path(source).stem,
        source=source,
        root=root_name,
        links=tuple(links[name] for name in [root_name, *(j.child for j in ordered)]),
        joints=tuple(ordered),
    )


def _floats(text: str | None, default: str) -> npt.NDArray[np.float64]:
    return np.array([float(v) for v in (text or default).replace(",", " ").split()], dtype=np.float64)


def _origin(element: etree._Element | None) -> Mat4:
    """``<origin xyz rpy>`` as ``T_parent_child``: R = Rz(yaw) · Ry(pitch) · Rx(roll), as urdfdom reads it."""
    if element is None:
        return _frozen(None)
    T = np.eye(4)
    T[:3, 3] = _floats(element.get("xyz"), "0 0 0")
    roll, pitch, yaw = _floats(element.get("rpy"), "0 0 0")
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    T[:3, :3] = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    return _frozen(T)


def _color(material: etree._Element | None) -> Rgba | None:
    color = material.find("color") if material is not None else None
    if color is None:
        return None
    r, g, b, a = (float(x) for x in _floats(color.get("rgba"), "1 1 1 1"))
    return (r, g, b, a)


def _named_colors(root: etree._Element) -> dict[str, Rgba]:
    """Materials by name, like urdfdom: top-level ones, then the first inline definition of each."""
    colors: dict[str, Rgba] = {}
    inline = (v.find("material") for link in root.iterchildren("link") for v in link.iterchildren("visual"))
    for material in (*root.iterchildren("material"), *inline):
        rgba = _color(material)
        if material is not None and material.get("name") and rgba is not None:
            colors.setdefault(str(material.get("name")), rgba)
    return colors


def _shape(
    element: etree._Element,
    material: etree._Element | None,
    named_colors: dict[str, Rgba],
    base_dir: Path,
    packages: PackageIndex,
) -> Shape | None:
    geometry = _geometry(element.find("geometry"), base_dir, packages)
    if isinstance(geometry, MeshFile) and geometry.path is None:
        return None
    rgba = _color(material)
    name = material.get("name") if material is not None else None
    if rgba is None and name:
        rgba = named_colors.get(name)
    return Shape(geometry=geometry, T_link_shape=_origin(element.find("origin")), rgba=rgba, material=name,
                 name=element.get("name"))  # fmt: skip


def _geometry(geometry: etree._Element | None, base_dir: Path, packages: PackageIndex) -> Geometry:
    shape = next(
        c for c in (geometry if geometry is not None else ()) if c.tag in ("box", "cylinder", "sphere", "mesh")
    )
    if shape.tag == "box":
        x, y, z = (float(v) for v in _floats(shape.get("size"), ""))
        return Box((x, y, z))
    if shape.tag == "cylinder":
        return Cylinder(float(shape.get("radius", "")), float(shape.get("length", "")))
    if shape.tag == "sphere":
        return Sphere(float(shape.get("radius", "")))
    filename = str(shape.get("filename"))
    sx, sy, sz = (float(v) for v in np.broadcast_to(_floats(shape.get("scale"), "1"), (3,)))
    return MeshFile(filename, packages.resolve_uri(filename, base_dir=base_dir), (sx, sy, sz))


def _number(element: etree._Element, name: str) -> float | None:
    value = element.get(name)
    return None if value is None else float(value)


def _joint(element: etree._Element, joint_names: set[str]) -> Joint:
    kind = str(element.get("type"))
    axis_element = element.find("axis")
    axis = _floats(axis_element.get("xyz") if axis_element is not None else None, "1 0 0")
    norm = float(np.linalg.norm(axis))
    ax, ay, az = (float(v) for v in (axis / norm if norm > 0 else np.array([1.0, 0.0, 0.0])))
    limit = None
    limit_element = element.find("limit")
    if limit_element is not None:
        lower, upper = _number(limit_element, "lower"), _number(limit_element, "upper")
        if kind in ("revolute", "prismatic") or (lower is not None and upper is not None):
            limit = Limit(  # a missing lower/upper reads as 0 on revolute and prismatic joints, like urdfdom
                lower=lower or 0.0,
                upper=upper or 0.0,
                effort=_number(limit_element, "effort"),
                velocity=_number(limit_element, "velocity"),
            )
    mimic = None
    mimic_element = element.find("mimic")
    if mimic_element is not None and mimic_element.get("joint") in joint_names:  # else it moves on its own
        multiplier, offset = _number(mimic_element, "multiplier"), _number(mimic_element, "offset")
        mimic = Mimic(str(mimic_element.get("joint")), 1.0 if multiplier is None else multiplier, offset or 0.0)
    parent, child = element.find("parent"), element.find("child")
    assert parent is not None and child is not None  # check_robot refused joints without them
    return Joint(
        name=str(element.get("name")),
        type=kind,
        parent=str(parent.get("link")),
        child=str(child.get("link")),
        T_parent_joint=_origin(element.find("origin")),
        axis=(ax, ay, az),
        limit=limit,
        mimic=mimic,
    )


def _topological(links: dict[str, Link], joints: list[Joint], source: str) -> tuple[str, list[Joint]]:
    """Root link and joints ordered parent-first, by an iterative breadth-first walk (no recursion).

    :func:`r2d2_viz.robot.urdf_check.check_robot` has already refused robots without exactly one root, with
    cycles or with joints that reach unknown links."""
    children: dict[str, list[Joint]] = {}
    child_links = set()
    for joint in joints:
        children.setdefault(joint.parent, []).append(joint)
        child_links.add(joint.child)
    root = next(name for name in links if name not in child_links)
    ordered: list[Joint] = []
    queue = deque([root])
    while queue:
        for joint in children.get(queue.popleft(), ()):
            ordered.append(joint)
            queue.append(joint.child)
    return root, ordered
