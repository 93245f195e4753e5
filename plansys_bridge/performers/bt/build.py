"""Turn a tree file's elements into a py_trees tree (BehaviorTree.CPP v4 subset).

The control and decorator nodes PlanSys2's examples use, mapped to py_trees:

=====================  ==========================================================
``Sequence``            ``Sequence(memory=True)``: children in order, resumes where it was
``ReactiveSequence``    ``Sequence(memory=False)``: every tick re-checks from the first
``Fallback``            ``Selector(memory=True)``
``ReactiveFallback``    ``Selector(memory=False)``
``Inverter``            ``Inverter``
``RetryUntilSuccessful`` ``Retry`` (``num_attempts``; -1: forever)
``Timeout``             :class:`~.nodes.ClockTimeout` (``msec`` of mission time)
``ForceSuccess``        ``FailureIsSuccess``; ``ForceFailure``: ``SuccessIsFailure``
=====================  ==========================================================

Leaves are node types (:mod:`.nodes`): ``<Move goal="{arg2}"/>`` or, in the
explicit form, ``<Action ID="Move" .../>`` / ``<Condition ID="..."/>``.
"""

from __future__ import annotations

from collections.abc import Mapping

import py_trees

from plansys_bridge.performers.bt.nodes import BtContext, BtNode, ClockTimeout
from plansys_bridge.performers.bt.xml_tree import Element

__all__ = ["CONTROL_NODES", "DECORATORS", "build_tree"]

CONTROL_NODES = {
    "Sequence": (py_trees.composites.Sequence, True),
    "ReactiveSequence": (py_trees.composites.Sequence, False),
    "Fallback": (py_trees.composites.Selector, True),
    "ReactiveFallback": (py_trees.composites.Selector, False),
}
DECORATORS = (
    "Inverter",
    "RetryUntilSuccessful",
    "Timeout",
    "ForceSuccess",
    "ForceFailure",
)


def build_tree(
    element: Element, types: Mapping[str, type[BtNode]], context: BtContext
) -> py_trees.behaviour.Behaviour:
    """The py_trees tree of ``element``; bad input raises ``BtXmlError`` at its line."""
    name = element.attrs.get("name", element.tag)
    if element.tag in CONTROL_NODES:
        cls, memory = CONTROL_NODES[element.tag]
        if not element.children:
            raise element.error("a control node needs at least one child")
        children = [build_tree(c, types, context) for c in element.children]
        return cls(name, memory=memory, children=children)
    if element.tag in DECORATORS:
        return _decorator(element, name, types, context)
    tag = element.tag
    attrs = {k: v for k, v in element.attrs.items() if k != "name"}
    if tag in ("Action", "Condition"):
        if "ID" not in attrs:
            raise element.error("needs an ID attribute naming the node type")
        tag = attrs.pop("ID")
    cls_ = types.get(tag)
    if cls_ is None:
        known = ", ".join(sorted([*CONTROL_NODES, *DECORATORS, *types]))
        raise element.error(f"unknown node type {tag!r} (known: {known})")
    if element.children:
        raise element.error(f"{tag} is a leaf node: it takes no children")
    if element.tag == "Condition" and not cls_.condition:
        raise element.error(f"{tag} is an action node, not a condition")
    if cls_.ports is not None:
        extra = sorted(set(attrs) - cls_.ports)
        if extra:
            allowed = ", ".join(sorted(cls_.ports)) or "none"
            raise element.error(f"unknown port(s) {', '.join(extra)} of {tag} (ports: {allowed})")
    missing = sorted(cls_.required - set(attrs))
    if missing:
        raise element.error(f"{tag} needs port(s) {', '.join(missing)}")
    try:
        return cls_(name if "name" in element.attrs else tag, attrs, context)
    except (TypeError, ValueError) as exc:
        raise element.error(f"cannot create {tag}: {exc}") from exc


def _decorator(
    element: Element, name: str, types: Mapping[str, type[BtNode]], context: BtContext
) -> py_trees.behaviour.Behaviour:
    if len(element.children) != 1:
        raise element.error(f"a decorator has exactly one child, found {len(element.children)}")
    child = build_tree(element.children[0], types, context)
    tag = element.tag
    if tag == "Inverter":
        return py_trees.decorators.Inverter(name, child)
    if tag == "ForceSuccess":
        return py_trees.decorators.FailureIsSuccess(name, child)
    if tag == "ForceFailure":
        return py_trees.decorators.SuccessIsFailure(name, child)
    if tag == "RetryUntilSuccessful":
        attempts = _number(element, "num_attempts", integer=True)
        return py_trees.decorators.Retry(name, child, 2**31 if attempts < 0 else int(attempts))
    msec = _number(element, "msec", integer=False)
    if msec < 0:
        raise element.error(f"msec must be >= 0, got {msec:g}")
    return ClockTimeout(name, child, msec / 1000.0, context.clock)


def _number(element: Element, key: str, *, integer: bool) -> float:
    raw = element.attrs.get(key)
    if raw is None:
        raise element.error(f"needs the {key} attribute")
    try:
        return int(raw) if integer else float(raw)
    except ValueError:
        raise element.error(
            f"{key} must be a{'n integer' if integer else ' number'}, got {raw!r}"
        ) from None
