"""Evaluating PDDL conditions and applying effects against a :class:`State`.

Why it is built this way:

* Quantifiers and derived-predicate bodies are solved as joins: a conjunction's
  positive atoms bind variables from the fact index (most selective first), and only
  variables no atom can bind are enumerated over the objects of their type. An
  ``exists`` over rooms connected to the robot's room touches the robot's few facts,
  not every room pair.
* Derived predicates are computed once per state snapshot (cached on the state),
  stratum by stratum: a predicate used under negation (or in a ``forall`` or an
  ``imply`` antecedent) is complete before any rule reading it runs; recursive rules
  in one stratum iterate to a fixpoint. A domain whose derived predicates depend
  negatively on themselves is refused when the evaluator is built.
* Effects follow PDDL: every condition and value is read in the old state, deletes
  are applied before adds, increases on one fluent accumulate.
"""

from __future__ import annotations

import contextlib
import itertools
from collections import OrderedDict
from collections.abc import Iterable, Iterator, Mapping, Sequence

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.formulas import (
    DELTA,
    compare,
    conjuncts,
    delta_variants,
    describe_expr,
    fluent_text,
    free_vars,
    negate,
    predicate_uses,
)
from plansys_bridge.knowledge.grounding import (
    GroundAction,
    UnboundVariableError,
    ground_args,
    normalize_bindings,
    substitute_condition,
    substitute_effect,
)
from plansys_bridge.knowledge.state import Args, FluentKey, State
from plansys_bridge.pddl.model import (
    NO_EFFECT,
    OBJECT_TYPE,
    TRUE,
    Action,
    AddEffect,
    And,
    AndEffect,
    AnyAction,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DeleteEffect,
    DerivedPredicate,
    Domain,
    DurationRef,
    DurativeAction,
    Effect,
    Equals,
    Exists,
    FluentRef,
    Forall,
    ForallEffect,
    Imply,
    Negate,
    Not,
    Number,
    NumericEffect,
    NumExpr,
    Or,
    TypedName,
    WhenEffect,
)
from plansys_bridge.pddl.types import TypeHierarchy

__all__ = [
    "EvaluationError",
    "Evaluator",
    "GroundAction",
    "UnboundVariableError",
    "UndefinedFluentError",
]


class EvaluationError(KnowledgeError):
    """A condition or effect cannot be evaluated (division by zero, no ?duration, ...)."""


class UndefinedFluentError(EvaluationError):
    """A numeric fluent was read before any value was given to it."""

    def __init__(self, name: str, args: tuple[str, ...]) -> None:
        self.fluent = (name, args)
        text = "(" + " ".join((name, *args)) + ")"
        super().__init__(f"fluent {text} is undefined")


_EMPTY: frozenset[Args] = frozenset()
_CACHE_LIMIT = 4096
_VarTypes = dict[str, frozenset[str] | None]  # variable -> accepted object types (None: any)


class _Ctx:
    """What one evaluation needs: the state, ?duration, and derived-fact tables."""

    __slots__ = ("delta", "derived", "duration", "ev", "state")

    def __init__(
        self,
        ev: Evaluator,
        state: State,
        duration: float | None,
        derived: dict[str, set[Args]] | None = None,
    ) -> None:
        self.ev = ev
        self.state = state
        self.duration = duration
        self.derived = derived
        self.delta: dict[str, set[Args]] | None = None

    def tuples(self, predicate: str) -> frozenset[Args] | set[Args]:
        if predicate in self.ev._derived_rules:
            if self.derived is not None and predicate in self.derived:
                return self.derived[predicate]
            return self.ev._derived_table(self.state).get(predicate, _EMPTY)
        if self.delta is not None and predicate in self.delta:
            return self.delta[predicate]
        return self.state.tuples(predicate)


