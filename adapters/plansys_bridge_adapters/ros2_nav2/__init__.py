"""Nav2 on ROS 2 over Cyclone DDS: the ``ros2_nav2`` performer and a NavigateToPose double."""
