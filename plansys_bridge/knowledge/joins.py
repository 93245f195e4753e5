"""Solving a conjunction as a join: the bindings of some variables that make it hold.

Why joins: quantifiers, ``forall`` effects and derived-predicate bodies would
otherwise enumerate every combination of objects. Here a conjunction's positive
atoms bind variables from the fact index (most selective first, with a per-position
index on large tables), conditions already ground filter early, an ``exists`` joins
in with its variables renamed, a disjunction branches, and only variables no atom
can bind are enumerated over the objects of their type. An ``exists`` over rooms
connected to the robot's room touches the robot's few facts, not every room pair.

:class:`JoinSolver` is the base of the reasoner (:mod:`.reasoner`), which supplies
what a condition means (``_holds``); caches here are keyed by object identity and
checked, so shared domain models are never copied.
"""

from __future__ import annotations

import contextlib
import itertools
from collections import OrderedDict
from collections.abc import Callable, Iterable, Iterator, Mapping

from plansys_bridge.knowledge.context import EvalContext
from plansys_bridge.knowledge.formulas import conjuncts, free_vars
from plansys_bridge.knowledge.grounding import UnboundVariableError, substitute_condition
from plansys_bridge.knowledge.state import Args, State
from plansys_bridge.pddl.model import OBJECT_TYPE, Atom, Condition, Exists, Or, TypedName
from plansys_bridge.pddl.types import TypeHierarchy

__all__ = ["JoinSolver", "VarTypes"]

CACHE_LIMIT = 4096
VarTypes = dict[str, frozenset[str] | None]
"""Variable -> accepted object types (None: any object)."""


class JoinSolver:
    """Joins over one type hierarchy; subclasses say what a condition means."""

    def __init__(self, types: TypeHierarchy) -> None:
        self.types = types
        self._free_cache: dict[int, tuple[Condition, frozenset[str]]] = {}
        self._rename_cache: dict[int, tuple[Exists, VarTypes, list[Condition]]] = {}
        self._fresh = itertools.count(1)  # next() is atomic: evaluators are shared by threads
        self._accept_cache: dict[tuple[str, ...], frozenset[str] | None] = {}
        self._position_index: OrderedDict[
            tuple[int, int], tuple[frozenset[Args], dict[str, list[Args]]]
        ] = OrderedDict()

    _holds: Callable[[Condition, Mapping[str, str], EvalContext], bool]
    """Does a condition hold: set by the subclass that gives conditions their meaning."""

    def _scope(
        self, variables: tuple[TypedName, ...], b: Mapping[str, str]
    ) -> tuple[dict[str, str], VarTypes]:
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
        self, variables: tuple[TypedName, ...], b: Mapping[str, str], ctx: EvalContext
    ) -> Iterator[dict[str, str]]:
        inner, var_types = self._scope(variables, b)
        yield from self._bind_rest(inner, list(var_types), var_types, ctx)

    def _bind_rest(
        self, b: dict[str, str], names: list[str], var_types: VarTypes, ctx: EvalContext
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
        if len(self._free_cache) > CACHE_LIMIT:
            self._free_cache.clear()
        self._free_cache[id(cond)] = (cond, result)
        return result

    def _solve(
        self, cond: Condition, b: dict[str, str], var_types: VarTypes, ctx: EvalContext
    ) -> Iterator[dict[str, str]]:
        """Bindings extending ``b`` that give every variable of ``var_types`` an object
        of its type and make ``cond`` hold."""
        yield from self._join(conjuncts(cond), b, var_types, ctx)

    def _join(
        self, parts: list[Condition], b: dict[str, str], var_types: VarTypes, ctx: EvalContext
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

    def _renamed(self, cond: Exists) -> tuple[VarTypes, list[Condition]]:
        """An ``exists`` with fresh variable names, ready to join into a conjunction."""
        entry = self._rename_cache.get(id(cond))
        if entry is not None and entry[0] is cond:
            return entry[1], entry[2]
        suffix = next(self._fresh)
        mapping = {v.name: f"{v.name}#{suffix}" for v in cond.variables}
        extra: VarTypes = {mapping[v.name]: self._accepted(v.types) for v in cond.variables}
        body = conjuncts(substitute_condition(cond.body, mapping))
        if len(self._rename_cache) > CACHE_LIMIT:
            self._rename_cache.clear()
        self._rename_cache[id(cond)] = (cond, extra, body)
        return extra, body

    def _match(
        self, atom: Atom, b: dict[str, str], var_types: VarTypes, ctx: EvalContext
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
