"""A performer that counts every auction message the hub hands it (routing tests)."""

from __future__ import annotations

import asyncio
from collections import Counter
from typing import Any

from plansys_bridge.hub.messages import ActionExecution
from plansys_bridge.performers.base import ActionGoal, ActionPerformer


class Counting(ActionPerformer):
    """Counts every auction message it is handed; its goals take one second."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.heard: Counter[str] = Counter()

    def _on_action_msg(self, msg: object) -> None:
        if isinstance(msg, ActionExecution):
            self.heard[msg.type.name] += 1
        super()._on_action_msg(msg)

    async def execute(self, goal: ActionGoal) -> str | None:
        await asyncio.sleep(1.0)
        return None
