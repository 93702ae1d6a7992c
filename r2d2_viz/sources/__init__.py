"""Where the app's data comes from: synthetic motion, bags, a live ROS 2 graph."""
