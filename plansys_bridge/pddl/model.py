"""The typed PDDL model: immutable dataclasses shared by every part of the project.

Why frozen dataclasses: models are hashed into sets (facts), shared between the
knowledge base, the planner and the executor without defensive copies, and compared
for the parser/writer round trip. Names are stored lower-case (PDDL is
case-insensitive). Terms are plain strings: a variable keeps its leading ``?``
(``"?r"``), an object or constant is its bare name (``"r2d2"``). That keeps grounding
a cheap tuple substitution.

Source locations are kept on the nodes a user can get wrong (declarations and uses)
but excluded from equality, so a round-tripped model compares equal.

Conditions, effects and numeric expressions are walked through
:mod:`plansys_bridge.pddl.walkers`, which reads each node's children off these
field types. A construct that can be written with older ones says so in a
``lower()`` method, and every walk without a method of its own for it uses that.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from typing import Literal, TypeAlias

from plansys_bridge.errors import SourceLocation

Term: TypeAlias = str
"""A variable (``"?x"``) or an object/constant name (``"kitchen"``)."""

OBJECT_TYPE = "object"
NUMBER_TYPE = "number"


def is_variable(term: Term) -> bool:
    """True for ``?x`` terms."""
    return term.startswith("?")


# ---------------------------------------------------------------- declarations


@dataclass(frozen=True)
class TypedName:
    """A parameter, object or constant with its type(s); ``either`` gives several."""

    name: str
    types: tuple[str, ...] = (OBJECT_TYPE,)
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)


@dataclass(frozen=True)
class TypeDef:
    """A declared type and its direct parent types (``either`` parents allowed)."""

    name: str
    parents: tuple[str, ...] = (OBJECT_TYPE,)
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)


@dataclass(frozen=True)
class PredicateDef:
    name: str
    parameters: tuple[TypedName, ...] = ()
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)

    @property
    def arity(self) -> int:
        return len(self.parameters)


@dataclass(frozen=True)
class FunctionDef:
    name: str
    parameters: tuple[TypedName, ...] = ()
    return_type: str = NUMBER_TYPE
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)

    @property
    def arity(self) -> int:
        return len(self.parameters)


# ---------------------------------------------------------------- numeric expressions


@dataclass(frozen=True)
class Number:
    value: float


@dataclass(frozen=True)
class FluentRef:
    """A function application ``(battery ?r)`` used as a numeric value."""

    name: str
    args: tuple[Term, ...] = ()
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)


@dataclass(frozen=True)
class DurationRef:
    """``?duration`` inside a durative action."""


@dataclass(frozen=True)
class BinaryOp:
    op: Literal["+", "-", "*", "/"]
    left: NumExpr
    right: NumExpr


@dataclass(frozen=True)
class Negate:
    operand: NumExpr


NumExpr: TypeAlias = Number | FluentRef | DurationRef | BinaryOp | Negate


# ---------------------------------------------------------------- conditions


@dataclass(frozen=True, init=False)
class Atom:
    """A predicate application; ground when no argument is a variable.

    Its hash is worked out once, when it is made, and handed to Python without a
    Python-level call: facts are hashed over and over (journaled tables, sets of
    facts, memos, the executor's sets), and a ``def __hash__`` costs a Python frame
    each time (the generated one also built and hashed a tuple). The slot named
    ``__hash__`` holds the bound ``__index__`` of the kept hash, a C method returning
    that very int, which the interpreter's hash slot calls as it would a method;
    ``hash(atom)`` is ``hash((predicate, args))`` as before. Equality, ``repr`` and
    ``fields`` are the dataclass's own; the kept hash is left out of pickles and
    copies (string hashes differ from one process to the next) and worked out
    again when they are loaded. Arguments that cannot be hashed (a list) make an
    atom whose hashing fails as it always did, with the same ``TypeError``.
    """

    __slots__ = ("__dict__", "__hash__", "__weakref__")

    predicate: str
    args: tuple[Term, ...] = ()
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)

    def __init__(
        self, predicate: str, args: tuple[Term, ...] = (), loc: SourceLocation | None = None
    ) -> None:
        # Written straight into the instance dict: a frozen dataclass's own __init__
        # goes through object.__setattr__ once per field.
        d = self.__dict__
        d["predicate"] = predicate
        d["args"] = args
        d["loc"] = loc
        try:
            kept = hash((predicate, args)).__index__
        except TypeError:  # unhashable arguments (a list): hashing fails as it always did
            kept = partial(hash, (predicate, args))
        _set_hash(self, kept)

    def __getstate__(self) -> dict[str, object]:
        return {"predicate": self.predicate, "args": self.args, "loc": self.loc}

    def __setstate__(self, state: dict[str, object]) -> None:
        Atom.__init__(self, **state)  # type: ignore[arg-type]

    def __str__(self) -> str:
        return "(" + " ".join((self.predicate, *self.args)) + ")"


_set_hash = Atom.__dict__["__hash__"].__set__
"""Writes an atom's ``__hash__`` slot (the frozen dataclass refuses attribute writes)."""


@dataclass(frozen=True)
class Equals:
    """Object equality ``(= ?a ?b)``."""

    left: Term
    right: Term


@dataclass(frozen=True)
class Not:
    operand: Condition


@dataclass(frozen=True)
class And:
    operands: tuple[Condition, ...] = ()


@dataclass(frozen=True)
class Or:
    operands: tuple[Condition, ...] = ()


@dataclass(frozen=True)
class Imply:
    antecedent: Condition
    consequent: Condition

    def lower(self) -> Condition:
        """``(or (not a) b)``: what a walk without an ``imply`` of its own sees."""
        return Or((Not(self.antecedent), self.consequent))


@dataclass(frozen=True)
class Exists:
    variables: tuple[TypedName, ...]
    body: Condition


@dataclass(frozen=True)
class Forall:
    variables: tuple[TypedName, ...]
    body: Condition

    def lower(self) -> Condition:
        """``(not (exists (...) (not body)))``, for walks without a ``forall`` of their own."""
        return Not(Exists(self.variables, Not(self.body)))


@dataclass(frozen=True)
class Compare:
    """Numeric comparison; ``=`` between numeric expressions lands here."""

    op: Literal["<", "<=", "=", ">=", ">"]
    left: NumExpr
    right: NumExpr


Condition: TypeAlias = Atom | Equals | Not | And | Or | Imply | Exists | Forall | Compare

TRUE = And(())
"""The empty conjunction: a condition that always holds."""


# ---------------------------------------------------------------- effects


@dataclass(frozen=True)
class AddEffect:
    atom: Atom


@dataclass(frozen=True)
class DeleteEffect:
    atom: Atom


@dataclass(frozen=True)
class NumericEffect:
    op: Literal["assign", "increase", "decrease", "scale-up", "scale-down"]
    fluent: FluentRef
    value: NumExpr


@dataclass(frozen=True)
class AndEffect:
    effects: tuple[Effect, ...] = ()


@dataclass(frozen=True)
class WhenEffect:
    condition: Condition
    effect: Effect


@dataclass(frozen=True)
class ForallEffect:
    variables: tuple[TypedName, ...]
    effect: Effect


Effect: TypeAlias = AddEffect | DeleteEffect | NumericEffect | AndEffect | WhenEffect | ForallEffect

NO_EFFECT = AndEffect(())


# ---------------------------------------------------------------- actions


@dataclass(frozen=True)
class DurationConstraint:
    """``(= ?duration expr)``; ``<=``/``>=`` for duration inequalities."""

    op: Literal["=", "<=", ">="]
    value: NumExpr


@dataclass(frozen=True)
class Action:
    """A plain ``:action``. The executor treats its precondition as over-all and its
    effect as at-end (PlanSys2's rule)."""

    name: str
    parameters: tuple[TypedName, ...] = ()
    precondition: Condition = TRUE
    effect: Effect = NO_EFFECT
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)


