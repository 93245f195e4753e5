"""All-or-nothing changes to the knowledge, and what each one changed.

Why it is built this way: instances, facts and fluent values live in journaled
tables that log what each change touches. A failed change is undone from that log,
and what changed is computed from it (net of what came back), so a subscriber gets
exactly one :class:`KnowledgeChange` per change (or per transaction) saying
precisely what moved, however the change was made, at a cost in the size of the
change rather than of the knowledge. One re-entrant lock: adapters and the
executor call in from other threads.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import NamedTuple, Self

from plansys_bridge.knowledge.journal import JournaledTable
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import Atom, Condition

__all__ = ["ChangeTracker", "KnowledgeChange"]

log = logging.getLogger("plansys_bridge.knowledge.problem_expert")


@dataclass(frozen=True)
class KnowledgeChange:
    """What one change (or one transaction) did to the knowledge."""

    version: int
    reason: str
    added_instances: Mapping[str, str] = field(default_factory=dict)
    removed_instances: Mapping[str, str] = field(default_factory=dict)
    added_facts: frozenset[Atom] = frozenset()
    removed_facts: frozenset[Atom] = frozenset()
    changed_fluents: Mapping[FluentKey, float] = field(default_factory=dict)
    removed_fluents: frozenset[FluentKey] = frozenset()
    goal_changed: bool = False
    goal: Condition | None = None
    state: State | None = field(default=None, compare=False, repr=False)
    """The snapshot right after the change (read it without taking the lock)."""


class _Mark(NamedTuple):
    """Where a change started: log positions of the tables, the goal and the state.

    A named tuple: one is made per change, and a frozen dataclass costs several
    times as much to build."""

    instances: int
    facts: int
    fluents: int
    goal: Condition | None
    state: State


class ChangeTracker:
    """The tables, goal and state of the knowledge, changed only inside ``_change``."""

    def __init__(self, constants: Mapping[str, str]) -> None:
        self._lock = threading.RLock()
        self._instances: JournaledTable[str, str] = JournaledTable()
        self._facts: JournaledTable[Atom, None] = JournaledTable()
        self._fluents: JournaledTable[FluentKey, float] = JournaledTable()
        self._goal: Condition | None = None
        self._state = State(objects=dict(constants))
        self._subscribers: list[Callable[[KnowledgeChange], None]] = []
        self._depth = 0
        self.version = 0

    def _mark(self) -> _Mark:
        return _Mark(
            self._instances.mark(),
            self._facts.mark(),
            self._fluents.mark(),
            self._goal,
            self._state,
        )

    def _undo(self, mark: _Mark) -> None:
        self._instances.undo(mark.instances)
        self._facts.undo(mark.facts)
        self._fluents.undo(mark.fluents)
        self._goal = mark.goal
        self._state = mark.state

    @contextmanager
    def _change(self, reason: str, *, steps: bool = False) -> Iterator[None]:
        """Run a change all-or-nothing; notify once when the outermost block ends.

        Single operations validate everything before they touch anything, so inside
        a transaction they need no undo point of their own; ``steps=True`` marks one
        that mutates as it goes (a whole problem), which is then undone on its own
        when it fails, even if the surrounding transaction carries on.
        """
        with self._lock:
            if self._depth:
                if not steps:
                    yield
                    return
                inner = self._mark()
                try:
                    yield
                except BaseException:
                    self._undo(inner)
                    raise
                return
            start = self._mark()
            self._depth = 1
            try:
                yield
            except BaseException:
                self._undo(start)
                raise
            finally:
                self._depth = 0
            try:
                change = self._change_since(start, reason)
            finally:
                for table in (self._instances, self._facts, self._fluents):
                    table.forget_log()
            if change is not None:
                self._notify(change)

    @contextmanager
    def transaction(self) -> Iterator[Self]:
        """Several changes as one: all applied or none, one notification."""
        with self._change("transaction", steps=True):
            yield self

    def _change_since(self, start: _Mark, reason: str) -> KnowledgeChange | None:
        """What the tables' logs say moved since ``start``; None when nothing did."""
        added, removed = self._facts.changes_since(start.facts)
        changed_fluents, fluents_before = self._fluents.changes_since(start.fluents)
        removed_fluents = frozenset(k for k in fluents_before if k not in self._fluents)
        added_instances, removed_instances = self._instances.changes_since(start.instances)
        goal_changed = start.goal is not self._goal and start.goal != self._goal
        if not (
            added
            or removed
            or changed_fluents
            or removed_fluents
            or added_instances
            or removed_instances
            or goal_changed
        ):
            return None
        self.version += 1
        return KnowledgeChange(
            version=self.version,
            reason=reason,
            added_instances=added_instances,
            removed_instances=removed_instances,
            added_facts=frozenset(added),
            removed_facts=frozenset(removed),
            changed_fluents=changed_fluents,
            removed_fluents=removed_fluents,
            goal_changed=goal_changed,
            goal=self._goal,
            state=self._state,
        )

    def _notify(self, change: KnowledgeChange) -> None:
        for callback in list(self._subscribers):
            try:
                callback(change)
            except Exception:  # a broken subscriber must not break the knowledge
                log.exception("knowledge subscriber %r failed", callback)

    def subscribe(self, callback: Callable[[KnowledgeChange], None]) -> Callable[[], None]:
        """Call ``callback`` after every change; returns a function that unsubscribes."""
        with self._lock:
            self._subscribers.append(callback)

        def unsubscribe() -> None:
            with self._lock:
                if callback in self._subscribers:
                    self._subscribers.remove(callback)

        return unsubscribe
