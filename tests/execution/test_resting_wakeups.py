"""A knowledge change wakes exactly the resting branches whose over-all
requirement reads something it touched (all of them when objects come or go),
found by the names the change touched rather than by asking every branch."""

from __future__ import annotations

from types import SimpleNamespace

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.plan_context import PlanContext
from plansys_bridge.knowledge.changes import KnowledgeChange
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Atom
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.planning.plan import parse_plan
from plansys_bridge.planning.plan_graph import build_plan_graph

DOMAIN = parse_domain(
    """(define (domain w) (:requirements :typing :durative-actions :fluents)
      (:types robot)
      (:predicates (ok ?r - robot) (lit) (done ?r - robot))
      (:functions (charge ?r - robot))
      (:durative-action work :parameters (?r - robot) :duration (= ?duration 5)
        :condition (over all (ok ?r)) :effect (at end (done ?r)))
      (:durative-action watch :parameters (?r - robot) :duration (= ?duration 5)
        :condition (over all (and (lit) (> (charge ?r) 0))) :effect (at end (done ?r)))
      (:durative-action idle :parameters (?r - robot) :duration (= ?duration 5)
        :effect (at end (done ?r))))""",
    "<w>",
)
PLAN = "0: (work r1) [5]\n0: (watch r2) [5]\n0: (idle r3) [5]\n"
READS = [{"ok"}, {"lit", "charge"}, set()]
NAMES = ["ok", "lit", "done", "charge"]


def _context() -> PlanContext:
    k = ProblemExpert(DOMAIN)
    for r in ("r1", "r2", "r3"):
        k.add_instance(r, "robot")
    k.add_predicate("(ok r1)")
    k.add_predicate("(lit)")
    k.set_function("(= (charge r2) 1)")
    graph = build_plan_graph(parse_plan(PLAN), DOMAIN, k.state())
    ctx = PlanContext(
        # only the clock, and whether the execution info has an audience (it has)
        hub=SimpleNamespace(clock=VirtualClock(), has_audience=lambda topic: True),  # type: ignore[arg-type]
        knowledge=k,
        evaluator=k.evaluator,
        graph=graph,
        options=ExecutorOptions(),
        plan_id="p",
        plan_index=0,
    )
    for rt in ctx.actions:
        rt.may_rest = True
    return ctx


def _change(
    facts: list[str], fluents: list[str], removed: list[str], objects: bool
) -> KnowledgeChange:
    return KnowledgeChange(
        version=1,
        reason="test",
        added_instances={"r9": "robot"} if objects else {},
        added_facts=frozenset(Atom(n, ("r1",)) for n in facts[::2]),
        removed_facts=frozenset(Atom(n, ("r2",)) for n in facts[1::2]),
        changed_fluents={(n, ("r2",)): 2.0 for n in fluents},
        removed_fluents=frozenset((n, ("r1",)) for n in removed),
    )


_NAME_LISTS = st.lists(st.sampled_from(NAMES), max_size=3)
Touch = tuple[list[str], list[str], list[str], bool]
_OPS = st.lists(
    st.tuples(
        st.sampled_from(["rest", "resume", "change"]),
        st.integers(0, 2),
        st.tuples(_NAME_LISTS, _NAME_LISTS, _NAME_LISTS, st.booleans()),
    ),
    max_size=12,
)


@settings(max_examples=80, deadline=None)
@given(ops=_OPS)
def test_a_change_wakes_the_branches_that_read_it(ops: list[tuple[str, int, Touch]]) -> None:
    ctx = _context()
    resting: set[int] = set()
    active = set(ctx.active)
    for op, index, (facts, fluents, removed, objects) in ops:
        if op == "rest":
            ctx.rest(ctx.actions[index])
            resting.add(index)
            active.discard(index)
        elif op == "resume":
            ctx.resume(index)
            if index in resting:
                resting.discard(index)
                active.add(index)
        else:
            ctx.knowledge_changed(_change(facts, fluents, removed, objects))
            touched = set(facts) | set(fluents) | set(removed)
            woken = {i for i in resting if objects or touched & READS[i]}
            resting -= woken
            active |= woken
        assert ctx.resting == resting and ctx.active == active
        readers = {n: {i for i in resting if n in READS[i]} for n in NAMES}
        assert ctx._readers == {n: found for n, found in readers.items() if found}


def test_the_names_an_over_all_reads() -> None:
    ctx = _context()
    assert [ctx._over_all_reads(rt) for rt in ctx.actions] == [frozenset(r) for r in READS]
