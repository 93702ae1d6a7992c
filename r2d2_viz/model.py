"""URDF → an immutable robot model.

The file is read and validated by :mod:`r2d2_viz.urdf_check` (safe XML, one-line errors), parsed
element by element by yourdfpy, and turned into frozen dataclasses that the rest of the app uses.
Nothing here is specific to the R2D2: any URDF with box, cylinder, sphere (and mesh) geometry loads.

Poses are 4×4 homogeneous matrices named after the frames they map between:
``Joint.T_parent_joint`` maps joint-frame coordinates into the parent link's frame (the URDF
``<origin>`` of the joint), ``Shape.T_link_shape`` maps shape coordinates into its link's frame.
"""

from __future__ import annotations

import gc
import io
import warnings
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cached_property
from importlib import resources
from pathlib import Path

import numpy as np
import numpy.typing as npt
import yourdfpy
from lxml import etree

from .errors import UrdfError
from .packages import PackageIndex
from .urdf_check import JOINT_TYPES, check_robot, parse_urdf_xml, read_urdf_xml

JointType = str
"""One of :data:`r2d2_viz.urdf_check.JOINT_TYPES` (checked before a model is built)."""
MOVABLE_TYPES: tuple[str, ...] = JOINT_TYPES[:3]
"""revolute, continuous, prismatic: the joints a joint state moves."""

Mat4 = npt.NDArray[np.float64]
Rgba = tuple[float, float, float, float]


def default_urdf_path() -> Path:
    """The tutorial's R2D2, shipped as package data (``r2d2_viz/assets/r2d2.urdf``)."""
    return Path(str(resources.files("r2d2_viz") / "assets" / "r2d2.urdf"))


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


@dataclass(frozen=True)
class Robot:
    """A validated robot: one root link, every other link the child of exactly one joint.

    ``joints`` are in topological order (a joint's parent link is the root or the child of an
    earlier joint); ``links`` start with the root and follow the same order.
    """

    name: str
    source: str
    """File name, used in messages."""
    root: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    warnings: tuple[str, ...] = ()

    def joint(self, name: str) -> Joint:
        try:
            return self._joints_by_name[name]
        except KeyError:
            raise KeyError(f"no joint {name!r}; joints are {', '.join(j.name for j in self.joints)}") from None

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
    return Robot(robot.name, robot.source, robot.root, robot.links, robot.joints, tuple(notes))


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
    """Convert a validated ``<robot>`` element into a :class:`Robot`.

    Shapes whose mesh file cannot be found are left out (:func:`check_robot` warns about them).
    """
    if root.get("name") is None:  # optional for urdf_check, required by yourdfpy
        root.set("name", Path(source).stem)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            urdf = yourdfpy.URDF.load(
                io.BytesIO(etree.tostring(root)),  # validated, entity-free XML, parsed again by yourdfpy
                build_scene_graph=False,
                build_collision_scene_graph=False,
                load_meshes=False,
                load_collision_meshes=False,
            ).robot
    except (ValueError, KeyError, IndexError, TypeError, AttributeError) as exc:  # validator should catch first
        raise UrdfError(f"{source}: cannot parse: {exc}") from None

    named_colors = _named_colors(urdf)
    index = packages or PackageIndex.from_environ()
    links = {
        link.name: Link(
            name=link.name,
            visuals=tuple(
                s for v in link.visuals if (s := _shape(v, v.material, named_colors, base_dir, index)) is not None
            ),
            collisions=tuple(
                s for c in link.collisions if (s := _shape(c, None, named_colors, base_dir, index)) is not None
            ),
        )
        for link in urdf.links
    }
    joint_names = {j.name for j in urdf.joints}
    joints = [_joint(j, joint_names) for j in urdf.joints]
    root_name, ordered = _topological(links, joints, source)
    return Robot(
        name=urdf.name,
        source=source,
        root=root_name,
        links=tuple(links[name] for name in [root_name, *(j.child for j in ordered)]),
        joints=tuple(ordered),
    )