@dataclass(frozen=True)
class DurativeAction:
    name: str
    parameters: tuple[TypedName, ...] = ()
    duration: tuple[DurationConstraint, ...] = ()
    at_start: Condition = TRUE
    over_all: Condition = TRUE
    at_end: Condition = TRUE
    start_effect: Effect = NO_EFFECT
    end_effect: Effect = NO_EFFECT
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)


AnyAction: TypeAlias = Action | DurativeAction


@dataclass(frozen=True)
class DerivedPredicate:
    """``(:derived (p ?x) condition)``; ``head`` parameters are typed."""

    head: PredicateDef
    condition: Condition
    loc: SourceLocation | None = field(default=None, compare=False, hash=False, repr=False)


# ---------------------------------------------------------------- domain / problem


@dataclass(frozen=True)
class Domain:
    name: str
    requirements: tuple[str, ...] = ()
    types: tuple[TypeDef, ...] = ()
    constants: tuple[TypedName, ...] = ()
    predicates: tuple[PredicateDef, ...] = ()
    functions: tuple[FunctionDef, ...] = ()
    actions: tuple[AnyAction, ...] = ()
    derived: tuple[DerivedPredicate, ...] = ()
    source: str | None = field(default=None, compare=False, hash=False, repr=False)
    """File name(s) the domain was read from, for error messages."""


@dataclass(frozen=True)
class FluentValue:
    """An ``(= (f o1 o2) 3.5)`` initial value."""

    fluent: FluentRef
    value: float


@dataclass(frozen=True)
class Metric:
    direction: Literal["minimize", "maximize"]
    expression: NumExpr | Literal["total-time"]


@dataclass(frozen=True)
class Problem:
    name: str
    domain_name: str
    requirements: tuple[str, ...] = ()
    objects: tuple[TypedName, ...] = ()
    init: tuple[Atom, ...] = ()
    init_fluents: tuple[FluentValue, ...] = ()
    goal: Condition = TRUE
    metric: Metric | None = None
    source: str | None = field(default=None, compare=False, hash=False, repr=False)
