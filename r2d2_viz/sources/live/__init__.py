"""Live ROS 2 graphs without ROS: Cyclone DDS readers of raw CDR messages, named and configured as ROS 2 does, and
the live source sorting what arrives. Subscribe only; ``cyclonedds`` imported lazily; imports ``msgs`` and below."""
