"""Live ROS 1 adapter: the ``ros1_move_base`` performer kind drives move_base.

* :mod:`.settings` reads the performer's mission entry (master, action namespace,
  frame, named locations) and checks every destination the domain allows;
* :mod:`.performer` is ``MoveBasePerformer``, an actionlib client of move_base on the
  project's own ROS 1 client (:mod:`plansys_bridge.ros1`, no rospy).

Nothing is imported here, so loading the package needs no optional dependency.
"""
