"""The one-behaviour standard action behaves exactly as the standard subtree.

Each scenario (success, at-start timeout, over-all violation, overrun, cancel, a
failure with running actions halted or left to finish) runs twice on the virtual
clock: once with the default (a :class:`StandardAction` per action) and once with
``action_template`` building the standard py_trees subtree. Everything observable
must be the same: the records, every message on the hub with its mission time,
and the knowledge at the end.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Sequence
from dataclasses import asdict, replace
from types import SimpleNamespace

import py_trees
import pytest
from execution_helpers import Event, PerformerSpec, knowledge_from, load_domain, run_scenario

from plansys_bridge.clock import VirtualClock
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.plan_context import PlanContext
from plansys_bridge.execution.standard_action import StandardAction
from plansys_bridge.execution.tree_builder import PlanRoot, build_tree, default_template
from plansys_bridge.hub.messages import Topics
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.planning.plan import parse_plan
from plansys_bridge.planning.plan_graph import build_plan_graph

PERFORMERS = [
    PerformerSpec(
        "r2d2_node",
        {"move": ["r2d2"], "patrol": ["r2d2"], "askcharge": ["r2d2"], "charge": ["r2d2"]},
        {"move": 5.0, "patrol": 2.0, "askcharge": 5.0, "charge": 5.0},
        {"feedback_period": 1.0},
    ),
    PerformerSpec("c3po_node", {"patrol": ["c3po"], "move": ["c3po"]}, {"patrol": 20.0}),
]
SLOW = [PerformerSpec("slow", {"patrol": ["r2d2"], "move": ["r2d2"]}, {"move": 20.0})]

PLAN = (
    "0.000: (patrol r2d2 kitchen) [2.000]\n"
    "2.001: (move r2d2 kitchen hall) [5.000]\n"
    "7.002: (patrol r2d2 hall) [2.000]\n"
)
PARALLEL = "0: (move r2d2 kitchen hall) [5]\n0: (patrol c3po hall) [20]\n"


def _knowledge(*extra: str) -> ProblemExpert:
    """The scenarios' world; ``extra``: more facts."""
    return knowledge_from(
        load_domain("simple_example.pddl"),
        instances={
            "r2d2": "robot",
            "c3po": "robot",
            "kitchen": "room",
            "hall": "room",
            "dock": "room",
        },
        facts=[
            "(robot_at r2d2 kitchen)",
            "(robot_at c3po hall)",
            "(connected kitchen hall)",
            "(connected hall kitchen)",
            "(charging_point_at dock)",
            "(battery_full r2d2)",
            *extra,
        ],
        goal="(and (patrolled kitchen) (patrolled hall))",
    )


def _remove(fact: str) -> Callable[[ProblemExpert, Executor], None]:
    return lambda knowledge, _e: knowledge.remove_predicate(fact)


def _cancel(_k: ProblemExpert, executor: Executor) -> None:
    executor.cancel()


SCENARIOS: dict[str, tuple[str, Sequence[PerformerSpec], ExecutorOptions, list[Event]]] = {
    "success": (PLAN, PERFORMERS, ExecutorOptions(), []),
    "at_start_timeout": (
        PLAN,
        PERFORMERS,
        ExecutorOptions(at_start_timeout=3.0),
        [(1.0, _remove("(connected kitchen hall)"))],
    ),
    "over_all_violation": (
        PLAN,
        PERFORMERS,
        ExecutorOptions(),
        [(4.0, _remove("(battery_full r2d2)"))],
    ),
    "overrun": (PLAN, SLOW, ExecutorOptions(overrun_percentage=50.0), []),
    "cancel": (PLAN, PERFORMERS, ExecutorOptions(), [(3.0, _cancel)]),
    "failure_halts": (
        PARALLEL,
        PERFORMERS,
        ExecutorOptions(halt_on_failure=True),
        [(3.0, _remove("(battery_full r2d2)"))],
    ),
    "failure_lets_finish": (
        PARALLEL,
        PERFORMERS,
        ExecutorOptions(),
        [(3.0, _remove("(battery_full r2d2)"))],
    ),
}


def _observed(name: str, *, subtree: bool) -> tuple[object, ...]:
    text, performers, options, events = SCENARIOS[name]
    if subtree:
        options = replace(options, action_template=default_template)
    return observe(text, performers, options, events, _knowledge())


