"""Several robots in one run: every namespace with a ``robot_description`` is a robot, drawn from its own description,
moved by its own ``joint_states``, its frames kept apart from the other robots' by a prefix.

Two conventions are found in the wild, and both end in the same frames (``robot2/base_link``):

* (A) one ``/tf`` whose frames already carry the prefix (robot_state_publisher's ``frame_prefix``), beside
  ``/robot1/robot_description`` and ``/robot1/joint_states``;
* (B) namespaced ``/robot2/tf`` and ``/robot2/tf_static`` with bare frames: those topics are read with every frame
  renamed ``robot2/<frame>``, except the frames robots share (``map``, ``world``, ``earth``: ``--shared-frames``).

Which one a robot follows is read from the recording: its root link prefixed among the frames of ``/tf`` is (A); its
own TF topics are (B). The robot's links are renamed with the same prefix, so its kinematics and the recorded
transforms name the same frames. Pure: no rerun import.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace

from r2d2_viz.kinematics.tree import KinematicTree, compile_tree
from r2d2_viz.robot.model import Robot, parse_urdf
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.sources.bag_joints import JOINT_STATE, read_robot_description
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.base import TfRecords

DESCRIPTION = "robot_description"
SHARED_FRAMES = ("map", "world", "earth")
"""Frames every robot's tree may hang from; never prefixed (``--shared-frames`` changes them)."""


@dataclass(frozen=True)
class RobotPlan:
    """One robot of a run: its namespace (``""`` for the root one), kinematics, joint-states topic and frame prefix
    (``""`` or ``"robot2/"``: the robot's links are named with it)."""

    namespace: str
    tree: KinematicTree
    joints_topic: str
    prefix: str = ""
    description: str | None = None

    @property
    def name(self) -> str:
        """How messages name the robot: its namespace, or ``/`` for the root one."""
        return self.namespace or "/"


def description_namespaces(topics: Iterable[str]) -> list[str]:
    """The namespaces (``""``, ``/robot1``) of the topics named ``<namespace>/robot_description``, sorted."""
    suffix = "/" + DESCRIPTION
    return sorted(t[: -len(suffix)] for t in topics if t.endswith(suffix))


def topic(namespace: str, name: str) -> str:
    """``/robot2`` + ``tf`` → ``/robot2/tf``."""
    return f"{namespace}/{name}"


def prefix_of(namespace: str) -> str:
    """The frame prefix of a namespace: ``/robot2`` → ``robot2/``."""
    return namespace.strip("/") + "/" if namespace.strip("/") else ""


def prefixed_robot(robot: Robot, prefix: str) -> Robot:
    """``robot`` with every link (hence every frame it names) prefixed; joints keep their names (joint states name
    them bare)."""
    if not prefix:
        return robot
    links = tuple(replace(link, name=prefix + link.name) for link in robot.links)
    joints = tuple(replace(j, parent=prefix + j.parent, child=prefix + j.child) for j in robot.joints)
    return Robot(robot.name, robot.source, prefix + robot.root, links, joints, robot.warnings)


def renamed(records: TfRecords, prefix: str, shared: Sequence[str] = SHARED_FRAMES) -> TfRecords:
    """Convention (B): ``records`` with every frame but the shared ones named ``<prefix><frame>`` (a leading ``/``,
    as tf1 wrote, dropped; a frame that already carries the prefix kept)."""
    if not prefix:
        return records
    keep = set(shared)
    cache: dict[str, str] = {}

    def name(frame: str) -> str:
        if (new := cache.get(frame)) is None:
            bare = frame.lstrip("/")
            new = bare if bare in keep or bare.startswith(prefix) else prefix + bare
            cache[frame] = new
        return new

    return replace(
        records, parents=tuple(name(p) for p in records.parents), children=tuple(name(c) for c in records.children)
    )


def tf_frames(records: Iterable[TfRecords | None]) -> set[str]:
    return {f for r in records if r is not None for f in (*r.parents, *r.children)}


def choose_prefix(namespace: str, root: str, *, own_tf: bool, frames: set[str], several: bool) -> str:
    """The frame prefix of the robot in ``namespace`` whose root link is ``root``: none for the root namespace; (A)
    when ``/tf`` names its root prefixed, (B) when it has TF topics of its own; a lone namespaced robot whose bare
    root is in ``/tf`` (only its description namespaced) keeps bare frames; otherwise prefixed (never two robots on
    one name)."""
    prefix = prefix_of(namespace)
    if not prefix or prefix + root in frames or own_tf:
        return prefix
    return "" if root in frames and not several else prefix


