"""ROS-bag adapter: replay recorded navigation as a performer, and bridge ROS 1 bags.

* :mod:`.reader` streams poses (Odometry, PoseStamped, PoseWithCovarianceStamped)
  from ROS 1 bags and ROS 2 bags (sqlite3 or MCAP), converting ROS 1 messages to
  their ROS 2 types;
* :mod:`.route` says which bag window serves which move and measures progress;
* :mod:`.performer` is the ``rosbag`` performer kind, ``BagNavigationPerformer``;
* :mod:`.convert` copies a bag into a ROS 2 MCAP bag
  (``python -m plansys_bridge_adapters.rosbag.convert``);
* :mod:`.generate` writes the project's demo bags
  (``python -m plansys_bridge_adapters.rosbag.generate bags/``).

Nothing is imported here, so loading the package needs no optional dependency.
"""
