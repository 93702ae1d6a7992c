"""A robot's kinematic tree as text, the way urdfdom's ``check_urdf`` prints it (``r2d2-viz --tree``).

``check_urdf`` prints the robot's name, a banner, the root link with its number of children, then every link
under its parent, four spaces deeper per level, ``child(N):  <link>``. urdfdom keeps its joints in a
``std::map`` by name and gives each link its children in that order (``ModelInterface::initTree``), so the
children of a link are listed by their joint's name, not in the file's order. Each child line here also names
its joint and the joint's type, after two spaces: ``child(1):  head  (joint swivel, continuous)``; the rest of the
line is check_urdf's own, so what reads its output still reads ours.
"""

from __future__ import annotations

from collections.abc import Iterator

from r2d2_viz.robot.model import Joint, Robot

BANNER = "---------- Successfully Parsed XML ---------------"


def tree_lines(robot: Robot) -> Iterator[str]:
    """``check_urdf``'s lines for ``robot`` (without line ends), depth first, iteratively (a deep chain of
    thousands of links recurses nowhere)."""
    children: dict[str, list[Joint]] = {}
    for joint in sorted(robot.joints, key=lambda j: j.name.encode("utf-8")):  # std::map<std::string>: bytes
        children.setdefault(joint.parent, []).append(joint)
    yield f"robot name is: {robot.name}"
    yield BANNER
    yield f"root Link: {robot.root} has {len(children.get(robot.root, ()))} child(ren)"
    stack: list[tuple[int, int, Joint]] = [
        (1, n, joint) for n, joint in reversed(list(enumerate(children.get(robot.root, ()), start=1)))
    ]
    while stack:
        depth, number, joint = stack.pop()
        yield f"{'    ' * depth}child({number}):  {joint.child}  (joint {joint.name}, {joint.type})"
        below = children.get(joint.child, ())
        stack.extend((depth + 1, n, j) for n, j in reversed(list(enumerate(below, start=1))))
