"""The plan graph: causal links, threats, parallelism, and rejection of bad plans.

Several cases reproduce PlanSys2 reports where its builder got the structure wrong:
#211 (two actions that may run together were serialised), required concurrency (an
action that needs another's at-start effect while it runs), #155/#184/#331 (robots
that share nothing must not wait for each other).
"""

from __future__ import annotations

import html
import re
import shutil
import subprocess

import networkx as nx
import pytest
from execution_helpers import door_setup, knowledge_from, load_domain

from plansys_bridge.errors import ExecutionError
from plansys_bridge.execution.dot import plan_graph_to_dot
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.pddl.model import Atom
from plansys_bridge.pddl.parser import parse_condition, parse_domain, parse_effect
from plansys_bridge.planning.effect_access import reads_fixed, writes_fixed
from plansys_bridge.planning.plan import parse_plan
from plansys_bridge.planning.plan_graph import PlanGraph, PlanGraphError, build_plan_graph

FACTORY_PLAN = """
0.000: (move robot3 assembly_zone wheels_zone)  [5.000]
0.000: (move robot2 assembly_zone steering_wheels_zone)  [5.000]
0.000: (move robot1 assembly_zone body_car_zone)  [5.000]
5.001: (transport robot3 wheel_3 wheels_zone assembly_zone)  [5.000]
5.001: (transport robot2 steering_wheel_1 steering_wheels_zone assembly_zone)  [5.000]
5.001: (transport robot1 body_car_1 body_car_zone assembly_zone)  [5.000]
10.002: (assemble robot3 assembly_zone wheel_3 body_car_1 steering_wheel_1 car_1)  [5.000]
10.002: (move robot2 assembly_zone wheels_zone)  [5.000]
10.002: (move robot1 assembly_zone steering_wheels_zone)  [5.000]
"""


DOOR_PASSES = """
0.000: (hold_open holder d1) [10.000]
0.001: (pass walker d1) [3.000]
0.002: (pass walker2 d1) [3.000]
"""
"""One robot holds the door while two walkers pass it (door_setup's domain)."""


def test_factory_robots_run_in_parallel_and_wait_only_for_what_they_need() -> None:
    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    graph = build_plan_graph(parse_plan(FACTORY_PLAN), domain, k.state())
    graph.check()
    assert graph.roots() == [0, 1, 2]
    # each transport waits for its own robot's move only
    assert graph.predecessors(3) == [0]
    assert graph.predecessors(4) == [1]
    assert graph.predecessors(5) == [2]
    # assembling car_1 needs the three pieces brought by the three transports
    assert sorted(graph.predecessors(6)) == [3, 4, 5]
    assert graph.waits(6, "start") and all(p == "end" for _, p in graph.waits(6, "start"))
    reasons = graph.graph.edges[4, 6]["reason"]
    assert "(piece_at steering_wheel_1 assembly_zone)" in reasons
    assert nx.is_directed_acyclic_graph(graph.graph)
    schedule = graph.earliest_schedule()
    assert schedule[:3] == [0.0, 0.0, 0.0]
    assert schedule[6] == pytest.approx(10.0)


def test_actions_needing_only_an_at_start_effect_start_together_issue_211() -> None:
    """#211: two actions at 0 and 0.001 "shall be executed together or the second wait
    for the first to start"; PlanSys2 made the second wait for the first's end."""
    domain, k = door_setup()
    plan = parse_plan("0.000: (hold_open holder d1) [10.000]\n0.001: (pass walker d1) [3.000]\n")
    graph = build_plan_graph(plan, domain, k.state())
    graph.check()
    # pass needs hold_open's *start* effect, not its end (PlanSys2 would wait 10 s)
    assert graph.waits(1, "start") == ((0, "start"),)
    # hold_open's end closes the door, so it must wait for pass to end
    assert graph.waits(0, "end") == ((1, "end"),)
    assert graph.graph.edges[0, 1]["points"] == {("start", "start")}
    assert graph.graph.edges[1, 0]["points"] == {("end", "end")}


def test_two_independent_passes_do_not_wait_for_each_other() -> None:
    domain, k = door_setup()
    plan = parse_plan(DOOR_PASSES)
    graph = build_plan_graph(plan, domain, k.state())
    graph.check()
    # both only need the door open; the shared (increase (total-cost) 1) commutes
    assert not graph.graph.has_edge(1, 2) and not graph.graph.has_edge(2, 1)
    assert graph.waits(1, "start") == graph.waits(2, "start") == ((0, "start"),)


