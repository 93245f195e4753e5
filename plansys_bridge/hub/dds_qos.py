"""PlanSys2's quality of service per topic, as upstream creates its publishers.

From PlanSys2 2.0.12 (branch rolling), ``rclcpp::QoS(N)`` being keep-last N,
reliable, volatile:

=========================  ===============================  ======================
topic                      upstream                         here
=========================  ===============================  ======================
actions_hub                ``QoS(100).reliable()``          reliable, volatile, 100
                           (ActionExecutor.cpp,
                           ActionExecutorClient.cpp)
performers_status          ``QoS(100).reliable()``          reliable, volatile, 100
                           (ActionExecutorClient.cpp)
action_execution_info      depth ``100`` (ExecutorNode.cpp) reliable, volatile, 100
executing_plan             ``QoS(100).transient_local()``   reliable, transient-local,
                           (ExecutorNode.cpp)               100
problem_expert/knowledge   ``QoS(100).transient_local()``   reliable, transient-local,
                           (ProblemExpertNode.cpp)          100
dot_graph                  depth ``1`` (ExecutorNode.cpp)   reliable, volatile, 1
=========================  ===============================  ======================

Transient-local topics are latched: a node that joins late (a monitor, a second
terminal) gets the executing plan and the current knowledge at once. The project's
wrapper topics (``rt/plansys_bridge/...``) use the QoS of the topic they wrap.
"""

from __future__ import annotations

from dataclasses import dataclass

from plansys_bridge.hub.messages import Topics

__all__ = ["TOPIC_QOS", "TopicQos"]


@dataclass(frozen=True)
class TopicQos:
    """The writer QoS of one topic: history depth and whether it is latched."""

    depth: int
    transient_local: bool = False
    reliable: bool = True


TOPIC_QOS: dict[str, TopicQos] = {
    Topics.ACTIONS_HUB: TopicQos(100),
    Topics.PERFORMERS_STATUS: TopicQos(100),
    Topics.ACTION_EXECUTION_INFO: TopicQos(100),
    Topics.EXECUTING_PLAN: TopicQos(100, transient_local=True),
    Topics.KNOWLEDGE: TopicQos(100, transient_local=True),
    Topics.DOT_GRAPH: TopicQos(1),
    Topics.SIGNED: TopicQos(100),  # the signed auction messages, as actions_hub
}
"""Writer QoS by hub topic, as PlanSys2 sets it."""
