"""ROS interface definitions: the vendored upstream texts and what is generated from them.

``ros2/<pkg>/{msg,srv,action}/`` holds upstream's files unchanged (origin and licence in
each ``SOURCE.md``); :mod:`.definitions` reads them, :mod:`.typestore` registers them
in a rosbags typestore (bags, MCAP schemas) and :mod:`.dds` turns them into Cyclone DDS
types with ROS 2's names (``plansys_bridge.interfaces.dds.dds_type("std_msgs/msg/String")``).
"""