class Evaluator:
    """Evaluates conditions and applies effects of one domain (see module docs)."""

    def __init__(self, domain: Domain) -> None:
        self.domain = domain
        self.types = TypeHierarchy(domain)
        self._actions: dict[str, AnyAction] = {a.name: a for a in domain.actions}
        self._derived_rules: dict[str, list[DerivedPredicate]] = {}
        for rule in domain.derived:
            self._derived_rules.setdefault(rule.head.name, []).append(rule)
        self._strata = self._stratify()
        self._free_cache: dict[int, tuple[Condition, frozenset[str]]] = {}
        self._rename_cache: dict[int, tuple[Exists, _VarTypes, list[Condition]]] = {}
        self._fresh = itertools.count(1)  # next() is atomic: evaluators are shared by threads
        self._variant_cache: dict[tuple[str, ...], list[tuple[DerivedPredicate, Condition]]] = {}
        self._accept_cache: dict[tuple[str, ...], frozenset[str] | None] = {}
        self._position_index: OrderedDict[
            tuple[int, int], tuple[frozenset[Args], dict[str, list[Args]]]
        ] = OrderedDict()

    # ================================================================= public API

    def holds(
        self,
        cond: Condition,
        state: State,
        bindings: Mapping[str, str] | None = None,
        duration: float | None = None,
    ) -> bool:
        """True when ``cond`` holds in ``state`` with ``bindings`` (``?x`` -> object)."""
        b = normalize_bindings(bindings) if bindings else {}
        return self._holds(cond, b, _Ctx(self, state, duration))

    def value(
        self,
        expr: NumExpr,
        state: State,
        bindings: Mapping[str, str] | None = None,
        duration: float | None = None,
    ) -> float:
        """The value of a numeric expression; an undefined fluent raises naming it."""
        b = normalize_bindings(bindings) if bindings else {}
        return self._value(expr, b, _Ctx(self, state, duration))

    def apply(
        self,
        effect: Effect,
        state: State,
        bindings: Mapping[str, str] | None = None,
        duration: float | None = None,
    ) -> State:
        """The state after ``effect`` (PDDL semantics: read old state, deletes then adds)."""
        adds, deletes, updates = self.changes(effect, state, bindings, duration)
        return state.with_changes(adds=adds, deletes=deletes, fluents=updates)

    def changes(
        self,
        effect: Effect,
        state: State,
        bindings: Mapping[str, str] | None = None,
        duration: float | None = None,
    ) -> tuple[list[Atom], list[Atom], dict[FluentKey, float]]:
        """What ``effect`` would do: (adds, deletes, new fluent values), nothing applied."""
        b = normalize_bindings(bindings) if bindings else {}
        ctx = _Ctx(self, state, duration)
        adds: list[Atom] = []
        deletes: list[Atom] = []
        numeric: list[tuple[str, FluentKey, float]] = []
        self._collect(effect, b, ctx, adds, deletes, numeric)
        updates: dict[FluentKey, float] = {}
        for op, key, val in numeric:
            current = updates.get(key)
            if current is None:
                current = state.value(*key)
            if op == "assign":
                updates[key] = val
                continue
            if current is None:
                raise UndefinedFluentError(*key)
            if op == "increase":
                updates[key] = current + val
            elif op == "decrease":
                updates[key] = current - val
            elif op == "scale-up":
                updates[key] = current * val
            else:
                if val == 0:
                    raise EvaluationError(f"scale-down of {fluent_text(key)} by zero")
                updates[key] = current / val
        return adds, deletes, updates

    def satisfying_bindings(
        self,
        cond: Condition,
        state: State,
        variables: Sequence[TypedName],
        bindings: Mapping[str, str] | None = None,
        duration: float | None = None,
    ) -> Iterator[dict[str, str]]:
        """Every binding of ``variables`` (objects of their types) making ``cond`` hold."""
        b = normalize_bindings(bindings) if bindings else {}
        ctx = _Ctx(self, state, duration)
        var_types = {v.name: self._accepted(v.types) for v in variables}
        for v in var_types:
            b.pop(v, None)
        seen: set[tuple[str, ...]] = set()
        for found in self._solve(cond, b, var_types, ctx):
            key = tuple(found[v] for v in var_types)
            if key not in seen:
                seen.add(key)
                yield dict(zip(var_types, key, strict=True))

    def derived_facts(self, state: State) -> dict[str, frozenset[Args]]:
        """Every derived predicate's true argument tuples in ``state``."""
        return dict(self._derived_table(state))

    def get_action(self, name: str) -> AnyAction:
        try:
            return self._actions[name.lower()]
        except KeyError:
            raise KnowledgeError(f"unknown action {name!r} in domain {self.domain.name}") from None

    def ground_action(
        self,
        action: AnyAction | str,
        args: Sequence[str],
        state: State | None = None,
    ) -> GroundAction:
        """``action`` with ``args`` for its parameters.

        With a ``state`` the arguments are checked (known objects of the right type)
        and the duration is evaluated there; without one a duration that reads
        fluents is left as None.
        """
        act = self.get_action(action) if isinstance(action, str) else action
        arguments = tuple(a.lower() for a in args)
        if len(arguments) != len(act.parameters):
            raise KnowledgeError(
                f"action {act.name} takes {len(act.parameters)} arguments, got {len(arguments)}: "
                f"({' '.join((act.name, *arguments))})"
            )
        if state is not None:
            for param, arg in zip(act.parameters, arguments, strict=True):
                obj_type = state.objects.get(arg)
                if obj_type is None:
                    raise KnowledgeError(
                        f"action ({act.name} {' '.join(arguments)}): unknown object {arg!r}"
                    )
                if not self.types.is_subtype_of_any((obj_type,), param.types):
                    raise KnowledgeError(
                        f"action ({act.name} {' '.join(arguments)}): {arg} is a {obj_type}, "
                        f"parameter {param.name} wants {' or '.join(param.types)}"
                    )
        b = {p.name: a for p, a in zip(act.parameters, arguments, strict=True)}
        if isinstance(act, Action):
            return GroundAction(
                name=act.name,
                args=arguments,
                bindings=b,
                at_start=TRUE,
                over_all=substitute_condition(act.precondition, b),
                at_end=TRUE,
                start_effect=NO_EFFECT,
                end_effect=substitute_effect(act.effect, b),
                duration=None,
                durative=False,
                action=act,
            )
        return GroundAction(
            name=act.name,
            args=arguments,
            bindings=b,
            at_start=substitute_condition(act.at_start, b),
            over_all=substitute_condition(act.over_all, b),
            at_end=substitute_condition(act.at_end, b),
            start_effect=substitute_effect(act.start_effect, b),
            end_effect=substitute_effect(act.end_effect, b),
            duration=self._duration(act, b, state),
            durative=True,
            action=act,
        )

    def _duration(
        self, act: DurativeAction, b: dict[str, str], state: State | None
    ) -> float | None:
        for constraint in act.duration:
            if constraint.op != "=":
                continue
            if state is None:
                try:
                    return self._value(constraint.value, b, _Ctx(self, State(), None))
                except EvaluationError:
                    return None
            return self._value(constraint.value, b, _Ctx(self, state, None))
        return None

    # ------------------------------------------------- atoms for the plan graph

    def condition_atoms(
        self,
        cond: Condition,
        bindings: Mapping[str, str] | None = None,
        state: State | None = None,
    ) -> tuple[set[Atom], set[Atom]]:
        """Ground base atoms ``cond`` needs true (positive) and false (negative).

        Derived atoms are replaced by the base atoms their rules read. With a
        ``state``, a disjunction (or an ``exists``) contributes only the first
        alternative that holds there; without one (or when none holds) all of them.
        """
        from plansys_bridge.knowledge.plan_atoms import AtomWalker

        walker = AtomWalker(self, state)
        walker.walk(cond, normalize_bindings(bindings) if bindings else {}, True)
        return walker.positive, walker.negative

    def condition_fluents(
        self,
        cond: Condition,
        bindings: Mapping[str, str] | None = None,
        state: State | None = None,
    ) -> set[FluentKey]:
        """Ground fluents a condition reads (comparisons; derived bodies included)."""
        from plansys_bridge.knowledge.plan_atoms import AtomWalker

        walker = AtomWalker(self, state)
        walker.walk(cond, normalize_bindings(bindings) if bindings else {}, True)
        return walker.fluents

    def effect_atoms(
        self,
        effect: Effect,
        bindings: Mapping[str, str] | None = None,
        state: State | None = None,
    ) -> tuple[set[Atom], set[Atom], set[FluentKey]]:
        """(adds, deletes, numeric fluent keys) an effect may change.

        With a ``state``, conditional effects count only when their condition holds
        there and ``forall`` ranges over its objects; without one every conditional
        effect counts and ``forall`` ranges over the domain's constants.
        """
        from plansys_bridge.knowledge.plan_atoms import effect_atoms

        return effect_atoms(self, effect, normalize_bindings(bindings) if bindings else {}, state)

    def _context(self, state: State) -> _Ctx:
        return _Ctx(self, state, None)

    def _constants_state(self) -> State:
        return State(objects={c.name: c.types[0] for c in self.domain.constants})

    # ================================================================= conditions

    def _holds(self, cond: Condition, b: Mapping[str, str], ctx: _Ctx) -> bool:
        kind = type(cond)
        if kind is Atom:
            atom: Atom = cond  # type: ignore[assignment]
            return ground_args(atom.args, b) in ctx.tuples(atom.predicate)
        if kind is And:
            return all(self._holds(c, b, ctx) for c in cond.operands)  # type: ignore[union-attr]
        if kind is Not:
            return not self._holds(cond.operand, b, ctx)  # type: ignore[union-attr]
        if kind is Or:
            return any(self._holds(c, b, ctx) for c in cond.operands)  # type: ignore[union-attr]
        if kind is Compare:
            cmp: Compare = cond  # type: ignore[assignment]
            return compare(cmp.op, self._value(cmp.left, b, ctx), self._value(cmp.right, b, ctx))
        if kind is Equals:
            eq: Equals = cond  # type: ignore[assignment]
            left, right = ground_args((eq.left, eq.right), b)
            return left == right
        if kind is Imply:
            imp: Imply = cond  # type: ignore[assignment]
            return not self._holds(imp.antecedent, b, ctx) or self._holds(imp.consequent, b, ctx)
        if kind is Exists:
            ex: Exists = cond  # type: ignore[assignment]
            inner, var_types = self._scope(ex.variables, b)
            return next(self._solve(ex.body, inner, var_types, ctx), None) is not None
        if kind is Forall:
            fa: Forall = cond  # type: ignore[assignment]
            inner, var_types = self._scope(fa.variables, b)
            return next(self._solve(negate(fa.body), inner, var_types, ctx), None) is None
        raise TypeError(f"not a condition: {cond!r}")

    def _scope(
        self, variables: tuple[TypedName, ...], b: Mapping[str, str]
    ) -> tuple[dict[str, str], _VarTypes]:
        var_types = {v.name: self._accepted(v.types) for v in variables}
        inner = {k: v for k, v in b.items() if k not in var_types}
        return inner, var_types

    def _accepted(self, types: tuple[str, ...]) -> frozenset[str] | None:
        """Object types usable for a variable of ``types``; None means any object."""
        try:
            return self._accept_cache[types]
        except KeyError:
            pass
        accepted: frozenset[str] | None
        if OBJECT_TYPE in types:
            accepted = None
        else:
            acc: set[str] = set()
            for t in types:
                acc |= self.types.subtypes(t)
            accepted = frozenset(acc)
        self._accept_cache[types] = accepted
        return accepted

    def _objects_of(self, accepted: frozenset[str] | None, state: State) -> tuple[str, ...]:
        cache = state.object_cache()
        key = (id(self), accepted)
        found = cache.get(key)
        if found is None:
            objects = state.objects
            if accepted is None:
                found = tuple(objects)
            else:
                found = tuple(o for o, t in objects.items() if t in accepted)
            cache[key] = found
        return found

    def _enumerate(
        self, variables: tuple[TypedName, ...], b: Mapping[str, str], ctx: _Ctx
    ) -> Iterator[dict[str, str]]:
        inner, var_types = self._scope(variables, b)
        yield from self._bind_rest(inner, list(var_types), var_types, ctx)

    def _bind_rest(
        self, b: dict[str, str], names: list[str], var_types: _VarTypes, ctx: _Ctx
    ) -> Iterator[dict[str, str]]:
        if not names:
            yield b
            return
        name, rest = names[0], names[1:]
        for obj in self._objects_of(var_types[name], ctx.state):
            nb = dict(b)
            nb[name] = obj
            yield from self._bind_rest(nb, rest, var_types, ctx)

    # ------------------------------------------------------------------ joins

    def _free(self, cond: Condition) -> frozenset[str]:
        """Variables a condition reads that no quantifier inside it binds."""
        entry = self._free_cache.get(id(cond))
        if entry is not None and entry[0] is cond:
            return entry[1]
        result = frozenset(free_vars(cond))
        if len(self._free_cache) > _CACHE_LIMIT:
            self._free_cache.clear()
        self._free_cache[id(cond)] = (cond, result)
        return result

    def _solve(
        self, cond: Condition, b: dict[str, str], var_types: _VarTypes, ctx: _Ctx
    ) -> Iterator[dict[str, str]]:
        """Bindings extending ``b`` that give every variable of ``var_types`` an object
        of its type and make ``cond`` hold."""
        yield from self._join(conjuncts(cond), b, var_types, ctx)

    def _join(
        self, parts: list[Condition], b: dict[str, str], var_types: _VarTypes, ctx: _Ctx
    ) -> Iterator[dict[str, str]]:
        unbound = [v for v in var_types if v not in b]
        if not unbound:
            if all(self._holds(c, b, ctx) for c in parts):
                yield b
            return
        pending = set(unbound)
        # Conditions that are already ground filter first; an ``exists`` joins in with
        # its variables renamed; then the atom with the fewest candidate facts binds
        # variables; a disjunction branches; only then are objects enumerated.
        best: Atom | None = None
        best_size = -1
        branch: Or | None = None
        rest: list[Condition] = []
        for i, c in enumerate(parts):
            free = self._free(c)
            if not free & pending:
                if not self._holds(c, b, ctx):
                    return
                continue
            if isinstance(c, Exists):
                extra, body = self._renamed(c)
                merged = dict(var_types)
                merged.update(extra)
                kept = [*rest, *(x for x in (best, branch) if x is not None)]
                yield from self._join(kept + body + parts[i + 1 :], b, merged, ctx)
                return
            if isinstance(c, Atom):
                size = len(ctx.tuples(c.predicate))
                if best is None or size < best_size:
                    if best is not None:
                        rest.append(best)
                    best, best_size = c, size
                    continue
            elif isinstance(c, Or) and branch is None:
                branch = c
                continue
            rest.append(c)
        if best is not None:
            if branch is not None:
                rest.append(branch)
            for nb in self._match(best, b, var_types, ctx):
                yield from self._join(rest, nb, var_types, ctx)
            return
        if branch is not None:
            for option in branch.operands:
                yield from self._join([*conjuncts(option), *rest], b, var_types, ctx)
            return
        name = unbound[0]
        for obj in self._objects_of(var_types[name], ctx.state):
            nb = dict(b)
            nb[name] = obj
            yield from self._join(rest, nb, var_types, ctx)

    def _renamed(self, cond: Exists) -> tuple[_VarTypes, list[Condition]]:
        """An ``exists`` with fresh variable names, ready to join into a conjunction."""
        entry = self._rename_cache.get(id(cond))
        if entry is not None and entry[0] is cond:
            return entry[1], entry[2]
        suffix = next(self._fresh)
        mapping = {v.name: f"{v.name}#{suffix}" for v in cond.variables}
        extra: _VarTypes = {mapping[v.name]: self._accepted(v.types) for v in cond.variables}
        body = conjuncts(substitute_condition(cond.body, mapping))
        if len(self._rename_cache) > _CACHE_LIMIT:
            self._rename_cache.clear()
        self._rename_cache[id(cond)] = (cond, extra, body)
        return extra, body

    def _match(
        self, atom: Atom, b: dict[str, str], var_types: _VarTypes, ctx: _Ctx
    ) -> Iterator[dict[str, str]]:
        """Bindings extending ``b`` under which ``atom`` is one of the facts."""
        pattern: list[str | None] = []
        new_vars: list[tuple[int, str]] = []
        first_bound = -1
        for i, term in enumerate(atom.args):
            if term[:1] == "?":
                if term in b:
                    pattern.append(b[term])
                    if first_bound < 0:
                        first_bound = i
                elif term in var_types:
                    pattern.append(None)
                    new_vars.append((i, term))
                else:
                    raise UnboundVariableError(f"variable {term} is not bound in {atom}")
            else:
                pattern.append(term)
                if first_bound < 0:
                    first_bound = i
        tuples = ctx.tuples(atom.predicate)
        candidates: Iterable[Args]
        if first_bound >= 0 and isinstance(tuples, frozenset) and len(tuples) > 8:
            value = pattern[first_bound]
            assert value is not None
            candidates = self._by_position(tuples, first_bound).get(value, ())
        else:
            candidates = list(tuples)
        objects = ctx.state.objects
        for args in candidates:
            ok = True
            for want, have in zip(pattern, args, strict=True):
                if want is not None and want != have:
                    ok = False
                    break
            if not ok:
                continue
            nb = dict(b)
            for i, var in new_vars:
                obj = args[i]
                seen = nb.get(var)
                if seen is not None:
                    if seen != obj:
                        ok = False
                        break
                    continue
                accepted = var_types[var]
                if accepted is not None and objects.get(obj) not in accepted:
                    ok = False
                    break
                if accepted is None and obj not in objects:
                    ok = False
                    break
                nb[var] = obj
            if ok:
                yield nb

    def _by_position(self, tuples: frozenset[Args], position: int) -> dict[str, list[Args]]:
        key = (id(tuples), position)
        entry = self._position_index.get(key)
        if entry is not None and entry[0] is tuples:
            with contextlib.suppress(KeyError):  # another thread may have evicted it
                self._position_index.move_to_end(key)
            return entry[1]
        index: dict[str, list[Args]] = {}
        for args in tuples:
            index.setdefault(args[position], []).append(args)
        self._position_index[key] = (tuples, index)
        if len(self._position_index) > 512:
            with contextlib.suppress(KeyError):
                self._position_index.popitem(last=False)
        return index

    # ============================================================ derived predicates

    def _stratify(self) -> list[list[str]]:
        names = list(self._derived_rules)
        if not names:
            return []
        deps: dict[str, list[tuple[str, bool]]] = {n: [] for n in names}
        for name, rules in self._derived_rules.items():
            for rule in rules:
                for pred, negative in predicate_uses(rule.condition, False):
                    if pred in self._derived_rules:
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
                                f"derived predicate {name} of domain {self.domain.name} depends "
                                f"negatively on itself through {pred} (not stratifiable)"
                            )
        strata: dict[int, list[str]] = {}
        for name in names:
            strata.setdefault(level[name], []).append(name)
        return [strata[k] for k in sorted(strata)]

    def _derived_table(self, state: State) -> dict[str, frozenset[Args]]:
        cache = state.cache()
        key = (id(self), "derived")
        table = cache.get(key)
        if table is None:
            table = self._compute_derived(state)
            cache[key] = table
        return table

    def _compute_derived(self, state: State) -> dict[str, frozenset[Args]]:
        """Semi-naive fixpoint per stratum: after a first full round, a recursive rule
        is re-run only in variants reading the facts the previous round found."""
        work: dict[str, set[Args]] = {}
        ctx = _Ctx(self, state, None, work)
        for stratum in self._strata:
            for name in stratum:
                work[name] = set(state.tuples(name))
            delta: dict[str, set[Args]] = {name: set() for name in stratum}
            for name in stratum:
                for rule in self._derived_rules[name]:
                    self._fire(rule, rule.condition, work[name], delta[name], ctx)
            variants = self._deltadelta_variants(stratum)
            while any(delta.values()):
                ctx.delta = {name + DELTA: tuples for name, tuples in delta.items()}
                delta = {name: set() for name in stratum}
                for rule, body in variants:
                    name = rule.head.name
                    self._fire(rule, body, work[name], delta[name], ctx)
            ctx.delta = None
        return {name: frozenset(tuples) for name, tuples in work.items()}

    def _fire(
        self,
        rule: DerivedPredicate,
        body: Condition,
        target: set[Args],
        new: set[Args],
        ctx: _Ctx,
    ) -> None:
        head = [p.name for p in rule.head.parameters]
        var_types = {p.name: self._accepted(p.types) for p in rule.head.parameters}
        for nb in self._solve(body, {}, var_types, ctx):
            args = tuple(nb[v] for v in head)
            if args not in target:
                target.add(args)
                new.add(args)

    def _deltadelta_variants(self, stratum: list[str]) -> list[tuple[DerivedPredicate, Condition]]:
        key = tuple(stratum)
        found = self._variant_cache.get(key)
        if found is None:
            names = set(stratum)
            found = [
                (rule, variant)
                for name in stratum
                for rule in self._derived_rules[name]
                for variant in delta_variants(rule.condition, names)
            ]
            self._variant_cache[key] = found
        return found

    # ==================================================================== numbers

    def _value(self, expr: NumExpr, b: Mapping[str, str], ctx: _Ctx) -> float:
        kind = type(expr)
        if kind is Number:
            return expr.value  # type: ignore[union-attr]
        if kind is FluentRef:
            ref: FluentRef = expr  # type: ignore[assignment]
            args = ground_args(ref.args, b)
            val = ctx.state.value(ref.name, args)
            if val is None:
                raise UndefinedFluentError(ref.name, args)
            return val
        if kind is BinaryOp:
            op: BinaryOp = expr  # type: ignore[assignment]
            left = self._value(op.left, b, ctx)
            right = self._value(op.right, b, ctx)
            if op.op == "+":
                return left + right
            if op.op == "-":
                return left - right
            if op.op == "*":
                return left * right
            if right == 0:
                raise EvaluationError(f"division by zero in {describe_expr(op)}")
            return left / right
        if kind is Negate:
            return -self._value(expr.operand, b, ctx)  # type: ignore[union-attr]
        if kind is DurationRef:
            if ctx.duration is None:
                raise EvaluationError("?duration used where no duration is known")
            return ctx.duration
        raise TypeError(f"not a numeric expression: {expr!r}")

    # ==================================================================== effects

    def _collect(
        self,
        effect: Effect,
        b: Mapping[str, str],
        ctx: _Ctx,
        adds: list[Atom],
        deletes: list[Atom],
        numeric: list[tuple[str, FluentKey, float]],
    ) -> None:
        kind = type(effect)
        if kind is AndEffect:
            for sub in effect.effects:  # type: ignore[union-attr]
                self._collect(sub, b, ctx, adds, deletes, numeric)
        elif kind is AddEffect:
            atom = effect.atom  # type: ignore[union-attr]
            adds.append(Atom(atom.predicate, ground_args(atom.args, b)))
        elif kind is DeleteEffect:
            atom = effect.atom  # type: ignore[union-attr]
            deletes.append(Atom(atom.predicate, ground_args(atom.args, b)))
        elif kind is NumericEffect:
            num: NumericEffect = effect  # type: ignore[assignment]
            key = (num.fluent.name, ground_args(num.fluent.args, b))
            numeric.append((num.op, key, self._value(num.value, b, ctx)))
        elif kind is WhenEffect:
            when: WhenEffect = effect  # type: ignore[assignment]
            if self._holds(when.condition, b, ctx):
                self._collect(when.effect, b, ctx, adds, deletes, numeric)
        elif kind is ForallEffect:
            fa: ForallEffect = effect  # type: ignore[assignment]
            inner, var_types = self._scope(fa.variables, b)
            body = fa.effect
            if isinstance(body, WhenEffect):
                # Let the condition drive the grounding instead of every combination.
                for nb in self._solve(body.condition, inner, var_types, ctx):
                    self._collect(body.effect, nb, ctx, adds, deletes, numeric)
            else:
                for nb in self._bind_rest(inner, list(var_types), var_types, ctx):
                    self._collect(body, nb, ctx, adds, deletes, numeric)
        else:
            raise TypeError(f"not an effect: {effect!r}")
