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
from dataclasses import dataclass
from typing import Any, ClassVar

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.settings import is_number, settings_from_mapping
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)

__all__ = ["FaultPlan", "SimulatedPerformer"]

log = logging.getLogger(__name__)

DurationHint = Callable[[ActionGoal], float | None]


@dataclass(frozen=True)
class FaultPlan:
    """Seeded fault rates for a :class:`SimulatedPerformer` (all off by default)."""

    die_rate: float = 0.0
    """Probability that a goal makes the performer die part-way through."""
    lose_finish_rate: float = 0.0
    """Probability that a goal's FINISH is never sent."""
    never_answer: bool = False
    """Ignore every REQUEST (while still sending heartbeats)."""
    revive_after: float | None = None
    """Mission seconds after dying before the performer is back (None: stays dead)."""
    die_at: float = 0.5
    """Fraction of the action's duration at which a dying performer goes silent."""

    def __post_init__(self) -> None:
        for name in ("die_rate", "lose_finish_rate"):
            value = getattr(self, name)
            if not is_number(value) or not 0.0 <= value <= 1.0:
                raise ConfigError(f"must be a probability in [0, 1], got {value!r}", key=name)
        if not is_number(self.die_at) or not 0.0 <= self.die_at < 1.0:
            raise ConfigError(f"must be a fraction in [0, 1), got {self.die_at!r}", key="die_at")
        if self.revive_after is not None and (
            not is_number(self.revive_after) or self.revive_after < 0
        ):
            raise ConfigError(
                f"must be a number >= 0, got {self.revive_after!r}", key="revive_after"
            )
        if not isinstance(self.never_answer, bool):
            raise ConfigError(
                f"must be true or false, got {self.never_answer!r}", key="never_answer"
            )

    @classmethod
    def from_config(cls, config: object, key: str) -> FaultPlan:
        return settings_from_mapping(cls, config, key)


class SimulatedPerformer(ActionPerformer):
    """Sleeps for the action's duration on the mission clock, sending progress feedback."""

    settings_keys: ClassVar[frozenset[str]] = frozenset(
        {
            "durations",
            "default_duration",
            "success_rate",
            "seed",
            "feedback_period",
            "faults",
        }
    )

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        heartbeat_period: float = 1.0,
        commit_timeout: float = 2.0,
        durations: Mapping[str, float] | None = None,
        default_duration: float = 1.0,
        success_rate: float = 1.0,
        seed: int = 0,
        feedback_period: float | None = 1.0,
        faults: FaultPlan | Mapping[str, Any] | None = None,
        duration_hint: DurationHint | None = None,
    ) -> None:
        super().__init__(
            context,
            node_name,
            actions,
            heartbeat_period=heartbeat_period,
            commit_timeout=commit_timeout,
        )
        if not is_number(default_duration) or default_duration < 0:
            raise ValueError(f"default_duration must be >= 0, got {default_duration!r}")
        if not is_number(success_rate) or not 0.0 <= success_rate <= 1.0:
            raise ValueError(f"success_rate must be in [0, 1], got {success_rate!r}")
        if feedback_period is not None and (not is_number(feedback_period) or feedback_period <= 0):
            raise ValueError(f"feedback_period must be > 0 or None, got {feedback_period!r}")
        self.durations: dict[str, float] = {}
        for name, seconds in (durations or {}).items():
            if not is_number(seconds) or seconds < 0:
                raise ValueError(f"duration of {name!r} must be a number >= 0, got {seconds!r}")
            self.durations[name.strip().lower()] = float(seconds)
        self.default_duration = float(default_duration)
        self.success_rate = float(success_rate)
        self.feedback_period = None if feedback_period is None else float(feedback_period)
        self.faults = (
            faults if isinstance(faults, FaultPlan) else FaultPlan.from_config(faults, "faults")
        )
        self.duration_hint = duration_hint
        self.seed = seed
        self._rng = random.Random(f"{seed}:{node_name}:outcome")
        self._fault_rng = random.Random(f"{seed}:{node_name}:faults")
        self.dead = False
        self.unresponsive = self.faults.never_answer
        self._die_next = False
        self._lose_next_finish = False
        self._drop_finish = False
        self._revive_timer: asyncio.TimerHandle | None = None
        self.stats: dict[str, int] = {"succeeded": 0, "failed": 0, "died": 0, "lost_finish": 0}

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

    @classmethod
    def from_config(
        cls, config: Mapping[str, Any], context: PerformerContext, *, key: str = "performer"
    ) -> list[ActionPerformer]:
        parsed = cls.parse_config(config, key=key)
        s = parsed.settings
        durations = s.get("durations", {})
        if not isinstance(durations, Mapping):
            raise ConfigError(
                "must map action names (or action texts) to seconds", key=f"{key}.durations"
            )
        for name, seconds in durations.items():
            if not isinstance(name, str) or not is_number(seconds) or seconds < 0:
                raise ConfigError(
                    f"must be a number of seconds >= 0, got {seconds!r}",
                    key=f"{key}.durations.{name}",
                )
            # an action name, or a full action text "(move r1 a b)"
            action = name.strip().lstrip("(").split(maxsplit=1)[:1]
            if not action or action[0].lower() not in parsed.actions:
                raise ConfigError(
                    f"not one of this performer's actions ({', '.join(parsed.actions)})",
                    key=f"{key}.durations.{name}",
                )
        for name, low, high in (("default_duration", 0.0, math.inf), ("success_rate", 0.0, 1.0)):
            if name in s and (not is_number(s[name]) or not low <= s[name] <= high):
                raise ConfigError(
                    f"must be a number in [{low:g}, {high:g}], got {s[name]!r}", key=f"{key}.{name}"
                )
        if (
            "feedback_period" in s
            and s["feedback_period"] is not None
            and (not is_number(s["feedback_period"]) or s["feedback_period"] <= 0)
        ):
            raise ConfigError(
                f"must be a number > 0 (or null for no feedback), got {s['feedback_period']!r}",
                key=f"{key}.feedback_period",
            )
        if "seed" in s and (isinstance(s["seed"], bool) or not isinstance(s["seed"], int)):
            raise ConfigError(f"must be an integer, got {s['seed']!r}", key=f"{key}.seed")
        faults = FaultPlan.from_config(s.get("faults"), f"{key}.faults")
        return [
            cls(
                context,
                parsed.name,
                parsed.actions,
                heartbeat_period=parsed.heartbeat_period,
                commit_timeout=parsed.commit_timeout,
                durations=durations,
                default_duration=s.get("default_duration", 1.0),
                success_rate=s.get("success_rate", 1.0),
                seed=s.get("seed", 0),
                feedback_period=s.get("feedback_period", 1.0),
                faults=faults,
            )
        ]
