"""The plan graph builder's short ways agree with its general way, on random plans.

The builder keeps what a ground action reads and writes when it is the same in
every state, applies plain effects without the evaluator, watches only over-all
requirements some action can break, records a happening's accesses in one call,
reduces the orderings with bit sets and makes the orderings and their texts only
when asked. Here every one of those is compared with the general way: accesses
asked at every happening in the state of the moment, every over-all requirement
watched, a reduction by networkx, and the views read from the orderings. The
random plans mix causal links, threats, commuting and assigning numeric effects,
disjunctions, conditional effects and plans that break their own requirements.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import networkx as nx
import pytest
from execution_helpers import knowledge_from
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.planning import ground_moves
from plansys_bridge.planning.effect_access import condition_vars, effect_access, literal_atoms
from plansys_bridge.planning.happening_order import happening_order
from plansys_bridge.planning.orderings import GROUND
from plansys_bridge.planning.plan import Plan, PlanStep
from plansys_bridge.planning.plan_graph import PlanGraph, build_plan_graph
from plansys_bridge.planning.var_history import var_text

DOMAIN = parse_domain(
    """
(define (domain toy)
  (:requirements :typing :durative-actions :numeric-fluents :conditional-effects
                 :disjunctive-preconditions :negative-preconditions)
  (:types spot)
  (:predicates (at ?s - spot) (open ?s - spot) (lit ?s - spot) (road ?a ?b - spot))
  (:functions (energy) (count ?s - spot))
  (:durative-action go
    :parameters (?a ?b - spot)
    :duration (= ?duration 2)
    :condition (and (at start (at ?a)) (over all (open ?b)) (over all (road ?a ?b)))
    :effect (and (at start (not (at ?a))) (at end (at ?b)) (at end (decrease (energy) 1))))
  (:durative-action toggle
    :parameters (?s - spot)
    :duration (= ?duration 1)
    :condition (at start (or (at ?s) (lit ?s)))
    :effect (and (at end (when (open ?s) (not (open ?s))))
                 (at end (when (not (open ?s)) (open ?s)))))
  (:durative-action light
    :parameters (?s - spot)
    :duration (= ?duration 3)
    :condition (and (at start (>= (energy) 1)) (over all (not (lit ?s))))
    :effect (and (at start (increase (count ?s) 1)) (at end (lit ?s))
                 (at end (assign (energy) (- (energy) 1)))))
  (:action reset
    :parameters (?s - spot)
    :precondition (lit ?s)
    :effect (and (not (lit ?s)) (assign (count ?s) 0) (increase (energy) 2)))
)
""",
    "<toy>",
)

SPOTS = ("s1", "s2", "s3")
ARITY = {"go": 2, "toggle": 1, "light": 1, "reset": 1}


def _knowledge():  # type: ignore[no-untyped-def]
    return knowledge_from(
        DOMAIN,
        instances=dict.fromkeys(SPOTS, "spot"),
        facts=["(at s1)", "(open s2)", "(open s3)", "(road s1 s2)", "(road s2 s3)", "(road s3 s1)"],
        functions=["(= (energy) 3)", *(f"(= (count {s}) 0)" for s in SPOTS)],
    )


@st.composite
def plans(draw: st.DrawFn) -> Plan:
    steps = []
    for _ in range(draw(st.integers(1, 14))):
        action = draw(st.sampled_from(sorted(ARITY)))
        args = tuple(draw(st.sampled_from(SPOTS)) for _ in range(ARITY[action]))
        time = draw(st.integers(0, 24)) / 2
        duration = 0.0 if action == "reset" else draw(st.sampled_from([0.5, 1.0, 2.0, 3.0]))
        steps.append(PlanStep(time, action, args, duration))
    return Plan(tuple(steps))


@contextlib.contextmanager
def general_way() -> Iterator[None]:
    """Nothing kept per ground action, no plain effects, every over-all watched."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(ground_moves, "reads_fixed", lambda cond, derived: False)
        mp.setattr(ground_moves, "writes_fixed", lambda effect: False)
        mp.setattr(ground_moves, "written_names", lambda effect: None)
        yield


