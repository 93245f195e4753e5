"""What an effect reads and how it writes: the accesses the plan graph orders.

A conditional effect reads its condition, a numeric effect reads the fluents of its
value, and numeric updates of one kind (increases, scalings) commute with each
other while an assignment commutes with nothing. The plan graph builder uses these
to decide which happenings must keep their plan order. Effects and expressions
are walked with :mod:`plansys_bridge.pddl.walkers`, so a new construct is walked
here as its lowered form without an edit.
"""

from __future__ import annotations

from collections.abc import Container, Iterable, Iterator, Mapping
from collections.abc import Set as AbstractSet
from dataclasses import dataclass
from typing import TypeAlias

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    TRUE,
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
    FluentRef,
    ForallEffect,
    Negate,
    Not,
    Number,
    NumericEffect,
    NumExpr,
    WhenEffect,
    is_variable,
)
from plansys_bridge.pddl.walkers import Visitor, iter_nodes
from plansys_bridge.planning.orderings import GROUND

__all__ = [
    "EffectAccess",
    "Var",
    "condition_vars",
    "effect_access",
    "expr_fluents",
    "fixed_condition_vars",
    "fixed_effect_access",
    "fixed_reads",
    "ground_fluent",
    "literal_atoms",
    "numeric_class",
    "reads_fixed",
    "var_key",
    "walk_effect",
    "writes_fixed",
    "written_names",
]

Parts = Iterator[tuple[Effect, Mapping[str, str]]]

Var: TypeAlias = tuple[str, object]
"""("a", Atom) for a ground atom, ("f", FluentKey) for a numeric fluent."""


def var_key(var: Var) -> tuple[str, str, tuple[str, ...]]:
    """A sort key for variables: kind, predicate or function name, arguments.

    Why: the sets of variables an effect or condition reads and writes iterate in
    the order of their hashes, which follow the string hash seed; the plan graph
    visits them in this order instead, so the fact an ordering's reason names (when
    several order the same pair) is the same in every process."""
    kind, what = var
    if kind == "a":
        atom: Atom = what  # type: ignore[assignment]
        return kind, atom.predicate, atom.args
    key: FluentKey = what  # type: ignore[assignment]
    return kind, key[0], key[1]


def _atom_key(atom: Atom) -> tuple[str, tuple[str, ...]]:
    return atom.predicate, atom.args


def numeric_class(op: str) -> str:
    """Which numeric updates commute: ``add`` (increase/decrease) with each other,
    ``mul`` (scalings) with each other, an ``assign`` with nothing."""
    if op in ("increase", "decrease"):
        return "add"
    if op in ("scale-up", "scale-down"):
        return "mul"
    return "assign"


def walk_effect(effect: Effect, bindings: Mapping[str, str], ev: Evaluator, state: State) -> Parts:
    """Sub-effects with their bindings: every conditional effect (its condition is
    read) and every leaf; a ``forall`` is expanded over the objects of its
    variables' types in ``state`` (as the evaluator applies it)."""
    return _EffectParts(ev, state).walk(effect, bindings)


class _EffectParts(Visitor[Parts]):
    kinds = ("effect",)

    def __init__(self, ev: Evaluator, state: State) -> None:
        self.ev = ev
        self.state = state

    def walk_and_effect(self, effect: AndEffect, bindings: Mapping[str, str]) -> Parts:
        for sub in effect.effects:
            yield from self.walk(sub, bindings)

    def walk_when_effect(self, effect: WhenEffect, bindings: Mapping[str, str]) -> Parts:
        yield effect, bindings
        yield from self.walk(effect.effect, bindings)

    def walk_forall_effect(self, effect: ForallEffect, bindings: Mapping[str, str]) -> Parts:
        for found in self.ev.satisfying_bindings(TRUE, self.state, effect.variables, bindings):
            yield from self.walk(effect.effect, {**bindings, **found})

    def _leaf(self, effect: Effect, bindings: Mapping[str, str]) -> Parts:
        yield effect, bindings

    walk_add_effect = walk_delete_effect = walk_numeric_effect = _leaf


