"""rosbag adapter."""
