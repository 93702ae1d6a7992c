"""What drives a robot: the source protocol and every source — generated motions, ROS 2 bags (joint states,
recorded TF) and their replay. No rerun; imports ``msgs``, ``kinematics``, ``robot`` and below.
"""
