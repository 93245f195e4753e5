"""The ``bt`` performer kind: PlanSys2's BTAction, an action carried out by a tree.

In a mission file::

    - kind: bt
      name: r2d2_transport
      actions: {transport: [r2d2]}
      trees: {transport: bt/transport.xml}     # per action, relative to the mission
      plugins: [my_robot.bt_nodes]             # modules with BT_NODES (optional)
      tick_period: 0.1                         # mission seconds between ticks

Each goal gets a fresh tree from its action's file, with the arguments on the
blackboard as ``arg0``, ``arg1``... (PlanSys2's convention, so ``goal="{arg2}"``
reads the same), ticked every ``tick_period`` on the mission clock: SUCCESS
finishes the action, FAILURE fails it naming the node that failed, RUNNING sends
FEEDBACK with the share of leaves done. A CANCEL halts the tree (each running node's
``halt()``). Tree files and node types are checked when the mission loads.
"""

from __future__ import annotations

import asyncio
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import py_trees
from py_trees.common import Status

from plansys_bridge.clock import VirtualClock
from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.bt.build import build_tree
from plansys_bridge.performers.bt.nodes import BtContext, BtNode, node_types
from plansys_bridge.performers.bt.xml_tree import BtXmlError, Element, main_tree, read_bt_file

__all__ = ["BTActionPerformer"]


class BTActionPerformer(ActionPerformer):
    """Runs each action as the behaviour tree its file describes (see module docs)."""

    settings_keys: ClassVar[frozenset[str]] = frozenset({"trees", "plugins", "tick_period"})

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        trees: Mapping[str, Element],
        types: Mapping[str, type[BtNode]],
        tick_period: float = 0.1,
        heartbeat_period: float = 1.0,
        commit_timeout: float = 2.0,
    ) -> None:
        super().__init__(
            context,
            node_name,
            actions,
            heartbeat_period=heartbeat_period,
            commit_timeout=commit_timeout,
        )
        self.trees = dict(trees)
        self.types = dict(types)
        self.tick_period = tick_period

    def tree_for(self, goal: ActionGoal) -> py_trees.behaviour.Behaviour:
        """A fresh tree for ``goal`` (its arguments on the blackboard)."""
        board = {f"arg{i}": arg for i, arg in enumerate(goal.arguments)}
        board["action"] = goal.action
        ctx = BtContext(self.clock, self.context.knowledge, board)
        return build_tree(self.trees[goal.action], self.types, ctx)

    async def execute(self, goal: ActionGoal) -> str | None:
        root = self.tree_for(goal)
        leaves = [b for b in root.iterate() if not b.children]
        try:
            while True:
                try:
                    root.tick_once()
                except PlansysBridgeError as exc:
                    raise ActionFailed(f"behavior tree error: {exc}") from exc
                if root.status == Status.SUCCESS:
                    return "behavior tree returned SUCCESS"
                if root.status == Status.FAILURE:
                    raise ActionFailed(f"behavior tree returned FAILURE{_culprit(root)}")
                done = sum(1 for leaf in leaves if leaf.status == Status.SUCCESS)
                self.feedback(done / max(1, len(leaves)), "behavior tree returned RUNNING")
                await self.clock.sleep(self.tick_period)
        except asyncio.CancelledError:
            root.stop(Status.INVALID)  # halt() of every running node
            raise

    @classmethod
    def from_config(
        cls, config: Mapping[str, Any], context: PerformerContext, *, key: str = "performer"
    ) -> list[ActionPerformer]:
        parsed = cls.parse_config(config, key=key)
        s = parsed.settings
        plugins = s.get("plugins", [])
        if not isinstance(plugins, list) or not all(isinstance(p, str) for p in plugins):
            raise ConfigError("must be a list of module names", key=f"{key}.plugins")
        types = node_types(plugins, key=f"{key}.plugins")
        period = s.get("tick_period", 0.1)
        if isinstance(period, bool) or not isinstance(period, int | float) or not period > 0:
            raise ConfigError(f"must be a number > 0, got {period!r}", key=f"{key}.tick_period")
        files = s.get("trees")
        if not isinstance(files, Mapping) or not files:
            raise ConfigError(
                "must map each action to its tree file, e.g. {move: bt/move.xml}",
                key=f"{key}.trees",
            )
        trees: dict[str, Element] = {}
        for action, file in files.items():
            where = f"{key}.trees.{action}"
            name = str(action).strip().lower()
            if name not in parsed.actions:
                raise ConfigError(
                    f"not one of this performer's actions ({', '.join(parsed.actions)})", key=where
                )
            if not isinstance(file, str):
                raise ConfigError(f"must be a file path, got {file!r}", key=where)
            path = Path(file) if Path(file).is_absolute() else context.base_dir / file
            try:
                trees[name] = main_tree(read_bt_file(path))
                # built once now: a wrong node or port is an error at load, not mid-mission
                probe = BtContext(VirtualClock(), context.knowledge, _probe())
                build_tree(trees[name], types, probe)
            except BtXmlError as exc:
                raise ConfigError(str(exc), key=where) from exc
        missing = sorted(set(parsed.actions) - set(trees))
        if missing:
            raise ConfigError(f"no tree file for {', '.join(missing)}", key=f"{key}.trees")
        return [
            cls(
                context,
                parsed.name,
                parsed.actions,
                trees=trees,
                types=types,
                tick_period=float(period),
                heartbeat_period=parsed.heartbeat_period,
                commit_timeout=parsed.commit_timeout,
            )
        ]


def _probe() -> dict[str, str]:
    return {f"arg{i}": f"arg{i}" for i in range(32)} | {"action": "action"}


def _culprit(root: py_trees.behaviour.Behaviour) -> str:
    """`` at <node>: why`` for the deepest failed node, for the FINISH message."""
    failed = [b for b in root.iterate() if b.status == Status.FAILURE and not b.children]
    if not failed:
        return ""
    node = failed[-1]
    why = f": {node.feedback_message}" if node.feedback_message else ""
    return f" at {node.name}{why}"
