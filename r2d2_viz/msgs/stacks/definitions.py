"""Message definitions of the navigation and perception stacks' displays, carried for live graphs (a bag carries
its own): nav2_msgs' ``ParticleCloud`` and ``VoxelGrid`` (ros-navigation/navigation2, ``nav2_msgs/msg/*.msg``)
and vision_msgs 4.x's ``Detection2DArray`` / ``Detection3DArray`` (ros-perception/vision_msgs 4.1.1,
``vision_msgs/msg/*.msg``), each with the types it uses that no distro's store has; comments dropped, fields as
upstream writes them."""

from __future__ import annotations

PARTICLE_CLOUD = "nav2_msgs/msg/ParticleCloud"
VOXEL_GRID = "nav2_msgs/msg/VoxelGrid"
DETECTION_2D_ARRAY = "vision_msgs/msg/Detection2DArray"
DETECTION_3D_ARRAY = "vision_msgs/msg/Detection3DArray"

STACK_TYPES = {
    "nav2_msgs/msg/Particle": "geometry_msgs/Pose pose\nfloat64 weight\n",
    PARTICLE_CLOUD: "std_msgs/Header header\nParticle[] particles\n",
    VOXEL_GRID: "std_msgs/Header header\nuint32[] data\ngeometry_msgs/Point32 origin\n"
    "geometry_msgs/Vector3 resolutions\nuint32 size_x\nuint32 size_y\nuint32 size_z\n",
    "vision_msgs/msg/Point2D": "float64 x\nfloat64 y\n",
    "vision_msgs/msg/Pose2D": "vision_msgs/Point2D position\nfloat64 theta\n",
    "vision_msgs/msg/ObjectHypothesis": "string class_id\nfloat64 score\n",
    "vision_msgs/msg/ObjectHypothesisWithPose": "ObjectHypothesis hypothesis\ngeometry_msgs/PoseWithCovariance pose\n",
    "vision_msgs/msg/BoundingBox2D": "vision_msgs/Pose2D center\nfloat64 size_x\nfloat64 size_y\n",
    "vision_msgs/msg/BoundingBox3D": "geometry_msgs/Pose center\ngeometry_msgs/Vector3 size\n",
    "vision_msgs/msg/Detection2D": "std_msgs/Header header\nObjectHypothesisWithPose[] results\n"
    "BoundingBox2D bbox\nstring id\n",
    DETECTION_2D_ARRAY: "std_msgs/Header header\nDetection2D[] detections\n",
    "vision_msgs/msg/Detection3D": "std_msgs/Header header\nObjectHypothesisWithPose[] results\n"
    "BoundingBox3D bbox\nstring id\n",
    DETECTION_3D_ARRAY: "std_msgs/Header header\nDetection3D[] detections\n",
}
"""In dependency order (each registered after the types it names)."""