def parents_of(records: Iterable[TfRecords | None]) -> dict[str, str]:
    """Child frame → its parent in the recorded transforms (the last one recorded)."""
    parent: dict[str, str] = {}
    for r in records:
        if r is not None:
            parent.update(zip(r.children, r.parents, strict=True))
    return parent


def parent_chain(frame: str, parent: Mapping[str, str]) -> list[str]:
    """``frame`` and its ancestors (``parent``: :func:`parents_of`), up to the root of its tree."""
    chain = [frame]
    while (up := parent.get(chain[-1])) is not None and up not in chain:
        chain.append(up)
    return chain


def unreached(robot: RobotPlan, fixed_frame: str, parents: Mapping[str, str]) -> str | None:
    """One line naming ``robot`` when its tree does not reach ``fixed_frame`` through the recorded transforms
    (``parents``: :func:`parents_of`)."""
    root = robot.tree.robot.root
    chain = parent_chain(root, parents)
    if fixed_frame in chain or root == fixed_frame:
        return None
    if len(chain) == 1:
        return (
            f"robot {robot.name}: no recorded transform places its root {root!r}; it is drawn at the fixed frame "
            f"{fixed_frame!r}'s origin"
        )
    return (
        f"robot {robot.name}: its tree ends at {chain[-1]!r}, not the fixed frame {fixed_frame!r}; "
        "it is not shown in the 3D view"
    )


def plan_robots(
    descriptions: Sequence[tuple[str, Robot, str]],
    topics: Iterable[str],
    frames: set[str],
    compile_tree: Callable[[Robot], KinematicTree],
) -> tuple[RobotPlan, ...]:
    """The robots of ``descriptions`` (namespace, robot, URDF text), each with its prefix (see
    :func:`choose_prefix`); ``topics``: the bag's, ``frames``: those of its ``/tf`` and ``/tf_static``."""
    present = set(topics)
    several = len(descriptions) > 1
    out = []
    for namespace, robot, text in descriptions:
        own_tf = bool(namespace) and any(topic(namespace, n) in present for n in ("tf", "tf_static"))
        prefix = choose_prefix(namespace, robot.root, own_tf=own_tf, frames=frames, several=several)
        tree = compile_tree(prefixed_robot(robot, prefix))
        out.append(RobotPlan(namespace, tree, topic(namespace, "joint_states"), prefix, text))
    return tuple(out)


def robots_read(robots: Sequence[RobotPlan]) -> set[str]:
    """The topics the namespaced robots' pipeline reads (not left to other displays)."""
    names = ("robot_description", "joint_states", "tf", "tf_static")
    return {topic(r.namespace, n) for r in robots if r.namespace for n in names}


def tf_topics(robots: Sequence[RobotPlan], topics: Iterable[str], name: str) -> dict[str, str]:
    """``/tf`` (or ``/tf_static``: ``name``) and the robots' own namespaced ones present in ``topics`` → the prefix
    their frames take (convention B; ``""`` for the shared one)."""
    present = set(topics)
    out = {"/" + name: ""}
    for r in robots:
        if r.namespace and topic(r.namespace, name) in present:
            out[topic(r.namespace, name)] = r.prefix
    return out


def namespaced_robots(
    bag: Bag, namespaces: Sequence[str], frames: set[str], packages: PackageIndex | None
) -> tuple[RobotPlan, ...]:
    """Every namespace's robot in ``bag`` (``frames``: those of its ``/tf`` and ``/tf_static``)."""
    found = []
    for namespace in namespaces:
        name = topic(namespace, DESCRIPTION)
        text = read_robot_description(bag, name)
        if text is not None:
            robot = parse_urdf(text, source=f"{bag.path.name}:{name}", base_dir=bag.path.parent, packages=packages)
            found.append((namespace, robot, text))
    return plan_robots(found, bag.topics, frames, compile_tree)


def joint_topics_of(
    bag: Bag, robots: Sequence[RobotPlan], selected: set[str]
) -> list[tuple[str, tuple[str, ...] | None]]:
    """Each robot's joint-states topic and its joints (None: the topic is not replayed)."""
    return [
        (
            r.joints_topic,
            r.tree.actuated if r.joints_topic in selected and bag.require_type(r.joints_topic, JOINT_STATE) else None,
        )
        for r in robots
    ]
