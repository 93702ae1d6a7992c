"""URDF validation, without ROS and without trusting the input.

:func:`read_urdf_xml` (from :mod:`r2d2_viz.robot.urdf_xml`) turns a file into a ``<robot>`` element, refusing
anything that is not a small, well-formed, UTF-8 XML document free of entity declarations.
:func:`check_robot` then validates the URDF structure and numbers the way urdfdom would — accepting, with a
warning, what urdfdom accepts — with one-line messages of the form ``<file name>: <element>: <problem>``.
Unknown elements and attributes are ignored.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import NoReturn
from urllib.parse import unquote, urlsplit

from lxml import etree

from r2d2_viz.errors import listed
from r2d2_viz.robot.packages import PackageIndex, uri_package
from r2d2_viz.robot.urdf_xml import MAX_FILE_BYTES, _fail, _one_line, _q, parse_urdf_xml, read_urdf_xml

__all__ = ["JOINT_TYPES", "MAX_FILE_BYTES", "check_robot", "parse_urdf_xml", "read_urdf_xml", "resolve_mesh_path"]

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
SHAPES = ("box", "cylinder", "sphere", "mesh")
_AXIS_TYPES = frozenset({"revolute", "continuous", "prismatic", "planar"})
_LIMITED_TYPES = frozenset({"revolute", "prismatic"})
_INFINITY = re.compile(r"[+-]?inf(?:inity)?\Z", re.IGNORECASE)
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z")


# --------------------------------------------------------------------------- meshes


def resolve_mesh_path(filename: str, base_dir: Path, packages: PackageIndex | None = None) -> Path | None:
    """Best-effort local file for a URDF mesh ``filename`` (plain path, file:// or package://), else None.
    ``packages`` finds ``package://`` packages (by default: above ``base_dir`` and the ROS environment)."""
    return (packages or PackageIndex.from_environ()).resolve_uri(filename, base_dir=base_dir)


# --------------------------------------------------------------------------- structure


def _children(el: etree._Element, tag: str) -> Iterator[etree._Element]:
    return (child for child in el if child.tag == tag)


def _first(el: etree._Element, tag: str) -> etree._Element | None:
    return next(_children(el, tag), None)


class _Checker:
    def __init__(self, source: str, base_dir: Path, packages: PackageIndex | None = None) -> None:
        self.source = _one_line(source) or "<urdf>"
        self.base_dir = base_dir
        self.packages = packages or PackageIndex.from_environ()
        self.warnings: list[str] = []
        self.materials: set[str] = set()
        self.meshes: dict[str, tuple[Path | None, str]] = {}
        self.missing_packages: dict[str, dict[str, list[str]]] = {}
        """Package not found -> kind ("visual", "collision") -> the mesh files it would have given, once a shape."""

    def fail(self, where: str, problem: str) -> NoReturn:
        _fail(self.source, where, problem)

    def warn(self, where: str, problem: str) -> None:
        self.warnings.append(_one_line(f"{self.source}: {where}: {problem}"))

    def numbers(
        self, where: str, el: etree._Element, attr: str, count: int, *, infinite_ok: bool = False
    ) -> tuple[float, ...] | None:
        """``count`` finite numbers from attribute ``attr`` of ``el``; None if the attribute is absent.
        ``infinite_ok`` also takes ``inf``, ``-inf`` and overflowing numbers (limits meaning "unlimited")."""
        raw = el.get(attr)
        if raw is None:
            return None
        tokens = raw.split()
        what = f"<{el.tag}> {attr}={_q(raw)}"
        if len(tokens) != count:
            plural = "number" if count == 1 else "numbers"
            self.fail(where, f"{what}: expected {count} {plural}, got {len(tokens)}")
        values: list[float] = []
        for token in tokens:
            value = float(token) if _NUMBER.match(token) or (infinite_ok and _INFINITY.match(token)) else math.nan
            if math.isnan(value) or (math.isinf(value) and not infinite_ok):
                self.fail(where, f"{what}: {_q(token, 30)} is not a finite number")
            values.append(value)
        return tuple(values)

    def positive(self, where: str, el: etree._Element, attr: str, count: int) -> None:
        values = self.numbers(where, el, attr, count)
        if values is None:
            self.fail(where, f"<{el.tag}> has no {attr} attribute")
        if any(v <= 0 for v in values):
            self.fail(where, f"<{el.tag}> {attr}={_q(el.get(attr, ''))}: must be positive")

    def origin(self, where: str, el: etree._Element) -> None:
        origin = _first(el, "origin")
        if origin is not None:
            self.numbers(where, origin, "xyz", 3)
            self.numbers(where, origin, "rpy", 3)

    def material(self, where: str, el: etree._Element) -> bool:
        """Check a <material>; return True if it defines a colour or texture."""
        color = _first(el, "color")
        if color is not None:
            rgba = self.numbers(where, color, "rgba", 4)
            if rgba is None:
                self.fail(where, "<color> has no rgba attribute")
            if any(not 0.0 <= v <= 1.0 for v in rgba):
                self.fail(where, f"<color> rgba={_q(color.get('rgba', ''))}: components must be in [0, 1]")
        texture = _first(el, "texture")
        return color is not None or (texture is not None and bool(texture.get("filename")))

    def geometry(self, where: str, el: etree._Element, kind: str) -> None:
        geometry = _first(el, "geometry")
        if geometry is None:
            self.fail(where, f"<{kind}> has no <geometry>")
        shapes = [child for child in geometry if isinstance(child.tag, str)]
        expected = f"expected one of {', '.join(SHAPES)}"
        if not shapes:
            self.fail(where, f"<geometry> has no shape; {expected}")
        for shape in shapes:
            if shape.tag not in SHAPES:
                self.fail(where, f"<geometry>: unknown shape <{_q(str(shape.tag), 40)[1:-1]}>; {expected}")
        if len(shapes) > 1:
            self.fail(where, f"<geometry> has {len(shapes)} shapes; expected exactly one")
        shape = shapes[0]
        if shape.tag == "box":
            self.positive(where, shape, "size", 3)
        elif shape.tag == "cylinder":
            self.positive(where, shape, "radius", 1)
            self.positive(where, shape, "length", 1)
        elif shape.tag == "sphere":
            self.positive(where, shape, "radius", 1)
        else:
            scale = self.numbers(where, shape, "scale", 3)
            if scale is not None and 0.0 in scale:
                self.fail(where, f"<mesh> scale={_q(shape.get('scale', ''))}: must not be zero")
            filename = (shape.get("filename") or "").strip()
            if not filename:
                self.fail(where, "<mesh> has no filename")
            if filename not in self.meshes:
                self.meshes[filename] = self.packages.explain(filename, base_dir=self.base_dir)
            found, reason = self.meshes[filename]
            if found is None:
                package = uri_package(filename)
                if package is not None and self.packages.lookup(package, near=self.base_dir) is None:
                    file = filename.partition("://")[2].lstrip("/")  # package:// and package:/// alike
                    self.missing_packages.setdefault(package, {}).setdefault(kind, []).append(file)
                else:
                    self.warn(where, f"{reason}; {kind} skipped")

    def package_warnings(self) -> None:
        """One line per ROS package not found: how many meshes it would have given (a Husky's description named 35
        meshes in two packages: 35 lines before)."""
        for package, kinds in self.missing_packages.items():
            shapes = sum(len(files) for files in kinds.values())
            files = len({f for names in kinds.values() for f in names})
            split = ", ".join(f"{len(kinds[k])} {k}" for k in ("visual", "collision") if k in kinds)
            self.warnings.append(
                _one_line(
                    f"{self.source}: package {_q(package)} not found: {shapes} mesh{'es' if shapes > 1 else ''} "
                    f"skipped ({split}; {files} file{'s' if files > 1 else ''}); give its folder with "
                    f"--package-path DIR or --package-path {package}=DIR "
                    f"(looked in {self.packages.where(near=self.base_dir)})"
                )
            )

    def link(self, where: str, link: etree._Element) -> list[tuple[str, str]]:
        """Check a <link>; return its (where, material name) references to resolve later."""
        refs: list[tuple[str, str]] = []
        inertial = _first(link, "inertial")
        if inertial is not None:
            self.origin(f"{where}: <inertial>", inertial)
            mass = _first(inertial, "mass")
            if mass is not None:
                self.numbers(f"{where}: <inertial>", mass, "value", 1)
            inertia = _first(inertial, "inertia")
            if inertia is not None:
                for attr in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
                    self.numbers(f"{where}: <inertial>", inertia, attr, 1)
        for kind in ("visual", "collision"):
            for index, el in enumerate(_children(link, kind), start=1):
                at = f"{where}: {kind} #{index}"
                self.origin(at, el)
                self.geometry(at, el, kind)
                material = _first(el, "material") if kind == "visual" else None
                if material is not None:
                    mat_name = material.get("name") or ""
                    if self.material(f"{at}: material {_q(mat_name)}", material):
                        self.materials.add(mat_name)
                    elif mat_name:
                        refs.append((at, mat_name))
        return refs

    def joint(self, where: str, joint: etree._Element, links: dict[str, int]) -> tuple[str, str]:
        """Check a <joint>; return (parent link, child link)."""
        jtype = joint.get("type")
        expected = f"expected one of {', '.join(JOINT_TYPES)}"
        if jtype is None:
            self.fail(where, f"missing type attribute; {expected}")
        if jtype not in JOINT_TYPES:
            self.fail(where, f"unknown joint type {_q(jtype)}; {expected} (urdfdom: has no known type)")
        ends: list[str] = []
        for role in ("parent", "child"):
            el = _first(joint, role)
            if el is None or el.get("link") is None:
                self.fail(where, f"missing <{role} link=...>")
            name = el.get("link", "")
            if name not in links:
                # Suggest a near miss, but keep hostile input (huge names, many links) cheap.
                short = [n for n in links if len(n) <= 64] if len(name) <= 64 and len(links) <= 5000 else []
                close = difflib.get_close_matches(name, short, n=1)
                hint = f" (did you mean {_q(close[0])}?)" if close else ""
                self.fail(where, f"{role} link {_q(name)} does not exist{hint}")
            ends.append(name)
        self.origin(where, joint)
        axis_el = _first(joint, "axis")
        if axis_el is not None:
            axis = self.numbers(where, axis_el, "xyz", 3)
            if jtype in _AXIS_TYPES and axis is not None and math.fsum(v * v for v in axis) < 1e-24:
                self.fail(where, f"<axis> xyz={_q(axis_el.get('xyz', ''))}: must not be a zero vector")
        limit = _first(joint, "limit")
        if limit is None and jtype in _LIMITED_TYPES:
            self.fail(where, f"{jtype} joint has no <limit lower=... upper=...> (urdfdom: does not specify limits)")
        if limit is not None:
            # Limits may be infinite or huge (urdfdom reads "inf"; ±1e16 means unlimited): accepted here.
            bounds = [self.numbers(where, limit, attr, 1, infinite_ok=True) for attr in ("lower", "upper")]
            for attr in ("effort", "velocity"):
                self.numbers(where, limit, attr, 1, infinite_ok=True)
            if jtype in _LIMITED_TYPES:
                for attr, value in zip(("lower", "upper"), bounds, strict=True):
                    if value is None:  # urdfdom: "joint limit: no lower, defaults to 0"
                        self.warn(where, f"<limit> has no {attr}; read as 0, like urdfdom")
                lower, upper = ((0.0,) if value is None else value for value in bounds)
                if lower[0] > upper[0]:
                    # urdfdom does not check it, but no position satisfies such a limit: refused.
                    self.fail(where, f"<limit> lower={lower[0]:g} is greater than upper={upper[0]:g}")
                if lower[0] == math.inf or upper[0] == -math.inf:
                    self.fail(where, f"<limit> lower={lower[0]:g} upper={upper[0]:g} leaves no position")
        return ends[0], ends[1]


def _names(el_list: Iterable[etree._Element], kind: str, checker: _Checker) -> dict[str, int]:
    seen: dict[str, int] = {}
    for index, el in enumerate(el_list, start=1):
        name = el.get("name")
        if not name:
            checker.fail(f"{kind} #{index}", "missing name attribute")
        if name in seen:
            checker.fail(f"{kind} {_q(name)}", f"duplicate {kind} name (also {kind} #{seen[name]})")
        seen[name] = index
    return seen


def check_robot(
    root: etree._Element, *, source: str, base_dir: Path | None = None, packages: PackageIndex | None = None
) -> list[str]:
    """Validate structure and numbers; raise UrdfError on the first problem; return non-fatal warnings
    (e.g. mesh file missing: "<source>: link 'x': mesh file 'foo.stl' not found; visual skipped") as strings.

    Relative mesh paths resolve against ``base_dir``, by default the directory of the file
    ``read_urdf_xml`` read (else the current directory); ``package://`` URIs through ``packages``.
    """
    if base_dir is None:
        url = root.getroottree().docinfo.URL
        base_dir = Path(unquote(urlsplit(url).path) if url.startswith("file:") else url).parent if url else Path()
    checker = _Checker(source, base_dir, packages)
    if root.tag != "robot":
        checker.fail("root", f"element is <{_q(str(root.tag), 80)[1:-1]}>; expected <robot>")
    robot = f"robot {_q(root.get('name', ''))}" if root.get("name") else "robot"
    link_els = list(_children(root, "link"))
    joint_els = list(_children(root, "joint"))
    if not link_els:
        checker.fail(robot, "has no <link> elements")  # urdfdom: "No link elements found in urdf file"
    links = _names(link_els, "link", checker)
    joint_names = _names(joint_els, "joint", checker)

    for material in _children(root, "material"):
        name = material.get("name") or ""
        if checker.material(f"material {_q(name)}", material):
            checker.materials.add(name)
    refs = [ref for el in link_els for ref in checker.link(f"link {_q(el.get('name', ''))}", el)]
    for where, name in refs:
        if name not in checker.materials:
            checker.warn(where, f"material {_q(name)} is not defined; default colour used")

    parent_joint: dict[str, str] = {}  # child link -> joint name
    parent_link: dict[str, str] = {}  # child link -> parent link
    children: dict[str, list[str]] = {}
    mimics: dict[str, str] = {}
    for joint in joint_els:
        jname = joint.get("name", "")
        where = f"joint {_q(jname)}"
        parent, child = checker.joint(where, joint, links)
        if child in parent_joint:
            checker.fail(where, f"child link {_q(child)} is already the child of joint {_q(parent_joint[child])}")
        parent_joint[child] = jname
        parent_link[child] = parent
        children.setdefault(parent, []).append(child)
        mimic = _first(joint, "mimic")
        if mimic is not None:
            target = mimic.get("joint")
            if not target:
                checker.fail(where, "<mimic> has no joint attribute (urdfdom: no mimic joint specified)")
            checker.numbers(where, mimic, "multiplier", 1)
            checker.numbers(where, mimic, "offset", 1)
            if target in joint_names:
                mimics[jname] = target
            else:  # urdfdom and robot_state_publisher accept it: the joint moves on its own
                checker.warn(where, f"<mimic> joint {_q(target)} does not exist; ignored: the joint moves on its own")

    roots = [name for name in links if name not in parent_joint]
    if len(roots) > 1:
        shown = listed(_q(r, 40) for r in roots)
        checker.fail(
            robot,
            f"more than one root link ({len(roots)}: {shown}); every other link needs a parent joint "
            "(urdfdom: two root links found)",
        )
    reached: set[str] = set(roots)
    stack = list(roots)
    while stack:
        for child in children.get(stack.pop(), ()):
            if child not in reached:
                reached.add(child)
                stack.append(child)
    if len(reached) < len(links):
        start = next(name for name in links if name not in reached)
        path: dict[str, None] = {}
        link = start
        while link not in path:
            path[link] = None
            link = parent_link[link]
        loop = list(path)[list(path).index(link) :]
        shown = " -> ".join(_q(n, 40) for n in loop[:6]) + (" -> …" if len(loop) > 6 else "")
        checker.fail(f"joint {_q(parent_joint[loop[0]])}", f"closes a kinematic loop: {shown} -> {_q(loop[0], 40)}")

    acyclic: set[str] = set()
    for jname in mimics:
        chain: dict[str, None] = {}
        current = jname
        while current in mimics and current not in acyclic:
            if current in chain:
                checker.fail(f"joint {_q(jname)}", "<mimic> joints form a loop")
            chain[current] = None
            current = mimics[current]
        acyclic.update(chain)
    checker.package_warnings()
    return checker.warnings
