"""Running sensing rules: samples in, knowledge changes out, at most every ``every`` s.

Each change goes through the problem expert like any other (validated, journaled,
one notification per change), so the executor re-checks over-all conditions and
replans exactly as it does for a timed event, the mission publishes the new
knowledge on the hub and a recording keeps it. A change the knowledge refuses,
or a sample the rule cannot evaluate, is logged once per rule and reason; the
source keeps feeding and the other rules keep working.
"""

from __future__ import annotations

import asyncio
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from plansys_bridge.clock import Clock
from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.problem_expert import ProblemExpert

from .expressions import Sample
from .load import LoadedRule
from .rules import Change

__all__ = ["RuleRunner", "SensingEngine"]

log = logging.getLogger(__name__)

OnSensed = Callable[[LoadedRule, Change, float], None]


class RuleRunner:
    """One rule at run time: decides on each sample, rate-limits, writes."""

    def __init__(
        self,
        rule: LoadedRule,
        knowledge: ProblemExpert,
        clock: Clock,
        on_sensed: OnSensed | None = None,
    ) -> None:
        self.rule = rule
        self.knowledge = knowledge
        self.clock = clock
        self.on_sensed = on_sensed
        self.logic = rule.logic()
        self.every = rule.config.every or 0.0
        self.last_write = -math.inf
        self.pending: Change | None = None
        self._timer: asyncio.TimerHandle | None = None
        self._complaints: set[str] = set()
        self.samples = 0
        self.writes = 0

    def feed(self, sample: Sample) -> None:
        """Handle one message's values (called on the event loop by the source)."""
        self.samples += 1
        try:
            change = self.logic.decide(sample)
        except PlansysBridgeError as exc:
            self._complain(f"cannot evaluate: {exc}")
            return
        if change is not None:
            self.offer(change)

    def offer(self, change: Change) -> None:
        """Write now, or keep it for the end of the ``every`` interval."""
        now = self.clock.now()
        due = self.last_write + self.every
        if now >= due:
            self._write(change, now)
            return
        self.pending = change
        if self._timer is None:
            loop = asyncio.get_running_loop()
            self._timer = loop.call_later((due - now) * self.clock.time_scale, self._flush)

    def _flush(self) -> None:
        self._timer = None
        change, self.pending = self.pending, None
        if change is not None:
            self._write(change, self.clock.now())

    def _write(self, change: Change, now: float) -> None:
        self.last_write = now
        try:
            if change.kind == "function":
                moved = self.knowledge.set_function(change.text())
            elif change.value:
                moved = self.knowledge.add_predicate(change.target)
            else:
                moved = self.knowledge.remove_predicate(change.target)
        except PlansysBridgeError as exc:
            self._complain(f"the knowledge refused {change.text()}: {exc}")
            return
        if moved:
            self.writes += 1
            if self.on_sensed is not None:
                self.on_sensed(self.rule, change, now)

    def _complain(self, text: str) -> None:
        if text not in self._complaints:
            self._complaints.add(text)
            log.error("%s: %s", self.rule.describe(), text)

    def stop(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None


class SensingEngine:
    """The mission's rules attached to their sources."""

    def __init__(
        self,
        rules: Sequence[LoadedRule],
        knowledge: ProblemExpert,
        clock: Clock,
        on_sensed: OnSensed | None = None,
    ) -> None:
        self.runners = [RuleRunner(r, knowledge, clock, on_sensed) for r in rules]
        self._detach: list[Callable[[], None]] = []

    def start(self, performers: Mapping[str, Any]) -> None:
        """Hook every rule to its source; ``performers`` by name (the running ones)."""
        try:
            for runner in self.runners:
                name = runner.rule.config.performer
                performer = performers.get(name) if name is not None else None
                if name is not None and performer is None:
                    # ``plansys-bridge run --no-performers``: the link is in another process
                    log.warning(
                        "%s: performer %s runs in another process; its rule does not run here",
                        runner.rule.describe(),
                        name,
                    )
                    continue
                self._detach.append(runner.rule.source.attach(performer, runner.feed))
        except BaseException:
            self.stop()
            raise

    def stop(self) -> None:
        for detach in reversed(self._detach):
            try:
                detach()
            except Exception:  # one broken source must not keep the others attached
                log.exception("detaching a sensing source failed")
        self._detach.clear()
        for runner in self.runners:
            runner.stop()


def start_sensing(
    mission: Any,
    knowledge: ProblemExpert,
    clock: Clock,
    performers: Sequence[Any],
    say: Callable[[str], None],
    events: list[str],
) -> SensingEngine | None:
    """Load the mission's rules and attach them to the started ``performers``.

    Every predicate a rule sets or clears is said (``[  12.0] sensed: +(battery_low
    uav1) (sensing[0] ...)``) and listed in ``events`` with the mission's timed
    events; function updates are logged at debug level (they may come every second).
    """
    from .load import load_rules

    rules = load_rules(mission, knowledge)
    if not rules:
        return None
    t0 = clock.now()

    def on_sensed(rule: LoadedRule, change: Change, now: float) -> None:
        if change.kind == "function":
            log.debug("%s: %s", rule.describe(), change.text())
            return
        events.append(f"t={now - t0:.1f} {change.text()} (sensed)")
        say(f"[{now - t0:8.1f}] sensed: {change.text()} ({rule.describe()})")

    engine = SensingEngine(rules, knowledge, clock, on_sensed)
    engine.start({p.node_name: p for p in performers})
    return engine
