"""What a performer is handed and what it may use.

An :class:`ActionGoal` is one action instance of the plan; :class:`ActionFailed`
is how ``execute()`` says it did not work; a :class:`PerformerContext` holds the
hub, the clock and the knowledge a performer may read. :func:`arguments_match` is
PlanSys2's rule for a performer specialised to some arguments (it lives with the hub's
routing, which applies it to hand a REQUEST only to the performers it fits).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from plansys_bridge.clock import Clock
from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution
from plansys_bridge.hub.routing import arguments_match

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert
    from plansys_bridge.performers.bid_costs import BidCosts

__all__ = [
    "ActionFailed",
    "ActionGoal",
    "PerformerContext",
    "arguments_match",
    "goal_of",
    "same_goal",
]


@dataclass(frozen=True)
class ActionGoal:
    """One action instance handed to a performer."""

    action: str
    arguments: tuple[str, ...]
    request_id: str

    @property
    def full_name(self) -> str:
        return "(" + " ".join((self.action, *self.arguments)) + ")"


class ActionFailed(PlansysBridgeError):
    """Raise from ``execute()`` to finish the action unsuccessfully with this message."""


@dataclass
class PerformerContext:
    """What a performer may use: the hub, the clock, the knowledge, where its files are."""

    hub: Hub
    clock: Clock
    knowledge: ProblemExpert | None = None
    base_dir: Path = field(default_factory=Path)
    recorder: object | None = None
    bid_costs: Mapping[str, BidCosts] = field(default_factory=dict)
    """Learned costs by performer name (the mission's ``bid_costs:`` file)."""


def same_goal(goal: ActionGoal, msg: ActionExecution) -> bool:
    """Does ``msg`` talk about ``goal``? (request_id when both have one, else the action text)."""
    if goal.request_id and msg.request_id and goal.request_id != msg.request_id:
        return False
    return goal.action == msg.action and goal.arguments == tuple(msg.arguments)


last_request: list[tuple[object, ActionGoal]] = [(None, ActionGoal("", (), ""))]
"""``[(REQUEST, its goal)]``: what :func:`goal_of` hands out again; the performer base
class reads it inline (every bidder but the first of an auction finds its goal here)."""


def goal_of(msg: ActionExecution) -> ActionGoal:
    """The goal a REQUEST asks for, one object for every performer handed it.

    On a hub every performer offering the action gets the same REQUEST object, one
    after another; building a goal each made an auction among N bidders build N
    equal goals. The goal of the last REQUEST is kept (by identity of the message,
    which is frozen) and handed out again: goals are frozen too, so sharing is safe.
    The entry is read and replaced whole, so loops on other threads cannot mix two.
    """
    last_msg, last_goal = last_request[0]
    if last_msg is msg:
        return last_goal
    # ActionGoal(...) filled in at once (a frozen dataclass's __init__ sets each field
    # through object.__setattr__): one goal per REQUEST, the goal is new and unshared.
    goal = _new(ActionGoal)
    arguments = msg.arguments
    goal.__dict__.update(
        action=msg.action,
        arguments=arguments if arguments.__class__ is tuple else tuple(arguments),
        request_id=msg.request_id,
    )
    last_request[0] = (msg, goal)
    return goal


_new = object.__new__
