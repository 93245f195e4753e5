"""A mission's domain and knowledge, loaded and checked before anything starts.

The domain files, the problem file and the inline knowledge go in one transaction,
and the mission's other references to them (performers' actions, timed events) are
checked against them, so a typo is an error naming its key at load, not a
performer that never bids or an event refused halfway through a run.
"""

from __future__ import annotations

from collections.abc import Mapping

from plansys_bridge.errors import ConfigError, PddlError
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.learning.function_file import load_function_file
from plansys_bridge.mission.file_keys import keyed
from plansys_bridge.mission_config import EventConfig, MissionConfig
from plansys_bridge.pddl.model import Domain
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.textfile import TextFileError, read_text

__all__ = ["apply_event", "build_knowledge", "load_domain"]


def load_domain(mission: MissionConfig) -> Domain:
    """The mission's domain files, parsed and merged; a file that cannot be read is
    an error naming the mission file and its ``domain`` entry."""
    paths = mission.domain_paths
    try:
        return parse_domain_files(paths)
    except PddlError as exc:
        cause = exc.__cause__
        if not isinstance(cause, TextFileError):
            raise
        i = next((i for i, p in enumerate(paths) if str(p) == cause.path), 0)
        key = "domain" if len(paths) == 1 else f"domain[{i}]"
        raise ConfigError(str(cause), key=key, file=mission.source) from exc


def build_knowledge(mission: MissionConfig, domain: Domain) -> ProblemExpert:
    """The problem expert with the mission's problem file and inline knowledge.

    All of it goes in one transaction: a bad entry leaves nothing half-loaded, and
    the error names the entry's key in the mission file. The mission's other
    references to the domain and the knowledge are checked here too, before anything
    starts: each performer's actions must be actions of the domain, and each timed
    event must be a change the knowledge would accept (it is tried, then undone).
    """
    knowledge = ProblemExpert(domain)
    with knowledge.transaction():
        if mission.problem is not None:
            path = mission.resolve(mission.problem)
            with keyed(mission, "problem"):
                knowledge.load_problem(read_text(path, "problem file"), filename=str(path))
        for name, type_name in mission.knowledge.instances.items():
            with keyed(mission, f"knowledge.instances.{name}"):
                knowledge.add_instance(name, type_name)
        for i, fact in enumerate(mission.knowledge.predicates):
            with keyed(mission, f"knowledge.predicates[{i}]"):
                knowledge.add_predicate(fact)
        for i, value in enumerate(mission.knowledge.functions):
            with keyed(mission, f"knowledge.functions[{i}]"):
                knowledge.set_function(value)
        for i, name in enumerate(mission.knowledge.function_files):
            load_function_file(knowledge, mission.resolve(name), f"knowledge.function_files[{i}]")
        if mission.goal is not None:
            with keyed(mission, "goal"):
                knowledge.set_goal(mission.goal)
        _check_performer_actions(mission, knowledge)
        _rehearse_events(mission, knowledge)
    if mission.sensing:
        from plansys_bridge.sensing.load import load_rules

        load_rules(mission, knowledge)  # every rule's names, before anything starts
    return knowledge


def _check_performer_actions(mission: MissionConfig, knowledge: ProblemExpert) -> None:
    """A performer offering an action the domain lacks, or specialised to an object
    the mission does not have, is a typo, not a capability: it never bids, and the
    action it was meant for finds no performer."""
    domain = knowledge.domain
    known = {a.name for a in domain.actions}
    objects = set(knowledge.get_instances()) | {c.name for c in domain.constants}
    for i, entry in enumerate(mission.performers):
        actions = getattr(entry, "actions", None)
        specs = actions if isinstance(actions, Mapping) else {}
        names = list(actions) if isinstance(actions, Mapping | list | tuple) else []
        for name in names:
            if not isinstance(name, str):
                continue
            where = f"performers[{i}].actions.{name}"
            if name.strip().lower() not in known:
                raise ConfigError(
                    f"domain {domain.name} has no action {name!r} "
                    f"(its actions: {', '.join(sorted(known)) or 'none'})",
                    key=where,
                    file=mission.source,
                )
            spec = specs.get(name)
            for j, arg in enumerate(spec if isinstance(spec, list | tuple) else ()):
                if isinstance(arg, str) and arg.strip() and arg.strip().lower() not in objects:
                    raise ConfigError(
                        f"no object {arg!r} in the mission's knowledge or the domain's constants",
                        key=f"{where}[{j}]",
                        file=mission.source,
                    )


class _Rehearsed(Exception):
    """Ends the trial run of the events so that the transaction undoes it."""


def _rehearse_events(mission: MissionConfig, knowledge: ProblemExpert) -> None:
    """Apply every timed event now and undo them: one the knowledge would refuse at
    its time (unknown object or predicate, a typo) is an error at load instead."""
    if not mission.events:
        return
    try:
        with knowledge.transaction():
            for i, event in enumerate(mission.events):
                with keyed(mission, f"events[{i}].{_event_key(event)}"):
                    apply_event(knowledge, event)
            raise _Rehearsed
    except _Rehearsed:
        pass


def _event_key(event: EventConfig) -> str:
    return next(
        k for k in ("add_predicate", "remove_predicate", "set_function") if getattr(event, k)
    )


def apply_event(knowledge: ProblemExpert, event: EventConfig) -> str:
    """Make the event's change; returns it as text (``+(p a)``, ``-(p a)``, ``(= (f) 1)``)."""
    if event.add_predicate:
        knowledge.add_predicate(event.add_predicate)
        return f"+{event.add_predicate}"
    if event.remove_predicate:
        knowledge.remove_predicate(event.remove_predicate)
        return f"-{event.remove_predicate}"
    knowledge.set_function(event.set_function or "")
    return f"{event.set_function}"