def _facts(graph: PlanGraph) -> object:
    state = graph.final_state
    assert state is not None
    return sorted(map(str, state.facts)), sorted(state.fluents.items())


def _networkx_reduction(unreduced: PlanGraph) -> set[tuple[int, int, str, str]]:
    """The happening edges networkx keeps (each start -> end being implicit)."""
    happenings = nx.DiGraph()
    n = len(unreduced.steps)
    happenings.add_nodes_from(range(2 * n))
    happenings.add_edges_from((2 * i, 2 * i + 1) for i in range(n))
    for o in unreduced.orderings:
        src = 2 * o.source + (o.source_point == "end")
        dst = 2 * o.target + (o.target_point == "end")
        happenings.add_edge(src, dst)
    kept = nx.transitive_reduction(happenings)
    return {
        (o.source, o.target, o.source_point, o.target_point)
        for o in unreduced.orderings
        if kept.has_edge(
            2 * o.source + (o.source_point == "end"), 2 * o.target + (o.target_point == "end")
        )
    }


def _reference_edges(plan: Plan, state: State) -> set[tuple[int, str, int, str, str, str]]:
    """The unreduced orderings worked out the plain way, apart from the builder:
    every access of every happening listed in plan order, then walked once with,
    per variable, its current run of commuting accesses and the run before."""
    ev = Evaluator(DOMAIN)
    ground = [ev.ground_action(s.action, s.arguments, state) for s in plan.steps]
    accesses: list[tuple[object, int, int, str]] = []  # (var, head, tail, op)
    order = happening_order(plan.steps)
    for h in order:
        i, end = divmod(h, 2)
        g, dur = ground[i], plan.steps[i].duration
        effect = g.end_effect if end else g.start_effect
        found = effect_access(ev, effect, state)
        reads = [*condition_vars(ev, g.at_end if end else g.at_start, GROUND, state), *found.read]
        accesses += [(var, h, h, "read") for var in reads]
        accesses += [(var, h, h, kind) for var, kind in found.writes]
        state = ev.apply(effect, state, GROUND, dur)
        if not end:
            accesses += [
                (v, h, h + 1, "read") for v in condition_vars(ev, g.over_all, GROUND, state)
            ]
    pos = {h: p for p, h in enumerate(order)}
    initial = _knowledge().state()
    edges: dict[tuple[int, int], tuple[str, object]] = {}
    runs: dict[object, tuple[str, list[tuple[int, str]], list[tuple[int, str]]]] = {}
    writer: dict[object, int] = {}
    for var, head, tail, op in accesses:
        atom = var[0] == "a"  # type: ignore[index]
        if var not in runs:
            runs[var] = (("add" if var[1] in initial else "del") if atom else "read", [], [])  # type: ignore[index]
        run_kind, run, before = runs[var]
        links: list[tuple[int, str]] = []
        if op == "read" and atom:
            if var in writer:
                links.append((writer[var], "causal"))
        else:
            if op != run_kind or op == "assign":
                before, run, run_kind = run, [], op
                runs[var] = (run_kind, run, before)
            for src, src_op in before:
                kind = "causal" if op == "read" else "threat" if src_op == "read" else "effects"
                links.append((src, kind))
            if op != "read":
                writer[var] = head
        run.append((tail, op))
        for src, kind in links:
            if src // 2 == head // 2 or pos[src] >= pos[head]:
                continue  # same step, or against the plan
            if (src, head) not in edges or (kind == "causal" != edges[(src, head)][0]):
                edges[(src, head)] = (kind, var)
    points = ("start", "end")
    return {
        (src // 2, points[src % 2], dst // 2, points[dst % 2], kind, var_text(var))  # type: ignore[arg-type]
        for (src, dst), (kind, var) in edges.items()
    }


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(plans())
def test_the_short_ways_and_the_general_way_agree(plan: Plan) -> None:
    k = _knowledge()
    fast = build_plan_graph(plan, DOMAIN, k.state())
    with general_way():
        general = build_plan_graph(plan, DOMAIN, k.state())
    assert fast.orderings == general.orderings
    assert fast.unexplained == general.unexplained
    assert dict(fast.achievers) == dict(general.achievers)
    assert list(fast.achievers) == list(general.achievers)  # in the order first achieved
    assert _facts(fast) == _facts(general)
    # the bit-set reduction keeps what networkx keeps
    unreduced = build_plan_graph(plan, DOMAIN, k.state(), reduce=False)
    assert {
        (o.source, o.source_point, o.target, o.target_point, o.kind, o.subject)
        for o in unreduced.orderings
    } == _reference_edges(plan, k.state())
    assert {(o.source, o.target, o.source_point, o.target_point) for o in fast.orderings} == (
        _networkx_reduction(unreduced)
    )
    assert set(fast.orderings) <= set(unreduced.orderings)
    # the views made lazily equal those read from the orderings
    lazy = build_plan_graph(plan, DOMAIN, k.state())
    reasons = list(lazy.edge_reasons())  # before the orderings are made
    told = PlanGraph(plan, fast.steps, fast.ground, orderings=fast.orderings)
    assert reasons == list(told.edge_reasons()) == list(fast.edge_reasons())
    for i in range(len(plan)):
        for point in ("start", "end"):
            assert lazy.waits(i, point) == told.waits(i, point)  # type: ignore[arg-type]
    assert lazy.roots() == told.roots()
    assert lazy.earliest_schedule() == told.earliest_schedule()
    assert sorted(lazy.graph.edges(data="reason")) == sorted(told.graph.edges(data="reason"))


def test_the_random_plans_meet_every_case() -> None:
    """The domain makes every kind of ordering and both kinds of problem."""
    k = _knowledge()
    plan = Plan(
        (
            PlanStep(2.5, "light", ("s2",), 2.0),
            PlanStep(4.5, "go", ("s2", "s3"), 2.0),
            PlanStep(2.5, "light", ("s2",), 2.0),  # the same again, lit by the first
        )
    )
    graph = build_plan_graph(plan, DOMAIN, k.state())
    kinds = {o.kind for o in graph.orderings}
    assert kinds == {"causal", "threat", "effects"}
    whens = {(u.when, bool(u.detail)) for u in graph.unexplained}
    assert ("over all", True) in whens  # broken while it runs
    assert ("at start", False) in whens  # go leaves from where no robot is
    with general_way():
        assert build_plan_graph(plan, DOMAIN, k.state()).orderings == graph.orderings


def test_fixed_accesses_read_off_the_structure_equal_the_evaluators() -> None:
    """Same sets in the same iteration order (which picks an ordering's subject
    when two variables order the same pair of happenings)."""
    from plansys_bridge.planning.effect_access import (
        fixed_condition_vars,
        reads_fixed,
        writes_fixed,
    )

    k = _knowledge()
    state = k.state()
    ev = Evaluator(DOMAIN)
    seen = 0
    for name, arity in ARITY.items():
        for args in [(a,) for a in SPOTS] if arity == 1 else [(a, b) for a in SPOTS for b in SPOTS]:
            g = ev.ground_action(name, args, state)
            for cond in (g.at_start, g.over_all, g.at_end):
                if reads_fixed(cond, ev._derived_rules):
                    fast = fixed_condition_vars(cond)
                    assert fast is not None
                    general = condition_vars(ev, cond, GROUND, state)
                    assert fast == general and list(fast) == list(general)
                    seen += 1
            for effect in (g.start_effect, g.end_effect):
                if writes_fixed(effect):
                    fast_access = effect_access(ev, effect, state, True)
                    general_access = effect_access(ev, effect, state)
                    assert list(fast_access.adds) == list(general_access.adds)
                    assert list(fast_access.deleted) == list(general_access.deleted)
                    assert fast_access.read == general_access.read
                    assert fast_access.writes == general_access.writes
                    assert list(fast_access.written) == list(general_access.written)
                    seen += 1
    assert seen > 30


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(plans())
def test_the_executors_views_equal_its_own_loops_over_waits(plan: Plan) -> None:
    """dependents(), roots(), start_waits and end_waits say what the executor
    worked out from waits() itself (sets filled in the same order iterate alike)."""
    graph = build_plan_graph(plan, DOMAIN, _knowledge().state())
    n = len(plan)
    expected: list[set[int]] = [set() for _ in range(n)]
    for i in range(n):
        for point in ("start", "end"):
            for j, _ in graph.waits(i, point):  # type: ignore[arg-type]
                expected[j].add(i)
    found = graph.dependents()
    assert found == expected
    assert [list(s) for s in found] == [list(s) for s in expected]
    assert found is not graph.dependents()  # the caller's own sets
    assert graph.roots() == [i for i in range(n) if not graph.waits(i, "start")]
    for i in range(n):
        assert graph.start_waits[i] is graph.waits(i, "start")
        assert graph.end_waits[i] is graph.waits(i, "end")


def test_dependents_of_a_chain_and_a_fork() -> None:
    """Hand-checked: go s1->s2 then go s2->s3 (the second needs the first's end)."""
    plan = Plan(
        (
            PlanStep(0.0, "go", ("s1", "s2"), 2.0),
            PlanStep(2.5, "go", ("s2", "s3"), 2.0),
            PlanStep(0.0, "light", ("s3",), 1.0),
        )
    )
    graph = build_plan_graph(plan, DOMAIN, _knowledge().state())
    deps = graph.dependents()
    assert 1 in deps[0]
    assert 0 not in deps[1]
    assert graph.roots() == [i for i in range(3) if not graph.start_waits[i]]
    assert 0 in graph.roots() and 1 not in graph.roots()


_ATOMS = [f"({p} {s})" for p in ("at", "open", "lit") for s in SPOTS] + [
    f"(road {a} {b})" for a in SPOTS for b in SPOTS
]


@settings(max_examples=40, deadline=None)
@given(st.sets(st.sampled_from(_ATOMS)))
def test_conditions_of_literals_hold_as_the_evaluator_says(true: set[str]) -> None:
    """The builder checks a condition of ground literals on its atoms' truth values
    (literal_atoms); in any state that must be what Evaluator.holds says."""
    k = knowledge_from(
        DOMAIN,
        instances=dict.fromkeys(SPOTS, "spot"),
        facts=sorted(true),
        functions=["(= (energy) 1)"],
    )
    state = k.state()
    ev = Evaluator(DOMAIN)
    checked = 0
    for name, arity in ARITY.items():
        for args in [(a,) for a in SPOTS] if arity == 1 else [(a, b) for a in SPOTS for b in SPOTS]:
            g = ev.ground_action(name, args, state)
            for cond in (g.at_start, g.over_all, g.at_end):
                atoms = literal_atoms(cond)
                if atoms is None:
                    continue
                by_values = all(a in state for a in atoms[0]) and not any(
                    a in state for a in atoms[1]
                )
                assert by_values == ev.holds(cond, state), (name, args, cond)
                checked += 1
    assert checked > 20


@settings(max_examples=100, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from([0.0, 0.1, 0.2, 0.3, 1.0000004, 0.9999996, 2.5, 1e-7]),
            st.sampled_from([0.0, -0.0, 0.1, 0.2, 1.5, 2.0000001]),
        ),
        max_size=12,
    )
)
def test_the_happening_order_is_the_plain_sort(times: list[tuple[float, float]]) -> None:
    """happening_order's comprehensions sort as a key function per happening
    would: by the time rounded to the microsecond, ends with a duration first,
    then by step, starts before ends (sums such as 0.1 + 0.2 included)."""
    steps = [PlanStep(t, "reset", ("s1",), d) for t, d in times]

    def key(h: int) -> tuple[float, int, int, int]:
        step, end = steps[h // 2], h % 2
        t = step.time + (step.duration if end and step.duration > 0 else 0.0)
        return (round(t, 6), 0 if end and step.duration > 0 else 1, h // 2, end)

    assert happening_order(steps) == sorted(range(2 * len(steps)), key=key)
