"""The action runs of recorded missions, grouped the ways a planner or an auction
can use them.

A run is one action of one plan as the recording shows it: its ground text, the
performer that won its auction, whether it succeeded and, when it did, how long
it took from its first EXECUTING status to its SUCCEEDED one (the same times the
reports draw). Cancelled actions and actions that never started say nothing
about the action itself (the executor halted them, or a requirement never held)
and are left out.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.hub.messages import ActionStatus, Topics
from plansys_bridge.learning.stats import DurationStats, summarise
from plansys_bridge.monitoring.watch import MissionWatch, WatchEvent
from plansys_bridge.pddl.model import Domain

__all__ = [
    "ActionRun",
    "LearnError",
    "Learned",
    "known_functions",
    "learn",
    "read_runs",
    "runs_from_watch",
    "stats_of",
]

Ground = tuple[str, tuple[str, ...]]
"""(action name, arguments)."""


class LearnError(PlansysBridgeError):
    """Recordings that cannot be learned from (unreadable, or not of this domain)."""


@dataclass(frozen=True)
class ActionRun:
    action: str
    arguments: tuple[str, ...]
    performer: str
    succeeded: bool
    duration: float
    """Seconds from EXECUTING to SUCCEEDED (0 for a failed run)."""
    planned: float
    """The duration the plan gave it."""
    recording: str

    @property
    def ground(self) -> Ground:
        return self.action, self.arguments

    @property
    def text(self) -> str:
        return "(" + " ".join((self.action, *self.arguments)) + ")"


def runs_from_watch(
    watch: MissionWatch, recording: str, assigned: Mapping[int, float] | None = None
) -> list[ActionRun]:
    """The finished runs of every plan ``watch`` saw. ``assigned`` gives, by
    ``id(view)``, when an action's auction confirmed its performer: the run is timed
    from then, not from EXECUTING (an action may wait for its performer to be free)."""
    runs = []
    for view in watch.actions:
        if view.start is None or view.end is None:
            continue
        start = max(view.start, (assigned or {}).get(id(view), view.start))
        if view.status not in (ActionStatus.SUCCEEDED, ActionStatus.FAILED):
            continue
        name, *args = view.text.strip("()").lower().split()
        ok = view.status == ActionStatus.SUCCEEDED
        runs.append(
            ActionRun(
                action=name,
                arguments=tuple(args),
                performer=view.performer,
                succeeded=ok,
                duration=max(0.0, view.end - start) if ok else 0.0,
                planned=view.planned_duration,
                recording=recording,
            )
        )
    return runs


def read_runs(paths: Sequence[str | Path], domain: Domain) -> list[ActionRun]:
    """Every run of the recordings at ``paths``; an action the domain does not have
    (or with another number of arguments) is an error naming the recording."""
    from plansys_bridge.report.model import ReportError
    from plansys_bridge.report.recording import watch_recording

    arity = {a.name.lower(): len(a.parameters) for a in domain.actions}
    runs: list[ActionRun] = []
    for path in paths:
        assigned: dict[int, float] = {}

        def on_event(event: WatchEvent, assigned: dict[int, float] = assigned) -> None:
            if event.kind == "assigned" and event.action is not None:
                assigned[id(event.action)] = event.stamp

        try:
            watch, _first, _last = watch_recording(path, on_event)
        except ReportError as exc:
            raise LearnError(str(exc)) from exc
        for run in runs_from_watch(watch, str(path), assigned):
            expected = arity.get(run.action)
            if expected is None:
                raise LearnError(
                    f"{path}: action {run.text} is not an action of domain {domain.name!r}"
                )
            if expected != len(run.arguments):
                raise LearnError(
                    f"{path}: action {run.text} has {len(run.arguments)} arguments, "
                    f"domain {domain.name!r} gives {run.action} {expected}"
                )
            runs.append(run)
    return runs


K = TypeVar("K", str, Ground, tuple[str, str], tuple[str, Ground])


def known_functions(paths: Sequence[str | Path]) -> set[str]:
    """The ground functions the recorded missions had a value for, as texts
    (``(move_time robot1 hall kitchen)``), from each recording's first knowledge."""
    from plansys_bridge.monitoring import msgs
    from plansys_bridge.monitoring.mcap_scan import McapScanError, mcap_files, scan_mcap
    from plansys_bridge.monitoring.recorder import bag_topic

    topic = bag_topic(Topics.KNOWLEDGE)
    store = msgs.hub_typestore()
    found: set[str] = set()
    for path in paths:
        for file in mcap_files(Path(path)):
            try:
                first = next(iter(scan_mcap(file, {topic})), None)
            except McapScanError as exc:
                raise LearnError(str(exc)) from exc
            if first is None:
                continue
            try:
                knowledge: Any = store.deserialize_cdr(first.data, first.msgtype)
            except Exception as exc:  # rosbags raises several kinds on a bad payload
                raise LearnError(f"{first.place}: cannot decode {topic}: {exc}") from exc
            for value in knowledge.functions:
                head = " ".join(value.lower().split())
                if head.startswith("(= (") and ")" in head:
                    found.add(head[3 : head.index(")") + 1])
            break
    return found


@dataclass
class Learned:
    """Runs grouped by action, by ground action and by performer."""

    runs: list[ActionRun] = field(default_factory=list)
    recordings: int = 0
    known: set[str] = field(default_factory=set)
    """Ground functions the recorded missions had values for (see :func:`known_functions`)."""

    def grouped(self, key: Callable[[ActionRun], K]) -> dict[K, list[ActionRun]]:
        """The runs by ``key``, keys sorted."""
        groups: dict[K, list[ActionRun]] = {}
        for run in self.runs:
            groups.setdefault(key(run), []).append(run)
        return dict(sorted(groups.items()))

    def stats(self, key: Callable[[ActionRun], K]) -> dict[K, DurationStats]:
        return {k: stats_of(v) for k, v in self.grouped(key).items()}

    def by_action(self) -> dict[str, DurationStats]:
        return self.stats(lambda r: r.action)

    def by_ground(self) -> dict[Ground, DurationStats]:
        return self.stats(lambda r: r.ground)

    def by_performer(self) -> dict[tuple[str, str], DurationStats]:
        return self.stats(lambda r: (r.performer, r.action))

    def by_performer_ground(self) -> dict[tuple[str, Ground], DurationStats]:
        return self.stats(lambda r: (r.performer, r.ground))


def stats_of(runs: Iterable[ActionRun]) -> DurationStats:
    """Durations of the successful runs, failures counted."""
    runs = list(runs)
    return summarise((r.duration for r in runs if r.succeeded), sum(not r.succeeded for r in runs))


def learn(runs: Sequence[ActionRun], recordings: int, known: set[str] | None = None) -> Learned:
    if not runs:
        raise LearnError("the recordings hold no finished action to learn from")
    return Learned(list(runs), recordings, set(known or ()))
