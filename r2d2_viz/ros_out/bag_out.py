"""``--save out.mcap``: any run written as a ROS 2 bag (rosbag2, MCAP storage) instead of a Rerun recording:
``/joint_states`` and the source's frame tracks on ``/tf`` per sample, the fixed joints (and the fixed frame →
root when nothing moves the root) on ``/tf_static``, the URDF on ``/robot_description`` — what
robot_state_publisher and a joint state publisher would have put on the wire. Pure: no rerun import."""

from __future__ import annotations

from pathlib import Path

from r2d2_viz.errors import UsageError
from r2d2_viz.ros_out.bag_write import BagWriter, StaticTransform
from r2d2_viz.sources.plan import RunPlan

CHUNK_SAMPLES = 10_000


def write_bag(path: Path, plan: RunPlan, description: str) -> int:
    """Write the run as a bag at ``path`` with ``description`` (URDF text) on /robot_description; returns the
    number of samples."""
    tree, source = plan.tree, plan.source
    if tree is None or not plan.moves_robot:
        raise UsageError(f"--save {path}: a bag needs a robot and joint states to write")
    frames = source.frames if source is not None else ()
    clock = source.clock if source is not None else "timestamp"
    translation, quat = tree.static_translation_quat()
    static = [
        StaticTransform(tree.robot.joint(name).parent, tree.robot.joint(name).child, translation[i], quat[i])
        for i, name in enumerate(tree.static)
    ]
    if not plan.root_placed and not any(child == tree.robot.root for _, child in frames):
        static.append(StaticTransform(plan.fixed_frame, tree.robot.root, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
    samples = 0
    with BagWriter(path, robot_description=description, static_transforms=static, clock=clock) as writer:
        for window in plan.windows(CHUNK_SAMPLES):
            chunk = window.joints
            if chunk is not None and len(chunk):
                writer.write_samples(chunk.times_ns, chunk.joints, chunk.positions, chunk.frames)
                samples += len(chunk)
    return samples