def test_plan_breaking_an_over_all_requirement_is_rejected_naming_it() -> None:
    domain, k = door_setup()
    # the door closes at 5.0 while pass needs it open until 6.0
    plan = parse_plan("0.000: (hold_open holder d1) [5.000]\n3.000: (pass walker d1) [3.000]\n")
    graph = build_plan_graph(plan, domain, k.state())
    with pytest.raises(PlanGraphError) as info:
        graph.check()
    err = info.value
    assert err.step == 1 and err.action == "(pass walker d1)"
    assert err.when == "over all" and err.requirement == "(door_open d1)"
    assert "broken by step 0 (hold_open holder d1)" in str(err)


def test_unexplained_at_start_requirement_names_action_and_requirement() -> None:
    domain = load_domain("simple_example.pddl")
    k = knowledge_from(
        domain,
        instances={"r2d2": "robot", "kitchen": "room", "hall": "room", "garden": "room"},
        facts=["(robot_at r2d2 kitchen)", "(connected kitchen hall)", "(battery_full r2d2)"],
    )
    plan = parse_plan("0: (move r2d2 kitchen hall) [5]\n5.001: (move r2d2 hall garden) [5]\n")
    graph = build_plan_graph(plan, domain, k.state())
    with pytest.raises(ExecutionError) as info:
        graph.check()
    assert isinstance(info.value, PlanGraphError)
    text = str(info.value)
    assert "step 1 (move r2d2 hall garden)" in text
    assert "at start requirement (connected hall garden)" in text
    # the move to the hall is explained: robot_at by the knowledge
    assert all(p.step == 1 for p in info.value.problems)


def test_unknown_action_or_arity_names_the_step() -> None:
    domain = load_domain("simple_example.pddl")
    k = knowledge_from(domain, instances={"r2d2": "robot", "kitchen": "room"})
    with pytest.raises(ExecutionError, match=r"plan step 0 \(fly r2d2\).*no action 'fly'"):
        build_plan_graph(parse_plan("0: (fly r2d2) [1]\n"), domain, k.state())
    with pytest.raises(ExecutionError, match=r"plan step 0 \(patrol r2d2\)"):
        build_plan_graph(parse_plan("0: (patrol r2d2) [1]\n"), domain, k.state())


def test_a_chain_keeps_only_direct_edges_and_deleters_wait_for_readers() -> None:
    """The plan of PlanSys2's examples PR #12 / #190 ("road trip"): PlanSys2 started a
    patrol and the move away from the patrolled room together; the move deletes what
    the patrol needs over all, so it must wait for the patrol's end."""
    domain = load_domain("simple_example.pddl")
    k = knowledge_from(
        domain,
        instances={"r2d2": "robot", "a": "room", "b": "room", "c": "room"},
        facts=["(robot_at r2d2 a)", "(connected a b)", "(connected b c)", "(battery_full r2d2)"],
    )
    plan = parse_plan(
        "0: (patrol r2d2 a) [2]\n2.001: (move r2d2 a b) [5]\n"
        "7.002: (patrol r2d2 b) [2]\n9.003: (move r2d2 b c) [5]\n"
    )
    graph = build_plan_graph(plan, domain, k.state())
    graph.check()
    assert sorted(graph.graph.edges) == [(0, 1), (1, 2), (2, 3)]
    # the move may start only once patrolling a is over (it deletes robot_at a)
    assert graph.graph.edges[0, 1]["orderings"][0].kind == "threat"
    assert graph.graph.edges[1, 2]["orderings"][0].kind == "causal"
    unreduced = build_plan_graph(plan, domain, k.state(), reduce=False)
    assert len(unreduced.orderings) >= len(graph.orderings)


def test_numeric_reads_wait_for_changes_and_changes_for_reads() -> None:
    domain = load_domain("domain_charging.pddl")
    k = knowledge_from(
        domain,
        instances={"r1": "robot", "wp1": "waypoint", "wp2": "waypoint"},
        facts=[
            "(robot_at r1 wp1)",
            "(connected wp1 wp2)",
            "(connected wp2 wp1)",
            "(charger_at wp2)",
        ],
        functions=[
            "(= (speed r1) 1)",
            "(= (max_range r1) 100)",
            "(= (state_of_charge r1) 50)",
            "(= (distance wp1 wp2) 10)",
            "(= (distance wp2 wp1) 10)",
        ],
    )
    plan = parse_plan(
        "0: (move r1 wp1 wp2) [10]\n10.001: (charge r1 wp2) [5]\n15.002: (move r1 wp2 wp1) [10]\n"
    )
    graph = build_plan_graph(plan, domain, k.state())
    graph.check()
    subjects = {o.subject for o in graph.orderings}
    assert "(state_of_charge r1)" in subjects or "(robot_at r1 wp2)" in subjects
    assert nx.has_path(graph.graph, 1, 2)
    assert graph.final_state is not None
    assert graph.final_state.value("state_of_charge", ("r1",)) == pytest.approx(90.0)


