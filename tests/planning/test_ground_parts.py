"""Ground parts and the working state give the validator what footprints, the
evaluator and state snapshots give, without building them per happening."""

from __future__ import annotations

import itertools

import pytest
from tasks import classical, concurrent, numeric, temporal

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Atom, DurativeAction
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.planning.ground_parts import GroundParts
from plansys_bridge.planning.mutex import Footprint, Footprints, interference
from plansys_bridge.planning.planner import Planner
from plansys_bridge.planning.validation import initial_state
from plansys_bridge.planning.validation_state import WorkingState


def _prints(task: object) -> list[tuple[GroundParts | Footprint, Footprint]]:
    """Every happening of the task's plan: its parts (or asked footprint) and the
    footprint the evaluator finds."""
    domain, problem = task()  # type: ignore[operator]
    plan = Planner().solve(domain, problem).plan
    assert plan is not None
    ev = Evaluator(domain)
    footprints = Footprints(ev)
    state = initial_state(domain, problem)
    out: list[tuple[GroundParts | Footprint, Footprint]] = []
    for step in plan.steps:
        action, bindings = ev.bind(step.action, step.arguments, state)
        pairs = (
            [(action.at_start, action.start_effect), (action.at_end, action.end_effect)]
            if isinstance(action, DurativeAction)
            else [(action.precondition, action.effect)]
        )
        for condition, effect in pairs:
            parts = footprints.parts(condition, effect, bindings)
            asked = footprints._asked(condition, effect, dict(bindings), state)
            out.append((parts if parts is not None else asked, asked))
    return out


@pytest.mark.parametrize("task", [temporal, numeric, concurrent, classical])
def test_parts_interfere_exactly_when_footprints_do(task: object) -> None:
    prints = _prints(task)
    compared = 0
    for (a, fa), (b, fb) in itertools.permutations(prints, 2):
        assert interference(a, b) == fa.interferes(fb)
        compared += 1
    assert compared
    for parts, asked in prints:
        if isinstance(parts, GroundParts):
            assert parts.footprint() == asked


def test_parts_name_the_atom_a_footprint_names() -> None:
    domain, problem = temporal()
    ev = Evaluator(domain)
    footprints = Footprints(ev)
    action = next(a for a in domain.actions if isinstance(a, DurativeAction) and a.start_effect)
    names = [p.name for p in action.parameters]
    objects = list(initial_state(domain, problem).objects)
    bindings = dict(zip(names, objects, strict=False))
    if len(bindings) < len(names):
        pytest.skip("the temporal task has too few objects for this action")
    parts = footprints.parts(action.at_start, action.start_effect, bindings)
    assert parts is not None
    # the same happening twice interferes with itself on what its start changes
    shared = interference(parts, parts)
    assert shared == parts.footprint().interferes(parts.footprint())
    assert shared is not None


def test_the_working_state_keeps_the_last_change_of_each_atom() -> None:
    base = State([Atom("p", ("a",)), Atom("q", ("a",))], {}, {"a": "thing"})
    now = WorkingState(base)
    now.change([("p", ("a",))], [("p", ("a",))])  # delete then add: still there
    assert now.has("p", ("a",))
    now.change([("r", ("a",))], [("q", ("a",))])
    now.change([], [("r", ("a",))])  # added by one happening, deleted by the next
    assert not now.has("q", ("a",)) and not now.has("r", ("a",))
    state = now.state()
    expected = base.with_changes(
        adds=[Atom("p", ("a",)), Atom("r", ("a",))],
        deletes=[Atom("p", ("a",)), Atom("q", ("a",))],
    ).with_changes(deletes=[Atom("r", ("a",))])
    assert state == expected
    assert now.state() is state  # nothing pending: the same snapshot


def test_compiled_parts_put_arguments_and_constants_in_place() -> None:
    """The generated grounder: parameters by position (one used twice), constants of
    the domain (text that is not a Python name), atoms of one and of no argument."""
    domain = parse_domain(
        """(define (domain g) (:requirements :strips :typing :durative-actions)
        (:types thing) (:constants home-base - thing)
        (:predicates (at ?a ?b - thing) (ready ?a - thing) (idle) (linked ?a ?b - thing))
        (:durative-action go :parameters (?x ?y - thing) :duration (= ?duration 1)
          :condition (and (at start (at ?x ?y)) (at start (idle))
                          (at start (not (linked ?y ?y))) (over all (ready ?x)))
          :effect (and (at start (not (at ?x ?y))) (at end (at ?x home-base))
                       (at end (linked ?x ?x)))))""",
        "<g>",
    )
    action = domain.actions[0]
    assert isinstance(action, DurativeAction)
    footprints = Footprints(Evaluator(domain))
    names = tuple(p.name for p in action.parameters)
    bindings = dict(zip(names, ("r1", "dock"), strict=True))
    start = footprints.parts(action.at_start, action.start_effect, bindings)
    end = footprints.parts(action.at_end, action.end_effect, bindings)
    assert start is not None and end is not None
    assert start.positive == [("at", ("r1", "dock")), ("idle", ())]
    assert start.negative == [("linked", ("dock", "dock"))]
    assert start.deletes == [("at", ("r1", "dock"))] and start.adds == []
    assert end.adds == [("at", ("r1", "home-base")), ("linked", ("r1", "r1"))]
    # the same atoms as the lifted footprint grounded the general way
    template = footprints._template(action.at_end, action.end_effect)
    assert template is not None
    assert end.footprint() == template.ground(bindings)
    # another step of the action gets its own atoms
    other = footprints.parts(action.at_end, action.end_effect, {"?x": "r2", "?y": "a"})
    assert other is not None and other.adds == [
        ("at", ("r2", "home-base")),
        ("linked", ("r2", "r2")),
    ]
    assert end.adds == [("at", ("r1", "home-base")), ("linked", ("r1", "r1"))]
    # a later validation (its own footprints) reuses the generated function
    again = Footprints(Evaluator(domain)).compiled(action.at_end, action.end_effect, names)
    first = footprints.compiled(action.at_end, action.end_effect, names)
    assert again is not None and first is not None and again is not first
    assert again._ground is first._ground
