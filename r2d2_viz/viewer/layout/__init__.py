"""The viewer's layout: an RViz view spec as a Rerun blueprint, a camera fitted to the robot, and the plan of
how a run is shown. Imports ``viewer``'s names, ``rviz``, ``sources`` and below.
"""
