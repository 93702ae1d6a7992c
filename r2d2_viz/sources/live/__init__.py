"""Live ROS 2 graphs without ROS: Cyclone DDS readers of raw CDR messages, named and configured as ROS 2 does.
Subscribe only (nothing is ever published); ``cyclonedds`` is an optional dependency, imported lazily."""
