"""The type hierarchy of a domain: subtype tests and type-filtered object lists.

Everything that grounds or checks PDDL asks "is this object a ``room``?" many
times, so ancestors are computed once per type and cached as frozensets.
``either`` parents make the hierarchy a DAG rather than a tree; that is handled
naturally by walking all parents.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from plansys_bridge.pddl.model import OBJECT_TYPE, Domain


class TypeHierarchy:
    """Subtype relation of ``domain``'s types; ``object`` is the root of all."""

    def __init__(self, domain: Domain) -> None:
        parents: dict[str, set[str]] = {OBJECT_TYPE: set()}
        for typedef in domain.types:
            if typedef.name == OBJECT_TYPE:
                continue
            entry = parents.setdefault(typedef.name, set())
            entry.update(p for p in typedef.parents if p != typedef.name)
        for entry in list(parents.values()):
            for parent in entry:
                parents.setdefault(parent, {OBJECT_TYPE} if parent != OBJECT_TYPE else set())
        self._parents = parents
        self._ancestors: dict[str, frozenset[str]] = {}
        self._subtypes: dict[str, frozenset[str]] = {}

    @property
    def types(self) -> frozenset[str]:
        """Every known type, ``object`` included."""
        return frozenset(self._parents)

    def __contains__(self, name: object) -> bool:
        return name in self._parents

    def parents(self, t: str) -> frozenset[str]:
        return frozenset(self._parents.get(t, ()))

    def ancestors(self, t: str) -> frozenset[str]:
        """``t``, its parents, their parents ... and ``object``."""
        cached = self._ancestors.get(t)
        if cached is not None:
            return cached
        seen = {t, OBJECT_TYPE}
        stack = [t]
        while stack:
            for parent in self._parents.get(stack.pop(), ()):
                if parent not in seen:
                    seen.add(parent)
                    stack.append(parent)
        result = frozenset(seen)
        self._ancestors[t] = result
        return result

    def is_subtype(self, sub: str, sup: str) -> bool:
        """True when every ``sub`` is a ``sup`` (reflexive; all types are objects)."""
        return sup == OBJECT_TYPE or sub == sup or sup in self.ancestors(sub)

    def is_subtype_of_any(self, subs: Iterable[str], sups: Iterable[str]) -> bool:
        """``either`` on both sides: some ``sub`` is a subtype of some ``sup``."""
        sups = tuple(sups)
        return any(self.is_subtype(s, p) for s in subs for p in sups)

    def compatible(self, a: Iterable[str], b: Iterable[str]) -> bool:
        """Some type in ``a`` and some in ``b`` share objects (one is below the other)."""
        b = tuple(b)
        return any(self.is_subtype(x, y) or self.is_subtype(y, x) for x in a for y in b)

    def subtypes(self, t: str) -> set[str]:
        """All types below ``t``, ``t`` included."""
        cached = self._subtypes.get(t)
        if cached is None:
            cached = frozenset(s for s in self._parents if t in self.ancestors(s)) | {t}
            self._subtypes[t] = cached
        return set(cached)

    def objects_of_type(self, t: str, objects: Mapping[str, str]) -> list[str]:
        """Names in ``objects`` (name -> type) whose type is ``t`` or below it."""
        if t == OBJECT_TYPE:
            return list(objects)
        below = self.subtypes(t)
        return [name for name, typ in objects.items() if typ in below]

    def cycle(self) -> list[str] | None:
        """A cycle in the declared hierarchy, if there is one."""
        state: dict[str, int] = {}
        path: list[str] = []

        def visit(node: str) -> list[str] | None:
            state[node] = 1
            path.append(node)
            for parent in sorted(self._parents.get(node, ())):
                if state.get(parent) == 1:
                    return [*path[path.index(parent) :], parent]
                if parent not in state:
                    found = visit(parent)
                    if found:
                        return found
            path.pop()
            state[node] = 2
            return None

        for node in sorted(self._parents):
            if node not in state:
                found = visit(node)
                if found:
                    return found
        return None
