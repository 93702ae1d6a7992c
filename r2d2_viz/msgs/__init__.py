"""ROS messages without ROS: CDR layouts of JointState and TF, and a decoder per RViz display type (one table) into
rerun-free shapes, bulk numpy where volume matters. Pure (numpy, rosbags); imports only ``errors`` and ``arrays``.
"""
