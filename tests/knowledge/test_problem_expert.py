"""The problem expert, mirroring plansys2_problem_expert's tests, plus atomicity,
notifications, transactions and threads."""

from __future__ import annotations

import contextlib
import threading
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from knowledge_paths import PROBLEM_EXPERT_PDDL, read

from plansys_bridge.errors import KnowledgeError, PddlError, PlansysBridgeError
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.problem_expert import KnowledgeChange, ProblemExpert
from plansys_bridge.pddl.model import (
    Action,
    AddEffect,
    AndEffect,
    Atom,
    DeleteEffect,
    FluentRef,
    FluentValue,
    Number,
    NumericEffect,
)
from plansys_bridge.pddl.parser import parse_condition, parse_problem


def test_addget_instances(simple: ProblemExpert) -> None:
    assert simple.add_instance("Paco", "person")
    assert not simple.add_instance("Paco", "person")  # already there
    with pytest.raises(KnowledgeError, match="SCIENTIFIC"):
        simple.add_instance("Paco", "SCIENTIFIC")
    with pytest.raises(KnowledgeError, match="already exists with type person"):
        simple.add_instance("paco", "robot")
    assert simple.add_instance("r2d2", "robot")
    assert list(simple.get_instances().items()) == [("paco", "person"), ("r2d2", "robot")]
    assert simple.remove_instance("Paco")
    assert simple.get_instances() == {"r2d2": "robot"}
    assert simple.get_instance("paco") is None
    assert simple.get_instance("R2D2") == "robot"
    assert not simple.remove_instance("paco")


def test_instance_names_are_checked(simple: ProblemExpert) -> None:
    for bad in ("", "1robot", "r2 d2", "(r2d2)", "?r"):
        with pytest.raises(KnowledgeError):
            simple.add_instance(bad, "robot")
    assert simple.get_instances() == {}


def test_add_functions_and_problem_text(simple: ProblemExpert) -> None:
    assert simple.add_instance("bedroom", "room")
    assert simple.add_instance("kitchen", "room_with_teleporter")
    assert simple.set_function("(= (room_distance bedroom kitchen) 1.23)")
    assert simple.set_function(
        FluentValue(FluentRef("room_distance", ("kitchen", "bedroom")), 2.34)
    )
    assert simple.set_function("(= (room_distance kitchen bedroom) 3.45)")  # update
    assert not simple.set_function("(= (room_distance kitchen bedroom) 3.45)")  # no change
    assert simple.get_function("room_distance", ("kitchen", "bedroom")) == 3.45
    assert simple.get_function("(room_distance bedroom kitchen)") == 1.23
    with pytest.raises(PlansysBridgeError, match="room_temperature"):
        simple.set_function("(= (room_temperature bedroom kitchen) 2.34)")
    with pytest.raises(KnowledgeError, match="room_temperature"):
        simple.remove_function("room_temperature", ("bedroom", "kitchen"))

    problem = parse_problem(simple.get_problem_text(), simple.domain)
    assert problem.init_fluents == (
        FluentValue(FluentRef("room_distance", ("bedroom", "kitchen")), 1.23),
        FluentValue(FluentRef("room_distance", ("kitchen", "bedroom")), 3.45),
    )
    assert simple.remove_instance("kitchen")
    assert simple.get_functions() == []


def test_addget_predicates(simple: ProblemExpert) -> None:
    for name, typ in (
        ("paco", "person"),
        ("r2d2", "robot"),
        ("bedroom", "room"),
        ("kitchen", "room"),
    ):
        assert simple.add_instance(name, typ)
    assert simple.get_predicates() == []
    assert simple.add_predicate("(robot_at r2d2 bedroom)")
    assert not simple.add_predicate(Atom("robot_at", ("r2d2", "bedroom")))  # already there
    assert simple.add_predicate("(robot_at r2d2 kitchen)")
    assert simple.add_predicate("(person_at paco bedroom)")
    assert simple.add_predicate("(person_at paco kitchen)")
    with pytest.raises(PlansysBridgeError):  # wrong arity
        simple.add_predicate("(person_at paco kitchen r2d2 bedroom)")
    with pytest.raises(PlansysBridgeError):  # wrong types
        simple.add_predicate("(person_at kitchen paco)")
    with pytest.raises(KnowledgeError, match="expects 2 arguments"):
        simple.add_predicate(Atom("person_at", ("paco", "kitchen", "r2d2", "bedroom")))
    with pytest.raises(KnowledgeError, match="kitchen is a room"):
        simple.add_predicate(Atom("person_at", ("kitchen", "paco")))
    assert len(simple.get_predicates()) == 4
    assert simple.get_predicate("(robot_at r2d2 kitchen)") == Atom("robot_at", ("r2d2", "kitchen"))
    assert simple.remove_predicate("(person_at paco kitchen)")
    assert not simple.remove_predicate("(person_at paco kitchen)")
    assert len(simple.get_predicates()) == 3

    # a subtype instance is accepted where its parent type is wanted
    assert simple.add_instance("bathroom", "room_with_teleporter")
    assert simple.add_predicate("(is_teleporter_enabled bathroom)")
    assert simple.add_predicate("(is_teleporter_destination bathroom)")
    with pytest.raises(KnowledgeError, match="wants room_with_teleporter"):
        simple.add_predicate(Atom("is_teleporter_enabled", ("kitchen",)))
    assert simple.remove_instance("bathroom")
    assert not simple.exist_predicate(
        "(is_teleporter_destination bathroom)".replace("bathroom", "kitchen")
    )
    assert all("bathroom" not in a.args for a in simple.get_predicates())


