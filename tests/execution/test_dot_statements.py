"""The DOT view writes a node's statement from a quoted label prefix and a cached
state tail; it must be what the general statement writer makes of the whole label."""

from __future__ import annotations

import pytest
from execution_helpers import knowledge_from, load_domain
from hypothesis import given
from hypothesis import strategies as st

from plansys_bridge.execution.dot import IncrementalDot, _quoted_inner, _statement
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.planning.plan import Plan, PlanStep, parse_plan
from plansys_bridge.planning.plan_graph import PlanGraph, build_plan_graph

_PLAN = """
0.000: (move robot3 assembly_zone wheels_zone) [5.000]
0.000: (move robot2 assembly_zone steering_wheels_zone) [5.000]
5.001: (transport robot3 wheel_3 wheels_zone assembly_zone) [5.000]
10.002: (move robot3 assembly_zone body_car_zone) [5.000]
"""

_TEXT = st.text(alphabet=st.sampled_from(list('ab "\\\r\n{}[];,=-x\t\x00')), max_size=12)
"""Texts with what DOT quoting changes; a NUL takes the dot view's one-by-one path."""


def _graph(steps: list[PlanStep]) -> PlanGraph:
    return PlanGraph(plan=Plan(tuple(steps)), steps=tuple(steps), ground=(), orderings=())


@given(
    st.lists(
        st.tuples(_TEXT, st.lists(_TEXT, max_size=3), st.floats(0, 1e6), st.floats(0, 1e3)),
        min_size=1,
        max_size=4,
    )
)
def test_node_statements_are_what_the_general_writer_makes(
    rows: list[tuple[str, list[str], float, float]],
) -> None:
    steps = [PlanStep(t, name, tuple(args), d) for name, args, t, d in rows]
    dot = IncrementalDot(_graph(steps))
    for status in ActionStatus:
        for i, step in enumerate(steps):
            label = f"{i}: {step.text}\n[{step.time:.3f}, {step.duration:.3f}] "
            label += status.name.lower()
            colour = {
                ActionStatus.NOT_EXECUTED: "white",
                ActionStatus.EXECUTING: "yellow",
                ActionStatus.SUCCEEDED: "palegreen",
                ActionStatus.FAILED: "tomato",
                ActionStatus.CANCELLED: "orange",
            }[status]
            assert dot._node(i, status) == _statement(f"a{i}", label=label, fillcolor=colour)


def test_a_state_change_rewrites_its_node_only() -> None:
    steps = [PlanStep(float(i), "go", (f"r{i}",), 1.0) for i in range(3)]
    dot = IncrementalDot(_graph(steps))
    before = dot.text()
    dot.set_status(1, ActionStatus.FAILED)
    after = dot.text()
    assert before.replace(
        "1: (go r1)\\n[1.000, 1.000] not_executed", "1: (go r1)\\n[1.000, 1.000] failed"
    ) == after.replace("fillcolor=tomato", "fillcolor=white")
    with pytest.raises(IndexError):
        dot.set_status(3, ActionStatus.FAILED)


@given(st.lists(_TEXT, max_size=6))
def test_texts_quoted_together_are_quoted_as_each_alone(texts: list[str]) -> None:
    together = _quoted_inner(texts)
    assert together == [
        _statement("x", label=t)[len("x [label=") : -len("];\n")][1:-1] for t in texts
    ]


def test_edge_statements_are_what_the_general_writer_makes() -> None:
    domain = load_domain("factory.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    graph = build_plan_graph(parse_plan(_PLAN), domain, k.state())
    text = IncrementalDot(graph).text()
    edges = sorted(graph.graph.edges(data=True))
    assert edges
    expected = "".join(_statement(f"a{s} -> a{d}", tooltip=data["reason"]) for s, d, data in edges)
    assert expected in text
