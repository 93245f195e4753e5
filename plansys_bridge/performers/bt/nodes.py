"""Node types of behaviour-tree actions: the base class, the built-ins, the plugins.

An action or condition node of a tree file (``<Move goal="{arg2}"/>``) is a
:class:`BtNode`: a py_trees behaviour whose ``tick_node()`` returns SUCCESS,
FAILURE or RUNNING, with the element's attributes as *ports* (``{arg2}`` reads the
blackboard, where the action's arguments are ``arg0``, ``arg1``... as PlanSys2's
BTAction puts them). Time is the mission clock's (``self.now()``), so trees run on
the virtual clock too.

Node types are plugins, as BehaviorTree.CPP's are: the built-ins here, classes
registered under the ``plansys_bridge.bt_nodes`` entry-point group (name = the
XML tag), and modules named in the performer's ``plugins:`` list, each with a
``BT_NODES = {"Move": Move, ...}`` mapping (PlanSys2's ``plugins`` parameter).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import TYPE_CHECKING, ClassVar

import py_trees
from py_trees.common import Status

from plansys_bridge.errors import ConfigError, PlansysBridgeError

if TYPE_CHECKING:
    from plansys_bridge.clock import Clock
    from plansys_bridge.knowledge.problem_expert import ProblemExpert

__all__ = [
    "ENTRY_POINT_GROUP",
    "AlwaysFailure",
    "AlwaysSuccess",
    "BtContext",
    "BtNode",
    "CheckPredicate",
    "ClockTimeout",
    "Wait",
    "node_types",
]

ENTRY_POINT_GROUP = "plansys_bridge.bt_nodes"


@dataclass
class BtContext:
    """What nodes of one running tree share."""

    clock: Clock
    knowledge: ProblemExpert | None = None
    blackboard: dict[str, str] = field(default_factory=dict)
    """``arg0``, ``arg1``... the action's arguments; ``action`` its name."""


class BtNode(py_trees.behaviour.Behaviour):
    """Base of every action and condition node type (see module docs).

    ``ports``: the attributes the type accepts (None: any); ``required``: those it
    needs. ``condition = True`` marks a condition node (``<Condition ID=...>``).
    """

    ports: ClassVar[frozenset[str] | None] = None
    required: ClassVar[frozenset[str]] = frozenset()
    condition: ClassVar[bool] = False

    def __init__(self, name: str, attributes: Mapping[str, str], context: BtContext) -> None:
        super().__init__(name)
        self.attributes = dict(attributes)
        self.context = context

    def port(self, key: str, default: str | None = None) -> str:
        """The attribute ``key`` with ``{name}`` replaced from the blackboard."""
        raw = self.attributes.get(key, default)
        if raw is None:
            raise PlansysBridgeError(f"{self.name}: port {key!r} is not set")
        return _substitute(raw, self.context.blackboard, self.name)

    def now(self) -> float:
        return self.context.clock.now()

    def update(self) -> Status:
        return self.tick_node()

    def tick_node(self) -> Status:  # pragma: no cover - every node type implements it
        raise NotImplementedError

    def halt(self) -> None:
        """Optional: stop what the node started (the tree was halted or cancelled)."""

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self.status == Status.RUNNING:
            self.halt()


def _substitute(raw: str, blackboard: Mapping[str, str], where: str) -> str:
    out: list[str] = []
    rest = raw
    while "{" in rest:
        before, _, after = rest.partition("{")
        key, closed, rest = after.partition("}")
        if not closed:
            raise PlansysBridgeError(f"{where}: unclosed '{{' in {raw!r}")
        if key not in blackboard:
            known = ", ".join(sorted(blackboard)) or "none"
            raise PlansysBridgeError(f"{where}: no blackboard entry {key!r} (has: {known})")
        out += [before, blackboard[key]]
    out.append(rest)
    return "".join(out)


class AlwaysSuccess(BtNode):
    ports = frozenset()

    def tick_node(self) -> Status:
        return Status.SUCCESS


class AlwaysFailure(BtNode):
    ports = frozenset()

    def tick_node(self) -> Status:
        return Status.FAILURE


class Wait(BtNode):
    """RUNNING for ``seconds`` (or ``msec``) of mission time, then SUCCESS."""

    ports = frozenset({"seconds", "msec"})

    def initialise(self) -> None:
        if "msec" in self.attributes:
            span = float(self.port("msec")) / 1000.0
        else:
            span = float(self.port("seconds", "1"))
        self.until = self.now() + span

    def tick_node(self) -> Status:
        return Status.SUCCESS if self.now() >= self.until else Status.RUNNING


class CheckPredicate(BtNode):
    """Condition: ``predicate="(robot_at {arg0} {arg2})"`` holds in the knowledge."""

    ports = frozenset({"predicate"})
    required = frozenset({"predicate"})
    condition = True

    def tick_node(self) -> Status:
        knowledge = self.context.knowledge
        if knowledge is None:
            raise PlansysBridgeError(f"{self.name}: no knowledge to check predicates against")
        return (
            Status.SUCCESS if knowledge.exist_predicate(self.port("predicate")) else Status.FAILURE
        )


class ClockTimeout(py_trees.decorators.Decorator):
    """BehaviorTree.CPP's ``Timeout``: the child fails once it ran ``msec`` of mission time."""

    def __init__(
        self, name: str, child: py_trees.behaviour.Behaviour, seconds: float, clock: Clock
    ) -> None:
        super().__init__(name=name, child=child)
        self.seconds = seconds
        self.clock = clock
        self.deadline = 0.0

    def initialise(self) -> None:
        self.deadline = self.clock.now() + self.seconds

    def update(self) -> Status:
        if self.decorated.status == Status.RUNNING and self.clock.now() >= self.deadline:
            self.decorated.stop(Status.INVALID)
            self.feedback_message = f"timed out after {self.seconds:g} s"
            return Status.FAILURE
        return self.decorated.status


BUILTIN: dict[str, type[BtNode]] = {
    "AlwaysSuccess": AlwaysSuccess,
    "AlwaysFailure": AlwaysFailure,
    "Wait": Wait,
    "CheckPredicate": CheckPredicate,
}


def node_types(plugins: Iterable[str] = (), *, key: str = "plugins") -> dict[str, type[BtNode]]:
    """Every node type by XML tag: built-ins, entry points, then ``plugins`` modules."""
    types: dict[str, type[BtNode]] = dict(BUILTIN)
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        types[ep.name] = _checked(ep.load(), f"entry point {ep.name} ({ep.value})", key)
    for i, module_name in enumerate(plugins):
        where = f"{key}[{i}]"
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:
            raise ConfigError(
                f"cannot import node plugin {module_name!r}: {exc}", key=where
            ) from exc
        table = getattr(module, "BT_NODES", None)
        if not isinstance(table, Mapping):
            raise ConfigError(
                f"module {module_name!r} has no BT_NODES mapping of tag -> node class", key=where
            )
        for tag, cls in table.items():
            types[str(tag)] = _checked(cls, f"{module_name}.BT_NODES[{tag!r}]", where)
    return types


def _checked(cls: object, what: str, key: str) -> type[BtNode]:
    if not (isinstance(cls, type) and issubclass(cls, BtNode)):
        raise ConfigError(f"{what} is not a BtNode subclass", key=key)
    return cls


NodeFactory = Callable[[str, Mapping[str, str], BtContext], BtNode]