def test_addget_functions_charging(pe_domain) -> None:  # type: ignore[no-untyped-def]
    pe = ProblemExpert(pe_domain("domain_charging.pddl"))
    for name, typ in (("r2d2", "robot"), ("wp1", "waypoint"), ("wp2", "waypoint")):
        assert pe.add_instance(name, typ)
    assert pe.get_functions() == []
    assert pe.set_function("(= (speed r2d2) 3)")
    assert pe.set_function("(= (distance wp1 wp2) 15)")
    with pytest.raises(PlansysBridgeError):
        pe.set_function("(= (speed r2d2 wp1) 3)")
    with pytest.raises(PlansysBridgeError):
        pe.set_function("(= (distance r2d2 wp1) 3)")
    assert len(pe.get_functions()) == 2
    assert pe.get_function("(distance wp1 wp2)") == 15
    with pytest.raises(KnowledgeError):
        pe.remove_function("speed", ("r2d2", "wp1"))
    assert pe.remove_function("distance", ("wp1", "wp2"))
    assert not pe.remove_function("distance", ("wp1", "wp2"))
    assert pe.get_functions() == [FluentValue(FluentRef("speed", ("r2d2",)), 3.0)]


def test_addget_goals(simple: ProblemExpert) -> None:
    for name, typ in (
        ("paco", "person"),
        ("r2d2", "robot"),
        ("bedroom", "room"),
        ("kitchen", "room"),
    ):
        simple.add_instance(name, typ)
    assert simple.set_goal("(and (robot_at r2d2 bedroom)(person_at paco kitchen))")
    assert simple.set_goal("(and (robot_at r2d2 bedroom)(not(person_at paco kitchen)))")
    assert simple.get_goal() == parse_condition(
        "(and (robot_at r2d2 bedroom) (not (person_at paco kitchen)))", simple.domain
    )
    assert simple.clear_goal()
    assert simple.clear_goal()
    assert simple.get_goal() is None
    assert simple.set_goal(
        "(and (or (robot_at r2d2 bedroom) (robot_at r2d2 kitchen)) (not (person_at paco kitchen)))"
    )
    with pytest.raises(KnowledgeError, match="empty"):
        simple.set_goal("")
    with pytest.raises(PlansysBridgeError, match="hallway"):
        simple.set_goal("(and (robot_at r2d2 hallway))")
    with pytest.raises(PlansysBridgeError, match="flying"):
        simple.set_goal("(and (flying r2d2))")
    # the refused goals left the previous one in place
    assert "or" in repr(simple.get_goal()).lower()