def test_ordered_subgoals_and_dot() -> None:
    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    graph = build_plan_graph(parse_plan(FACTORY_PLAN), domain, k.state())
    goals = [Atom("car_assembled", ("car_1",)), Atom("robot_at", ("robot2", "wheels_zone"))]
    ordered = graph.ordered_subgoals(goals)
    assert ordered == [(goals[0], 6), (goals[1], 7)]
    statuses = [ActionStatus.SUCCEEDED] * 3 + [ActionStatus.EXECUTING]
    statuses += [ActionStatus.NOT_EXECUTED] * 5
    dot = plan_graph_to_dot(graph, statuses, goals)
    assert dot.startswith("digraph plan {\nrankdir=LR;")
    assert 'a0 [label="0: (move robot3 assembly_zone wheels_zone)' in dot
    # one DOT line break between the action and its times (a doubled backslash
    # would show a literal \n in the rendered picture)
    assert "wheels_zone)\\n[0.000, " in dot and "\\\\n" not in dot
    assert '"plan \\"a\\\\b\\"\\nnext"' in plan_graph_to_dot(graph, name='plan "a\\b"\nnext')
    assert "fillcolor=palegreen" in dot and "fillcolor=yellow" in dot
    assert 'g0 [label="1. (car_assembled car_1)"]' in dot
    assert "a6 -> g0" in dot
    assert "a3 -> a6" in dot


def _factory_dot() -> str:
    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    graph = build_plan_graph(parse_plan(FACTORY_PLAN), domain, k.state())
    goals = [Atom("car_assembled", ("car_1",))]
    return plan_graph_to_dot(graph, [ActionStatus.SUCCEEDED], goals, name="plan-1/0")


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz (dot) is not installed")
def test_dot_labels_render_on_two_lines_with_graphviz() -> None:
    svg = subprocess.run(
        ["dot", "-Tsvg"], input=_factory_dot(), capture_output=True, text=True, check=True
    ).stdout
    texts = [html.unescape(t) for t in re.findall(r"<text[^>]*>([^<]*)</text>", svg)]
    assert "0: (move robot3 assembly_zone wheels_zone)" in texts
    assert "[0.000, 5.000] succeeded" in texts
    assert "[5.001, 5.000] not_executed" in texts
    assert "1. (car_assembled car_1)" in texts
    assert not any("\\" in t for t in texts), [t for t in texts if "\\" in t]


def test_dot_reads_back_with_pydot() -> None:
    pydot = pytest.importorskip("pydot")
    [graph] = pydot.graph_from_dot_data(_factory_dot())
    assert graph.get_name() == '"plan-1/0"'
    [plan, _goals] = graph.get_subgraphs()
    labels = {n.get_name(): n.get("label") for n in plan.get_nodes() if n.get("label")}
    # DOT's one-character escape between the two lines, as Graphviz reads it
    assert labels["a0"] == '"0: (move robot3 assembly_zone wheels_zone)\\n[0.000, 5.000] succeeded"'
    assert len(labels) == 9 and all(label.count("\\") == 1 for label in labels.values())
    edges = {(e.get_source(), e.get_destination()) for e in graph.get_edges()}
    assert ("a3", "a6") in edges and ("a6", "g0") in edges