def _named_colors(urdf: yourdfpy.Robot) -> dict[str, Rgba]:
    """Materials by name, like urdfdom: top-level ones, then the first inline definition of each."""
    colors: dict[str, Rgba] = {}

    def register(material: yourdfpy.Material | None) -> None:
        if material is not None and material.name and material.color is not None:
            colors.setdefault(material.name, _rgba(material.color.rgba))

    for material in urdf.materials:
        register(material)
    for link in urdf.links:
        for visual in link.visuals:
            register(visual.material)
    return colors


def _rgba(values: npt.ArrayLike) -> Rgba:
    r, g, b, a = (float(x) for x in np.asarray(values, dtype=np.float64).reshape(4))
    return (r, g, b, a)


def _shape(
    element: yourdfpy.Visual | yourdfpy.Collision,
    material: yourdfpy.Material | None,
    named_colors: dict[str, Rgba],
    base_dir: Path,
    packages: PackageIndex,
) -> Shape | None:
    geometry = _geometry(element.geometry, base_dir, packages)
    if isinstance(geometry, MeshFile) and geometry.path is None:
        return None
    rgba: Rgba | None = None
    if material is not None:
        if material.color is not None:
            rgba = _rgba(material.color.rgba)
        elif material.name:
            rgba = named_colors.get(material.name)
    return Shape(
        geometry=geometry,
        T_link_shape=_frozen(element.origin),
        rgba=rgba,
        material=material.name if material is not None else None,
        name=element.name,
    )


def _geometry(geometry: yourdfpy.Geometry, base_dir: Path, packages: PackageIndex) -> Geometry:
    if geometry.box is not None:
        x, y, z = (float(v) for v in geometry.box.size)
        return Box((x, y, z))
    if geometry.cylinder is not None:
        return Cylinder(float(geometry.cylinder.radius), float(geometry.cylinder.length))
    if geometry.sphere is not None:
        return Sphere(float(geometry.sphere.radius))
    mesh = geometry.mesh
    scale = np.broadcast_to(np.asarray(1.0 if mesh.scale is None else mesh.scale, dtype=np.float64), (3,))
    sx, sy, sz = (float(v) for v in scale)
    return MeshFile(mesh.filename, packages.resolve_uri(mesh.filename, base_dir=base_dir), (sx, sy, sz))


def _joint(joint: yourdfpy.Joint, joint_names: set[str]) -> Joint:
    axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), dtype=np.float64)
    norm = float(np.linalg.norm(axis))
    ax, ay, az = (float(v) for v in (axis / norm if norm > 0 else np.array([1.0, 0.0, 0.0])))
    limit = None
    bounded = joint.type in ("revolute", "prismatic")  # a missing lower/upper reads as 0 there, like urdfdom
    if joint.limit is not None and (bounded or (joint.limit.lower is not None and joint.limit.upper is not None)):
        limit = Limit(
            lower=float(joint.limit.lower or 0.0),
            upper=float(joint.limit.upper or 0.0),
            effort=None if joint.limit.effort is None else float(joint.limit.effort),
            velocity=None if joint.limit.velocity is None else float(joint.limit.velocity),
        )
    mimic = None
    if joint.mimic is not None and joint.mimic.joint in joint_names:  # else moves on its own (check_robot warns)
        mimic = Mimic(joint.mimic.joint, float(joint.mimic.multiplier), float(joint.mimic.offset))
    return Joint(
        name=joint.name,
        type=joint.type,
        parent=joint.parent,
        child=joint.child,
        T_parent_joint=_frozen(joint.origin),
        axis=(ax, ay, az),
        limit=limit,
        mimic=mimic,
    )


def _topological(links: dict[str, Link], joints: list[Joint], source: str) -> tuple[str, list[Joint]]:
    """Root link and joints ordered parent-first, by an iterative breadth-first walk (no recursion).

    :func:`r2d2_viz.urdf_check.check_robot` has already refused robots without exactly one root, with
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