def ground_fluent(ref: FluentRef, bindings: Mapping[str, str]) -> FluentKey | None:
    """``ref`` with ``bindings`` substituted, or None while a variable is left."""
    args = tuple(bindings.get(a, a) if is_variable(a) else a for a in ref.args)
    if any(is_variable(a) for a in args):
        return None
    return (ref.name, args)


def expr_fluents(expr: NumExpr, bindings: Mapping[str, str]) -> set[FluentKey]:
    """The ground fluents a numeric expression reads."""
    keys = (ground_fluent(n, bindings) for n in iter_nodes(expr) if isinstance(n, FluentRef))
    return {key for key in keys if key is not None}


_EXPRESSIONS = (Number, FluentRef, DurationRef, BinaryOp, Negate)


def reads_fixed(cond: Condition, derived: Container[str], positive: bool = True) -> bool:
    """Whether what ``cond`` reads is the same in every state.

    Why: the plan graph asks for the atoms and fluents each happening's condition
    reads, and a plan repeats the same ground actions many times. The answer depends
    on the state only through a choice (a disjunction, a quantifier, a conjunction
    under a negation, several rules of a derived predicate) or a derived predicate's
    body; a condition with none of those (conjunctions of literals and comparisons,
    the usual case) reads the same atoms everywhere, so its answer can be kept.
    Anything not recognised here counts as not fixed.
    """
    kind = type(cond)
    if kind is Atom:
        return cond.predicate not in derived  # type: ignore[union-attr]
    if kind is Equals:
        return True
    if kind is And:
        return positive and all(reads_fixed(c, derived) for c in cond.operands)  # type: ignore[union-attr]
    if kind is Not:
        return reads_fixed(cond.operand, derived, not positive)  # type: ignore[union-attr]
    if kind is Compare:
        return all(type(n) in _EXPRESSIONS for n in iter_nodes(cond) if n is not cond)
    return False


def writes_fixed(effect: Effect) -> bool:
    """Whether what ``effect`` reads and writes is the same in every state: no
    conditional effect and no ``forall`` (see :func:`reads_fixed` for why)."""
    kind = type(effect)
    if kind is AndEffect:
        return all(writes_fixed(e) for e in effect.effects)  # type: ignore[union-attr]
    if kind is NumericEffect:
        value = effect.value  # type: ignore[union-attr]
        return all(type(n) in _EXPRESSIONS for n in iter_nodes(value))
    return kind is AddEffect or kind is DeleteEffect


def written_names(effect: Effect) -> set[tuple[str, str]] | None:
    """``("a", predicate)`` and ``("f", fluent name)`` of everything ``effect`` may
    change, in any state; None when it holds a construct not known here (it may
    then change anything).

    Why: an over-all requirement on a variable no action changes (a map's
    ``connected`` facts) can never be broken, so the plan graph builder need not
    watch it while its action runs.
    """
    kind = type(effect)
    if kind is AddEffect or kind is DeleteEffect:
        return {("a", effect.atom.predicate)}  # type: ignore[union-attr]
    if kind is NumericEffect:
        return {("f", effect.fluent.name)}  # type: ignore[union-attr]
    if kind is WhenEffect or kind is ForallEffect:
        return written_names(effect.effect)  # type: ignore[union-attr]
    if kind is AndEffect:
        names: set[tuple[str, str]] = set()
        for sub in effect.effects:  # type: ignore[union-attr]
            found = written_names(sub)
            if found is None:
                return None
            names |= found
        return names
    return None


def condition_vars(
    ev: Evaluator, cond: Condition, bindings: Mapping[str, str], state: State
) -> set[Var]:
    """Every base atom and fluent ``cond`` reads in ``state`` (derived predicates
    expanded; of a disjunction only the branch that holds there)."""
    if isinstance(cond, And) and not cond.operands:
        return set()
    pos, neg = ev.condition_atoms(cond, bindings, state)
    out: set[Var] = {("a", atom) for atom in pos | neg}
    out |= {("f", key) for key in ev.condition_fluents(cond, bindings, state)}
    return out


def fixed_condition_vars(cond: Condition) -> set[Var] | None:
    """:func:`condition_vars` of a ground condition :func:`reads_fixed` accepts,
    read off its structure: the same set, built in the same order (atoms in the
    order the evaluator's walk meets them, positive then negative, then fluents),
    so that it also iterates the same way. None when an argument is a variable
    (the evaluator's walk names it).

    Why: a plan has a few conditions per ground action, and the evaluator's walk
    sets up an evaluation context for each; these need none.
    """
    found = fixed_reads(cond)
    return None if found is None else found[0]


