"""PlanSys2's ``Node`` / ``Tree`` / ``Param`` messages to and from PDDL.

PlanSys2's services carry facts, fluents and goals as ``plansys2_msgs/Node`` and
``plansys2_msgs/Tree`` (a flat list of nodes, node 0 the root, ``children`` indexing
into the list). PlanSys2 itself reads them by printing PDDL
(``parser::pddl::toString``) and writes them by parsing PDDL; this module does the
same against the project's PDDL model, so every check the knowledge base makes on
PDDL text applies to what a ROS 2 client sends.

Node types and constants are those of ``plansys2_msgs/msg/Node.msg``.
"""

from __future__ import annotations

from typing import Any

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.interfaces.dds import dds_type, ros2_constants
from plansys_bridge.pddl.model import (
    AddEffect,
    And,
    AndEffect,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DeleteEffect,
    DurationRef,
    Effect,
    Equals,
    Exists,
    FluentRef,
    FluentValue,
    Negate,
    Not,
    Number,
    NumericEffect,
    Or,
)
from plansys_bridge.pddl.walkers import Visitor
from plansys_bridge.pddl.writer import write_number

__all__ = [
    "atom_node",
    "condition_tree",
    "effect_tree",
    "fluent_node",
    "node_text",
    "param",
    "tree_text",
]

_N = ros2_constants("plansys2_msgs/msg/Node")
_COMPARE = {"=": "COMP_EQ", ">=": "COMP_GE", ">": "COMP_GT", "<=": "COMP_LE", "<": "COMP_LT"}
_ARITH = {"*": "ARITH_MULT", "/": "ARITH_DIV", "+": "ARITH_ADD", "-": "ARITH_SUB"}
_OPERATOR = {_N[v]: k for k, v in (_COMPARE | _ARITH).items()}


def _node_type() -> type[Any]:
    return dds_type("plansys2_msgs/msg/Node")


def param(name: str, type: str = "") -> Any:
    """A ``plansys2_msgs/Param``."""
    return dds_type("plansys2_msgs/msg/Param")(name=name, type=type)


def atom_node(atom: Atom, node_id: int = 0) -> Any:
    """A fact as PlanSys2's PREDICATE node (parameters are the objects)."""
    return _node_type()(
        node_type=_N["PREDICATE"],
        node_id=node_id,
        name=atom.predicate,
        parameters=[param(a) for a in atom.args],
    )


def fluent_node(fluent: FluentRef | FluentValue, node_id: int = 0) -> Any:
    """A fluent (with its value, for a FluentValue) as a FUNCTION node."""
    ref = fluent.fluent if isinstance(fluent, FluentValue) else fluent
    value = fluent.value if isinstance(fluent, FluentValue) else 0.0
    return _node_type()(
        node_type=_N["FUNCTION"],
        node_id=node_id,
        name=ref.name,
        parameters=[param(a) for a in ref.args],
        value=float(value),
    )


def _application(node: Any) -> str:
    return "(" + " ".join([node.name, *(p.name for p in node.parameters)]) + ")"


def node_text(node: Any) -> str:
    """A single PREDICATE or FUNCTION node as PDDL: ``(at r1 kitchen)``, ``(= (battery r1) 80)``."""
    if node.node_type == _N["PREDICATE"]:
        return _application(node)
    if node.node_type == _N["FUNCTION"]:
        return f"(= {_application(node)} {write_number(node.value)})"
    raise KnowledgeError(
        f"node {node.name!r}: expected a PREDICATE or FUNCTION node, got type {node.node_type}"
    )


def tree_text(tree: Any) -> str:
    """A Tree as PDDL, as PlanSys2's ``parser::pddl::toString(tree)``."""
    nodes = list(tree.nodes)
    if not nodes:
        return ""
    return _text(nodes, 0, set())


def _text(nodes: list[Any], index: int, seen: set[int]) -> str:
    if not 0 <= index < len(nodes):
        raise KnowledgeError(f"tree node {index} does not exist ({len(nodes)} nodes)")
    if index in seen:
        raise KnowledgeError(f"tree node {index} is reached twice (the tree has a cycle)")
    seen.add(index)
    node = nodes[index]
    kids = [_text(nodes, int(c), seen) for c in node.children]
    t = node.node_type
    if t in (_N["AND"], _N["OR"]):
        text = "(" + " ".join(["and" if t == _N["AND"] else "or", *kids]) + ")"
    elif t == _N["NOT"]:
        text = f"(not {' '.join(kids)})"
    elif t in (_N["PREDICATE"], _N["FUNCTION"]):
        text = _application(node)
    elif t == _N["NUMBER"]:
        text = write_number(node.value)
    elif t == _N["CONSTANT"] or t == _N["PARAMETER"]:
        text = node.name
    elif t == _N["EXPRESSION"]:
        op = _OPERATOR.get(node.expression_type)
        if op is None:
            raise KnowledgeError(f"tree node {index}: unknown expression type")
        text = f"({op} {' '.join(kids)})"
    elif t == _N["EXISTS"]:
        variables = " ".join(f"{p.name} - {p.type or 'object'}" for p in node.parameters)
        text = f"(exists ({variables}) {' '.join(kids)})"
    else:
        raise KnowledgeError(f"tree node {index}: node type {t} cannot appear in a condition")
    return f"(not {text})" if node.negate else text


