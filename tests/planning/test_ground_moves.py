"""The plan graph's short ways against straightforward references.

fixed_reads walks a condition once for its variables and its literals (the
evaluator's walk and literal_atoms are the references); whether a part reads and
writes the same in every state is asked once per action (each ground action's
own answer is the reference); happening_order and waits_of make their keys and
tuples without a call per item (a sort with a key function and a loop that
appends are the references); a happening records only the reads of variables an
action may change (every read recorded is the reference: the orderings agree).
"""

from __future__ import annotations

import random

import pytest
from execution_helpers import knowledge_from
from hypothesis import given, settings
from hypothesis import strategies as st
from test_plan_graph_general import ARITY, DOMAIN, SPOTS, _knowledge, plans

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.pddl.model import Condition
from plansys_bridge.pddl.parser import parse_condition
from plansys_bridge.planning import ground_moves
from plansys_bridge.planning.effect_access import (
    condition_vars,
    fixed_reads,
    literal_atoms,
    reads_fixed,
    writes_fixed,
)
from plansys_bridge.planning.happening_order import happening_order
from plansys_bridge.planning.orderings import GROUND
from plansys_bridge.planning.plan import Plan, PlanStep
from plansys_bridge.planning.plan_graph import build_plan_graph
from plansys_bridge.planning.step_edges import waits_of

_LEAVES = ["(at s1)", "(open s2)", "(lit s3)", "(road s1 s2)", "(>= (energy) 1)", "(= s1 s2)"]


def _conditions() -> st.SearchStrategy[str]:
    return st.recursive(
        st.sampled_from(_LEAVES),
        lambda inner: st.one_of(
            inner.map(lambda c: f"(not {c})"),
            st.lists(inner, min_size=0, max_size=4).map(lambda cs: f"(and {' '.join(cs)})"),
        ),
        max_leaves=8,
    )


@settings(max_examples=200, deadline=None)
@given(_conditions())
def test_fixed_reads_is_the_evaluators_walk_and_literal_atoms(text: str) -> None:
    cond: Condition = parse_condition(text, DOMAIN)
    if not reads_fixed(cond, frozenset()):
        return
    found = fixed_reads(cond)
    assert found is not None
    listed, literals = found
    state = _knowledge().state()
    general = condition_vars(Evaluator(DOMAIN), cond, GROUND, state)
    assert listed == general and list(listed) == list(general)  # same iteration order
    assert literals == literal_atoms(cond)


def test_fixed_reads_tells_literals_from_the_rest() -> None:
    literal = parse_condition("(and (at s1) (not (lit s3)) (and (open s2)))", DOMAIN)
    found = fixed_reads(literal)
    assert found is not None and found[1] is not None
    assert [str(a) for a in found[1][0]] == ["(at s1)", "(open s2)"]
    assert [str(a) for a in found[1][1]] == ["(lit s3)"]
    for text in ("(and (at s1) (>= (energy) 1))", "(not (not (at s1)))", "(= s1 s2)"):
        other = fixed_reads(parse_condition(text, DOMAIN))
        assert other is not None and other[1] is None, text


def test_fixedness_is_the_same_for_every_grounding_of_an_action() -> None:
    """The builder asks once per action; every ground action must answer alike."""
    ev = Evaluator(DOMAIN)
    state = _knowledge().state()
    for name, arity in ARITY.items():
        answers = set()
        for args in [(a,) for a in SPOTS] if arity == 1 else [(a, b) for a in SPOTS for b in SPOTS]:
            g = ev.ground_action(name, args, state)
            answers.add(
                (
                    tuple(
                        reads_fixed(c, ev._derived_rules)
                        for c in (g.at_start, g.over_all, g.at_end)
                    ),
                    tuple(writes_fixed(e) for e in (g.start_effect, g.end_effect)),
                )
            )
        assert len(answers) == 1, name


def _reference_order(steps: list[PlanStep]) -> list[int]:
    def key(h: int) -> tuple[float, int, int, int]:
        step = steps[h // 2]
        if h % 2 and step.duration > 0:
            return (round(step.time + step.duration, 6), 0, h // 2, 1)
        return (round(step.time, 6), 1, h // 2, h % 2)

    return sorted(range(2 * len(steps)), key=key)


@settings(max_examples=100, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.integers(0, 40).map(lambda t: t / 4 + 1e-7),
            st.sampled_from([0.0, 0.25, 1.0, 2.5, 1.0000004]),
        ),
        max_size=30,
    )
)
def test_happening_order_is_a_sort_by_time_with_ends_first(
    times: list[tuple[float, float]],
) -> None:
    steps = [PlanStep(t, "go", ("s1", "s2"), d) for t, d in times]
    assert happening_order(steps) == _reference_order(steps)


def test_waits_gathered_by_runs_equal_one_append_per_pair() -> None:
    rng = random.Random(3)
    for _ in range(200):
        n = rng.randint(1, 8)
        pairs = [(rng.randrange(2 * n), rng.randrange(2 * n)) for _ in range(rng.randint(0, 20))]
        if rng.random() < 0.5:
            pairs.sort(key=lambda p: p[1])
        start: list[list[tuple[int, str]]] = [[] for _ in range(n)]
        end: list[list[tuple[int, str]]] = [[] for _ in range(n)]
        for src, dst in pairs:
            (end if dst % 2 else start)[dst // 2].append((src // 2, ("start", "end")[src % 2]))
        assert waits_of(pairs, n) == ([tuple(w) for w in start], [tuple(w) for w in end])


@settings(max_examples=80, deadline=None)
@given(plans())
def test_reads_of_variables_nothing_changes_order_nothing(plan: Plan) -> None:
    """Recording every read (as if any action could change anything) gives the
    same orderings as recording only the reads of changeable variables."""
    fast = build_plan_graph(plan, DOMAIN, _knowledge().state(), reduce=False)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(ground_moves, "written_names", lambda effect: None)
        every = build_plan_graph(plan, DOMAIN, _knowledge().state(), reduce=False)
    assert fast.orderings == every.orderings
    assert fast.unexplained == every.unexplained


def test_a_plan_with_unchanged_facts_still_waits_on_changed_ones() -> None:
    """Hand-checked: road is read (over all) by every go and written by nothing."""
    k = knowledge_from(
        DOMAIN,
        instances=dict.fromkeys(SPOTS, "spot"),
        facts=["(at s1)", "(open s2)", "(open s3)", "(road s1 s2)", "(road s2 s3)"],
        functions=["(= (energy) 3)"],
    )
    plan = Plan((PlanStep(0.0, "go", ("s1", "s2"), 2.0), PlanStep(2.5, "go", ("s2", "s3"), 2.0)))
    graph = build_plan_graph(plan, DOMAIN, k.state())
    assert [(o.source, o.target, o.subject) for o in graph.orderings] == [(0, 1, "(at s2)")]
