"""A simulated performer: takes the time an action should take, then succeeds (mostly).

Used by demos, tests, experiments and the soak run. Durations come, in this order,
from a ``duration_hint`` callable (the executor can pass the planned duration), the
``durations`` table keyed by the full action text ``"(move r1 a b)"``, the same table
keyed by action name, and ``default_duration``. Time is the context clock's mission
time, so the same mission runs in real time, scaled, or on the virtual clock.

Fault injection reproduces what breaks PlanSys2 in the field, each with a seeded
random rate (for soak runs) or a one-shot trigger (for tests):

* *die mid-action*: the performer goes silent (no heartbeat, no feedback, no FINISH,
  no RESPONSE) part-way through; with ``revive_after`` it comes back later, as a
  restarted robot does, having dropped the goal;
* *lose FINISH*: the work completes but the FINISH message never arrives;
* *never answer*: the performer heartbeats but ignores every REQUEST.
"""

from __future__ import annotations

import asyncio
import logging
import math
import random
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Annotated, Any, TypedDict

from pydantic import Field, field_validator

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.settings import is_number
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.entry import PerformerConfig
from plansys_bridge.plugins import DirectSettings, validate_settings

if TYPE_CHECKING:
    from typing_extensions import Unpack

__all__ = ["FaultPlan", "SimulatedOptions", "SimulatedPerformer", "SimulatedSettings"]

log = logging.getLogger(__name__)

DurationHint = Callable[[ActionGoal], float | None]


class FaultPlan(DirectSettings):
    """Seeded fault rates for a :class:`SimulatedPerformer` (all off by default): the
    entry's ``faults:`` keys, also built directly by the soak and experiment runs."""

    die_rate: float = Field(0.0, ge=0.0, le=1.0)
    """Probability that a goal makes the performer die part-way through."""
    lose_finish_rate: float = Field(0.0, ge=0.0, le=1.0)
    """Probability that a goal's FINISH is never sent."""
    never_answer: bool = False
    """Ignore every REQUEST (while still sending heartbeats)."""
    revive_after: float | None = Field(None, ge=0.0)
    """Mission seconds after dying before the performer is back (None: stays dead)."""
    die_at: float = Field(0.5, ge=0.0, lt=1.0)
    """Fraction of the action's duration at which a dying performer goes silent."""

    @classmethod
    def from_config(cls, config: object, key: str) -> FaultPlan:
        """The plan a ``faults:`` mapping describes (null: no faults); errors name the key."""
        return validate_settings(cls, config, key=key)


def _none_is_default(value: object) -> object:
    """``faults: null`` in a mission file means no faults, as leaving the key out does."""
    return {} if value is None else value


class SimulatedSettings(DirectSettings):
    """The kind-specific keys of a ``kind: simulated`` performer entry."""

    durations: dict[str, Annotated[float, Field(ge=0.0)]] = Field(default_factory=dict)
    """Seconds per action name or per full action text ``"(move r1 a b)"``."""
    default_duration: float = Field(1.0, ge=0.0)
    success_rate: float = Field(1.0, ge=0.0, le=1.0)
    seed: int = 0
    feedback_period: float | None = Field(1.0, gt=0.0)
    """Mission seconds between two FEEDBACKs (null: none)."""
    faults: FaultPlan = Field(default_factory=FaultPlan)

    _faults = field_validator("faults", mode="before")(_none_is_default)


class SimulatedOptions(TypedDict, total=False):
    """The settings as keywords, for code that builds a performer without a mission file."""

    durations: Mapping[str, float]
    default_duration: float
    success_rate: float
    seed: int
    feedback_period: float | None
    faults: FaultPlan | Mapping[str, Any] | None


