"""Evaluating PDDL conditions and applying effects against a :class:`State`.

The public face of the knowledge layer's reasoning: the knowledge base, the plan
validator and the executor ask an :class:`Evaluator` whether a condition holds,
what a value is, what an effect changes, which bindings satisfy a condition, and
which atoms a step reads and writes. How it answers lives below it, one meaning
per module: :mod:`.reasoner` (what each construct means), :mod:`.joins`
(quantifiers as joins), :mod:`.derived` (derived predicates, stratified),
:mod:`.plan_atoms` (atoms a condition needs and an effect changes) and
:mod:`.grounding` (substituting objects for parameters).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.context import EvalContext, EvaluationError, UndefinedFluentError
from plansys_bridge.knowledge.formulas import fluent_text
from plansys_bridge.knowledge.grounding import (
    GroundAction,
    UnboundVariableError,
    effect_facts,
    normalize_bindings,
    substitution,
)
from plansys_bridge.knowledge.joins import CACHE_LIMIT
from plansys_bridge.knowledge.plan_atoms import AtomWalker, effect_atoms
from plansys_bridge.knowledge.reasoner import Changes, Reasoner
from plansys_bridge.knowledge.state import Args, FluentKey, State
from plansys_bridge.pddl.model import (
    NO_EFFECT,
    TRUE,
    Action,
    And,
    AnyAction,
    Atom,
    Condition,
    Domain,
    DurativeAction,
    Effect,
    NumExpr,
    TypedName,
)

__all__ = [
    "EvaluationError",
    "Evaluator",
    "GroundAction",
    "UnboundVariableError",
    "UndefinedFluentError",
]


def _plain_changes(effect: Effect) -> tuple[list[Atom], list[Atom]] | None:
    """(adds, deletes) of an effect that only adds and deletes atoms, worked out
    without an evaluation context (nothing is read from the state); None for any
    other effect. The atoms are made as the general walk makes them (no source
    location), and an unbound variable is the same error."""
    found = effect_facts(effect)
    if found is None:
        return None
    adds, deletes = found
    return [Atom(a.predicate, a.args) for a in adds], [Atom(d.predicate, d.args) for d in deletes]


class Evaluator(Reasoner):
    """Evaluates conditions and applies effects of one domain (see module docs)."""

    def __init__(self, domain: Domain) -> None:
        super().__init__(domain)
        self._actions: dict[str, AnyAction] = {a.name: a for a in domain.actions}
        self._plain_facts: dict[int, tuple[Condition, tuple[tuple[str, Args], ...] | None]] = {}
        self._plain_effects: dict[
            int, tuple[Effect, tuple[tuple[Atom, ...], tuple[Atom, ...]] | None]
        ] = {}

    # ================================================================= public API

    def holds(
        self,
        cond: Condition,
        state: State,
        bindings: Mapping[str, str] | None = None,
        duration: float | None = None,
    ) -> bool:
        """True when ``cond`` holds in ``state`` with ``bindings`` (``?x`` -> object).

        A ground atom or conjunction of ground atoms (the executor's requirements)
        is looked up in the state directly: its facts are listed once per condition
        (see :meth:`_plain`), and the plan graph and the executor ask about the
        same conditions again and again. The empty conjunction (``TRUE``, what a
        ground action without a condition has) holds at once."""
        if bindings:
            b = normalize_bindings(bindings)
        else:
            if cond.__class__ is And and not cond.operands:
                return True
            try:
                entry = self._plain_facts[id(cond)]
            except KeyError:
                entry = self._plain(cond)
            if entry[0] is not cond:
                entry = self._plain(cond)
            facts = entry[1]
            if facts is not None:
                # State.has_all, inlined: the executor asks about seven conditions
                # per action, and subscripts (no method call) find a predicate's set.
                index = state._index
                try:
                    for predicate, args in facts:
                        if args not in index[predicate]:
                            return False
                except KeyError:  # no fact of that predicate at all
                    return False
                return True
            b = {}
        return self._holds(cond, b, EvalContext(self, state, duration))

    def _plain(self, cond: Condition) -> tuple[Condition, tuple[tuple[str, Args], ...] | None]:
        """``(cond, facts)``: the (predicate, arguments) pairs that must all be facts
        for ``cond`` to hold when it is a base atom or a conjunction of them with no
        variable (it can then neither raise nor need an evaluation context), else
        ``(cond, None)``; remembered per condition object."""
        parts = cond.operands if type(cond) is And else (cond,)
        # Gathered in a tuple (no call per conjunct): each condition of a plan's
        # ground actions comes here once.
        facts: tuple[tuple[str, Args], ...] = ()
        plain = True
        for part in parts:
            if (
                type(part) is not Atom
                or part.predicate in self._derived_rules
                or type(part.args) is not tuple
            ):
                plain = False
                break
            # a loop, not all() of a generator (a call per argument)
            for a in part.args:
                if type(a) is not str or a[:1] == "?":
                    plain = False
                    break
            if not plain:
                break
            facts += ((part.predicate, part.args),)
        entry = (cond, facts if plain else None)
        if len(self._plain_facts) > CACHE_LIMIT:
            self._plain_facts.clear()
        self._plain_facts[id(cond)] = entry
        return entry

    def plain_changes(self, effect: Effect) -> tuple[tuple[Atom, ...], tuple[Atom, ...]] | None:
        """(adds, deletes) of an effect that only adds and deletes ground atoms,
        which are then the same in every state and with any duration; None for any
        other effect. An unbound variable raises, as :meth:`changes` does."""
        entry = self._plain_effects.get(id(effect))
        if entry is None or entry[0] is not effect:
            entry = self._plain_effect(effect)
        return entry[1]

    def _plain_effect(
        self, effect: Effect
    ) -> tuple[Effect, tuple[tuple[Atom, ...], tuple[Atom, ...]] | None]:
        """``(effect, plain changes or None)``, remembered per effect object (an
        effect that raises is not remembered, so it raises every time).

        Why: the executor applies each ground action's two effects once and works
        out the at-start one's delta first; the plan graph reads them too. Making
        their atoms again each time is most of what applying them costs."""
        found = _plain_changes(effect)
        entry = (effect, None if found is None else (tuple(found[0]), tuple(found[1])))
        if len(self._plain_effects) > CACHE_LIMIT:
            self._plain_effects.clear()
        self._plain_effects[id(effect)] = entry
        return entry

    def value(
        self,
        expr: NumExpr,
        state: State,
        bindings: Mapping[str, str] | None = None,
        duration: float | None = None,
    ) -> float:
        """The value of a numeric expression; an undefined fluent raises naming it."""
        b = normalize_bindings(bindings) if bindings else {}
        return self._value(expr, b, EvalContext(self, state, duration))

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
        """What ``effect`` would do: (adds, deletes, new fluent values), nothing applied.

        An effect of ground facts only is worked out once per effect object (see
        :meth:`plain_changes`) and handed out as new lists each time.
        """
        if not bindings:
            plain = self.plain_changes(effect)
            if plain is not None:  # the same answer in every state
                return list(plain[0]), list(plain[1]), {}
        b = normalize_bindings(bindings) if bindings else {}
        ctx = EvalContext(self, state, duration)
        gathered = Changes()
        self._collect(effect, b, ctx, gathered)
        updates: dict[FluentKey, float] = {}
        for op, key, val in gathered.numeric:
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
        return gathered.adds, gathered.deletes, updates

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
        ctx = EvalContext(self, state, duration)
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

    def bind(
        self, action: AnyAction | str, args: Sequence[str], state: State | None = None
    ) -> tuple[AnyAction, dict[str, str]]:
        """``action`` and its parameters' bindings to ``args``, nothing substituted.

        With a ``state`` the arguments are checked: known objects of the right type.
        """
        act = self.get_action(action) if isinstance(action, str) else action
        arguments = tuple([a.lower() for a in args])
        if len(arguments) != len(act.parameters):
            raise KnowledgeError(
                f"action {act.name} takes {len(act.parameters)} arguments, got {len(arguments)}: "
                f"({' '.join((act.name, *arguments))})"
            )
        if state is not None:
            objects = state.objects
            is_subtype = self.types.is_subtype
            for param, arg in zip(act.parameters, arguments, strict=True):
                obj_type = objects.get(arg)
                if obj_type is None:
                    raise KnowledgeError(
                        f"action ({act.name} {' '.join(arguments)}): unknown object {arg!r}"
                    )
                # types.is_subtype_of_any((obj_type,), param.types), as a loop
                for wanted in param.types:
                    if is_subtype(obj_type, wanted):
                        break
                else:
                    raise KnowledgeError(
                        f"action ({act.name} {' '.join(arguments)}): {arg} is a {obj_type}, "
                        f"parameter {param.name} wants {' or '.join(param.types)}"
                    )
        return act, {p.name: a for p, a in zip(act.parameters, arguments, strict=True)}

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
        act, b = self.bind(action, args, state)
        arguments = tuple(b.values())
        sub = substitution(b)  # one substitution for the five parts
        if isinstance(act, Action):
            return GroundAction(
                name=act.name,
                args=arguments,
                bindings=b,
                at_start=TRUE,
                over_all=sub(act.precondition),
                at_end=TRUE,
                start_effect=NO_EFFECT,
                end_effect=sub(act.effect),
                duration=None,
                durative=False,
                action=act,
            )
        return GroundAction(
            name=act.name,
            args=arguments,
            bindings=b,
            at_start=sub(act.at_start),
            over_all=sub(act.over_all),
            at_end=sub(act.at_end),
            start_effect=sub(act.start_effect),
            end_effect=sub(act.end_effect),
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
                    return self._value(constraint.value, b, self._context(State()))
                except EvaluationError:
                    return None
            return self._value(constraint.value, b, self._context(state))
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
        return effect_atoms(self, effect, normalize_bindings(bindings) if bindings else {}, state)
