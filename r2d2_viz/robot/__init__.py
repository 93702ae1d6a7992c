"""Robot descriptions → an immutable model: safe URDF XML, its checks, xacro (guarded, sandboxed) and ROS
packages found without ROS. Imports nothing of r2d2_viz but ``errors`` and ``arrays``.
"""
