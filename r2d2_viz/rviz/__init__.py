"""RViz configs (``.rviz``, ROS 1 and 2) → a view spec: displays, fixed frame, camera by RViz's own maths, and
the converter's mapping table. Pure (PyYAML); imports ``robot`` (the shipped config's path) and below.
"""
