"""Live ROS 2 graph tests (issue 19): real rclpy nodes in a loopback-only network namespace."""