def test_add_problem(simple: ProblemExpert) -> None:
    with pytest.raises(PlansysBridgeError):
        simple.load_problem("")
    with pytest.raises(PlansysBridgeError):
        simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_empty_domain.pddl"))
    with pytest.raises(PlansysBridgeError):  # a problem of another domain
        simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_charging.pddl"))
    with pytest.raises(PddlError):
        simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_unexpected_syntax.pddl"))
    assert simple.version == 0 and simple.get_instances() == {}

    simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"))
    for t in ("robot", "person", "room", "room_with_teleporter", "message", "ROBOT", "Person"):
        assert simple.domain_expert.is_valid_type(t)
    assert len(simple.get_instances()) == 6
    assert len(simple.get_predicates()) == 2
    assert len(simple.get_functions()) == 1
    for name in ("leia", "jack", "kitchen", "bedroom", "m1"):
        assert simple.exist_instance(name)
    for name in ("r2d2", "hallway", "m2"):
        assert not simple.exist_instance(name)
    assert not simple.exist_predicate("(robot_at leia hallway)")
    assert simple.exist_predicate("(robot_at leia kitchen)")
    assert simple.exist_predicate("(person_at jack bedroom)")
    assert simple.get_goal() == parse_condition("(and (robot_talk leia m1 jack))", simple.domain)

    # the written problem reads back as the same knowledge
    again = ProblemExpert(simple.domain_expert)
    again.load_problem(simple.get_problem_text())
    assert again.get_instances() == simple.get_instances()
    assert again.get_predicates() == simple.get_predicates()
    assert again.get_functions() == simple.get_functions()
    assert again.get_goal() == simple.get_goal()

    assert simple.clear_knowledge()
    assert simple.get_predicates() == [] and simple.get_functions() == []
    assert simple.get_instances() == {}


def test_add_problem_with_constants(pe_domain) -> None:  # type: ignore[no-untyped-def]
    pe = ProblemExpert(pe_domain("domain_simple_constants.pddl"))
    pe.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_constants_1.pddl"))
    assert pe.domain_expert.is_valid_type("teleporter_room")
    assert len(pe.get_instances()) == 7  # 4 constants + 3 objects
    assert len(pe.get_predicates()) == 2
    for name in ("leia", "lema", "jack", "john", "kitchen", "bedroom", "m1"):
        assert pe.exist_instance(name)
    problem = pe.to_problem()
    assert {o.name for o in problem.objects} == {"m1", "kitchen", "bedroom"}  # constants stay out
    with pytest.raises(KnowledgeError, match="constant"):
        pe.remove_instance("leia")
    with pytest.raises(KnowledgeError, match="constant"):
        pe.add_instance("leia", "person")

    first = pe.get_problem_text()
    pe.clear_knowledge()
    assert pe.get_instances() == pe.domain_expert.constants
    # the second problem re-declares the constants as objects: same knowledge
    pe.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_constants_2.pddl"))
    assert pe.get_problem_text() == first


def test_is_goal_satisfied(simple: ProblemExpert) -> None:
    for name, typ in (
        ("leia", "robot"),
        ("Jack", "person"),
        ("kitchen", "room"),
        ("bedroom", "room"),
        ("m1", "message"),
    ):
        simple.add_instance(name, typ)
    simple.add_predicate("(robot_at leia kitchen)")
    simple.add_predicate("(person_at Jack bedroom)")
    with pytest.raises(KnowledgeError, match="no goal"):
        simple.is_goal_satisfied()
    simple.set_goal("(and (robot_talk leia m1 Jack))")
    assert not simple.is_goal_satisfied()
    simple.add_predicate("(robot_talk leia m1 Jack)")
    assert simple.is_goal_satisfied()
    assert simple.is_goal_satisfied("(and (robot_at leia kitchen) (not (robot_at leia bedroom)))")


def test_removing_instance_clears_goal_naming_it(simple: ProblemExpert) -> None:
    simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"))
    simple.remove_instance("alice")
    assert simple.get_goal() is not None
    simple.remove_instance("m1")
    assert simple.get_goal() is None


def test_exists_and_numeric_goals(pe_domain) -> None:  # type: ignore[no-untyped-def]
    pe = ProblemExpert(pe_domain("domain_exists.pddl"))
    pe.add_predicate("(robot_at rob1 bedroom)")
    goal = "(exists (?ro - room) (and (robot_at rob1 ?ro) (charging_point_at ?ro)))"
    assert not pe.evaluate(goal)
    pe.add_predicate("(charging_point_at bedroom)")
    assert pe.evaluate(goal)
    pe.set_function("(= (battery_level rob1) 50)")
    pe.set_goal("(and (> (battery_level rob1) 1) (< (battery_level rob1) 200))")
    assert pe.is_goal_satisfied()
    pe.set_function("(= (battery_level rob1) 500)")
    assert not pe.is_goal_satisfied()
    assert pe.evaluate("(forall (?r - robot) (imply (robot_at ?r bedroom) (= ?r rob1)))")
    action = pe.domain_expert.get_action("action_test")
    assert isinstance(action, Action)
    assert not pe.evaluate(action.precondition, {"?r": "rob1"})
    pe.set_function("(= (battery_level rob1) 100)")
    assert pe.evaluate(action.precondition, {"r": "rob1"})
    assert not pe.evaluate(action.precondition, {"?r": "rob2"})  # rob2 is nowhere


