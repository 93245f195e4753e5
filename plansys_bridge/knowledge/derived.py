"""Derived predicates: which order to compute them in, and the facts they derive.

Why it is built this way: derived predicates are computed once per state snapshot
(the reasoner caches the table on the state), stratum by stratum. A predicate used
under negation (or in a ``forall`` or an ``imply`` antecedent) is complete before
any rule reading it runs; recursive rules in one stratum iterate to a fixpoint,
semi-naively (after a first full round, a rule is re-run only in variants reading
the facts the previous round found). A domain whose derived predicates depend
negatively on themselves is refused when the evaluator is built.
"""

from __future__ import annotations

from plansys_bridge.knowledge.context import DerivedSource, EvalContext, EvaluationError
from plansys_bridge.knowledge.formulas import DELTA, delta_variants, predicate_uses
from plansys_bridge.knowledge.joins import JoinSolver
from plansys_bridge.knowledge.state import Args, State
from plansys_bridge.pddl.model import Condition, DerivedPredicate, Domain

__all__ = ["DerivedRules", "stratify"]


def stratify(rules: dict[str, list[DerivedPredicate]], domain_name: str) -> list[list[str]]:
    """Derived predicate names in strata: each negative use is complete one stratum
    earlier; EvaluationError when a predicate depends negatively on itself."""
    names = list(rules)
    if not names:
        return []
    deps: dict[str, list[tuple[str, bool]]] = {n: [] for n in names}
    for name, bodies in rules.items():
        for rule in bodies:
            for pred, negative in predicate_uses(rule.condition, False):
                if pred in rules:
                    deps[name].append((pred, negative))
    # A level is the number of negative edges below a predicate; a cycle through
    # a negative edge would push levels past the number of predicates.
    level = dict.fromkeys(names, 0)
    changed = True
    while changed:
        changed = False
        for name in names:
            for pred, negative in deps[name]:
                need = level[pred] + (1 if negative else 0)
                if need > level[name]:
                    level[name] = need
                    changed = True
                    if need >= len(names):
                        raise EvaluationError(
                            f"derived predicate {name} of domain {domain_name} depends "
                            f"negatively on itself through {pred} (not stratifiable)"
                        )
    strata: dict[int, list[str]] = {}
    for name in names:
        strata.setdefault(level[name], []).append(name)
    return [strata[k] for k in sorted(strata)]


class DerivedRules:
    """The ``:derived`` rules of one domain, stratified, and their fixpoint."""

    def __init__(self, domain: Domain) -> None:
        self.rules: dict[str, list[DerivedPredicate]] = {}
        for rule in domain.derived:
            self.rules.setdefault(rule.head.name, []).append(rule)
        self.strata = stratify(self.rules, domain.name)
        self._variant_cache: dict[tuple[str, ...], list[tuple[DerivedPredicate, Condition]]] = {}

    def compute(
        self, solver: JoinSolver, source: DerivedSource, state: State
    ) -> dict[str, frozenset[Args]]:
        """Every derived predicate's facts in ``state`` (semi-naive, per stratum)."""
        work: dict[str, set[Args]] = {}
        ctx = EvalContext(source, state, None, work)
        for stratum in self.strata:
            for name in stratum:
                work[name] = set(state.tuples(name))
            delta: dict[str, set[Args]] = {name: set() for name in stratum}
            for name in stratum:
                for rule in self.rules[name]:
                    self._fire(solver, rule, rule.condition, work[name], delta[name], ctx)
            variants = self._delta_variants(stratum)
            while any(delta.values()):
                ctx.delta = {name + DELTA: tuples for name, tuples in delta.items()}
                delta = {name: set() for name in stratum}
                for rule, body in variants:
                    name = rule.head.name
                    self._fire(solver, rule, body, work[name], delta[name], ctx)
            ctx.delta = None
        return {name: frozenset(tuples) for name, tuples in work.items()}

    @staticmethod
    def _fire(
        solver: JoinSolver,
        rule: DerivedPredicate,
        body: Condition,
        target: set[Args],
        new: set[Args],
        ctx: EvalContext,
    ) -> None:
        head = [p.name for p in rule.head.parameters]
        var_types = {p.name: solver._accepted(p.types) for p in rule.head.parameters}
        for nb in solver._solve(body, {}, var_types, ctx):
            args = tuple(nb[v] for v in head)
            if args not in target:
                target.add(args)
                new.add(args)

    def _delta_variants(self, stratum: list[str]) -> list[tuple[DerivedPredicate, Condition]]:
        key = tuple(stratum)
        found = self._variant_cache.get(key)
        if found is None:
            names = set(stratum)
            found = [
                (rule, variant)
                for name in stratum
                for rule in self.rules[name]
                for variant in delta_variants(rule.condition, names)
            ]
            self._variant_cache[key] = found
        return found
