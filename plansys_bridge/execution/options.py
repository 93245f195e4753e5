"""How the executor behaves: timeouts, auction policy, replanning, templates.

One frozen dataclass so a mission file's settings, a test's tweaks and the CLI's
flags all end up in the same validated place; wrong values raise ``ConfigError``
naming the key (``execution.at_start_timeout``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.auction import AuctionPolicy

if TYPE_CHECKING:
    import py_trees

ActionTemplate = Callable[[Any], "py_trees.behaviour.Behaviour"]
"""Builds one action's subtree from the standard behaviours an
:class:`~plansys_bridge.execution.tree_builder.ActionNodes` hands out
(``nodes.default()`` is the standard subtree). The argument is typed ``Any`` here
because the nodes need a running plan's context, which needs these options: naming
the class would make the options and the behaviours import each other."""

__all__ = ["ActionTemplate", "ExecutorOptions"]


@dataclass(frozen=True)
class ExecutorOptions:
    """Executor settings (all times in mission seconds).

    * ``auction``: how each action's performer is found (see ``AuctionPolicy``).
    * ``at_start_timeout``: an at-start requirement that does not hold this long
      after the action's predecessors are done fails the action (PlanSys2 #218
      waits forever); ``None`` waits forever.
    * ``overrun_percentage``: fail an action running longer than its planned
      duration plus this percentage (the CheckTimeout behaviour); ``None``: never.
    * ``max_replans``: how many new plans may be requested after failures.
    * ``max_ticks_per_wake``: ticks in a row while something keeps changing (a
      guard against a template that changes state on every tick).
    * ``publish_dot``: publish the coloured DOT graph on ``dot_graph`` after
      changes (coalesced: at most once per wake-up). The text is kept between
      publications and only changed nodes are rewritten.
    * ``dot_period``: at most one DOT publication per this many mission seconds
      (0: after every change, which costs a whole graph per event on large plans);
      the final state is always published.
    * ``info_period``: an action's FEEDBACK is published as
      ``action_execution_info`` at most once per this many mission seconds (0:
      every one); status changes are always published at once.
    * ``halt_on_failure``: after a failure, also halt the actions still running
      (PlanSys2's behaviour) instead of letting them finish first; replanning then
      starts at once, but their work so far is lost.
    * ``rollback_on_halt``: when an action is halted or fails after its at-start
      effects were applied, undo those effects (each only if nothing changed it
      since), so the knowledge used for replanning does not keep half an action.
    * ``action_template``: builds every action's subtree (default: the standard one).
    * ``templates``: per action name, a template that replaces the default.
    * ``action_timeouts``: per action name, ``duration_overrun_percentage`` and/or
      ``at_start_timeout`` overriding the global ones for that action (PlanSys2's
      ``action_timeouts.<action>.duration_overrun_percentage`` parameters).
    """

    auction: AuctionPolicy = field(default_factory=AuctionPolicy)
    at_start_timeout: float | None = 10.0
    overrun_percentage: float | None = None
    max_replans: int = 3
    max_ticks_per_wake: int = 1000
    publish_dot: bool = True
    dot_period: float = 1.0
    info_period: float = 0.5
    halt_on_failure: bool = False
    rollback_on_halt: bool = True
    action_template: ActionTemplate | None = None
    templates: Mapping[str, ActionTemplate] = field(default_factory=dict)
    action_timeouts: Mapping[str, Mapping[str, float | None]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _optional_positive(self.at_start_timeout, "execution.at_start_timeout", allow_zero=True)
        _optional_positive(self.overrun_percentage, "execution.overrun_percentage", allow_zero=True)
        if self.dot_period is None:
            raise ConfigError("must be a number >= 0", key="execution.dot_period")
        _optional_positive(self.dot_period, "execution.dot_period", allow_zero=True)
        if self.info_period is None:
            raise ConfigError("must be a number >= 0", key="execution.info_period")
        _optional_positive(self.info_period, "execution.info_period", allow_zero=True)
        if isinstance(self.max_replans, bool) or not isinstance(self.max_replans, int):
            raise ConfigError(
                f"must be an integer, got {self.max_replans!r}", key="replanning.max_replans"
            )
        if self.max_replans < 0:
            raise ConfigError(f"must be >= 0, got {self.max_replans}", key="replanning.max_replans")
        if not isinstance(self.max_ticks_per_wake, int) or self.max_ticks_per_wake < 1:
            raise ConfigError(
                f"must be an integer >= 1, got {self.max_ticks_per_wake!r}",
                key="execution.max_ticks_per_wake",
            )
        for name, template in self.templates.items():
            if not callable(template):
                raise ConfigError("template must be callable", key=f"execution.templates.{name}")

        if not isinstance(self.action_timeouts, Mapping):
            raise ConfigError(
                "must map action names to {duration_overrun_percentage, at_start_timeout}",
                key="execution.action_timeouts",
            )
        for name, limits in self.action_timeouts.items():
            where = f"execution.action_timeouts.{name}"
            if not isinstance(limits, Mapping):
                raise ConfigError(
                    "must be a mapping {duration_overrun_percentage: N, at_start_timeout: S}",
                    key=where,
                )
            for limit, value in limits.items():
                if limit not in _ACTION_LIMITS:
                    raise ConfigError(
                        f"unknown setting (expected one of {', '.join(_ACTION_LIMITS)})",
                        key=f"{where}.{limit}",
                    )
                _optional_positive(value, f"{where}.{limit}", allow_zero=True)

    def overrun_for(self, action: str) -> float | None:
        """The overrun percentage of ``action``: its own limit, else the global one."""
        if not self.action_timeouts:  # asked once or twice per action: skip the search
            return self.overrun_percentage
        limits = _limits(self.action_timeouts, action)
        if "duration_overrun_percentage" in limits:
            return limits["duration_overrun_percentage"]
        return self.overrun_percentage

    def at_start_timeout_for(self, action: str) -> float | None:
        """The at-start timeout of ``action``: its own, else the global one."""
        if not self.action_timeouts:  # asked once or twice per action: skip the search
            return self.at_start_timeout
        limits = _limits(self.action_timeouts, action)
        if "at_start_timeout" in limits:
            return limits["at_start_timeout"]
        return self.at_start_timeout

    def template_for(self, action: str) -> ActionTemplate | None:
        """The template for ``action``: its own, else the global one, else None."""
        return self.templates.get(action, self.action_template)

    @classmethod
    def from_config(
        cls,
        config: Mapping[str, Any] | None,
        *,
        auction: Mapping[str, Any] | None = None,
        replanning: Mapping[str, Any] | None = None,
        key: str = "execution",
    ) -> ExecutorOptions:
        """Build from a mission file's ``execution:``, ``auction:`` and ``replanning:``
        sections; unknown keys raise ``ConfigError(key=...)``."""
        values: dict[str, Any] = {}
        allowed = {f.name for f in fields(cls)} - {
            "auction",
            "action_template",
            "templates",
            "max_replans",
        }
        for name, value in (config or {}).items():
            if name not in allowed:
                raise ConfigError(
                    f"unknown setting (expected one of {', '.join(sorted(allowed))})",
                    key=f"{key}.{name}",
                )
            values[name] = value
        for name, value in (replanning or {}).items():
            if name != "max_replans":
                raise ConfigError(
                    "unknown setting (expected max_replans)", key=f"replanning.{name}"
                )
            values["max_replans"] = value
        values["auction"] = AuctionPolicy.from_config(auction)
        return cls(**values)


_ACTION_LIMITS = ("duration_overrun_percentage", "at_start_timeout")


def _limits(table: Mapping[str, Mapping[str, float | None]], action: str) -> Mapping[str, Any]:
    """The limits of ``action`` (names compare case-insensitively, as PDDL's do)."""
    for name, limits in table.items():
        if name.lower() == action.lower():
            return limits
    return {}


def _optional_positive(value: object, key: str, *, allow_zero: bool) -> None:
    if value is None:
        return
    ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):  # type: ignore[operator]
        raise ConfigError(f"must be a number >= 0 or null, got {value!r}", key=key)