def test_derived_predicates(pe_domain) -> None:  # type: ignore[no-untyped-def]
    pe = ProblemExpert(pe_domain("domain_simple_derived.pddl"))
    pe.add_instance("leia", "robot")
    pe.add_instance("kitchen", "room")
    pe.add_predicate("(robot_at leia kitchen)")
    assert pe.exist_predicate("(inferred-robot_at leia kitchen)")
    with pytest.raises(KnowledgeError, match="derived"):
        pe.add_predicate("(inferred-robot_at leia kitchen)")
    pe.set_goal("(and (inferred-robot_at leia kitchen))")
    assert pe.is_goal_satisfied()
    pe.remove_predicate("(robot_at leia kitchen)")
    assert not pe.is_goal_satisfied()


# ------------------------------------------------------------ atomicity / notifications


def test_bad_problem_leaves_knowledge_unchanged(simple: ProblemExpert) -> None:
    simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"))
    before = (
        simple.get_instances(),
        simple.get_predicates(),
        simple.get_functions(),
        simple.get_goal(),
    )
    state, version = simple.state(), simple.version
    bad = read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl").replace(
        "(robot_at leia kitchen)", "(robot_at leia kitchen)\n    (robot_at leia hallway)"
    )
    with pytest.raises(PlansysBridgeError, match="hallway"):
        simple.load_problem(bad, replace=True)
    assert (
        simple.get_instances(),
        simple.get_predicates(),
        simple.get_functions(),
        simple.get_goal(),
    ) == before
    assert simple.state() == state and simple.version == version


def test_failed_model_load_rolls_back_every_part(simple: ProblemExpert) -> None:
    """A problem built in code skips the parser's checks; the expert's own catch it
    after objects were already added, and the rollback removes them again."""
    problem = parse_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"), simple.domain)
    from dataclasses import replace

    broken = replace(problem, init=(*problem.init, Atom("robot_at", ("m1", "kitchen"))))
    seen: list[KnowledgeChange] = []
    simple.subscribe(seen.append)
    with pytest.raises(KnowledgeError, match="m1 is a message"):
        simple.load(broken)
    assert simple.get_instances() == {} and simple.get_predicates() == []
    assert seen == [] and simple.version == 0


def test_subscribers_get_one_change_per_operation(simple: ProblemExpert) -> None:
    seen: list[KnowledgeChange] = []
    unsubscribe = simple.subscribe(seen.append)
    simple.add_instance("r2d2", "robot")
    simple.add_instance("kitchen", "room")
    simple.add_instance("r2d2", "robot")  # no change, no notification
    simple.add_predicate("(robot_at r2d2 kitchen)")
    assert [c.reason for c in seen] == ["add_instance", "add_instance", "add_predicate"]
    assert seen[-1].added_facts == {Atom("robot_at", ("r2d2", "kitchen"))}
    assert seen[-1].state == simple.state()
    assert [c.version for c in seen] == [1, 2, 3]

    simple.remove_instance("kitchen")
    assert seen[-1].removed_instances == {"kitchen": "room"}
    assert seen[-1].removed_facts == {Atom("robot_at", ("r2d2", "kitchen"))}

    simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"))
    assert seen[-1].reason == "load_problem" and len(seen) == 5
    assert seen[-1].goal_changed and len(seen[-1].added_instances) == 6
    assert seen[-1].changed_fluents == {("room_distance", ("kitchen", "bedroom")): 10.0}

    unsubscribe()
    simple.clear_knowledge()
    assert len(seen) == 5


def test_broken_subscriber_does_not_break_changes(simple: ProblemExpert) -> None:
    def broken(change: KnowledgeChange) -> None:
        raise RuntimeError("subscriber bug")

    simple.subscribe(broken)
    assert simple.add_instance("r2d2", "robot")
    assert simple.exist_instance("r2d2")


def test_transaction_commits_once_or_rolls_back(simple: ProblemExpert) -> None:
    seen: list[KnowledgeChange] = []
    simple.subscribe(seen.append)
    with simple.transaction() as pe:
        pe.add_instance("r2d2", "robot")
        pe.add_instance("kitchen", "room")
        pe.add_predicate("(robot_at r2d2 kitchen)")
    assert len(seen) == 1 and len(seen[0].added_instances) == 2
    state = simple.state()
    with pytest.raises(KnowledgeError), simple.transaction() as pe:
        pe.add_instance("bedroom", "room")
        pe.remove_predicate("(robot_at r2d2 kitchen)")
        pe.add_predicate(Atom("robot_at", ("r2d2", "hallway")))
    assert simple.state() == state and len(seen) == 1
    assert not simple.exist_instance("bedroom")
    assert simple.exist_predicate("(robot_at r2d2 kitchen)")


