"""The executor's generator-free tick agrees with py_trees' generator tick.

:meth:`PlanRoot.tick_once` steps standard branches by a plain call
(:meth:`StandardAction.tick_step`) instead of walking ``PlanRoot.tick``'s
generators; each scenario of ``test_standard_action`` runs both ways and must give
the same records, hub messages (with their mission times) and knowledge.
"""

from __future__ import annotations

import asyncio
from dataclasses import replace

import py_trees
import pytest
from test_standard_action import SCENARIOS, _context, _observed

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.execution import phases
from plansys_bridge.execution.behaviours import ActionBranch
from plansys_bridge.execution.standard_action import StandardAction
from plansys_bridge.execution.tree_builder import PlanRoot, build_tree, default_template


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_tick_once_matches_the_generator_tick(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    fast = _observed(name, subtree=False)
    with monkeypatch.context() as m:
        m.setattr(PlanRoot, "tick_once", py_trees.behaviour.Behaviour.tick_once)
        m.setattr(StandardAction, "tick_step", _counted(StandardAction.tick_step))
        general = _observed(name, subtree=False)
    assert fast == general
    assert _counted.calls > 0  # the general path still stepped standard branches


def _counted(method):  # type: ignore[no-untyped-def]
    def wrapper(self):  # type: ignore[no-untyped-def]
        _counted.calls += 1  # type: ignore[attr-defined]
        return method(self)

    _counted.calls = 0  # type: ignore[attr-defined]
    return wrapper


def test_the_generator_tick_yields_each_branch_it_steps_then_the_root() -> None:
    ctx = _context("0: (move r2d2 kitchen hall) [5]\n0: (patrol c3po hall) [20]\n")
    ctx.hub.publish = lambda *_a: None  # type: ignore[method-assign]  # the info is not looked at
    ctx.draining = True  # both branches end at their first phase, without a performer
    root = build_tree(ctx)
    ticked = list(root.tick())
    assert ticked == [*root.children, root]
    assert [b.status for b in root.children] == [py_trees.common.Status.SUCCESS] * 2
    assert root.status == py_trees.common.Status.SUCCESS
    assert all(rt.finished and rt.skipped for rt in ctx.actions)
    assert list(root.tick()) == [root]  # finished branches are not ticked again


def test_only_phases_with_an_entry_step_are_entered() -> None:
    """The standard action skips ``initialise`` where ``enters`` is False, so
    ``enters`` must be True exactly where a phase defines ``initialise``."""
    classes = [
        c for c in vars(phases).values() if isinstance(c, type) and issubclass(c, phases.Phase)
    ]
    entering = {c.__name__ for c in classes if c.enters}
    assert entering == {"AtStartReqPhase", "ExecutePhase", "OverrunPhase"}
    assert not phases.Phase.enters


def test_an_ended_execution_is_untracked_and_wakes_the_executor() -> None:
    """ExecutePhase tracks its outcome future itself (told by the client as it
    settles it): when it ends it leaves ``ctx.tasks``, its resting branch is active
    again and a tick is due."""
    ctx = _context("0: (move r2d2 kitchen hall) [5]\n")
    rt = ctx.actions[0]
    woken: list[bool] = []
    ctx.bind_wake(lambda: woken.append(True))
    execution = phases.ExecutePhase(ctx, rt)

    async def body() -> None:
        task = execution.task = asyncio.get_running_loop().create_task(asyncio.sleep(0))
        ctx.tasks.add(task)
        task.add_done_callback(lambda _task: execution._ended())
        ctx.active.discard(rt.index)
        ctx.resting.add(rt.index)
        ctx._reads[rt.index] = frozenset()
        await task
        await asyncio.sleep(0)

    asyncio.run(body())
    assert not ctx.tasks and woken == [True]
    assert rt.index in ctx.active and rt.index not in ctx.resting


@pytest.mark.parametrize("subtree", [False, True])
def test_a_knowledge_error_in_a_stateless_step_fails_the_action_with_its_label(
    subtree: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The standard action calls the stateless steps as plain functions; an error
    they raise fails the action with the same reason as the phase behaviour gives."""
    ctx = _context("0: (move r2d2 kitchen hall) [5]\n")
    ctx.hub.publish = lambda *_a: None  # type: ignore[method-assign]  # the info is not looked at
    if subtree:
        ctx.options = replace(ctx.options, action_template=default_template)

    def refuse(*_a: object) -> None:
        raise KnowledgeError("the knowledge is read-only")

    monkeypatch.setattr(ctx.knowledge, "apply", refuse)
    root = build_tree(ctx)
    root.tick_once()
    rt = ctx.actions[0]
    assert rt.finished and not rt.start_reached
    assert rt.record.message == "ApplyAtStartEffect: the knowledge is read-only"
    assert type(root.children[0]) is (ActionBranch if subtree else StandardAction)
