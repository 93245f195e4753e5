"""Immutable snapshots of the world: ground facts, numeric fluents and objects.

Why the layout: the executor checks conditions on every tick and the plan validator
applies thousands of actions, so a state is indexed by predicate (a lookup is one
dict access and one set membership test) and a new state shares every unchanged
predicate's set with its parent (copy-on-write per predicate). ``facts`` as a
frozenset of :class:`Atom` is built only when someone asks for it. Each state also
carries a private cache that evaluators use for derived predicates, so they are
computed once per snapshot.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence
from types import MappingProxyType
from typing import Any, TypeAlias

from plansys_bridge.pddl.model import Atom

FluentKey: TypeAlias = tuple[str, tuple[str, ...]]
"""``("battery", ("r2d2",))`` for ``(battery r2d2)``."""

Args: TypeAlias = tuple[str, ...]

_EMPTY: frozenset[Args] = frozenset()

_FEW = 4
"""Facts up to which :meth:`State.with_facts` edits predicate sets fact by fact."""


class State:
    """A snapshot of facts, fluent values and objects (name -> type, constants included).

    Treat it as immutable: every change goes through :meth:`with_changes`, which
    returns a new state. ``fluents`` and ``objects`` are read-only views.
    """

    __slots__ = ("_cache", "_facts", "_flat", "_fluents", "_index", "_object_cache", "_objects")

    def __init__(
        self,
        facts: Iterable[Atom] = (),
        fluents: Mapping[FluentKey, float] | None = None,
        objects: Mapping[str, str] | None = None,
    ) -> None:
        grouped: dict[str, set[Args]] = {}
        for atom in facts:
            grouped.setdefault(atom.predicate, set()).add(atom.args)
        self._index: dict[str, frozenset[Args]] = {p: frozenset(a) for p, a in grouped.items()}
        self._facts: frozenset[Atom] | None = None
        # Fluents are grouped by function name like facts by predicate, so a numeric
        # effect copies only its function's table.
        buckets: dict[str, dict[Args, float]] = {}
        for (name, args), value in (fluents or {}).items():
            buckets.setdefault(name, {})[args] = float(value)
        self._fluents: dict[str, dict[Args, float]] = buckets
        self._flat: dict[FluentKey, float] | None = None
        self._objects: dict[str, str] = dict(objects or {})
        self._cache: dict[Any, Any] | None = None
        self._object_cache: dict[Any, Any] = {}

    # ------------------------------------------------------------ reading

    @property
    def facts(self) -> frozenset[Atom]:
        """Every ground fact (built lazily, then kept)."""
        if self._facts is None:
            self._facts = frozenset(
                Atom(pred, args) for pred, tuples in self._index.items() for args in tuples
            )
        return self._facts

    @property
    def fluents(self) -> Mapping[FluentKey, float]:
        if self._flat is None:
            self._flat = {
                (name, args): value
                for name, table in self._fluents.items()
                for args, value in table.items()
            }
        return MappingProxyType(self._flat)

    @property
    def objects(self) -> Mapping[str, str]:
        return MappingProxyType(self._objects)

    def tuples(self, predicate: str) -> frozenset[Args]:
        """Argument tuples of every fact of ``predicate``."""
        return self._index.get(predicate, _EMPTY)

    def predicates(self) -> Iterator[str]:
        """Predicates with at least one fact."""
        return (p for p, t in self._index.items() if t)

    def has(self, predicate: str, args: Args) -> bool:
        return args in self._index.get(predicate, _EMPTY)

    def has_all(self, facts: Iterable[tuple[str, Args]]) -> bool:
        """True when every (predicate, arguments) pair is a fact (one call for a
        whole conjunction)."""
        index = self._index
        for predicate, args in facts:  # noqa: SIM110 (all() of a generator: a call per fact)
            if args not in index.get(predicate, _EMPTY):
                return False
        return True

    def __contains__(self, atom: object) -> bool:
        # The class compared first and the index subscripted: the executor asks
        # about each fact of an at-start effect, and isinstance and get are calls.
        if atom.__class__ is not Atom and not isinstance(atom, Atom):
            return False
        try:
            return atom.args in self._index[atom.predicate]
        except KeyError:
            return False

    def value(self, name: str, args: Args = ()) -> float | None:
        """The fluent's value, or None when it is undefined."""
        table = self._fluents.get(name)
        return None if table is None else table.get(args)

    def same_fluents(self, other: State) -> bool:
        """True when both states share one fluent table (no fluent changed between)."""
        return self._fluents is other._fluents

    def same_objects(self, other: State) -> bool:
        """True when both states share one object table (no object changed between)."""
        return self._objects is other._objects

    def __len__(self) -> int:
        return sum(len(t) for t in self._index.values())

    def cache(self) -> dict[Any, Any]:
        """Per-snapshot scratch space for evaluators (derived predicates).

        Made on first use: only a domain with derived predicates asks for it, and
        the executor makes two snapshots per action that nobody asks it of."""
        cache = self._cache
        if cache is None:
            cache = self._cache = {}
        return cache

    def object_cache(self) -> dict[Any, Any]:
        """Scratch space shared by every state with the same objects (type lookups)."""
        return self._object_cache

    # ------------------------------------------------------------ changing

    def with_changes(
        self,
        adds: Iterable[Atom] = (),
        deletes: Iterable[Atom] = (),
        fluents: Mapping[FluentKey, float] | None = None,
        removed_fluents: Iterable[FluentKey] = (),
        objects: Mapping[str, str] | None = None,
    ) -> State:
        """A new state: ``deletes`` removed, then ``adds`` added (PDDL order), fluents
        updated/removed, and ``objects`` replacing the object table when given."""
        index = self._index
        touched: dict[str, set[Args]] = {}
        for atom in deletes:
            current = touched.get(atom.predicate)
            if current is None:
                if atom.args not in index.get(atom.predicate, _EMPTY):
                    continue
                current = touched[atom.predicate] = set(index[atom.predicate])
            current.discard(atom.args)
        for atom in adds:
            current = touched.get(atom.predicate)
            if current is None:
                if atom.args in index.get(atom.predicate, _EMPTY):
                    continue
                current = touched[atom.predicate] = set(index.get(atom.predicate, _EMPTY))
            current.add(atom.args)
        new_index = index
        if touched:
            new_index = dict(index)
            for pred, tuples in touched.items():
                if tuples:
                    new_index[pred] = frozenset(tuples)
                else:
                    new_index.pop(pred, None)
        removed = tuple(removed_fluents)
        new_fluents = self._fluents
        if fluents or removed:
            new_fluents = dict(self._fluents)
            copied: set[str] = set()
            for (name, args), value in [*((k, None) for k in removed), *(fluents or {}).items()]:
                if name not in copied:
                    new_fluents[name] = dict(new_fluents.get(name, {}))
                    copied.add(name)
                if value is None:
                    new_fluents[name].pop(args, None)
                else:
                    new_fluents[name][args] = float(value)
            for name in copied:
                if not new_fluents[name]:
                    del new_fluents[name]
        if objects is None:
            new_objects, object_cache = self._objects, self._object_cache
        else:
            new_objects, object_cache = dict(objects), {}
        if new_index is index and new_fluents is self._fluents and objects is None:
            return self
        return State._build(new_index, new_fluents, new_objects, object_cache)

    def with_facts(self, deletes: Sequence[Atom], adds: Sequence[Atom]) -> State:
        """``with_changes(adds=adds, deletes=deletes)`` for an effect's few facts.

        Why: the executor applies two such effects per action. For a handful of
        facts one frozenset operation per fact on its predicate's set costs less
        than the general way's copy, edit and freeze; a fact in a set is copied
        once per fact of its predicate, so more facts go the general way.
        """
        if len(deletes) + len(adds) > _FEW:
            return self.with_changes(adds=adds, deletes=deletes)
        index = self._index
        new_index = index
        emptied = False
        # Subscripts rather than get(): no call when the predicate is there.
        for atom in deletes:
            try:
                current = new_index[atom.predicate]
            except KeyError:
                continue
            if atom.args not in current:
                continue
            if new_index is index:
                new_index = dict(index)
            # An emptied predicate keeps its place until the end, as in with_changes
            # (the index's order is the order predicates() lists them in).
            current = new_index[atom.predicate] = current.difference((atom.args,))
            emptied = emptied or not current
        for atom in adds:
            try:
                current = new_index[atom.predicate]
            except KeyError:
                current = _EMPTY
            if atom.args in current:
                continue
            if new_index is index:
                new_index = dict(index)
            new_index[atom.predicate] = current.union((atom.args,))
        if new_index is index:
            return self
        if emptied:
            for pred in [p for p, tuples in new_index.items() if not tuples]:
                del new_index[pred]
        # State._build, inlined (two of these per executed action)
        state = State.__new__(State)
        state._index = new_index
        state._facts = None
        state._fluents = self._fluents
        state._flat = None
        state._objects = self._objects
        state._cache = None
        state._object_cache = self._object_cache
        return state

    @staticmethod
    def _build(
        index: dict[str, frozenset[Args]],
        fluents: dict[str, dict[Args, float]],
        objects: dict[str, str],
        object_cache: dict[Any, Any],
    ) -> State:
        """A state from its tables as they are (``__init__`` regroups every fact)."""
        state = State.__new__(State)
        state._index = index
        state._facts = None
        state._fluents = fluents
        state._flat = None
        state._objects = objects
        state._cache = None
        state._object_cache = object_cache
        return state

    # ------------------------------------------------------------ comparing

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, State):
            return NotImplemented
        return (
            self._index == other._index
            and self._fluents == other._fluents
            and self._objects == other._objects
        )

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return (
            f"State({len(self)} facts, {sum(len(t) for t in self._fluents.values())} fluents, "
            f"{len(self._objects)} objects)"
        )