def test_apply_effect_is_validated_and_atomic(simple: ProblemExpert) -> None:
    simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"))
    move = simple.domain_expert.get_action("teleport")
    assert move is not None
    seen: list[KnowledgeChange] = []
    simple.subscribe(seen.append)
    simple.apply(
        AndEffect(
            (
                DeleteEffect(Atom("robot_at", ("leia", "kitchen"))),
                AddEffect(Atom("robot_at", ("leia", "bedroom"))),
            )
        )
    )
    assert simple.exist_predicate("(robot_at leia bedroom)")
    assert not simple.exist_predicate("(robot_at leia kitchen)")
    assert len(seen) == 1 and seen[0].reason == "apply"
    state = simple.state()
    with pytest.raises(KnowledgeError):
        simple.apply(
            AndEffect(
                (
                    NumericEffect(
                        "increase", FluentRef("room_distance", ("kitchen", "bedroom")), Number(1)
                    ),
                    AddEffect(Atom("robot_at", ("leia", "?r2"))),
                )
            ),
            {"?r2": "jack"},  # a person where a room is wanted
        )
    assert simple.state() == state and len(seen) == 1
    simple.apply(
        NumericEffect("increase", FluentRef("room_distance", ("kitchen", "bedroom")), Number(1))
    )
    assert simple.get_function("room_distance", ("kitchen", "bedroom")) == 11


def test_to_msg(simple: ProblemExpert) -> None:
    simple.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"))
    msg = simple.to_msg()
    assert msg.instances == ("leia", "jack", "alice", "kitchen", "bedroom", "m1")
    assert msg.predicates == ("(robot_at leia kitchen)", "(person_at jack bedroom)")
    assert msg.functions == ("(= (room_distance kitchen bedroom) 10)",)
    assert parse_condition(msg.goal, simple.domain) == simple.get_goal()


