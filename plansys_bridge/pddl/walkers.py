"""Walking the PDDL model: the one place that knows each node's shape, and the
visitor, collector and transformer bases every formula walk is written with.

Why: conditions, effects and numeric expressions are walked by the evaluator,
grounding, plan atoms, the checks, the writer, the PlanSys2 Tree converter and the
feature detection. Spelling out an ``isinstance`` chain over every node class in
each of them meant a new construct touched them all. Here (in the spirit of
unified-planning's walkers and Python's ``ast.NodeVisitor``):

* a node's *children*, *terms* and *bound variables* are read off its dataclass
  fields once per class (a field typed with model nodes holds children, one typed
  ``Term`` holds terms, ``variables`` binds names over the children), so a new
  node class is walked correctly by every generic walker without an edit;
* :meth:`Walker.walk` calls the method named after the node's class
  (``walk_atom``, ``walk_and_effect``, ``walk_fluent_ref``...), looked up once per
  (walker class, node class) and cached; a class the walker has no method for goes
  to :meth:`Walker.default`:

  - :class:`Visitor` (a walk that gives meaning: truth, text, a Tree) walks the
    node's :meth:`lower` form, the same construct written with older ones
    (``imply`` is ``(or (not a) b)``); a node without one is a ``TypeError``
    naming the walker and the node, never a silent wrong answer;
  - :class:`Collector` recurses into the children (a walk that gathers);
  - :class:`Transformer` rebuilds the node from its walked children and mapped
    terms, returning the very same node when nothing changed.

``tests/pddl/test_walkers.py`` checks, by introspecting ``model.py``, that every
walker in the project covers every node class it can meet, and that a construct
defined only by its dataclass (with a ``lower()``) is evaluated, written,
grounded, checked and converted with no other edit.
"""

from __future__ import annotations

import dataclasses
import re
import sys
import typing
from collections.abc import Callable, Iterator
from typing import Any, ClassVar, Generic, TypeVar, get_args

from plansys_bridge.pddl import model
from plansys_bridge.pddl.model import Condition, Effect, NumExpr

__all__ = [
    "NODE_KINDS",
    "NODE_TYPES",
    "Collector",
    "Node",
    "Transformer",
    "Visitor",
    "Walker",
    "bound_variables",
    "children",
    "iter_nodes",
    "method_name",
    "terms",
]

Node = Condition | Effect | NumExpr
"""Anything a walker walks."""

NODE_KINDS: dict[str, tuple[type, ...]] = {
    "condition": get_args(Condition),
    "effect": get_args(Effect),
    "expression": get_args(NumExpr),
}
"""The node classes of each kind, read from the model's type aliases."""

NODE_TYPES: tuple[type, ...] = tuple(t for kind in NODE_KINDS.values() for t in kind)

R = TypeVar("R")


# ---------------------------------------------------------------- shape


@dataclasses.dataclass(frozen=True)
class _Shape:
    """Where a node class keeps its children, terms and bound variables."""

    nodes: tuple[tuple[str, bool], ...]  # (field, holds a tuple of nodes)
    terms: tuple[tuple[str, bool], ...]  # (field, holds a tuple of terms)
    binds: bool  # has a ``variables`` field of TypedNames
    init: tuple[str, ...]  # constructor arguments, in order


_SHAPES: dict[type, _Shape] = {}
_TERM = re.compile(r"\bTerm\b")


def _holds_nodes(hint: Any) -> tuple[bool, bool]:
    """(holds model nodes, as a tuple) for a resolved field type."""
    origin = typing.get_origin(hint)
    if origin is tuple:
        inner = get_args(hint)
        return (_holds_nodes(inner[0])[0], True) if inner else (False, False)
    members = get_args(hint) if origin is not None else (hint,)
    return any(m in NODE_TYPES for m in members if isinstance(m, type)), False


def _shape(cls: type) -> _Shape:
    found = _SHAPES.get(cls)
    if found is not None:
        return found
    module = sys.modules.get(cls.__module__)
    namespace = {**vars(model), **(vars(module) if module else {})}
    hints = typing.get_type_hints(cls, globalns=namespace)
    nodes: list[tuple[str, bool]] = []
    term_fields: list[tuple[str, bool]] = []
    binds = False
    for f in dataclasses.fields(cls):
        is_node, many = _holds_nodes(hints[f.name])
        annotation = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", "")
        if is_node:
            nodes.append((f.name, many))
        elif _TERM.search(annotation):
            term_fields.append((f.name, annotation.startswith("tuple")))
        elif f.name == "variables":
            binds = True
    init = tuple(f.name for f in dataclasses.fields(cls) if f.init)
    found = _Shape(tuple(nodes), tuple(term_fields), binds, init)
    _SHAPES[cls] = found
    return found


