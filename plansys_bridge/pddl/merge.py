"""Merging domains: PlanSys2's ``a.pddl:b.pddl`` model files become one domain.

Several files (or one file that repeats itself, as PlanSys2's own merge outputs
do) may declare the same type, constant, predicate, function or action. An
identical repeat is dropped; a differing one is an error naming both places,
because silently keeping either would plan with a model the user did not write.
Predicates and functions are compared by their parameter *types*, so a repeat
may rename its parameters.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from typing import Any, TypeVar

from plansys_bridge.errors import PddlSemanticError, SourceLocation
from plansys_bridge.pddl.diagnostics import semantic_error
from plansys_bridge.pddl.model import (
    OBJECT_TYPE,
    Domain,
    FunctionDef,
    PredicateDef,
    TypeDef,
    TypedName,
)

T = TypeVar("T")


def _where(loc: SourceLocation | None) -> str:
    return str(loc) if loc is not None else "an unknown place"


def _merge(
    kind: str,
    items: Sequence[T],
    key: Callable[[T], str],
    signature: Callable[[T], Hashable],
    sources: Mapping[str, str],
) -> tuple[T, ...]:
    kept: dict[str, T] = {}
    for item in items:
        name = key(item)
        first = kept.get(name)
        if first is None:
            kept[name] = item
            continue
        if signature(first) != signature(item):
            first_loc: SourceLocation | None = getattr(first, "loc", None)
            loc: SourceLocation | None = getattr(item, "loc", None)
            raise semantic_error(
                f"conflicting definitions of {kind} '{name}': defined at {_where(first_loc)} "
                f"and differently at {_where(loc)}",
                loc,
                sources,
            )
    return tuple(kept.values())


def _param_types(params: tuple[TypedName, ...]) -> tuple[tuple[str, ...], ...]:
    return tuple(tuple(sorted(p.types)) for p in params)


def _type_signature(t: TypeDef) -> Hashable:
    return tuple(sorted(t.parents))


def _predicate_signature(p: PredicateDef) -> Hashable:
    return _param_types(p.parameters)


def _function_signature(f: FunctionDef) -> Hashable:
    return (_param_types(f.parameters), f.return_type)


def _constant_signature(c: TypedName) -> Hashable:
    return tuple(sorted(c.types))


def _identity(x: Any) -> Hashable:
    result: Hashable = x
    return result


def _with_implicit_parents(types: tuple[TypeDef, ...]) -> tuple[TypeDef, ...]:
    """Declare parent types used but never declared (``a b - place``) under object.

    PlanSys2's corpus relies on this, as do most planners; making them explicit
    keeps every consumer of ``Domain.types`` (and the writer) consistent.
    """
    declared = {t.name for t in types}
    implicit: dict[str, TypeDef] = {}
    for t in types:
        for parent in t.parents:
            if parent != OBJECT_TYPE and parent not in declared and parent not in implicit:
                implicit[parent] = TypeDef(parent, (OBJECT_TYPE,), t.loc)
    return (*types, *implicit.values()) if implicit else types


def merge_domains(domains: Sequence[Domain], sources: Mapping[str, str] | None = None) -> Domain:
    """One domain holding every definition of ``domains`` (identical repeats once).

    Raises PddlSemanticError naming both places when two definitions of the same
    name differ.
    """
    if not domains:
        raise PddlSemanticError("no domains to merge")
    sources = sources or {}
    requirements = tuple(dict.fromkeys(r for d in domains for r in d.requirements))
    types = _merge(
        "type",
        [t for d in domains for t in d.types if t.name != OBJECT_TYPE],
        lambda t: t.name,
        _type_signature,
        sources,
    )
    constants = _merge(
        "constant",
        [c for d in domains for c in d.constants],
        lambda c: c.name,
        _constant_signature,
        sources,
    )
    predicates = _merge(
        "predicate",
        [p for d in domains for p in d.predicates],
        lambda p: p.name,
        _predicate_signature,
        sources,
    )
    functions = _merge(
        "function",
        [f for d in domains for f in d.functions],
        lambda f: f.name,
        _function_signature,
        sources,
    )
    actions = _merge(
        "action", [a for d in domains for a in d.actions], lambda a: a.name, _identity, sources
    )
    types = _with_implicit_parents(types)
    derived = tuple(dict.fromkeys(x for d in domains for x in d.derived))
    name = domains[0].name if len(domains) == 1 else "_".join(d.name for d in domains)
    source_names = [d.source for d in domains if d.source]
    return Domain(
        name=name,
        requirements=requirements,
        types=types,
        constants=constants,
        predicates=predicates,
        functions=functions,
        actions=actions,
        derived=derived,
        source=":".join(source_names) if source_names else None,
    )