def test_concurrent_changes_are_all_kept(simple: ProblemExpert) -> None:
    simple.add_instance("r2d2", "robot")
    versions: list[int] = []
    simple.subscribe(lambda change: versions.append(change.version))

    def worker(k: int) -> None:
        for i in range(25):
            simple.add_instance(f"room_{k}_{i}", "room")
            simple.add_predicate(Atom("robot_at", ("r2d2", f"room_{k}_{i}")))

    threads = [threading.Thread(target=worker, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(simple.get_predicates()) == 100
    assert len(simple.state().tuples("robot_at")) == 100
    assert versions == sorted(versions) and len(set(versions)) == 200


def test_domain_expert_shared_between_experts(pe_domain) -> None:  # type: ignore[no-untyped-def]
    de: DomainExpert = pe_domain("domain_simple.pddl")
    first, second = ProblemExpert(de), ProblemExpert(de)
    first.add_instance("r2d2", "robot")
    assert not second.exist_instance("r2d2")


# ------------------------------------------------------------ properties

_OBJECTS = [
    ("r2d2", "robot"),
    ("leia", "robot"),
    ("kitchen", "room"),
    ("hall", "room_with_teleporter"),
]
_operation = st.one_of(
    st.tuples(st.just("add_instance"), st.sampled_from(_OBJECTS)),
    st.tuples(st.just("remove_instance"), st.sampled_from([n for n, _ in _OBJECTS])),
    st.tuples(
        st.just("add_predicate"),
        st.tuples(
            st.sampled_from(["r2d2", "leia", "kitchen"]),
            st.sampled_from(["kitchen", "hall", "leia"]),
        ),
    ),
    st.tuples(
        st.just("remove_predicate"),
        st.tuples(st.sampled_from(["r2d2", "leia"]), st.sampled_from(["kitchen", "hall"])),
    ),
    st.tuples(
        st.just("set_function"),
        st.tuples(st.sampled_from(["kitchen", "hall"]), st.integers(-5, 5)),
    ),
)


def _apply(pe: ProblemExpert, op: tuple[str, Any]) -> None:
    """One operation; refused ones (unknown objects, wrong types) raise KnowledgeError."""
    kind, arg = op
    if kind == "add_instance":
        pe.add_instance(arg[0], arg[1])
    elif kind == "remove_instance":
        pe.remove_instance(arg)
    elif kind == "add_predicate":
        pe.add_predicate(Atom("robot_at", arg))
    elif kind == "remove_predicate":
        pe.remove_predicate(Atom("robot_at", arg))
    else:
        pe.set_function(FluentValue(FluentRef("room_distance", (arg[0], "kitchen")), arg[1]))


def _snapshot(pe: ProblemExpert) -> tuple[object, ...]:
    return (pe.get_instances(), pe.get_predicates(), pe.get_functions(), pe.state())


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(before=st.lists(_operation, max_size=8), inside=st.lists(_operation, max_size=8))
def test_transactions_are_all_or_nothing(
    simple: ProblemExpert, before: list[tuple[str, Any]], inside: list[tuple[str, Any]]
) -> None:
    pe = ProblemExpert(simple.domain_expert)
    for op in before:
        with contextlib.suppress(KnowledgeError):
            _apply(pe, op)
    start, version = _snapshot(pe), pe.version

    # a failing transaction leaves everything as it was
    with pytest.raises(RuntimeError), pe.transaction():
        for op in inside:
            with contextlib.suppress(KnowledgeError):
                _apply(pe, op)
        raise RuntimeError("abort")
    assert _snapshot(pe) == start and pe.version == version

    # a committed transaction equals the same operations made one by one
    twin = ProblemExpert(simple.domain_expert)
    for op in before:
        with contextlib.suppress(KnowledgeError):
            _apply(twin, op)
    changes: list[KnowledgeChange] = []
    pe.subscribe(changes.append)
    with pe.transaction():
        for op in inside:
            with contextlib.suppress(KnowledgeError):
                _apply(pe, op)
    for op in inside:
        with contextlib.suppress(KnowledgeError):
            _apply(twin, op)
    assert _snapshot(pe) == _snapshot(twin)
    assert len(changes) == (0 if _snapshot(pe) == start else 1)
    # the state snapshot agrees with the listings
    assert pe.state().facts == set(pe.get_predicates())
    assert dict(pe.state().fluents) == {
        (f.fluent.name, f.fluent.args): f.value for f in pe.get_functions()
    }


_TOKENS = st.sampled_from(
    [
        "(",
        ")",
        "(",
        ")",
        "and",
        "or",
        "not",
        "exists",
        "forall",
        "imply",
        "=",
        ">",
        "-",
        "*",
        "robot_at",
        "person_at",
        "room_distance",
        "leia",
        "jack",
        "kitchen",
        "bedroom",
        "hall",
        "?r",
        "?x",
        "robot",
        "room",
        "3",
        "-1.5",
        "1e3",
        "(and)",
        ":goal",
        ";",
        "\n",
    ]
)
_texts = st.lists(_TOKENS, max_size=14).map(" ".join) | st.text(max_size=30)


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    text=_texts,
    method=st.sampled_from(
        [
            "set_goal",
            "add_predicate",
            "remove_predicate",
            "set_function",
            "evaluate",
            "exist_predicate",
        ]
    ),
)
def test_any_text_is_refused_cleanly_or_accepted(
    simple: ProblemExpert, text: str, method: str
) -> None:
    """Whatever the text, only the project's own errors come out, and a refused
    change leaves the knowledge as it was."""
    pe = ProblemExpert(simple.domain_expert)
    pe.load_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"))
    before, version = _snapshot(pe), pe.version
    goal = pe.get_goal()
    try:
        getattr(pe, method)(text)
    except PlansysBridgeError:
        assert _snapshot(pe) == before and pe.version == version and pe.get_goal() == goal


def test_failed_load_inside_a_transaction_is_undone_alone(simple: ProblemExpert) -> None:
    """A refused problem inside a transaction that goes on leaves no half of itself."""
    problem = parse_problem(read(PROBLEM_EXPERT_PDDL / "problem_simple_1.pddl"), simple.domain)
    from dataclasses import replace

    broken = replace(problem, init=(*problem.init, Atom("robot_at", ("m1", "kitchen"))))
    with simple.transaction() as pe:
        pe.add_instance("r2d2", "robot")
        with pytest.raises(KnowledgeError):
            pe.load(broken)
        with pytest.raises(KnowledgeError), pe.transaction():  # a nested transaction too
            pe.add_instance("c3po", "robot")
            raise KnowledgeError("changed my mind")
        pe.add_instance("kitchen", "room")
    assert simple.get_instances() == {"r2d2": "robot", "kitchen": "room"}
    assert simple.state().objects == {"r2d2": "robot", "kitchen": "room"}
    assert simple.get_predicates() == []