Literals: TypeAlias = tuple[tuple[Atom, ...], tuple[Atom, ...]]
"""The atoms that must be true and those that must be false (see :func:`literal_atoms`)."""


def fixed_reads(cond: Condition) -> tuple[set[Var], Literals | None] | None:
    """:func:`fixed_condition_vars` and :func:`literal_atoms` of a condition
    :func:`reads_fixed` accepts, in one walk (the plan graph builder asks for both
    once per ground action's condition); None when an argument is a variable."""
    if type(cond) is And and not cond.operands:
        return set(), ((), ())
    pos: set[Atom] = set()
    neg: set[Atom] = set()
    fluents: set[FluentKey] = set()
    true: list[Atom] = []
    false: list[Atom] = []
    literal = True
    stack: list[tuple[Condition, bool]] = [(cond, True)]
    while stack:
        node, positive = stack.pop()
        kind = type(node)
        if kind is Atom:
            args = node.args  # type: ignore[union-attr]
            if type(args) is not tuple or _variable_in(args):
                return None
            # the atom itself: equal, with the same hash, to the evaluator's new one
            if positive:
                pos.add(node)  # type: ignore[arg-type]
                true.append(node)  # type: ignore[arg-type]
            else:
                neg.add(node)  # type: ignore[arg-type]
                false.append(node)  # type: ignore[arg-type]
        elif kind is And:
            stack += [(c, positive) for c in reversed(node.operands)]  # type: ignore[union-attr]
        elif kind is Not:
            operand = node.operand  # type: ignore[union-attr]
            if not positive or type(operand) is not Atom:
                literal = False  # literals negate an atom, once
            stack.append((operand, not positive))
        elif kind is Compare:
            literal = False
            for n in iter_nodes(node):
                if type(n) is FluentRef:
                    if type(n.args) is not tuple or _variable_in(n.args):
                        return None
                    fluents.add((n.name, n.args))
        elif kind is Equals:
            literal = False
        else:
            return None
    out: set[Var] = {("a", atom) for atom in pos | neg}
    out |= {("f", key) for key in fluents}
    return out, (tuple(true), tuple(false)) if literal else None


def _variable_in(args: tuple[str, ...]) -> bool:
    """Whether an argument is a variable (a loop: ``any()`` of a generator is a
    call per argument)."""
    for a in args:  # noqa: SIM110
        if a[:1] == "?":
            return True
    return False


def literal_atoms(cond: Condition) -> tuple[tuple[Atom, ...], tuple[Atom, ...]] | None:
    """The atoms that must be true and those that must be false for ``cond`` to
    hold, when it is a conjunction of ground literals of base predicates (the
    caller checks :func:`reads_fixed`, which refuses derived ones); else None.

    Why: the plan graph builder checks such a condition (nearly every at-start
    requirement) on the truth values it keeps per atom, without a state."""
    pos: list[Atom] = []
    neg: list[Atom] = []
    stack: list[Condition] = [cond]
    while stack:
        node = stack.pop()
        kind = type(node)
        positive = kind is not Not
        if not positive:
            node = node.operand  # type: ignore[union-attr]
            kind = type(node)
        elif kind is And:
            stack += reversed(node.operands)  # type: ignore[union-attr]
            continue
        if kind is not Atom:
            return None
        args = node.args  # type: ignore[union-attr]
        if type(args) is not tuple or _variable_in(args):
            return None
        (pos if positive else neg).append(node)  # type: ignore[arg-type]
    return tuple(pos), tuple(neg)


