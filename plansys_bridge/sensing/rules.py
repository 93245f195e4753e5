"""A sensing rule: what it reads, what it writes, and when it changes its mind.

A rule maps one sensor stream (a MAVLink message, a CAN signal, a ROS topic) to one
predicate or one numeric function of the knowledge. Predicate rules have
hysteresis: ``when`` sets the predicate, ``clear_when`` (default: ``when`` no longer
holding) clears it, and between the two thresholds nothing changes, so a battery
hovering around 25 % does not make the planner replan on every sample. ``every``
limits how often the rule may write (in mission seconds); what arrives in between
is kept and the newest value is written when the interval ends, so the last word
of the sensor always reaches the knowledge.

:class:`RuleLogic` is the pure part (sample in, wanted change out) so that it can be
tested without a bus; :mod:`.engine` does the writing and the timing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from .expressions import Expression, Sample

__all__ = ["Change", "RuleConfig", "RuleLogic"]


class RuleConfig(BaseModel):
    """The keys every rule has; the source kind checks its own (``message``, ``signal``...)."""

    model_config = ConfigDict(extra="allow", frozen=True, populate_by_name=True)

    source: str = Field(alias="from")
    """Which kind of stream: ``mavlink``, ``can``, ``ros1``, ``ros2`` (or a plugin's)."""
    performer: str | None = None
    """The performer whose link is read (a MAVLink vehicle, a CAN base)."""
    when: str | None = None
    clear_when: str | None = None
    predicate: str | None = None
    function: str | None = None
    every: float | None = Field(None, ge=0)

    @model_validator(mode="after")
    def _one_target(self) -> RuleConfig:
        if (self.predicate is None) == (self.function is None):
            raise ValueError("a rule sets exactly one of predicate or function")
        if self.predicate is not None and self.when is None:
            raise ValueError("a predicate rule needs when: (the condition that sets it)")
        if self.clear_when is not None and self.predicate is None:
            raise ValueError("clear_when applies to predicate rules")
        return self

    @property
    def source_settings(self) -> dict[str, Any]:
        """The keys this model does not know: the source kind's own."""
        return dict(self.model_extra or {})


@dataclass(frozen=True)
class Change:
    """What a rule wants written: a predicate set (True) or cleared, or a value."""

    kind: Literal["predicate", "function"]
    target: str
    """``(battery_low copter1)`` or ``(battery_level base1)``."""
    value: bool | float

    def text(self) -> str:
        """As the knowledge reads it: ``+(p a)``, ``-(p a)``, ``(= (f a) 3)``."""
        if self.kind == "predicate":
            return f"{'+' if self.value else '-'}{self.target}"
        return f"(= {self.target} {self.value:g})"


class RuleLogic:
    """Decides, sample by sample, what a rule wants the knowledge to say.

    ``when``/``clear_when`` hold the hysteresis state: the predicate is set once
    ``when`` holds and stays set until ``clear_when`` holds. The first sample that
    decides either way is always reported (the knowledge may have started out
    different from what the sensor says); after that only changes are.
    """

    def __init__(
        self,
        *,
        predicate: str | None,
        function: str | None,
        when: Expression | None,
        clear_when: Expression | None,
        value: Expression | None,
    ) -> None:
        self.predicate = predicate
        self.function = function
        self.when = when
        self.clear_when = clear_when
        self.value = value
        self.active: bool | None = None
        """The predicate as last decided (None before the first deciding sample)."""

    def decide(self, sample: Sample) -> Change | None:
        """The change ``sample`` calls for, or None; ExpressionError when the sample
        lacks what the rule reads."""
        if self.predicate is not None:
            return self._decide_predicate(sample)
        if self.when is not None and not self.when.holds(sample):
            return None
        assert self.function is not None and self.value is not None
        return Change("function", self.function, self.value.number(sample))

    def _decide_predicate(self, sample: Sample) -> Change | None:
        assert self.predicate is not None and self.when is not None
        now: bool | None = None
        if self.active is not True and self.when.holds(sample):
            now = True
        elif self.active is not False:
            if self.clear_when is not None:
                cleared = self.clear_when.holds(sample)
            else:
                cleared = not self.when.holds(sample)
            if cleared:
                now = False
        if now is None or now == self.active:
            return None
        self.active = now
        return Change("predicate", self.predicate, now)
