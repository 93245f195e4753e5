"""ROS 2 services and actions over Cyclone DDS, framed as rmw_cyclonedds and rcl_action do.

:mod:`~plansys_bridge.ros2.node` (participant and reader thread),
:mod:`~plansys_bridge.ros2.services` (``rq/``/``rr/`` request-reply with the request
header), and the PlanSys2 services built on them. Needs the ``dds`` extra.
"""