def _fixed_effect_parts(
    effect: Effect,
) -> tuple[set[Atom], set[Atom], set[FluentKey], list[NumericEffect]] | None:
    """``Evaluator.effect_atoms`` of an effect :func:`writes_fixed` accepts (adds,
    deletes, numeric fluents, each set built in the evaluator's order) and its
    numeric leaves in order; None when an argument is a variable."""
    adds: set[Atom] = set()
    deletes: set[Atom] = set()
    fluents: set[FluentKey] = set()
    numeric: list[NumericEffect] = []
    stack: list[Effect] = [effect]
    while stack:
        node = stack.pop()
        kind = type(node)
        if kind is AndEffect:
            stack += reversed(node.effects)  # type: ignore[union-attr]
            continue
        if kind is NumericEffect:
            ref: FluentRef = node.fluent  # type: ignore[union-attr]
            if type(ref.args) is not tuple or _variable_in(ref.args):
                return None
            fluents.add((ref.name, ref.args))
            numeric.append(node)  # type: ignore[arg-type]
            continue
        atom: Atom = node.atom  # type: ignore[union-attr]
        if type(atom.args) is not tuple or _variable_in(atom.args):
            return None
        if type(atom) is not Atom:
            atom = Atom(atom.predicate, atom.args)
        (adds if kind is AddEffect else deletes).add(atom)
    return adds, deletes, fluents, numeric


@dataclass(frozen=True)
class EffectAccess:
    """What one ground effect reads and writes (see :func:`effect_access`)."""

    adds: AbstractSet[Atom]
    read: tuple[Var, ...]
    """In :func:`var_key` order."""
    writes: tuple[tuple[Var, str], ...]
    """(variable, kind of write: ``del``, ``add`` or a numeric class): the deletes,
    the adds, the fluents, each in :func:`var_key` order."""
    written: AbstractSet[Var]
    deleted: AbstractSet[Atom] = frozenset()
    """The atoms deleted and not added again."""
    plain: bool = False
    """Applying the effect to any state only deletes ``deleted`` and adds ``adds``."""


def effect_access(ev: Evaluator, effect: Effect, state: State, fixed: bool = False) -> EffectAccess:
    """What a ground effect reads and writes in ``state``: the conditions of its
    conditional effects and the values of its numeric effects are reads; deletes
    that it also adds count as adds. ``fixed``: the caller knows the effect does
    the same in every state (:func:`writes_fixed`)."""
    found = fixed_effect_access(effect) if fixed else None
    if found is not None:
        return found
    adds, deletes, numeric = ev.effect_atoms(effect, GROUND, state)
    walked = walk_effect(effect, GROUND, ev, state)
    return _access(ev, state, adds, deletes, numeric, walked, fixed)


def fixed_effect_access(effect: Effect) -> EffectAccess | None:
    """:func:`effect_access` of an effect :func:`writes_fixed` accepts, read off its
    structure without a state (the plan graph builder then need not bring its
    simulated state up to date); None when an argument is a variable."""
    parts = _fixed_effect_parts(effect)
    if parts is None:
        return None
    adds, deletes, numeric, leaves = parts
    return _access(None, None, adds, deletes, numeric, [(e, GROUND) for e in leaves], True)


def _access(
    ev: Evaluator | None,
    state: State | None,
    adds: AbstractSet[Atom],
    deletes: AbstractSet[Atom],
    numeric: AbstractSet[FluentKey],
    walked: Iterable[tuple[Effect, Mapping[str, str]]],
    fixed: bool,
) -> EffectAccess:
    read: set[Var] = set()
    ops: dict[FluentKey, str] = {}
    for sub, binds in walked:
        if isinstance(sub, WhenEffect):
            assert ev is not None and state is not None  # a fixed effect has no condition
            read |= condition_vars(ev, sub.condition, binds, state)
        elif isinstance(sub, NumericEffect):
            key = ground_fluent(sub.fluent, binds)
            if key is not None:
                cls = numeric_class(sub.op)
                ops[key] = cls if ops.get(key, cls) == cls else "assign"
            read |= {("f", k) for k in expr_fluents(sub.value, binds)}
    # in a fixed order (see var_key): deletes, adds, fluents, each sorted
    deleted = deletes - adds
    writes: list[tuple[Var, str]] = [
        (("a", atom), "del") for atom in sorted(deleted, key=_atom_key)
    ]
    writes += [(("a", atom), "add") for atom in sorted(adds, key=_atom_key)]
    writes += [(("f", key), ops.get(key, "assign")) for key in sorted(numeric)]
    written = {v for v, _ in writes}
    plain = fixed and not numeric
    reads = tuple(sorted(read, key=var_key))
    return EffectAccess(adds, reads, tuple(writes), written, deleted, plain)
