"""What the terminal needs to execute plans and see performers (the CLI provides it).

The terminal itself only talks to the knowledge and a planner; a :class:`Runner`
is how ``run`` and ``check actors`` reach a hub. ``plansys-bridge terminal
--mission M`` gives a :class:`~plansys_bridge.terminal.mission_runner.MissionRunner`;
tests may give the same with any mission file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from plansys_bridge.planning.plan import Plan

__all__ = ["Actor", "Runner"]


@dataclass(frozen=True)
class Actor:
    """A performer as its heartbeats show it."""

    name: str
    state: str
    """PlanSys2's state names: ``READY``, ``RUNNING``, ``NOT_READY``, ``FAILURE``."""
    actions: tuple[str, ...]
    """The actions it serves, with specialised arguments (``move [leia]``)."""
    seen_ago: float
    """Seconds since its last heartbeat arrived, when the listing was made, counted as
    heartbeat periods are: real seconds on the wall clock (whatever its time scale),
    mission seconds on the virtual clock."""


class Runner(Protocol):
    def execute(self, plan: Plan, *, to_goal: bool) -> str:
        """Execute ``plan``; returns the outcome to show (``error: ...`` when it failed).

        ``to_goal``: the plan is meant to reach the knowledge's goal, so a failure
        is replanned for (``run``); otherwise exactly ``plan`` runs and execution
        stops at its end or its first failure (``run action``, ``run num_actions``,
        ``run plan-file``).
        """
        ...

    def actors(self) -> list[Actor]:
        """The performers heard from now (PlanSys2 listens for two seconds)."""
        ...
