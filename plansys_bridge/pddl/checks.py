"""Semantic checks: the text parsed, but does it make sense against its domain?

Checked: unknown types, predicates, functions, objects/constants and variables;
wrong arity; argument type mismatches (subtypes and ``either`` respected);
conflicting duplicate declarations; cycles in the type hierarchy; requirements
that matter for execution (``:durative-actions``, ``:fluents`` /
``:numeric-fluents`` when numeric fluents are *used*, ``:derived-predicates``)
and unknown requirement names.

Leniency, on purpose, where PlanSys2's corpus relies on it: a variable may be
passed where a subtype is expected as long as the two types overlap (an untyped
``exists (?ro)`` over rooms is fine), declaring ``(:functions ...)`` without
``:fluents`` is fine, and a problem's ``(:domain ...)`` name is not compared with
the domain's (PlanSys2 merges domains under a new name). A variable whose type is
*disjoint* from the expected one is an error, and ground objects must have a
subtype of the expected type.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from plansys_bridge.errors import PddlSemanticError, SourceLocation
from plansys_bridge.pddl.diagnostics import nth_token_after, semantic_error
from plansys_bridge.pddl.model import (
    NUMBER_TYPE,
    OBJECT_TYPE,
    Action,
    AddEffect,
    Atom,
    Condition,
    DeleteEffect,
    Domain,
    DurationRef,
    DurativeAction,
    Effect,
    FluentRef,
    FluentValue,
    NumExpr,
    PredicateDef,
    Problem,
    TypedName,
    is_variable,
)
from plansys_bridge.pddl.requirements import (
    KNOWN_REQUIREMENTS,
    expand_requirements,
    requirement_loc,
)
from plansys_bridge.pddl.types import TypeHierarchy
from plansys_bridge.pddl.walkers import Collector, bound_variables, children, terms

Scope = Mapping[str, tuple[str, ...]]


def arg_error(
    message: str, node: Atom | FluentRef, index: int, sources: Mapping[str, str]
) -> PddlSemanticError:
    """An error pointing at argument ``index`` (0-based) of ``node``."""
    loc = node.loc
    if loc is not None:
        loc = nth_token_after(sources, loc, index + 1)
    return semantic_error(message, loc, sources)


def _fmt_types(types: tuple[str, ...]) -> str:
    return types[0] if len(types) == 1 else "(either " + " ".join(types) + ")"


class Checker(Collector):
    """Checks model nodes against one domain (and, for problems, its objects).

    ``objects`` maps every known object *and constant* to its types. When it is
    ``None`` (checking a domain, or a condition whose objects live elsewhere),
    names that are not constants are accepted unchecked.
    """

    def __init__(
        self,
        domain: Domain,
        sources: Mapping[str, str],
        objects: Mapping[str, tuple[str, ...]] | None = None,
        extra_requirements: tuple[str, ...] = (),
    ) -> None:
        self.domain = domain
        self.sources = sources
        self.hierarchy = TypeHierarchy(domain)
        self.requirements = expand_requirements((*domain.requirements, *extra_requirements))
        self.predicates: dict[str, PredicateDef] = {p.name: p for p in domain.predicates}
        self.derived_names = {d.head.name for d in domain.derived}
        for d in domain.derived:
            self.predicates.setdefault(d.head.name, d.head)
        self.functions = {f.name: f for f in domain.functions}
        self.constants: dict[str, tuple[str, ...]] = {c.name: c.types for c in domain.constants}
        self.objects = objects
        self.context: SourceLocation | None = None
        self._ancestors: dict[tuple[str, ...], frozenset[str]] = {}

    # ---------------------------------------------------------------- helpers

    def error(self, message: str, loc: SourceLocation | None = None) -> PddlSemanticError:
        return semantic_error(message, loc or self.context, self.sources)

    def need(self, requirements: tuple[str, ...], what: str, loc: SourceLocation | None) -> None:
        if not any(r in self.requirements for r in requirements):
            raise self.error(
                f"{what} needs the requirement {' or '.join(requirements)} in :requirements", loc
            )

    def ancestors(self, types: tuple[str, ...]) -> frozenset[str]:
        found = self._ancestors.get(types)
        if found is None:
            found = frozenset().union(*(self.hierarchy.ancestors(t) for t in types))
            self._ancestors[types] = found
        return found

    def check_type_names(self, types: tuple[str, ...], loc: SourceLocation | None) -> None:
        for t in types:
            if t not in self.hierarchy or (t != OBJECT_TYPE and t not in self._declared_types()):
                raise self.error(f"unknown type '{t}'", loc)

    def _declared_types(self) -> set[str]:
        declared = getattr(self, "_declared", None)
        if declared is None:
            declared = {t.name for t in self.domain.types} | {OBJECT_TYPE}
            self._declared = declared
        return declared

    def declare(self, names: tuple[TypedName, ...], outer: Scope) -> dict[str, tuple[str, ...]]:
        """A new variable scope: ``outer`` plus ``names`` (checked)."""
        scope = dict(outer)
        seen: set[str] = set()
        for var in names:
            if var.name in seen:
                raise self.error(f"variable {var.name} declared twice", var.loc)
            seen.add(var.name)
            self.check_type_names(var.types, var.loc)
            scope[var.name] = var.types
        return scope

    def term(
        self, node: Atom | FluentRef, index: int, expected: tuple[str, ...], scope: Scope, what: str
    ) -> None:
        arg = node.args[index]
        if is_variable(arg):
            types = scope.get(arg)
            if types is None:
                raise arg_error(f"undeclared variable {arg}", node, index, self.sources)
            if expected != (OBJECT_TYPE,) and not self.hierarchy.compatible(types, expected):
                raise arg_error(
                    f"{arg} is a {_fmt_types(types)} but argument {index + 1} of {what} "
                    f"'{node.name if isinstance(node, FluentRef) else node.predicate}' "
                    f"must be a {_fmt_types(expected)}",
                    node,
                    index,
                    self.sources,
                )
            return
        types = self.constants.get(arg)
        if types is None and self.objects is not None:
            types = self.objects.get(arg)
            if types is None:
                raise arg_error(f"unknown object '{arg}'", node, index, self.sources)
        if types is None or expected == (OBJECT_TYPE,):
            return
        ancestors = self.ancestors(types)
        if not any(e in ancestors for e in expected):
            raise arg_error(
                f"'{arg}' is a {_fmt_types(types)} but argument {index + 1} of {what} "
                f"'{node.name if isinstance(node, FluentRef) else node.predicate}' "
                f"must be a {_fmt_types(expected)}",
                node,
                index,
                self.sources,
            )

    def plain_term(self, term: str, scope: Scope) -> None:
        if is_variable(term):
            if term not in scope:
                raise self.error(f"undeclared variable {term}")
        elif self.objects is not None and term not in self.constants and term not in self.objects:
            raise self.error(f"unknown object '{term}'")

    # ---------------------------------------------------------------- nodes

    def atom(self, atom: Atom, scope: Scope) -> None:
        pred = self.predicates.get(atom.predicate)
        if pred is None:
            raise semantic_error(
                f"unknown predicate '{atom.predicate}'", atom.loc or self.context, self.sources
            )
        params = pred.parameters
        if len(atom.args) != len(params):
            signature = " ".join(f"{p.name} - {_fmt_types(p.types)}" for p in params)
            raise semantic_error(
                f"predicate '{atom.predicate}' takes {len(params)} argument(s) ({signature}), "
                f"given {len(atom.args)}",
                atom.loc or self.context,
                self.sources,
            )
        for i, param in enumerate(params):
            self.term(atom, i, param.types, scope, "predicate")

    def fluent(self, ref: FluentRef, scope: Scope) -> None:
        func = self.functions.get(ref.name)
        if func is None:
            raise self.error(f"unknown function '{ref.name}'", ref.loc)
        self.need((":numeric-fluents",), f"numeric fluent '{ref.name}'", ref.loc)
        params = func.parameters
        if len(ref.args) != len(params):
            raise self.error(
                f"function '{ref.name}' takes {len(params)} argument(s), given {len(ref.args)}",
                ref.loc,
            )
        for i, param in enumerate(params):
            self.term(ref, i, param.types, scope, "function")

    # A Collector: a node without a method of its own has its own terms checked,
    # its quantified variables declared, and its children walked.

    def default(self, node: Any, scope: Scope, duration_ok: bool = False) -> None:
        if bound_variables(node):
            scope = self.declare(node.variables, scope)
        for term in terms(node):
            self.plain_term(term, scope)
        for child in children(node):
            self.walk(child, scope, duration_ok)

    def walk_atom(self, atom: Atom, scope: Scope, duration_ok: bool = False) -> None:
        self.atom(atom, scope)

    def walk_fluent_ref(self, ref: FluentRef, scope: Scope, duration_ok: bool = False) -> None:
        self.fluent(ref, scope)

    def walk_duration_ref(self, expr: DurationRef, scope: Scope, duration_ok: bool = False) -> None:
        if not duration_ok:
            raise self.error("?duration used outside a durative action")

    def walk_add_effect(
        self, eff: AddEffect | DeleteEffect, scope: Scope, duration_ok: bool = False
    ) -> None:
        if eff.atom.predicate in self.derived_names:
            raise self.error(
                f"derived predicate '{eff.atom.predicate}' cannot be changed by an effect",
                eff.atom.loc,
            )
        self.atom(eff.atom, scope)

    walk_delete_effect = walk_add_effect

    def num(self, expr: NumExpr, scope: Scope, duration_ok: bool) -> None:
        self.walk(expr, scope, duration_ok)

    def condition(self, cond: Condition, scope: Scope, duration_ok: bool = False) -> None:
        self.walk(cond, scope, duration_ok)

    def effect(self, eff: Effect, scope: Scope, duration_ok: bool = False) -> None:
        self.walk(eff, scope, duration_ok)

    # ---------------------------------------------------------------- domain

    def check_domain(self) -> None:
        domain = self.domain
        for req in domain.requirements:
            if req not in KNOWN_REQUIREMENTS:
                raise self.error(
                    f"unknown requirement '{req}'",
                    requirement_loc(req, domain.source, self.sources),
                )
        for typedef in domain.types:
            self.check_type_names(typedef.parents, typedef.loc)
        cycle = self.hierarchy.cycle()
        if cycle:
            first = next((t for t in domain.types if t.name == cycle[0]), None)
            raise self.error(
                "cycle in the type hierarchy: " + " - ".join(cycle), first.loc if first else None
            )
        for const in domain.constants:
            self.check_type_names(const.types, const.loc)
        for pred in domain.predicates:
            self.declare(pred.parameters, {})
        for func in domain.functions:
            self.declare(func.parameters, {})
            if func.return_type != NUMBER_TYPE:
                raise self.error(
                    f"function '{func.name}' returns '{func.return_type}'; only number works",
                    func.loc,
                )
        for derived in domain.derived:
            self.context = derived.loc
            self.need((":derived-predicates",), "a :derived predicate", derived.loc)
            head = derived.head
            declared = self.predicates[head.name]
            if declared is not head and declared.arity != head.arity:
                raise self.error(
                    f"derived predicate '{head.name}' has {head.arity} parameter(s) but is "
                    f"declared with {declared.arity}",
                    derived.loc,
                )
            self.condition(derived.condition, self.declare(head.parameters, {}))
        for action in domain.actions:
            self.context = action.loc
            scope = self.declare(action.parameters, {})
            if isinstance(action, Action):
                self.condition(action.precondition, scope)
                self.effect(action.effect, scope)
                continue
            assert isinstance(action, DurativeAction)
            self.need((":durative-actions",), f"durative action '{action.name}'", action.loc)
            for constraint in action.duration:
                self.num(constraint.value, scope, duration_ok=False)
            for cond in (action.at_start, action.over_all, action.at_end):
                self.condition(cond, scope, duration_ok=True)
            for eff in (action.start_effect, action.end_effect):
                self.effect(eff, scope, duration_ok=True)
        self.context = None


def check_domain(domain: Domain, sources: Mapping[str, str]) -> None:
    """Raise PddlSemanticError on the first inconsistency in ``domain``."""
    Checker(domain, sources).check_domain()


def problem_objects(
    problem: Problem, domain: Domain | None, sources: Mapping[str, str]
) -> dict[str, tuple[str, ...]]:
    """Objects and constants of a problem, name -> types; duplicates must agree."""
    objects: dict[str, tuple[str, ...]] = {}
    where: dict[str, SourceLocation | None] = {}
    declared = [*(domain.constants if domain else ()), *problem.objects]
    for obj in declared:
        known = objects.get(obj.name)
        if known is not None and set(known) != set(obj.types):
            raise semantic_error(
                f"object '{obj.name}' declared as {_fmt_types(obj.types)} but already declared "
                f"as {_fmt_types(known)} at {where[obj.name] or 'the domain'}",
                obj.loc,
                sources,
            )
        objects[obj.name] = obj.types
        where.setdefault(obj.name, obj.loc)
    return objects


def check_problem(problem: Problem, domain: Domain | None, sources: Mapping[str, str]) -> None:
    """Check a problem's objects, init, goal and metric against ``domain``."""
    objects = problem_objects(problem, domain, sources)
    if domain is None:
        for req in problem.requirements:
            if req not in KNOWN_REQUIREMENTS:
                raise semantic_error(
                    f"unknown requirement '{req}'",
                    requirement_loc(req, problem.source, sources),
                    sources,
                )
        return
    checker = Checker(domain, sources, objects, problem.requirements)
    for obj in problem.objects:
        checker.check_type_names(obj.types, obj.loc)
    for atom in problem.init:
        checker.atom(atom, {})
    given: dict[tuple[str, tuple[str, ...]], FluentValue] = {}
    for value in problem.init_fluents:
        checker.fluent(value.fluent, {})
        first = given.setdefault((value.fluent.name, value.fluent.args), value)
        if first.value != value.value:
            ref = value.fluent
            raise checker.error(
                f"({' '.join((ref.name, *ref.args))}) is given two initial values: "
                f"{first.value:g} at {first.fluent.loc} and {value.value:g} here",
                ref.loc,
            )
    checker.condition(problem.goal, {})
    if problem.metric is not None and problem.metric.expression != "total-time":
        expr = problem.metric.expression
        assert not isinstance(expr, str)
        checker.num(expr, {}, duration_ok=False)


def _objects_as_types(objects: Mapping[str, str] | None) -> dict[str, tuple[str, ...]] | None:
    return None if objects is None else {name: (typ,) for name, typ in objects.items()}


def check_condition(
    cond: Condition,
    domain: Domain,
    variables: Scope,
    sources: Mapping[str, str],
    objects: Mapping[str, str] | None = None,
) -> None:
    """Check a stand-alone condition (a goal, a terminal query)."""
    Checker(domain, sources, _objects_as_types(objects)).condition(cond, variables)


def check_effect(
    eff: Effect,
    domain: Domain,
    variables: Scope,
    sources: Mapping[str, str],
    objects: Mapping[str, str] | None = None,
) -> None:
    Checker(domain, sources, _objects_as_types(objects)).effect(eff, variables)


def check_fluent_value(
    value: FluentValue,
    domain: Domain,
    sources: Mapping[str, str],
    objects: Mapping[str, str] | None = None,
) -> None:
    Checker(domain, sources, _objects_as_types(objects)).fluent(value.fluent, {})
