"""Runs written as ROS 2 bags (``--save out.mcap``): ``/joint_states``, ``/tf``, ``/tf_static`` and
``/robot_description`` with rosbags' writer. Imports ``sources``, ``msgs`` and below; no rerun.
"""