def condition_tree(cond: Condition, names: dict[str, str] | None = None) -> Any:
    """A condition as PlanSys2's Tree (node 0 the root; empty for no condition).

    ``names`` renames variables, as PlanSys2's domain expert calls an action's
    parameters ``?0``, ``?1``... or the objects a client asked for.
    """
    nodes: list[Any] = []
    if cond != And(()):
        _TreeBuilder(nodes).walk(cond)
    return _tree(nodes, names or {})


def effect_tree(effect: Effect, names: dict[str, str] | None = None) -> Any:
    """An effect as PlanSys2's Tree: AND, NOT of PREDICATE, FUNCTION_MODIFIER nodes.

    PlanSys2's Tree has no node for conditional or universal effects, so those are
    refused with a KnowledgeError rather than sent half.
    """
    nodes: list[Any] = []
    if effect != AndEffect(()):
        _TreeBuilder(nodes).walk(effect)
    return _tree(nodes, names or {})


def _tree(nodes: list[Any], names: dict[str, str]) -> Any:
    for node in nodes:
        for p in node.parameters:
            p.name = names.get(p.name, p.name)
        if node.node_type == _N["CONSTANT"]:
            node.name = names.get(node.name, node.name)
    return dds_type("plansys2_msgs/msg/Tree")(nodes=nodes)


def _new(nodes: list[Any], **fields: Any) -> Any:
    node = _node_type()(node_id=len(nodes), **fields)
    nodes.append(node)
    return node


class _TreeBuilder(Visitor[int]):
    """Appends a node (and its children) to ``nodes``; returns the node's index.

    PlanSys2's Tree has no node for ``imply`` or ``forall``: those are written as
    their ``lower()`` forms, ``(or (not a) b)`` and ``(not (exists (...) (not b)))``.
    """

    def __init__(self, nodes: list[Any]) -> None:
        self.nodes = nodes

    def _node(self, children: tuple[Any, ...] = (), **fields: Any) -> int:
        node = _new(self.nodes, **fields)
        node.children = [self.walk(c) for c in children]
        return int(node.node_id)

    # ------------------------------------------------------------ effects

    def walk_add_effect(self, effect: AddEffect) -> int:
        return self.walk(effect.atom)

    def walk_delete_effect(self, effect: DeleteEffect) -> int:
        return self.walk(Not(effect.atom))

    def walk_and_effect(self, effect: AndEffect) -> int:
        return self._node(effect.effects, node_type=_N["AND"])

    def walk_numeric_effect(self, effect: NumericEffect) -> int:
        kind = _N[effect.op.replace("-", "_").upper()]
        return self._node(
            (effect.fluent, effect.value), node_type=_N["FUNCTION_MODIFIER"], modifier_type=kind
        )

    def _no_tree(self, effect: Effect) -> int:
        raise KnowledgeError(f"{type(effect).__name__} has no PlanSys2 Tree form")

    walk_when_effect = walk_forall_effect = _no_tree

    # ------------------------------------------------------------ conditions

    def walk_atom(self, cond: Atom) -> int:
        self.nodes.append(atom_node(cond, len(self.nodes)))
        return len(self.nodes) - 1

    def walk_and(self, cond: And) -> int:
        return self._node(cond.operands, node_type=_N["AND"])

    def walk_or(self, cond: Or) -> int:
        return self._node(cond.operands, node_type=_N["OR"])

    def walk_not(self, cond: Not) -> int:
        return self._node((cond.operand,), node_type=_N["NOT"])

    def walk_exists(self, cond: Exists) -> int:
        parameters = [param(v.name, v.types[0]) for v in cond.variables]
        return self._node((cond.body,), node_type=_N["EXISTS"], parameters=parameters)

    def walk_compare(self, cond: Compare) -> int:
        kind = _N[_COMPARE[cond.op]]
        return self._node((cond.left, cond.right), node_type=_N["EXPRESSION"], expression_type=kind)

    def walk_equals(self, cond: Equals) -> int:
        node = _new(self.nodes, node_type=_N["EXPRESSION"], expression_type=_N["COMP_EQ"])
        node.children = [
            _new(self.nodes, node_type=_N["CONSTANT"], name=cond.left).node_id,
            _new(self.nodes, node_type=_N["CONSTANT"], name=cond.right).node_id,
        ]
        return int(node.node_id)

    # ------------------------------------------------------------ expressions

    def walk_number(self, expr: Number) -> int:
        return int(_new(self.nodes, node_type=_N["NUMBER"], value=float(expr.value)).node_id)

    def walk_fluent_ref(self, expr: FluentRef) -> int:
        self.nodes.append(fluent_node(expr, len(self.nodes)))
        return len(self.nodes) - 1

    def walk_negate(self, expr: Negate) -> int:
        return self.walk(BinaryOp("-", Number(0.0), expr.operand))

    def walk_duration_ref(self, expr: DurationRef) -> int:
        raise KnowledgeError("?duration has no PlanSys2 Tree form (it can appear in no goal)")

    def walk_binary_op(self, expr: BinaryOp) -> int:
        kind = _N[_ARITH[expr.op]]
        return self._node((expr.left, expr.right), node_type=_N["EXPRESSION"], expression_type=kind)
