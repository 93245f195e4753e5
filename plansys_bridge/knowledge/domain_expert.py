"""Read-only questions about a domain: types, constants, predicates, actions.

Why a wrapper around :class:`Domain`: callers (terminal, problem expert, planner
front end) ask by name and case-insensitively, and want derived predicates counted as
predicates even when a domain forgets to declare them in ``:predicates``. Lookups are
dictionaries built once.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.pddl.model import (
    OBJECT_TYPE,
    Action,
    AnyAction,
    DerivedPredicate,
    Domain,
    DurativeAction,
    FunctionDef,
    PredicateDef,
)
from plansys_bridge.pddl.types import TypeHierarchy


class DomainExpert:
    """Questions about one (possibly merged) domain."""

    def __init__(self, domain: Domain) -> None:
        self.domain = domain
        self.types = TypeHierarchy(domain)
        predicates: dict[str, PredicateDef] = {p.name: p for p in domain.predicates}
        for rule in domain.derived:
            predicates.setdefault(rule.head.name, rule.head)
        self._predicates = predicates
        self._functions = {f.name: f for f in domain.functions}
        self._actions: dict[str, AnyAction] = {a.name: a for a in domain.actions}
        self._constants = {c.name: c.types[0] for c in domain.constants}
        self._derived_names = {rule.head.name for rule in domain.derived}
        self._evaluator: Evaluator | None = None

    @classmethod
    def from_files(cls, paths: Sequence[str | Path] | str | Path) -> DomainExpert:
        """Parse and merge domain files (``a.pddl:b.pddl`` strings are split too)."""
        from plansys_bridge.pddl.parser import parse_domain_files

        if isinstance(paths, (str, Path)):
            paths = [paths]
        files: list[str | Path] = []
        for p in paths:
            files.extend(str(p).split(":") if isinstance(p, str) else [p])
        return cls(parse_domain_files(files))

    @classmethod
    def from_text(cls, text: str, filename: str = "<domain>") -> DomainExpert:
        from plansys_bridge.pddl.parser import parse_domain

        return cls(parse_domain(text, filename=filename))

    @property
    def name(self) -> str:
        return self.domain.name

    @property
    def evaluator(self) -> Evaluator:
        """One evaluator per domain, shared (its caches are per domain)."""
        if self._evaluator is None:
            self._evaluator = Evaluator(self.domain)
        return self._evaluator

    # ------------------------------------------------------------------ types

    def get_types(self) -> list[str]:
        """Declared types in declaration order (``object`` only if declared)."""
        return [t.name for t in self.domain.types]

    def get_subtypes(self, type_name: str) -> list[str]:
        """Types strictly below ``type_name``, sorted."""
        name = type_name.lower()
        return sorted(self.types.subtypes(name) - {name})

    def is_valid_type(self, type_name: str) -> bool:
        name = type_name.lower()
        return name == OBJECT_TYPE or name in self.types

    # ------------------------------------------------------------------ constants

    def get_constants(self, type: str | None = None) -> list[str]:
        """Constant names, optionally only those usable as ``type``."""
        if type is None:
            return list(self._constants)
        return self.types.objects_of_type(type.lower(), self._constants)

    def constant_type(self, name: str) -> str | None:
        return self._constants.get(name.lower())

    @property
    def constants(self) -> dict[str, str]:
        return dict(self._constants)

    # ------------------------------------------------------------------ predicates

    def get_predicates(self) -> list[PredicateDef]:
        """Declared predicates, plus derived heads the domain did not declare."""
        return list(self._predicates.values())

    def get_predicate(self, name: str) -> PredicateDef | None:
        return self._predicates.get(name.lower())

    def is_derived(self, name: str) -> bool:
        return name.lower() in self._derived_names

    def get_derived(self, name: str | None = None) -> list[DerivedPredicate]:
        """Every ``:derived`` rule, or the rules for predicate ``name``."""
        if name is None:
            return list(self.domain.derived)
        key = name.lower()
        return [r for r in self.domain.derived if r.head.name == key]

    # ------------------------------------------------------------------ functions

    def get_functions(self) -> list[FunctionDef]:
        return list(self._functions.values())

    def get_function(self, name: str) -> FunctionDef | None:
        return self._functions.get(name.lower())

    # ------------------------------------------------------------------ actions

    def get_actions(self) -> list[Action]:
        """Plain ``:action``s."""
        return [a for a in self.domain.actions if isinstance(a, Action)]

    def get_durative_actions(self) -> list[DurativeAction]:
        return [a for a in self.domain.actions if isinstance(a, DurativeAction)]

    def get_action(self, name: str) -> AnyAction | None:
        """An action of either kind by name."""
        return self._actions.get(name.lower())

    def get_action_names(self) -> list[str]:
        return list(self._actions)

    # ------------------------------------------------------------------ text

    def get_domain_text(self) -> str:
        """The (merged) domain as PDDL."""
        from plansys_bridge.pddl.writer import write_domain

        return write_domain(self.domain)
