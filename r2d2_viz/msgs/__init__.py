"""ROS messages without ROS: where the fields of CDR-encoded messages sit, decoded in bulk with numpy.
Pure (struct, numpy, rosbags); imports nothing of r2d2_viz but ``errors`` and ``arrays``.
"""
