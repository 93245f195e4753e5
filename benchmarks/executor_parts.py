"""Where an executor run's CPU time goes: exclusive CPU time per part.

Used by ``bench_executor_overhead.py --parts``. Each part is a set of functions
(the plan graph, applying effects to the knowledge, the tree's ticks, the
auction client's message handler, the hub's delivery, ...);
while one runs, its time is its own and not its caller's, so the parts add up to
the whole run. The functions are wrapped for the duration of a ``with`` block and
restored after it; the wrapping costs a few microseconds per call, so the figures
are a little higher than the bench's own. The performers subscribe before the
run, so their message handlers count as the hub's delivery. A hub binds its
transport's ``publish`` when it is made (and a performer the hub's), so the hubs and
performers that exist when timing starts are re-bound to the wrapped methods.
"""

from __future__ import annotations

import collections
import contextlib
import functools
import gc
import time
from collections.abc import Callable, Iterator
from typing import Any

from plansys_bridge.execution import executor, plan_context, tree_builder
from plansys_bridge.hub import transport
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.performers.base import ActionPerformer
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
    (transport.InProcessTransport, "publish_many", "hub: publish (hub/)"),
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
        parts = [p for p in PARTS if hasattr(p[0], p[1])]  # older code may lack some
        saved = [(owner, name, getattr(owner, name)) for owner, name, _ in parts]
        for (owner, name, part), (_o, _n, func) in zip(parts, saved, strict=True):
            setattr(owner, name, self.wrap(func, part))
        executor.build_tree = tree_builder.build_tree
        bound = _rebind_publishers()
        self.enter(OTHER)
        try:
            yield self
        finally:
            self.leave()
            for owner, name, func in saved:
                setattr(owner, name, func)
            executor.build_tree = tree_builder.build_tree
            for obj, name, value in bound:
                setattr(obj, name, value)


def _rebind_publishers() -> list[tuple[object, str, Any]]:
    """Point existing hubs (and performers sending straight to them) at the transport's
    methods as they are now (wrapped); returns what to put back."""
    saved: list[tuple[object, str, Any]] = []
    objects = gc.get_objects()
    for hub in [o for o in objects if isinstance(o, Hub) and "publish" in vars(o)]:
        saved += [(hub, "publish", hub.publish), (hub, "publish_many", hub.publish_many)]
        hub.publish = hub.transport.publish
        hub.publish_many = getattr(hub.transport, "publish_many", hub.publish_many)
    for performer in [o for o in objects if isinstance(o, ActionPerformer)]:
        if "_out" in vars(performer) and type(performer)._publish is ActionPerformer._publish:
            saved.append((performer, "_out", performer._out))
            performer._out = performer.hub.publish
    return saved
