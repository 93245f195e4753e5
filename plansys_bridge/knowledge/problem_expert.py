"""The live knowledge: instances, facts, fluent values and the goal.

Why it is built this way:

* Every change is validated against the domain (known predicate/function, arity,
  known objects, types including subtypes) before anything is touched, and every
  change runs inside one guarded block that undoes it if anything fails,
  so bad input never leaves the knowledge half-changed.
* Instances, facts and fluent values live in journaled tables that log what each
  change touches (:mod:`.changes`): a failed change is undone from that log, and a
  subscriber gets exactly one :class:`KnowledgeChange` per change (or transaction).
* What may be stored is checked in :mod:`.admission` before a change starts.
* Effects are applied in :mod:`.applying` (the executor's two calls per action).
* Facts live in a :class:`State` updated copy-on-write, so ``state()`` is free and
  the executor can keep old snapshots; insertion order is kept for listings.
* One re-entrant lock: adapters and the executor call in from other threads.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.hub.messages import Knowledge
from plansys_bridge.knowledge.admission import Admission
from plansys_bridge.knowledge.applying import EffectApplier
from plansys_bridge.knowledge.changes import AppliedEffect, KnowledgeChange
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.inputs import (
    check_atom,
    check_condition,
    check_fluent_value,
    check_text,
)
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    TRUE,
    Atom,
    Condition,
    Domain,
    FluentRef,
    FluentValue,
    Problem,
    TypedName,
)
from plansys_bridge.pddl.walkers import iter_nodes, terms

__all__ = ["AppliedEffect", "KnowledgeChange", "ProblemExpert"]


_NAME = re.compile(r"^[a-z][a-z0-9_\-]*$")


class ProblemExpert(EffectApplier):
    """The knowledge base of one domain (see module docs)."""

    def __init__(self, domain: Domain | DomainExpert) -> None:
        self.domain_expert = domain if isinstance(domain, DomainExpert) else DomainExpert(domain)
        self.domain = self.domain_expert.domain
        self.evaluator: Evaluator = self.domain_expert.evaluator
        self._types = self.domain_expert.types
        self._constants = self.domain_expert.constants
        super().__init__(self._constants)
        self._admit = Admission(self.domain_expert, self._object_type)

    # ================================================================ validation

    def _object_type(self, name: str) -> str | None:
        found = self._instances.get(name)
        return found if found is not None else self._constants.get(name)

    # ================================================================ parsing helpers

    def _atom(self, fact: Atom | str, *, known_objects: bool = True) -> Atom:
        if isinstance(fact, Atom):
            return check_atom(fact, "predicate")
        check_text(fact, "a predicate")
        from plansys_bridge.pddl.parser import parse_atom

        objects = self.get_instances() if known_objects else None
        return parse_atom(fact, self.domain, objects=objects)

    def _fluent_value(self, fv: FluentValue | str) -> FluentValue:
        if isinstance(fv, FluentValue):
            return check_fluent_value(fv)
        check_text(fv, "a function value")
        from plansys_bridge.pddl.parser import parse_fluent_value

        return parse_fluent_value(fv, self.domain, objects=self.get_instances())

    def _condition(self, cond: Condition | str) -> Condition:
        if not isinstance(cond, str):
            return check_condition(cond)
        if not cond.strip():
            raise KnowledgeError("empty condition")
        from plansys_bridge.pddl.parser import parse_condition

        return parse_condition(cond, self.domain, objects=self.get_instances())

    # ================================================================ instances

    def add_instance(self, name: str, type: str) -> bool:
        """Add an object; False when it already exists with that type."""
        obj = check_text(name, "an instance name").strip().lower()
        typ = check_text(type, "an instance type").strip().lower()
        if not _NAME.match(obj):
            raise KnowledgeError(f"instance {name!r}: not a valid PDDL name")
        if not self.domain_expert.is_valid_type(typ):
            raise KnowledgeError(f"instance {obj}: unknown type {type!r}")
        with self._change("add_instance"):
            if not self._put_instance(obj, typ):
                return False
            self._state = self._state.with_changes(objects={**self._state.objects, obj: typ})
            return True

    def _put_instance(self, obj: str, typ: str) -> bool:
        """Record an instance (state not updated); False when already there."""
        if obj in self._constants:
            if self._types.is_subtype(self._constants[obj], typ):
                return False
            raise KnowledgeError(
                f"instance {obj}: is a constant of type {self._constants[obj]} in the domain"
            )
        current = self._instances.get(obj)
        if current == typ:
            return False
        if current is not None:
            raise KnowledgeError(f"instance {obj}: already exists with type {current}")
        self._instances.set(obj, typ)
        return True

    def remove_instance(self, name: str) -> bool:
        """Remove an object with every fact and fluent naming it (and a goal naming it)."""
        obj = name.strip().lower()
        with self._change("remove_instance"):
            if obj in self._constants and obj not in self._instances:
                raise KnowledgeError(f"instance {obj}: is a constant of the domain")
            if obj not in self._instances:
                return False
            self._instances.delete(obj)
            gone = [a for a in self._facts if obj in a.args]
            for atom in gone:
                self._facts.delete(atom)
            keys = [k for k in self._fluents if obj in k[1]]
            for key in keys:
                self._fluents.delete(key)
            objects = dict(self._state.objects)
            del objects[obj]
            self._state = self._state.with_changes(
                deletes=gone, removed_fluents=keys, objects=objects
            )
            if self._goal is not None and obj in _condition_objects(self._goal):
                self._goal = None
            return True

    def get_instances(self) -> dict[str, str]:
        """Every object (name -> type), domain constants first."""
        with self._lock:
            return {**self._constants, **self._instances.copy()}

    def get_instance(self, name: str) -> str | None:
        """The type of an object (or constant), None when unknown."""
        with self._lock:
            return self._object_type(name.strip().lower())

    def exist_instance(self, name: str) -> bool:
        return self.get_instance(name) is not None

    # ================================================================ predicates

    def add_predicate(self, fact: Atom | str) -> bool:
        """Add a ground fact; False when it was already there."""
        with self._change("add_predicate"):
            atom = self._admit.fact(self._atom(fact))
            if atom in self._facts:
                return False
            self._facts.set(atom, None)
            self._state = self._state.with_changes(adds=(atom,))
            return True

    def remove_predicate(self, fact: Atom | str) -> bool:
        """Remove a ground fact; False when it was not there."""
        with self._change("remove_predicate"):
            atom = self._admit.fact(self._atom(fact))
            if atom not in self._facts:
                return False
            self._facts.delete(atom)
            self._state = self._state.with_changes(deletes=(atom,))
            return True

    def exist_predicate(self, fact: Atom | str) -> bool:
        """True when the fact holds (derived predicates are evaluated); a fact about
        an unknown object simply does not hold."""
        atom = self._atom(fact, known_objects=False)
        atom = Atom(atom.predicate.lower(), tuple(a.lower() for a in atom.args))
        with self._lock:
            if self.domain_expert.is_derived(atom.predicate):
                return self.evaluator.holds(atom, self._state)
            return atom in self._facts

    def get_predicates(self) -> list[Atom]:
        """Base facts in the order they were added."""
        with self._lock:
            return list(self._facts)

    def get_predicate(self, fact: Atom | str) -> Atom | None:
        atom = self._atom(fact)
        return atom if self.exist_predicate(atom) else None

    # ================================================================ functions

    def set_function(self, fv: FluentValue | str) -> bool:
        """Give a fluent a value (added or updated); False when it already had it."""
        with self._change("set_function"):
            value = self._fluent_value(fv)
            key = self._admit.fluent(value.fluent.name, value.fluent.args)
            if self._fluents.get(key) == value.value:
                return False
            self._fluents.set(key, float(value.value))
            self._state = self._state.with_changes(fluents={key: float(value.value)})
            return True

    def get_function(
        self, name: str, args: tuple[str, ...] | list[str] | None = None
    ) -> float | None:
        """A fluent's value: ``get_function("distance", ("wp1", "wp2"))`` or
        ``get_function("(distance wp1 wp2)")``; None when undefined."""
        key = self._fluent_key(name, args)
        with self._lock:
            return self._fluents.get(key)

    def remove_function(
        self, name: str | FluentValue, args: tuple[str, ...] | list[str] | None = None
    ) -> bool:
        """Forget a fluent's value; False when it had none."""
        with self._change("remove_function"):
            if isinstance(name, FluentValue):
                key = self._fluent_key(name.fluent.name, name.fluent.args)
            else:
                key = self._fluent_key(name, args)
            key = self._admit.fluent(*key)
            if key not in self._fluents:
                return False
            self._fluents.delete(key)
            self._state = self._state.with_changes(removed_fluents=(key,))
            return True

    def get_functions(self) -> list[FluentValue]:
        with self._lock:
            return [FluentValue(FluentRef(n, a), v) for (n, a), v in self._fluents.items()]

    @staticmethod
    def _fluent_key(name: str, args: tuple[str, ...] | list[str] | None) -> FluentKey:
        check_text(name, "a function name")
        if args is not None:
            args = [check_text(a, "a function argument") for a in args]
        if args is None:
            words = name.replace("(", " ").replace(")", " ").split()
            if words[:1] == ["="]:
                words = words[1:-1]
            if not words:
                raise KnowledgeError(f"function {name!r}: no function name")
            return words[0].lower(), tuple(w.lower() for w in words[1:])
        return name.lower(), tuple(a.lower() for a in args)

    # ================================================================ goal

    def set_goal(self, goal: Condition | str) -> bool:
        """Replace the goal (validated against the domain and the objects)."""
        with self._change("set_goal"):
            cond = self._condition(goal)
            self._admit.condition(cond, {})
            self._goal = cond
            return True

    def get_goal(self) -> Condition | None:
        with self._lock:
            return self._goal

    def clear_goal(self) -> bool:
        with self._change("clear_goal"):
            self._goal = None
            return True

    def is_goal_satisfied(self, goal: Condition | str | None = None) -> bool:
        """Does ``goal`` (by default the current goal) hold now?"""
        with self._lock:
            cond = self._condition(goal) if goal is not None else self._goal
            if cond is None:
                raise KnowledgeError("no goal is set")
            return self.evaluator.holds(cond, self._state)

    # ================================================================ whole problem

    def load_problem(self, text: str, filename: str = "<problem>", replace: bool = False) -> None:
        """Add a whole PDDL problem (objects, init, goal) - all of it or nothing.

        ``replace`` clears the knowledge first (in the same all-or-nothing step).
        """
        from plansys_bridge.pddl.parser import parse_problem

        if not text.strip():
            raise KnowledgeError(f"{filename}: empty problem")
        problem = parse_problem(text, self.domain, filename=filename)
        self.load(problem, replace=replace)

    def load(self, problem: Problem, replace: bool = False) -> None:
        """Add a parsed problem - all of it or nothing."""
        where = problem.source or problem.name
        if problem.domain_name.lower() != self.domain.name.lower():
            raise KnowledgeError(
                f"{where}: problem is for domain {problem.domain_name!r}, not {self.domain.name!r}"
            )
        with self._change("load_problem", steps=True):
            if replace:
                self._clear()
            # One state update for the whole problem: adding facts one by one would
            # copy each predicate's table once per fact.
            try:
                for obj in problem.objects:
                    name, typ = obj.name.lower(), obj.types[0].lower()
                    if not _NAME.match(name):
                        raise KnowledgeError(f"instance {obj.name!r}: not a valid PDDL name")
                    if not self.domain_expert.is_valid_type(typ):
                        raise KnowledgeError(f"instance {name}: unknown type {typ!r}")
                    self._put_instance(name, typ)
                facts = [self._admit.fact(check_atom(atom, "predicate")) for atom in problem.init]
                values: dict[FluentKey, float] = {}
                for fv in map(check_fluent_value, problem.init_fluents):
                    values[self._admit.fluent(fv.fluent.name, fv.fluent.args)] = float(fv.value)
                for atom in facts:
                    self._facts.set(atom, None)
                for key, number in values.items():
                    self._fluents.set(key, number)
                self._state = self._state.with_changes(
                    adds=facts,
                    fluents=values,
                    objects={**self._constants, **self._instances.copy()},
                )
                if problem.goal != TRUE:
                    self.set_goal(problem.goal)
            except KnowledgeError as exc:
                raise KnowledgeError(f"{where}: {exc}") from exc

    def _clear(self) -> None:
        self._instances.clear()
        self._facts.clear()
        self._fluents.clear()
        self._goal = None
        self._state = State(objects=self._constants)

    def clear_knowledge(self) -> bool:
        """Forget every instance, fact, fluent and the goal."""
        with self._change("clear_knowledge"):
            self._clear()
            return True

    def to_problem(self, name: str = "problem") -> Problem:
        """The knowledge as a problem model (constants stay in the domain)."""
        with self._lock:
            return Problem(
                name=name,
                domain_name=self.domain.name,
                objects=tuple(TypedName(n, (t,)) for n, t in self._instances.items()),
                init=tuple(self._facts),
                init_fluents=tuple(
                    FluentValue(FluentRef(n, a), v) for (n, a), v in self._fluents.items()
                ),
                goal=self._goal if self._goal is not None else TRUE,
            )

    def get_problem_text(self, name: str = "problem") -> str:
        from plansys_bridge.pddl.writer import write_problem

        return write_problem(self.to_problem(name))

    # ================================================================ evaluation

    def state(self) -> State:
        """The current snapshot (immutable; cheap to keep).

        While no change is under way this is the snapshot the last one left, read
        without the lock: the executor asks about five times per action, and the
        lock costs more than the read. While one is under way the lock is taken as
        before: its own thread (re-entrant) sees it as it goes, any other waits for
        it to end. ``_published`` is set before ``_depth`` drops to 0, so a reader
        that finds no change under way gets a finished snapshot, never a half-made
        one."""
        if self._depth:
            with self._lock:
                return self._state
        return self._published

    def evaluate(self, cond: Condition | str, bindings: Mapping[str, str] | None = None) -> bool:
        with self._lock:
            return self.evaluator.holds(self._condition(cond), self._state, bindings)

    # ================================================================ messages

    def to_msg(self) -> Knowledge:
        """The knowledge as PlanSys2 publishes it."""
        from plansys_bridge.pddl.writer import write_condition, write_fluent_value

        with self._lock:
            return Knowledge(
                instances=tuple(self.get_instances()),
                predicates=tuple(str(a) for a in self._facts),
                functions=tuple(
                    write_fluent_value(FluentValue(FluentRef(*k), v))
                    for k, v in self._fluents.items()
                ),
                goal=write_condition(self._goal) if self._goal is not None else "",
            )


def _condition_objects(cond: Condition) -> set[str]:
    """Object names (not variables) a condition mentions."""
    return {t for node in iter_nodes(cond) for t in terms(node) if not t.startswith("?")}