def observe(
    text: str,
    performers: Sequence[PerformerSpec],
    options: ExecutorOptions,
    events: list[Event],
    knowledge: ProblemExpert,
) -> tuple[object, ...]:
    """Everything observable of executing plan ``text``: the result, its records,
    every message on the hub with its mission time, the knowledge at the end."""

    async def body(executor: Executor):  # type: ignore[no-untyped-def]
        return await executor.execute(parse_plan(text), plan_id="p")

    run = run_scenario(
        load_domain("simple_example.pddl"),
        knowledge,
        body,
        performers,
        options=options,
        events=events,
        topics=(Topics.ACTIONS_HUB, Topics.ACTION_EXECUTION_INFO, Topics.DOT_GRAPH),
    )
    result = run.result
    return (
        result.status,
        result.message,
        result.finished,
        [asdict(a) for a in result.actions],
        [(t, topic, repr(m)) for t, topic, m in run.messages],
        sorted(map(str, knowledge.state().facts)),
    )


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_standard_action_matches_the_standard_subtree(name: str) -> None:
    compact = _observed(name, subtree=False)
    assert compact == _observed(name, subtree=True)


def test_scenarios_end_as_their_names_say() -> None:
    """Guards the comparison above against scenarios that all end the same way."""
    statuses = {
        name: _observed(name, subtree=False)[0] for name in ("success", "cancel", "overrun")
    }
    assert statuses == {"success": "succeeded", "cancel": "cancelled", "overrun": "failed"}


def test_one_behaviour_per_action_without_a_template() -> None:
    ctx = _context(PLAN)
    root = build_tree(ctx)
    assert isinstance(root, PlanRoot)
    assert [type(b) for b in root.iterate()] == [StandardAction] * 3 + [PlanRoot]


def _context(plan_text: str) -> PlanContext:
    knowledge = _knowledge()
    domain = load_domain("simple_example.pddl")
    graph = build_plan_graph(parse_plan(plan_text), domain, knowledge.state())
    return PlanContext(
        # only the clock is read, and whether the execution info has an audience (it has)
        hub=SimpleNamespace(clock=VirtualClock(), has_audience=lambda topic: True),  # type: ignore[arg-type]
        knowledge=knowledge,
        evaluator=Evaluator(domain),
        graph=graph,
        options=ExecutorOptions(),
        plan_id="p",
        plan_index=0,
    )


def test_a_deadline_wakes_its_resting_owner_only() -> None:
    ctx = _context(PARALLEL)
    for rt in ctx.actions:
        rt.may_rest = True
        ctx.rest(rt)
    assert ctx.resting == {0, 1} and not ctx.active
    ctx.schedule(ctx.now())  # a deadline of nobody's (the DOT's, a template's)
    ctx.pass_deadlines()
    assert ctx.resting == {0, 1}
    ctx.schedule(ctx.now() + 1.0, 1)
    ctx.schedule(ctx.now(), 0)
    assert ctx.next_deadline() == ctx.now()
    ctx.pass_deadlines()
    assert ctx.resting == {1} and ctx.active == {0}
    assert ctx.next_deadline() == ctx.now() + 1.0


def test_a_standard_action_has_what_a_py_trees_behaviour_has() -> None:
    """StandardAction has Behaviour.__init__'s attributes without setting them in its
    own __init__: the constant ones read from its class, the others (name, lists,
    uuid, logger, tick generator) made on first use, as py_trees would have made them."""
    ctx = _context(PLAN)
    root = build_tree(ctx)
    first, second = root.children[:2]
    assert set(vars(first)) == {"ctx", "rt", "parent"}  # parent: set by the root
    assert first.name == "(patrol r2d2 kitchen):0"
    reference = py_trees.behaviours.Success(first.name)
    made_on_use = {"id", "logger", "iterator"}
    for key, value in vars(reference).items():
        if key == "qualified_name":
            assert first.qualified_name == f"StandardAction/{first.name}"
        elif key == "parent":
            assert first.parent is root and second.parent is root
        elif key not in made_on_use:
            assert getattr(first, key) == value, key
    assert isinstance(first.id, uuid.UUID) and first.id == first.id != second.id
    first.children.append(reference)  # each behaviour's lists are its own
    assert first.children == [reference] and second.children == [] and second.blackboards == []
    first.children.clear()
    assert first.logger.prefix == py_trees.logging.Logger(first.name).prefix
    ctx.hub.publish = lambda *_a: None  # type: ignore[attr-defined]  # the info is not looked at
    ctx.draining = True  # the branch ends at its first phase, without a performer
    assert list(first.iterator) == [first]  # the generator tick, stepping the branch
    assert ctx.actions[0].finished and ctx.actions[0].skipped
    with pytest.raises(AttributeError, match="no_such_thing"):
        _ = first.no_such_thing
