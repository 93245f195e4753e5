"""ROS 1 <-> ROS 2 topic bridge."""