def _random_linearisation_is_valid(graph, domain, state, rng) -> list[str]:  # type: ignore[no-untyped-def]
    """Run the happenings in a random order that respects the graph; return every
    condition that fails on the way (none, if the graph is sound)."""
    from plansys_bridge.knowledge.evaluation import Evaluator

    ev = Evaluator(domain)
    n = len(graph.steps)
    preds: dict[int, set[int]] = {h: set() for h in range(2 * n)}
    for i in range(n):
        preds[2 * i + 1].add(2 * i)
    for o in graph.orderings:
        src = 2 * o.source + (o.source_point == "end")
        dst = 2 * o.target + (o.target_point == "end")
        preds[dst].add(src)
    done: set[int] = set()
    running: set[int] = set()
    errors: list[str] = []
    while len(done) < 2 * n:
        ready = [h for h in range(2 * n) if h not in done and preds[h] <= done]
        h = rng.choice(ready)
        i, is_end = divmod(h, 2)
        g, dur = graph.ground[i], graph.steps[i].duration
        cond = g.at_end if is_end else g.at_start
        if not ev.holds(cond, state, g.bindings, dur):
            errors.append(f"{graph.steps[i].text} {'end' if is_end else 'start'}")
        state = ev.apply(g.end_effect if is_end else g.start_effect, state, g.bindings, dur)
        if is_end:
            running.discard(i)
        else:
            running.add(i)
        for j in running:
            gj = graph.ground[j]
            if not ev.holds(gj.over_all, state, gj.bindings, graph.steps[j].duration):
                errors.append(f"{graph.steps[j].text} over all")
        done.add(h)
    return errors


@pytest.mark.parametrize("seed", range(5))
def test_every_order_the_graph_allows_is_valid(seed: int) -> None:
    import random

    from plansys_bridge.planning.planner import Planner

    rng = random.Random(seed)
    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    plan = Planner(timeout=30.0).solve(domain, k.to_problem()).plan
    assert plan is not None
    graph = build_plan_graph(plan, domain, k.state())
    graph.check()
    assert _random_linearisation_is_valid(graph, domain, k.state(), rng) == []
    door, dk = door_setup()
    door_plan = parse_plan(DOOR_PASSES)
    door_graph = build_plan_graph(door_plan, door, dk.state())
    assert _random_linearisation_is_valid(door_graph, door, dk.state(), rng) == []


def test_the_linearisation_check_catches_a_graph_without_orderings() -> None:
    import random

    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    graph = build_plan_graph(parse_plan(FACTORY_PLAN), domain, k.state())
    unordered = PlanGraph(graph.plan, graph.steps, graph.ground, orderings=())
    rng = random.Random(1)
    assert any(_random_linearisation_is_valid(unordered, domain, k.state(), rng) for _ in range(5))


