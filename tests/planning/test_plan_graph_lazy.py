"""The plan graph's networkx view is made on demand from the orderings, and the
build pauses the cyclic collector only while it runs.

The networkx graph and the DOT view are now made from the step-level edges the
builder keeps; these tests check that both say what the orderings say.
"""

from __future__ import annotations

import gc

import pytest
from execution_helpers import knowledge_from, load_domain
from test_plan_graph import FACTORY_PLAN

from plansys_bridge.errors import ExecutionError
from plansys_bridge.planning import ground_moves
from plansys_bridge.planning.plan import parse_plan
from plansys_bridge.planning.plan_graph import build_plan_graph

PLAN = FACTORY_PLAN + "10.002: (move robot3 assembly_zone body_car_zone)  [5.000]\n"


@pytest.mark.parametrize("reduce", [True, False])
def test_the_networkx_graph_says_what_the_orderings_say(reduce: bool) -> None:
    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    graph = build_plan_graph(parse_plan(PLAN), domain, k.state(), reduce=reduce)
    assert graph.orderings
    expected: dict[tuple[int, int], list[object]] = {}
    for o in graph.orderings:
        expected.setdefault((o.source, o.target), []).append(o)
    nx_graph = graph.graph
    assert graph.graph is nx_graph  # made once
    assert sorted(nx_graph.nodes) == list(range(len(graph.steps)))
    for i, step in enumerate(graph.steps):
        assert nx_graph.nodes[i] == {
            "action": step.text,
            "time": step.time,
            "duration": step.duration,
        }
    assert sorted(nx_graph.edges) == sorted(expected)
    for (src, dst), orderings in expected.items():
        data = nx_graph.edges[src, dst]
        assert data["orderings"] == orderings
        assert data["points"] == {(o.source_point, o.target_point) for o in orderings}
        assert data["reason"] == "; ".join(o.reason for o in orderings)  # type: ignore[attr-defined]
    assert list(graph.edge_reasons()) == [
        (src, dst, data["reason"]) for src, dst, data in sorted(nx_graph.edges(data=True))
    ]
    # the orderings are sorted by the plan position of their target, then source
    for o in graph.orderings:
        assert (o.source, o.source_point) in graph.waits(o.target, o.target_point)


@pytest.mark.parametrize("enabled", [True, False])
def test_the_build_leaves_the_collector_as_it_found_it(enabled: bool) -> None:
    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    was = gc.isenabled()
    try:
        (gc.enable if enabled else gc.disable)()
        build_plan_graph(parse_plan(PLAN), domain, k.state())
        assert gc.isenabled() is enabled
        with pytest.raises(ExecutionError, match="plan step 0"):
            build_plan_graph(parse_plan("0.0: (fly robot1) [1.0]"), domain, k.state())
        assert gc.isenabled() is enabled
    finally:
        (gc.enable if was else gc.disable)()


def test_plain_effects_and_the_general_path_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    """A plain effect is applied with State.with_changes and its adds are taken as
    achieved without a look-up; the evaluator's general path must say the same."""
    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    plain = build_plan_graph(parse_plan(PLAN), domain, k.state())
    monkeypatch.setattr(ground_moves, "writes_fixed", lambda effect: False)
    general = build_plan_graph(parse_plan(PLAN), domain, k.state())
    assert plain.achievers and plain.achievers == general.achievers
    assert plain.orderings == general.orderings
    assert plain.unexplained == general.unexplained
    assert plain.final_state is not None and general.final_state is not None
    assert plain.final_state.facts == general.final_state.facts
