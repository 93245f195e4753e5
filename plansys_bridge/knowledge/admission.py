"""What the knowledge base admits: facts, fluents and goals checked against the domain
and the objects it knows, before anything is stored.

Why apart from the knowledge base: the checks read the domain and the object table
but change nothing, so they can run before a change starts (a change either passes
every check or touches nothing). Messages name the thing and the reason:
``predicate (at r1 k): unknown object 'k'``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import Any

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.formulas import fluent_text
from plansys_bridge.knowledge.state import FluentKey
from plansys_bridge.pddl.model import Atom, Condition, DurationRef, Equals, FluentRef, TypedName
from plansys_bridge.pddl.walkers import Collector, children, terms

__all__ = ["Admission"]

Scope = Mapping[str, tuple[str, ...]]

_ADMITTED_LIMIT = 100_000
"""Facts remembered as admitted; past it, new ones are checked every time."""


class Admission:
    """Checks against one domain; ``object_type`` says what a name is (None: unknown)."""

    def __init__(self, domain_expert: DomainExpert, object_type: Callable[[str], str | None]):
        self.domain_expert = domain_expert
        self._types = domain_expert.types
        self._object_type = object_type
        self._goal_check = _GoalCheck(self)
        self._admitted: dict[tuple[str, tuple[str, ...]], Atom] = {}
        self._admitted_at = -1
        self._fitting: dict[tuple[str, tuple[str, ...]], bool] = {}

    def check_args(
        self, what: str, text: object, params: tuple[TypedName, ...], args: tuple[str, ...]
    ) -> None:
        """Known objects of the parameters' types; ``text`` names the thing in an
        error (an atom is written as PDDL only then)."""
        if len(args) != len(params):
            raise KnowledgeError(f"{what} {text}: expects {len(params)} arguments, got {len(args)}")
        for param, arg in zip(params, args, strict=True):
            if arg[:1] == "?":
                raise KnowledgeError(f"{what} {text}: {arg} is a variable, an object is needed")
            obj_type = self._object_type(arg)
            if obj_type is None:
                raise KnowledgeError(f"{what} {text}: unknown object {arg!r}")
            if not self._fits(obj_type, param.types):
                raise KnowledgeError(
                    f"{what} {text}: {arg} is a {obj_type}, parameter {param.name} "
                    f"wants {' or '.join(param.types)}"
                )

    def _fits(self, obj_type: str, wanted: tuple[str, ...]) -> bool:
        """Is an object of ``obj_type`` one of the ``wanted`` types? Remembered:
        the domain's types are fixed, and each fact the knowledge is given asks it
        once per argument."""
        key = (obj_type, wanted)
        fits = self._fitting.get(key)
        if fits is None:
            fits = self._fitting[key] = self._types.is_subtype_of_any((obj_type,), wanted)
        return fits

    def fact(self, atom: Atom) -> Atom:
        # map, not a comprehension: no call of its own (a fact per new fact applied)
        atom = Atom(atom.predicate.lower(), tuple(map(str.lower, atom.args)))
        pdef = self.domain_expert.get_predicate(atom.predicate)
        if pdef is None:
            raise KnowledgeError(f"predicate {atom}: unknown predicate {atom.predicate!r}")
        if self.domain_expert.is_derived(atom.predicate):
            raise KnowledgeError(
                f"predicate {atom}: {atom.predicate} is derived; it follows from other facts"
            )
        self.check_args("predicate", atom, pdef.parameters, atom.args)
        return atom

    def facts(self, atoms: Iterable[Atom], objects_version: int) -> list[Atom]:
        """``fact`` of each atom, remembering the atoms that passed.

        Why: an executor applies the same effects to the same objects over and over
        (a robot going back and forth), and the checks cost more than the change. An
        answer depends only on the domain (fixed) and the objects, so the memory is
        dropped whenever ``objects_version`` (the object table's write count) moves;
        an atom that fails is never remembered and fails every time.
        """
        if objects_version != self._admitted_at:
            self._admitted.clear()
            self._admitted_at = objects_version
        admitted = self._admitted
        out: list[Atom] = []
        for atom in atoms:
            # Keyed by (predicate, arguments): a tuple hashes and compares in C, an
            # atom through its Python __hash__ and __eq__.
            key = (atom.predicate, atom.args)
            checked = admitted.get(key)
            if checked is None:
                checked = self.fact(atom)
                if len(admitted) < _ADMITTED_LIMIT:
                    admitted[key] = checked
            out.append(checked)
        return out

    def fluent(self, name: str, args: tuple[str, ...]) -> FluentKey:
        key = (name.lower(), tuple(a.lower() for a in args))
        text = fluent_text(key)
        fdef = self.domain_expert.get_function(key[0])
        if fdef is None:
            raise KnowledgeError(f"function {text}: unknown function {key[0]!r}")
        self.check_args("function", text, fdef.parameters, key[1])
        return key

    def condition(self, cond: Condition, scope: Scope) -> None:
        """Known predicates/functions, arity, objects and (for objects) types."""
        self._goal_check.walk(cond, scope)

    def term_known(self, what: str, text: str, term: str, scope: Scope) -> None:
        if term.startswith("?"):
            if term not in scope:
                raise KnowledgeError(f"{what} {text}: variable {term} is not bound")
        elif self._object_type(term) is None:
            raise KnowledgeError(f"{what} {text}: unknown object {term!r}")

    def check_terms(
        self,
        what: str,
        text: str,
        params: tuple[TypedName, ...],
        args: tuple[str, ...],
        scope: Scope,
    ) -> None:
        if len(args) != len(params):
            raise KnowledgeError(f"{what} {text}: expects {len(params)} arguments, got {len(args)}")
        for param, arg in zip(params, args, strict=True):
            self.term_known(what, text, arg, scope)
            if arg.startswith("?"):
                continue
            obj_type = self._object_type(arg)
            assert obj_type is not None
            if not self._types.is_subtype_of_any((obj_type,), param.types):
                raise KnowledgeError(
                    f"{what} {text}: {arg} is a {obj_type}, parameter {param.name} "
                    f"wants {' or '.join(param.types)}"
                )


class _GoalCheck(Collector):
    """A condition's nodes checked in their variable scope (``walk(cond, scope)``)."""

    kinds = ("condition", "expression")

    def __init__(self, admission: Admission) -> None:
        self.a = admission

    def default(self, node: Any, scope: Scope) -> None:
        variables: tuple[TypedName, ...] = getattr(node, "variables", ())
        if variables:
            scope = dict(scope)
            for var in variables:
                for t in var.types:
                    if not self.a.domain_expert.is_valid_type(t):
                        raise KnowledgeError(
                            f"condition: variable {var.name} has unknown type {t!r}"
                        )
                scope[var.name] = var.types
        for term in terms(node):
            self.a.term_known("condition", repr(node), term, scope)
        for child in children(node):
            self.walk(child, scope)

    def walk_atom(self, cond: Atom, scope: Scope) -> None:
        pdef = self.a.domain_expert.get_predicate(cond.predicate)
        if pdef is None:
            raise KnowledgeError(f"condition {cond}: unknown predicate {cond.predicate!r}")
        self.a.check_terms("condition", str(cond), pdef.parameters, cond.args, scope)

    def walk_equals(self, cond: Equals, scope: Scope) -> None:
        for term in (cond.left, cond.right):
            self.a.term_known("condition", f"(= {cond.left} {cond.right})", term, scope)

    def walk_fluent_ref(self, expr: FluentRef, scope: Scope) -> None:
        text = fluent_text((expr.name, expr.args))
        fdef = self.a.domain_expert.get_function(expr.name)
        if fdef is None:
            raise KnowledgeError(f"condition {text}: unknown function {expr.name!r}")
        self.a.check_terms("condition", text, fdef.parameters, expr.args, scope)

    def walk_duration_ref(self, expr: DurationRef, scope: Scope) -> None:
        raise KnowledgeError("condition: ?duration is only meaningful inside an action")
