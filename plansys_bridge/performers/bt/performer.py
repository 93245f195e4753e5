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
``halt()``).

The keys are the :class:`BtSettings` model, checked when the mission loads (with
which action has which tree); the tree files are read, and each tree built once with
its node types, when the performer is built, before anything starts.
"""

from __future__ import annotations

import asyncio
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status
from pydantic import Field

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
from plansys_bridge.performers.entry import PerformerConfig
from plansys_bridge.plugins import PluginSettings

__all__ = ["BTActionPerformer", "BtSettings", "BtTrees"]


class BtSettings(PluginSettings):
    """The kind-specific keys of a ``kind: bt`` performer entry."""

    trees: dict[str, str] = Field(min_length=1)
    """Each action's tree file, relative to the mission file."""
    plugins: list[str] = Field(default_factory=list)
    """Modules with a ``BT_NODES`` mapping of tag -> node class."""
    tick_period: float = Field(0.1, gt=0.0)
    """Mission seconds between two ticks."""


@dataclass(frozen=True)
class BtTrees:
    """What the performer runs with: :class:`BtSettings` with the files read."""

    trees: dict[str, Element]
    """Action name -> the root element of its main tree."""
    types: dict[str, type[BtNode]]
    """Every node type by XML tag (built-ins, entry points, ``plugins``)."""
    tick_period: float = 0.1


class BTActionPerformer(ActionPerformer):
    """Runs each action as the behaviour tree its file describes (see module docs)."""

    Settings = BtSettings

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        settings: BtTrees,
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
        missing = sorted(set(self.actions) - set(settings.trees))
        if missing:
            raise ValueError(f"no tree for {', '.join(missing)}")
        self.trees = dict(settings.trees)
        self.types = dict(settings.types)
        self.tick_period = settings.tick_period

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
    def parse_config(cls, config: Mapping[str, Any], *, key: str = "performer") -> PerformerConfig:
        """The settings model, then what it cannot see: ``trees`` has one file for each
        action of the entry and none for another."""
        entry = super().parse_config(config, key=key)
        named = {action.strip().lower(): action for action in entry.settings.trees}
        for name, action in named.items():
            if name not in entry.actions:
                raise ConfigError(
                    f"not one of this performer's actions ({', '.join(entry.actions)})",
                    key=f"{key}.trees.{action}",
                )
        missing = sorted(set(entry.actions) - set(named))
        if missing:
            raise ConfigError(f"no tree file for {', '.join(missing)}", key=f"{key}.trees")
        return entry

    @classmethod
    def prepare(cls, entry: PerformerConfig, context: PerformerContext) -> PerformerConfig:
        """Read each tree file and build the tree once: a wrong node type or port is
        an error naming the key and the file's line now, not mid-mission."""
        settings: BtSettings = entry.settings
        types = node_types(settings.plugins, key=f"{entry.key}.plugins")
        trees: dict[str, Element] = {}
        for action, file in settings.trees.items():
            path = Path(file) if Path(file).is_absolute() else context.base_dir / file
            try:
                tree = main_tree(read_bt_file(path))
                probe = BtContext(VirtualClock(), context.knowledge, _probe())
                build_tree(tree, types, probe)
            except BtXmlError as exc:
                raise ConfigError(str(exc), key=f"{entry.key}.trees.{action}") from exc
            trees[action.strip().lower()] = tree
        return replace(entry, settings=BtTrees(trees, types, settings.tick_period))


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
