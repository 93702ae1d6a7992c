"""Several robots on a live graph (``r2d2-viz --ros``): every ``/<namespace>/robot_description`` is a robot, drawn
from its description and moved by its ``/<namespace>/joint_states`` by its own :class:`RobotStream`, its frames
prefixed as :func:`r2d2_viz.sources.robots.choose_prefix` says (the root namespace's robot is the run's own).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Protocol

import rerun as rr

from r2d2_viz.errors import R2d2VizError
from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import parse_urdf
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.sources.live.source import LiveBatch, LiveSource
from r2d2_viz.sources.robots import RobotPlan, choose_prefix, prefixed_robot, unreached
from r2d2_viz.sources.tf_check import urdf_edges
from r2d2_viz.viewer.layout.plan import ViewPlan
from r2d2_viz.viewer.notices import Notices
from r2d2_viz.viewer.stream import RobotStream
from r2d2_viz.viewer.tf_recorded import RecordedTf


class LiveScene(Protocol):
    """What of a live run's scene the robots draw into."""

    rec: rr.RecordingStream
    notices: Notices
    recorded: RecordedTf
    source: LiveSource
    view: ViewPlan
    fixed_frame: str
    children: set[str]


def robot_namespaces(batches: Iterable[LiveBatch]) -> tuple[str, ...]:
    """The namespaces of the robots the settle's ``batches`` described (``""``: ``/robot_description``'s), sorted,
    when there are several; else ``()`` (one robot keeps the single-robot names)."""
    names: set[str] = set()
    for batch in batches:
        names |= {namespace for namespace, _ in batch.robot_descriptions}
        names |= {""} if batch.descriptions else set()
    return tuple(sorted(names)) if len(names) > 1 else ()


class LiveRobots:
    """The namespaced robots of a live run (see the module docstring). ``batches``: what the settle received (which
    robots there are, which frames the graph has); ``sent``: the lateness hook, told of each chunk sent."""

    def __init__(
        self,
        scene: LiveScene,
        batches: Sequence[LiveBatch],
        packages: PackageIndex,
        sent: Callable[[str, Iterable[int]], None],
    ) -> None:
        self.scene, self.packages, self.sent = scene, packages, sent
        self.several = bool(robot_namespaces(batches))
        self.frames = {f for b in batches for r in b.tf for f in (*r.parents, *r.children)}
        self.parents: dict[str, str] = {}
        """Child frame → parent of the transforms received (:meth:`check`)."""
        self.texts: dict[str, str] = {}
        self.streams: dict[str, RobotStream] = {}
        self.plans: dict[str, RobotPlan] = {}
        self.edges: set[tuple[str, str]] = set()
        """The robots' URDF edges: drawn by their kinematics, not as recorded transforms."""

    def describe(self, batch: LiveBatch) -> None:
        """The batch's new namespaced descriptions, each robot (re)loaded."""
        for namespace, text in batch.robot_descriptions:
            if self.texts.get(namespace) != text:
                self._load(namespace, text)

    def _load(self, namespace: str, text: str) -> None:
        """A (new) description of the robot in ``namespace``: (re)loaded, or one line when it does not parse."""
        first = namespace not in self.texts
        self.texts[namespace] = text
        scene, topic = self.scene, f"{namespace}/robot_description"
        try:
            robot = parse_urdf(text, source=topic, packages=self.packages)
        except R2d2VizError as exc:
            scene.notices.report(f"{exc} (robot {namespace} not shown)", key=f"description {hash(text)}")
            return
        own_tf = any(f"{namespace}/{name}" in scene.source.subscribed for name in ("tf", "tf_static"))
        prefix = choose_prefix(namespace, robot.root, own_tf=own_tf, frames=self.frames, several=True)
        tree = compile_tree(prefixed_robot(robot, prefix))
        if (old := self.streams.pop(namespace, None)) is not None:
            old.finish()
        if not first:
            scene.notices.report(f"{topic} changed: robot {robot.name!r} reloaded", key=f"loaded {hash(text)}")
        stream = RobotStream(
            scene.rec,
            tree,
            clock="timestamp",
            fixed_frame=scene.fixed_frame,
            root_placed=tree.robot.root == scene.fixed_frame or tree.robot.root in scene.children,
            axis_length=scene.view.axis_length,
            show_names=scene.view.show_names,
            robot_name=namespace if self.several else "",
            frame_prefix=prefix,
        )
        stream.notices = scene.notices
        stream.log_static()
        self.streams[namespace] = stream
        self.plans[namespace] = RobotPlan(namespace, tree, f"{namespace}/joint_states", prefix, text)
        self.edges |= set(urdf_edges(tree))
        scene.recorded.skip |= self.edges
        scene.source.set_joints(tree.actuated, namespace)

    def send(self, batch: LiveBatch) -> int:
        """The batch's namespaced joint states; how many were sent."""
        for records in batch.tf:
            self.parents.update(zip(records.children, records.parents, strict=True))
        count = 0
        for namespace, chunk in batch.robot_joints.items():
            if (stream := self.streams.get(namespace)) is not None:
                stream.send(stream.prepare(chunk))
                count += len(chunk)
                self.sent(f"{namespace}/joint_states", (int(t) for t in chunk.times_ns))
        return count

    def check(self) -> None:
        """One line for each robot (when there are several) whose tree does not reach the fixed frame (said once)."""
        if not self.several:
            return
        for namespace, robot in self.plans.items():
            line = unreached(robot, self.scene.fixed_frame, self.parents)
            if line is not None:
                self.scene.notices.report(line, key=f"unreached {namespace}")

    def finish(self) -> None:
        self.check()
        for stream in self.streams.values():
            stream.finish()