class SimulatedPerformer(ActionPerformer):
    """Sleeps for the action's duration on the mission clock, sending progress feedback.

    Built from a mission entry it gets its validated :class:`SimulatedSettings` as
    ``settings=``; code building one directly may give the same values as keywords
    (:class:`SimulatedOptions`), which go through the same model.
    """

    Settings = SimulatedSettings

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        heartbeat_period: float = 1.0,
        commit_timeout: float = 2.0,
        settings: SimulatedSettings | None = None,
        duration_hint: DurationHint | None = None,
        **options: Unpack[SimulatedOptions],
    ) -> None:
        super().__init__(
            context,
            node_name,
            actions,
            heartbeat_period=heartbeat_period,
            commit_timeout=commit_timeout,
        )
        if settings is None:
            settings = _settings_of(options)
        elif options:
            raise TypeError(f"give settings= or keywords ({', '.join(options)}), not both")
        self.settings = settings
        self.durations: dict[str, float] = {
            name.strip().lower(): float(seconds) for name, seconds in settings.durations.items()
        }
        self.default_duration = float(settings.default_duration)
        self.success_rate = float(settings.success_rate)
        period = settings.feedback_period
        self.feedback_period = None if period is None else float(period)
        self.faults = settings.faults
        self.duration_hint = duration_hint
        self.seed = settings.seed
        self._rng = random.Random(f"{self.seed}:{node_name}:outcome")
        self._fault_rng = random.Random(f"{self.seed}:{node_name}:faults")
        self.dead = False
        self.unresponsive = self.faults.never_answer
        self._die_next = False
        self._lose_next_finish = False
        self._drop_finish = False
        self._revive_timer: asyncio.TimerHandle | None = None
        self.stats: dict[str, int] = {"succeeded": 0, "failed": 0, "died": 0, "lost_finish": 0}

    @classmethod
    def parse_config(cls, config: Mapping[str, Any], *, key: str = "performer") -> PerformerConfig:
        """The settings model, then what it cannot see: each ``durations`` key names one
        of the entry's actions (a misspelt one would silently never apply)."""
        entry = super().parse_config(config, key=key)
        for name in entry.settings.durations:
            # an action name, or a full action text "(move r1 a b)"
            action = name.strip().lstrip("(").split(maxsplit=1)[:1]
            if not action or action[0].lower() not in entry.actions:
                raise ConfigError(
                    f"not one of this performer's actions ({', '.join(entry.actions)})",
                    key=f"{key}.durations.{name}",
                )
        return entry

    # ------------------------------------------------------------------ durations

    def duration_for(self, goal: ActionGoal) -> float:
        """Mission seconds ``goal`` takes (hint, full text, action name, default)."""
        if self.duration_hint is not None:
            hinted = self.duration_hint(goal)
            if hinted is not None and is_number(hinted) and hinted >= 0:
                return float(hinted)
        by_text = self.durations.get(goal.full_name.lower())
        if by_text is not None:
            return by_text
        return self.durations.get(goal.action, self.default_duration)

    def set_duration(self, key: str, seconds: float) -> None:
        """Set the duration of an action name or of one full action text."""
        self.durations[key.strip().lower()] = float(seconds)

    # ------------------------------------------------------------------ fault triggers

    def die_during_next(self) -> None:
        """The next goal makes this performer go silent part-way through."""
        self._die_next = True

    def lose_next_finish(self) -> None:
        """The next goal's FINISH is not sent."""
        self._lose_next_finish = True

    def set_unresponsive(self, unresponsive: bool = True) -> None:
        """Ignore (or answer again) REQUESTs."""
        self.unresponsive = unresponsive

    def kill(self) -> None:
        """Go silent now, as a crashed node: nothing more is sent until :meth:`revive`."""
        if not self.dead:
            self.dead = True
            self.stats["died"] += 1
            self._release_commitment()
            if self.faults.revive_after is not None:
                self._revive_timer = asyncio.get_running_loop().call_later(
                    self.faults.revive_after * self.clock.time_scale, self.revive
                )

    def revive(self) -> None:
        """Come back as a restarted node: the goal held when dying is dropped."""
        if self._revive_timer is not None:
            self._revive_timer.cancel()
            self._revive_timer = None
        if not self.dead:
            return
        self.dead = False
        task = self._task
        if task is None:
            self._publish_status()
        elif not self._cancelling:
            self._cancelling = True
            task.cancel()  # the goal ends without FINISH; READY is announced after it

    # ------------------------------------------------------------------ performer

    def accepts(self, goal: ActionGoal) -> bool:
        return not (self.unresponsive or self.dead)

    async def execute(self, goal: ActionGoal) -> str | None:
        duration = self.duration_for(goal)
        succeed = self._rng.random() < self.success_rate
        die = self._die_next or (
            self.faults.die_rate > 0 and self._fault_rng.random() < self.faults.die_rate
        )
        lose_finish = self._lose_next_finish or (
            self.faults.lose_finish_rate > 0
            and self._fault_rng.random() < self.faults.lose_finish_rate
        )
        self._die_next = False
        self._lose_next_finish = False
        die_at = duration * self.faults.die_at if die else math.inf
        elapsed = 0.0
        while elapsed < duration or die:
            if elapsed >= die_at:
                self.kill()
                await asyncio.Event().wait()  # silent until revived (cancel) or stopped
            step = duration - elapsed
            if self.feedback_period is not None:
                step = min(step, self.feedback_period)
            if die:
                step = min(step, die_at - elapsed)
            await self.clock.sleep(step)
            elapsed += step
            if elapsed < duration and elapsed < die_at:
                self.feedback(
                    elapsed / duration if duration else 1.0, f"{elapsed:g}/{duration:g} s"
                )
        if lose_finish:
            self._drop_finish = True
        if not succeed:
            self.stats["failed"] += 1
            raise ActionFailed(
                f"{goal.full_name} failed (simulated, success rate {self.success_rate:g})"
            )
        self.stats["succeeded"] += 1
        return f"{goal.full_name} done in {duration:g} s"

    def _finish(self, goal: ActionGoal, success: bool, status: str) -> None:
        if self._drop_finish:
            self._drop_finish = False
            self.stats["lost_finish"] += 1
            log.info(
                "performer %s: FINISH of %s lost (fault injection)", self.node_name, goal.full_name
            )
            return
        super()._finish(goal, success, status)

    def _publish(self, topic: str, msg: object) -> None:
        if self.dead:
            return
        super()._publish(topic, msg)

    def _on_action_msg(self, msg: object) -> None:
        if self.dead:
            return  # a crashed node hears nothing either, CANCEL included
        super()._on_action_msg(msg)

    async def stop(self) -> None:
        if self._revive_timer is not None:
            self._revive_timer.cancel()
            self._revive_timer = None
        await super().stop()


def _settings_of(options: SimulatedOptions) -> SimulatedSettings:
    """Keyword settings through the model (plain mappings are fine here)."""
    data: dict[str, Any] = dict(options)
    for name in ("durations", "faults"):
        if isinstance(data.get(name), Mapping):
            data[name] = dict(data[name])
    return validate_settings(SimulatedSettings, data)
