"""The URDF workbench in the viewer: what RViz's RobotModel shows of a description beyond its shapes (mass
properties, link axes), and the joint sliders of ``joint_state_publisher_gui``."""