def test_factory2_move_contradicts_itself_and_is_rejected_before_it_starts() -> None:
    """factory2's move deletes (robot_available ?r) at start yet needs it over all."""
    domain = load_domain("factory2.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    graph = build_plan_graph(parse_plan(FACTORY_PLAN), domain, k.state())
    with pytest.raises(PlanGraphError) as info:
        graph.check()
    first = info.value.problems[0]
    assert (first.step, first.when, first.requirement) == (
        0,
        "over all",
        "(robot_available robot3)",
    )


def test_conditions_of_conditional_effects_under_forall_are_protected() -> None:
    """``clean`` reads (dirty ?x) for every room through a forall/when effect; an action
    that later makes a room dirty must wait for it, or the room might stay dirty."""
    domain = parse_domain(
        """
        (define (domain house)
          (:requirements :typing :durative-actions :conditional-effects :universal-preconditions)
          (:types robot room)
          (:predicates (dirty ?x - room) (clean ?x - room) (at ?r - robot ?x - room))
          (:durative-action clean_all
            :parameters (?r - robot)
            :duration (= ?duration 5)
            :condition (and)
            :effect (forall (?x - room)
                      (at end (when (dirty ?x) (and (clean ?x) (not (dirty ?x)))))))
          (:durative-action mess
            :parameters (?r - robot ?x - room)
            :duration (= ?duration 2)
            :condition (at start (at ?r ?x))
            :effect (at end (dirty ?x))))
        """
    )
    k = knowledge_from(
        domain,
        instances={"vac": "robot", "kid": "robot", "hall": "room", "kitchen": "room"},
        facts=["(dirty hall)", "(at kid kitchen)"],
    )
    plan = parse_plan("0: (clean_all vac) [5]\n5.001: (mess kid kitchen) [2]\n")
    graph = build_plan_graph(plan, domain, k.state())
    graph.check()
    assert graph.waits(1, "end") == ((0, "end"),)
    assert "(dirty kitchen)" in graph.graph.edges[0, 1]["reason"]


CHOICE_DOMAIN = """
(define (domain choice)
  (:requirements :typing :durative-actions :disjunctive-preconditions)
  (:types robot)
  (:predicates (lit ?r - robot) (key ?r - robot) (done ?r - robot) (ready ?r - robot))
  (:durative-action go
    :parameters (?r - robot)
    :duration (= ?duration 1)
    :condition (and (at start (or (lit ?r) (key ?r))) (at start (ready ?r)))
    :effect (at end (done ?r)))
  (:durative-action darken
    :parameters (?r - robot)
    :duration (= ?duration 1)
    :condition (at start (lit ?r))
    :effect (at end (not (lit ?r))))
  (:durative-action unlock
    :parameters (?r - robot)
    :duration (= ?duration 1)
    :condition (at start (ready ?r))
    :effect (at end (key ?r)))
)
"""


def test_a_repeated_step_reads_the_branch_of_its_disjunction_that_holds_then() -> None:
    """The builder keeps what a repeated ground condition reads only when no state
    can change it; a disjunction is read anew each time: the second ``go`` runs on
    the key (the light is off by then), so it waits for ``unlock``, not ``darken``."""
    domain = parse_domain(CHOICE_DOMAIN)
    k = knowledge_from(domain, instances={"r1": "robot"}, facts=["(lit r1)", "(ready r1)"])
    plan = parse_plan(
        "0: (go r1) [1]\n1.001: (darken r1) [1]\n2.002: (unlock r1) [1]\n3.003: (go r1) [1]\n"
    )
    graph = build_plan_graph(plan, domain, k.state())
    graph.check()
    into_last = {(o.source, o.subject) for o in graph.orderings if o.target == 3}
    assert (2, "(key r1)") in into_last
    assert all(subject != "(lit r1)" for _, subject in into_last)
    # the fixed part (ready r1) is read by both runs of go and by unlock, written by none
    assert graph.ground[0] is graph.ground[3]


@pytest.mark.parametrize(
    ("text", "fixed"),
    [
        ("(and (a x) (not (b x)) (> (+ (f x) 1) 2) (= x y) (not (= x z)))", True),
        ("(or (a x) (b x))", False),
        ("(not (and (a x) (b x)))", False),
        ("(exists (?y - t) (a ?y))", False),
        ("(forall (?y - t) (a ?y))", False),
        ("(imply (a x) (b x))", False),
        ("(and (a x) (near x))", False),
        ("(not (near x))", False),
    ],
)
def test_only_conditions_without_a_choice_or_derived_atom_read_the_same_everywhere(
    text: str, fixed: bool
) -> None:
    assert reads_fixed(parse_condition(text), {"near"}) is fixed


@pytest.mark.parametrize(
    ("text", "fixed"),
    [
        ("(and (a x) (not (b x)) (increase (f x) (* 2 (g x))) (assign (h x) 3))", True),
        ("(and (a x) (when (b x) (c x)))", False),
        ("(forall (?y - t) (a ?y))", False),
    ],
)
def test_only_effects_without_when_or_forall_touch_the_same_everywhere(
    text: str, fixed: bool
) -> None:
    assert writes_fixed(parse_effect(text)) is fixed


TOGGLE_DOMAIN = """
(define (domain toggle)
  (:requirements :typing :durative-actions :numeric-fluents)
  (:types robot)
  (:predicates (on ?r - robot) (seen ?r - robot))
  (:functions (count ?r - robot))
  (:durative-action blink
    :parameters (?r - robot)
    :duration (= ?duration 1)
    :condition (at start (on ?r))
    :effect (and (at start (not (on ?r))) (at end (on ?r))
                 (at end (not (seen ?r))) (at end (seen ?r))))
  (:durative-action tick
    :parameters (?r - robot)
    :duration (= ?duration 1)
    :effect (at end (increase (count ?r) 2)))
)
"""


def test_repeated_steps_lead_to_the_state_their_effects_make() -> None:
    """The builder applies a repeated effect without a choice from what it found the
    first time; an atom both deleted and added stays true and numeric effects are
    still applied to the value of the moment."""
    domain = parse_domain(TOGGLE_DOMAIN)
    k = knowledge_from(domain, instances={"r1": "robot"}, facts=["(on r1)"])
    k.set_function("(= (count r1) 1)")
    plan = parse_plan(
        "0: (blink r1) [1]\n1.001: (tick r1) [1]\n2.002: (blink r1) [1]\n3.003: (tick r1) [1]\n"
    )
    graph = build_plan_graph(plan, domain, k.state())
    graph.check()
    final = graph.final_state
    assert final is not None
    assert final.facts == {Atom("on", ("r1",)), Atom("seen", ("r1",))}
    assert final.value("count", ("r1",)) == 5.0
    assert graph.achievers[Atom("seen", ("r1",))] == 2
