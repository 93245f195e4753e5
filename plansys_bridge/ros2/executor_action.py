"""PlanSys2's ExecutePlan action on DDS, run by the project's executor.

PlanSys2's executor node (plansys2_executor, ``src/plansys2_executor/ExecutorNode.cpp``,
branch rolling) serves ``plansys2_msgs/action/ExecutePlan`` as ``/execute_plan``: the
goal is a ``plansys2_msgs/Plan``; while it runs, feedback carries the
``ActionExecutionInfo`` of every action of the plan (``get_feedback_info``); the result
has ``success`` and the same list at the end. A cancel halts the plan (its running
actions get CANCEL) and ends the goal CANCELED.

Here the plan runs on :class:`~plansys_bridge.execution.executor.Executor` with the
mission's hub and knowledge, one goal at a time, as upstream (a second goal while one
runs is rejected). A plan that does not parse is rejected at once (``accepted:
false``); one that fails while running ends ABORTED with the actions' states.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.execution.executor import Executor
from plansys_bridge.hub.dds_codec import encode
from plansys_bridge.hub.messages import ActionExecutionInfo, PlanItem, Topics
from plansys_bridge.hub.messages import Plan as PlanMsg
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.planning.plan import Plan
from plansys_bridge.ros2.actions import GOAL_STATUS, ActionServer, ServerGoal
from plansys_bridge.ros2.node import Ros2Node

__all__ = ["EXECUTE_PLAN", "ExecutePlanServer"]

log = logging.getLogger(__name__)

EXECUTE_PLAN = "plansys2_msgs/action/ExecutePlan"


def plan_from_msg(msg: Any) -> Plan:
    """A ``plansys2_msgs/Plan`` sample as the project's plan (PlanningError if malformed)."""
    items = tuple(
        PlanItem(time=float(i.time), action=str(i.action), duration=float(i.duration))
        for i in msg.items
    )
    return Plan.from_msg(PlanMsg(items))


class ExecutePlanServer:
    """Serves ``/execute_plan`` with ``executor`` (see module docs)."""

    def __init__(self, node: Ros2Node, executor: Executor, action: str = "execute_plan") -> None:
        self.executor = executor
        self._busy = False
        self.server = ActionServer(node, action, EXECUTE_PLAN, self._execute, accept=self._accept)

    def _accept(self, goal: Any) -> bool:
        if self._busy:
            log.info("execute_plan: a plan is already executing; goal rejected")
            return False
        try:
            plan_from_msg(goal.plan)
        except PlansysBridgeError as exc:
            log.info("execute_plan: goal rejected: %s", exc)
            return False
        self._busy = True
        return True

    async def _execute(self, handle: ServerGoal) -> tuple[int, Any]:
        feedback_type = dds_type(f"{EXECUTE_PLAN}_Feedback")
        result_type = dds_type(f"{EXECUTE_PLAN}_Result")
        infos: dict[str, Any] = {}

        def on_info(info: ActionExecutionInfo) -> None:
            sample, _wrapped = encode(Topics.ACTION_EXECUTION_INFO, info)
            infos[info.action_full_name] = sample
            handle.publish_feedback(feedback_type(action_execution_status=list(infos.values())))

        plan = plan_from_msg(handle.goal.plan)
        plan_id = f"execute_plan-{handle.goal_id.hex()[:8]}"
        run = asyncio.ensure_future(self.executor.execute(plan, plan_id=plan_id, on_info=on_info))
        cancel = asyncio.ensure_future(handle.cancel_requested.wait())
        try:
            await asyncio.wait({run, cancel}, return_when=asyncio.FIRST_COMPLETED)
            if not run.done():
                self.executor.cancel(plan_id)
            result = await run
        finally:
            cancel.cancel()
            self._busy = False
        message = result_type(success=result.success, action_execution_status=list(infos.values()))
        if handle.cancel_requested.is_set() and result.status == "cancelled":
            return GOAL_STATUS["STATUS_CANCELED"], message
        if result.success:
            return GOAL_STATUS["STATUS_SUCCEEDED"], message
        log.info("execute_plan: plan %s ended %s: %s", plan_id, result.status, result.message)
        return GOAL_STATUS["STATUS_ABORTED"], message

    async def close(self) -> None:
        await self.server.close()
