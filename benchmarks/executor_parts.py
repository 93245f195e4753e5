"""Where an executor run's CPU time goes: exclusive CPU time per part.

Used by ``bench_executor_overhead.py --parts``. Each part is a set of functions
(the plan graph, applying effects to the knowledge, the tree's ticks, the
auction client's message handler, the hub's delivery, ...);
while one runs, its time is its own and not its caller's, so the parts add up to
the whole run. The functions are wrapped for the duration of a ``with`` block and
restored after it; the wrapping costs a few microseconds per call, so the figures
are a little higher than the bench's own. The performers subscribe before the
run, so their message handlers count as the hub's delivery.
"""

from __future__ import annotations

import collections
import contextlib
import functools
import time
from collections.abc import Callable, Iterator
from typing import Any

from plansys_bridge.execution import executor, plan_context, tree_builder
from plansys_bridge.hub import transport
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.planning.plan_graph import PlanGraph

OTHER = "other (event loop, auction and performer tasks)"

PARTS: list[tuple[object, str, str]] = [
    (executor.Executor, "build_graph", "plan graph (planning/)"),
    (PlanGraph, "check", "plan graph (planning/)"),
    (tree_builder, "build_tree", "behaviour tree: build"),
    (executor.Executor, "_tick", "behaviour tree: ticks"),
    (plan_context.PlanContext, "knowledge_changed", "behaviour tree: ticks"),
    (ProblemExpert, "apply", "knowledge: apply effects (knowledge/)"),
    (plan_context.PlanContext, "publish_info", "execution info"),
    (executor.Executor, "_publish_dot", "dot graph"),
    (ActionClient, "_on_action_msg", "auction client: hub messages (hub/)"),
    (transport.InProcessTransport, "publish", "hub: publish (hub/)"),
    (transport.InProcessTransport, "_drain", "hub: delivery, performers' handlers included"),
]


class Parts:
    """Exclusive CPU seconds per part (see module docs)."""

    def __init__(self) -> None:
        self.seconds: collections.Counter[str] = collections.Counter()
        self._stack: list[list[Any]] = []

    def enter(self, part: str) -> None:
        now = time.process_time()
        if self._stack:
            self.seconds[self._stack[-1][0]] += now - self._stack[-1][1]
        self._stack.append([part, now])

    def leave(self) -> None:
        now = time.process_time()
        part, since = self._stack.pop()
        self.seconds[part] += now - since
        if self._stack:
            self._stack[-1][1] = now

    def wrap(self, func: Callable[..., Any], part: str) -> Callable[..., Any]:
        @functools.wraps(func)
        def timed(*args: Any, **kwargs: Any) -> Any:
            self.enter(part)
            try:
                return func(*args, **kwargs)
            finally:
                self.leave()

        return timed

    @contextlib.contextmanager
    def timing(self) -> Iterator[Parts]:
        """Wrap the parts' functions for the block (the block's own time is OTHER)."""
        saved = [(owner, name, getattr(owner, name)) for owner, name, _ in PARTS]
        for (owner, name, part), (_o, _n, func) in zip(PARTS, saved, strict=True):
            setattr(owner, name, self.wrap(func, part))
        executor.build_tree = tree_builder.build_tree
        self.enter(OTHER)
        try:
            yield self
        finally:
            self.leave()
            for owner, name, func in saved:
                setattr(owner, name, func)
            executor.build_tree = tree_builder.build_tree