def _gather(node: Any, fields: tuple[tuple[str, bool], ...]) -> tuple[Any, ...]:
    out: list[Any] = []
    for name, many in fields:
        value = getattr(node, name)
        if many:
            out.extend(value)
        else:
            out.append(value)
    return tuple(out)


def children(node: Any) -> tuple[Any, ...]:
    """The node's direct sub-nodes (conditions, effects, expressions), in field order."""
    return _gather(node, _shape(type(node)).nodes)


def terms(node: Any) -> tuple[str, ...]:
    """The variables and objects the node itself names (not its children's)."""
    return _gather(node, _shape(type(node)).terms)


def bound_variables(node: Any) -> tuple[str, ...]:
    """Names a quantifier binds over its children (``()`` for other nodes)."""
    if not _shape(type(node)).binds:
        return ()
    return tuple(v.name for v in node.variables)


def iter_nodes(node: Any) -> Iterator[Any]:
    """The node and every node below it, parents first (like ``ast.walk``)."""
    stack = [node]
    while stack:
        current = stack.pop()
        yield current
        stack.extend(reversed(children(current)))


# ---------------------------------------------------------------- dispatch


def method_name(cls: type) -> str:
    """``walk_`` and the class name in snake case: ``AndEffect`` -> ``walk_and_effect``."""
    return "walk_" + re.sub(r"(?<!^)(?=[A-Z])", "_", cls.__name__).lower()


class Walker(Generic[R]):
    """Calls ``walk_<node class>(node, *args)``; see the module docs.

    ``kinds`` names the node kinds (keys of :data:`NODE_KINDS`) the walker is
    meant to meet; the coverage test checks it has an answer for each of their
    classes.
    """

    kinds: ClassVar[tuple[str, ...]] = ("condition", "effect", "expression")
    _methods: ClassVar[dict[type, Callable[..., Any]]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._methods = {}

    @classmethod
    def method_for(cls, node_type: type) -> Callable[..., Any]:
        """The function that walks ``node_type`` (its own method or ``default``)."""
        found = cls._methods.get(node_type)
        if found is None:
            found = getattr(cls, method_name(node_type), None) or cls.default
            cls._methods[node_type] = found
        return found

    @classmethod
    def handles(cls, node_type: type) -> bool:
        """True when the walker has a method of its own for ``node_type``."""
        return hasattr(cls, method_name(node_type))

    def walk(self, node: Any, *args: Any) -> R:
        fn = self._methods.get(node.__class__)
        if fn is None:
            fn = self.method_for(node.__class__)
        result: R = fn(self, node, *args)
        return result

    def default(self, node: Any, *args: Any) -> R:
        raise TypeError(f"{type(self).__name__} cannot walk {type(node).__name__}: {node!r}")


class Visitor(Walker[R]):
    """A walk that gives nodes a meaning; unknown nodes are walked as their ``lower()``."""

    def default(self, node: Any, *args: Any) -> R:
        lower = getattr(node, "lower", None)
        if lower is None:
            raise TypeError(
                f"{type(self).__name__} has no {method_name(type(node))} and "
                f"{type(node).__name__} has no lower(): cannot walk {node!r}"
            )
        return self.walk(lower(), *args)


class Collector(Walker[None]):
    """A walk that gathers; nodes without a method of their own are recursed into."""

    def default(self, node: Any, *args: Any) -> None:
        for child in children(node):
            self.walk(child, *args)


class Transformer(Walker[Any]):
    """A walk that rebuilds; by default a node is rebuilt from its walked children and
    its terms passed through :meth:`term` (the same node back when nothing changed)."""

    def term(self, term: str) -> str:
        return term

    def default(self, node: Any, *args: Any) -> Any:
        return self.rebuild(node, *args)

    def rebuild(self, node: Any, *args: Any) -> Any:
        shape = _shape(type(node))
        changes: dict[str, Any] = {}
        for name, many in shape.nodes:
            value = getattr(node, name)
            if many:
                new = tuple(self.walk(v, *args) for v in value)
                if any(a is not b for a, b in zip(new, value, strict=True)):
                    changes[name] = new
            else:
                new = self.walk(value, *args)
                if new is not value:
                    changes[name] = new
        for name, many in shape.terms:
            value = getattr(node, name)
            mapped = tuple(self.term(t) for t in value) if many else self.term(value)
            if mapped != value:
                changes[name] = mapped
        if not changes:
            return node
        return type(node)(*[changes.get(f, getattr(node, f)) for f in shape.init])
