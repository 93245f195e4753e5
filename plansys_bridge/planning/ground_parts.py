"""A plain happening's condition and effect with its step's arguments in place.

The plan validator checks each happening's condition, applies its effect and, when
it is simultaneous with others, compares what it touches with theirs. For a plain
action (see :class:`~plansys_bridge.planning.footprint.LiftedFootprint`) all three
come from the same ground atoms, so they are worked out once per happening, as
``(predicate, arguments)`` pairs: substituting the arguments for each of the three,
and building :class:`~plansys_bridge.knowledge.state.State` snapshots and
:class:`~plansys_bridge.pddl.model.Atom` objects for them, was most of a validation.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Protocol

from plansys_bridge.pddl.model import Atom
from plansys_bridge.planning.footprint import Args, Footprint, LiftedFootprint

__all__ = ["AtomKey", "CompiledParts", "GroundParts", "interference"]


class _Facts(Protocol):
    def has(self, predicate: str, args: Args) -> bool: ...


AtomKey = tuple[str, Args]

_Grounder = Callable[[Args], tuple[list[AtomKey], list[AtomKey], list[AtomKey], list[AtomKey]]]


@functools.lru_cache(maxsize=4096)
def _grounder(
    positive: tuple[tuple[str, Args], ...],
    negative: tuple[tuple[str, Args], ...],
    adds: tuple[tuple[str, Args], ...],
    deletes: tuple[tuple[str, Args], ...],
    names: Args,
) -> _Grounder:
    """A function from a step's argument values (in the order of ``names``) to the
    template's positive, negative, added and deleted atoms with them in place.

    Why generated: grounding is done for each of a plan's happenings, and a body
    that builds the four lists as literals (``[(p0, (v[0], v[2])), ...]``) is one
    Python call where a loop per part and a getter per atom were a dozen. The source
    holds only generated names and indices: the predicates and constant arguments
    (from the PDDL) are values in its namespace. Generated functions are kept by the
    atoms they ground (compiling one costs more than a validation grounds with it,
    and each validation has its own templates).
    """
    namespace: dict[str, object] = {}

    def value(item: object) -> str:
        name = f"k{len(namespace)}"
        namespace[name] = item
        return name

    def argument(arg: str) -> str:
        return f"v[{names.index(arg)}]" if arg in names else value(arg)

    def atoms(items: tuple[tuple[str, Args], ...]) -> str:
        out = []
        for predicate, args in items:
            inner = ", ".join([argument(a) for a in args])
            out.append(f"({value(predicate)}, ({inner}{',' if len(args) == 1 else ''}))")
        return "[" + ", ".join(out) + "]"

    body = ", ".join([atoms(positive), atoms(negative), atoms(adds), atoms(deletes)])
    exec(compile(f"def ground(v):\n    return ({body})\n", "<ground_parts>", "exec"), namespace)
    return namespace["ground"]  # type: ignore[return-value]


class CompiledParts:
    """A template with the function that puts a step's arguments in place (see
    :func:`_grounder`), for one order of parameters."""

    __slots__ = ("_ground", "template")

    def __init__(self, template: LiftedFootprint, names: Args) -> None:
        self.template = template
        self._ground = _grounder(
            template.positive, template.negative, template.adds, template.deletes, names
        )

    def ground(self, values: Args, bindings: Mapping[str, str]) -> GroundParts:
        """The parts of one happening whose arguments are ``values`` (``bindings``)."""
        positive, negative, adds, deletes = self._ground(values)
        return GroundParts(self.template, bindings, positive, negative, adds, deletes)


def _key_text(key: AtomKey) -> str:
    return "(" + " ".join((key[0], *key[1])) + ")"


class GroundParts:
    """A plain happening's condition and effect with its arguments in place, worked
    out once: its condition is checked, its footprint compared and its effect applied
    from these (substituting the arguments for each of the three was most of a
    validation's time). Atoms are ``(predicate, arguments)`` pairs here."""

    __slots__ = (
        "_bindings",
        "_footprint",
        "_reads",
        "_sets",
        "_template",
        "adds",
        "deletes",
        "negative",
        "positive",
    )

    def __init__(
        self,
        template: LiftedFootprint,
        bindings: Mapping[str, str],
        positive: list[AtomKey],
        negative: list[AtomKey],
        adds: list[AtomKey],
        deletes: list[AtomKey],
    ) -> None:
        self._template = template
        self._bindings = bindings
        self.positive = positive
        self.negative = negative
        self.adds = adds
        self.deletes = deletes
        self._footprint: Footprint | None = None
        self._reads: set[tuple[str, Args]] | None = None
        self._sets: tuple[set[AtomKey], set[AtomKey], set[AtomKey]] | None = None

    @property
    def literals(self) -> bool:
        """The condition is a conjunction of literals: :meth:`holds` decides it."""
        return self._template.literals

    @property
    def plain_effect(self) -> bool:
        """The effect is adds and deletes only (no numeric change): ``adds`` and
        ``deletes`` are all it does."""
        return not self._template.writes

    def holds(self, state: _Facts) -> bool:
        """Whether the condition, a conjunction of literals, holds in ``state``."""
        has = state.has
        for p, a in self.positive:
            if not has(p, a):
                return False
        return not self.negative or not any(has(p, a) for p, a in self.negative)

    def reads(self) -> set[tuple[str, Args]]:
        """The atoms and fluents the condition reads, as ``(name, arguments)``."""
        if self._reads is None:
            self._reads = {*self.positive, *self.negative}
            if self._template.fluent_reads:
                self._reads.update(self.footprint().fluent_reads)
        return self._reads

    def interferes(self, other: GroundParts | Footprint) -> str | None:
        """As :meth:`Footprint.interferes`; two happenings without numeric parts are
        compared on their atoms as pairs, without building footprints."""
        if isinstance(other, Footprint) or not (self._atoms_only and other._atoms_only):
            return self.footprint().interferes(_footprint(other))
        reads, adds, deletes = self._atom_sets()
        theirs_reads, theirs_adds, theirs_deletes = other._atom_sets()
        for common in (
            adds & theirs_deletes,
            deletes & theirs_adds,
            (adds | deletes) & theirs_reads,
            (theirs_adds | theirs_deletes) & reads,
        ):
            if common:
                return min(_key_text(key) for key in common)
        return None

    @property
    def _atoms_only(self) -> bool:
        return not (self._template.fluent_reads or self._template.writes)

    def _atom_sets(self) -> tuple[set[AtomKey], set[AtomKey], set[AtomKey]]:
        if self._sets is None:
            self._sets = ({*self.positive, *self.negative}, set(self.adds), set(self.deletes))
        return self._sets

    def footprint(self) -> Footprint:
        """What the happening reads and writes, built on first use."""
        if self._footprint is None:
            template = self._template
            if not self._atoms_only:
                self._footprint = template.ground(self._bindings)
            else:
                reads = {Atom(p, a) for p, a in self.positive}
                reads.update([Atom(p, a) for p, a in self.negative])
                self._footprint = Footprint(
                    reads,
                    {Atom(p, a) for p, a in self.adds},
                    {Atom(p, a) for p, a in self.deletes},
                    set(),
                    set(),
                    set(),
                )
        return self._footprint


def _footprint(print_: GroundParts | Footprint) -> Footprint:
    return print_ if isinstance(print_, Footprint) else print_.footprint()


def interference(a: GroundParts | Footprint, b: GroundParts | Footprint) -> str | None:
    """The shared atom or fluent that makes two happenings interfere, or None."""
    if isinstance(a, GroundParts):
        return a.interferes(b)
    return a.interferes(_footprint(b))
