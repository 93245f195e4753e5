"""Read a recorded mission back, re-run its plan, and compare the outcomes.

A mission bag written by :class:`~.recorder.MissionRecorder` holds the plan
(``/executing_plan``, or ``/plan``) and every auction message (``/actions_hub``, with
request ids on ``/plansys_bridge/actions_hub``). :func:`read_mission` streams it and
keeps only what a regression check needs: the plan, and for every action instance
who performed it and how it ended.

:func:`replay_plan` runs a recorded plan again on a hub with the same performers:
each action is auctioned at its planned start time (relative to the replay start),
exactly as recorded, without re-planning; :func:`rerun_mission` does it with the
performers of a mission file and records the re-run. :func:`compare_missions` then tells whether
the re-run matches: same plan, same performers, same outcomes (and, optionally,
durations within a tolerance). This turns any recorded run into a test.
"""

from __future__ import annotations

import asyncio
import logging
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from plansys_bridge.clock import run
from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy, full_action_name
from plansys_bridge.hub.hub import Hub

from . import msgs
from .recorder import BRIDGE_PREFIX, PLAN_TOPIC, bag_topic
from .rosbags_api import AnyReader, AnyReaderError, ReaderError, SerdeError, np

if TYPE_CHECKING:
    from plansys_bridge.mission_config import MissionConfig

log = logging.getLogger(__name__)

ACTIONS_TOPIC = bag_topic(hm.Topics.ACTIONS_HUB)
BRIDGE_ACTIONS_TOPIC = BRIDGE_PREFIX + ACTIONS_TOPIC
EXECUTING_PLAN_TOPIC = bag_topic(hm.Topics.EXECUTING_PLAN)
INFO_TOPIC = bag_topic(hm.Topics.ACTION_EXECUTION_INFO)


class MissionBagError(PlansysBridgeError):
    """A mission bag cannot be read or does not hold a mission."""


@dataclass
class RecordedAction:
    """One action instance as the bag tells it."""

    action: str
    """Full action text, e.g. ``(move tiago kitchen livingroom)``."""
    request_id: str = ""
    performer: str = ""
    success: bool | None = None
    """``None``: no FINISH recorded (cancelled, lost, or the run stopped)."""
    status: str = ""
    completion: float = 0.0
    requested: float | None = None
    started: float | None = None
    """Mission time of the CONFIRM."""
    finished: float | None = None
    cancelled: bool = False

    @property
    def duration(self) -> float | None:
        if self.started is None or self.finished is None:
            return None
        return self.finished - self.started

    @property
    def outcome(self) -> str:
        if self.cancelled:
            return "cancelled"
        if self.success is None:
            return "unfinished"
        return "succeeded" if self.success else "failed"


@dataclass
class RecordedMission:
    """What a mission bag says happened."""

    path: Path
    plans: list[hm.Plan] = field(default_factory=list)
    actions: list[RecordedAction] = field(default_factory=list)
    final_info: dict[str, hm.ActionStatus] = field(default_factory=dict)
    """Last ActionExecutionInfo status per action text."""
    topics: dict[str, int] = field(default_factory=dict)
    """Messages per bag topic."""

    @property
    def plan(self) -> hm.Plan | None:
        """The first plan executed (or, without one, the first plan recorded)."""
        return self.plans[0] if self.plans else None

    @property
    def succeeded(self) -> bool:
        return bool(self.actions) and all(a.success for a in self.actions)

    def outcomes(self) -> Counter[tuple[str, str, str]]:
        """Multiset of ``(action, performer, outcome)`` over every action instance."""
        return Counter((a.action, a.performer, a.outcome) for a in self.actions)


def _float32(value: float) -> float:
    """The shortest decimal that a float32 field stands for (3.000999927 -> 3.001)."""
    return float(str(np.float32(value)))


def _plan_from_ros(msg: Any) -> hm.Plan:
    return hm.Plan(
        tuple(
            hm.PlanItem(time=_float32(i.time), action=i.action, duration=_float32(i.duration))
            for i in msg.items
        )
    )


def read_mission(path: str | Path) -> RecordedMission:
    """Stream a mission bag and rebuild its plan and action outcomes."""
    path = Path(path)
    mission = RecordedMission(path)
    wanted = {EXECUTING_PLAN_TOPIC, PLAN_TOPIC, ACTIONS_TOPIC, BRIDGE_ACTIONS_TOPIC, INFO_TOPIC}
    executed: list[hm.Plan] = []
    planned: list[hm.Plan] = []
    by_request: dict[str, RecordedAction] = {}
    open_by_text: dict[str, list[RecordedAction]] = {}
    has_bridge = False
    try:
        with AnyReader([path], default_typestore=msgs.hub_typestore()) as reader:
            mission.topics = {name: info.msgcount for name, info in reader.topics.items()}
            has_bridge = BRIDGE_ACTIONS_TOPIC in mission.topics
            conns = [c for c in reader.connections if c.topic in wanted]
            # (rosbags reads every topic when given no connection at all)
            for conn, timestamp, raw in reader.messages(conns) if conns else ():
                if conn.topic == ACTIONS_TOPIC and has_bridge:
                    continue  # the bridge topic carries the same messages with request ids
                msg: Any = reader.deserialize(raw, conn.msgtype)
                now = timestamp / 1e9
                if conn.topic == EXECUTING_PLAN_TOPIC:
                    executed.append(_plan_from_ros(msg))
                elif conn.topic == PLAN_TOPIC:
                    planned.append(_plan_from_ros(msg))
                elif conn.topic == INFO_TOPIC:
                    mission.final_info[msg.action_full_name] = hm.ActionStatus(msg.status)
                else:
                    request_id = msg.request_id if conn.topic == BRIDGE_ACTIONS_TOPIC else ""
                    execution = msg.execution if conn.topic == BRIDGE_ACTIONS_TOPIC else msg
                    _track(mission, by_request, open_by_text, execution, request_id, now)
    except (AnyReaderError, ReaderError, SerdeError, OSError, KeyError, ValueError) as exc:
        raise MissionBagError(f"{path}: cannot read mission bag: {exc}") from exc
    mission.plans = executed or planned
    return mission


def _track(
    mission: RecordedMission,
    by_request: dict[str, RecordedAction],
    open_by_text: dict[str, list[RecordedAction]],
    msg: Any,
    request_id: str,
    now: float,
) -> None:
    """Fold one ActionExecution into the per-instance records."""
    kind = hm.ExecutionType(msg.type)
    text = full_action_name(msg.action, tuple(msg.arguments))
    record: RecordedAction | None
    if request_id:
        record = by_request.get(request_id)
    else:
        pending = open_by_text.get(text, [])
        record = pending[-1] if pending else None
    if kind is hm.ExecutionType.REQUEST:
        if record is None:
            record = RecordedAction(action=text, request_id=request_id, requested=now)
            mission.actions.append(record)
            if request_id:
                by_request[request_id] = record
            open_by_text.setdefault(text, []).append(record)
        return
    if record is None:
        return
    if kind is hm.ExecutionType.CONFIRM:
        # A later CONFIRM is a re-auction after a lost performer: the new one counts.
        record.performer = msg.node_id
        record.started = now
        record.cancelled = False
        record.success = None
        record.finished = None
    elif kind is hm.ExecutionType.FEEDBACK and msg.node_id == record.performer:
        record.completion = float(msg.completion)
    elif kind is hm.ExecutionType.FINISH and msg.node_id == record.performer:
        record.success = bool(msg.success)
        record.status = msg.status
        record.completion = float(msg.completion)
        record.finished = now
        _close(open_by_text, text, record)
    elif kind is hm.ExecutionType.CANCEL and msg.node_id == record.performer:
        record.cancelled = True
        record.finished = now
        _close(open_by_text, text, record)


def _close(
    open_by_text: dict[str, list[RecordedAction]], text: str, record: RecordedAction
) -> None:
    pending = open_by_text.get(text, [])
    if record in pending:
        pending.remove(record)


@dataclass(frozen=True)
class MissionComparison:
    """The differences between two runs; empty means the re-run matches."""

    differences: tuple[str, ...]

    @property
    def same(self) -> bool:
        return not self.differences

    def __str__(self) -> str:
        if self.same:
            return "same plan, same performers, same outcomes"
        return "\n".join(self.differences)


def compare_missions(
    expected: RecordedMission,
    actual: RecordedMission,
    *,
    compare_performers: bool = True,
    duration_tolerance: float | None = None,
) -> MissionComparison:
    """Compare plan and outcomes of two runs.

    ``duration_tolerance`` (fraction, e.g. 0.05) also compares each action's
    duration (CONFIRM to FINISH), matched by action text in order.
    """
    diffs: list[str] = []
    plan_a = expected.plan.items if expected.plan else ()
    plan_b = actual.plan.items if actual.plan else ()
    if [i.action for i in plan_a] != [i.action for i in plan_b]:
        diffs.append(f"plan differs: {[i.action for i in plan_a]} != {[i.action for i in plan_b]}")
    else:
        for a, b in zip(plan_a, plan_b, strict=True):
            if abs(a.time - b.time) > 1e-3 or abs(a.duration - b.duration) > 1e-3:
                diffs.append(
                    f"plan timing differs for {a.action}: {a.time:.3f}+{a.duration:.3f} "
                    f"!= {b.time:.3f}+{b.duration:.3f}"
                )

    def key(a: RecordedAction) -> tuple[str, str, str]:
        return (a.action, a.performer if compare_performers else "", a.outcome)

    out_a = Counter(key(a) for a in expected.actions)
    out_b = Counter(key(a) for a in actual.actions)
    for item in sorted((out_a - out_b).elements()):
        diffs.append(f"missing in re-run: {_describe(item)}")
    for item in sorted((out_b - out_a).elements()):
        diffs.append(f"only in re-run: {_describe(item)}")
    if duration_tolerance is not None:
        diffs.extend(_duration_differences(expected.actions, actual.actions, duration_tolerance))
    return MissionComparison(tuple(diffs))


def _describe(item: tuple[str, str, str]) -> str:
    action, performer, outcome = item
    by = f" by {performer}" if performer else ""
    return f"{action}{by} {outcome}"


def _duration_differences(
    a: Sequence[RecordedAction], b: Sequence[RecordedAction], tolerance: float
) -> Iterable[str]:
    durations_b: dict[str, list[float]] = {}
    for r in b:
        if r.duration is not None:
            durations_b.setdefault(r.action, []).append(r.duration)
    for r in a:
        if r.duration is None or not durations_b.get(r.action):
            continue
        other = durations_b[r.action].pop(0)
        if abs(other - r.duration) > tolerance * max(r.duration, 1e-9):
            yield f"duration of {r.action}: {r.duration:.3f} s != {other:.3f} s"


async def replay_plan(
    hub: Hub,
    plan: hm.Plan,
    *,
    policy: AuctionPolicy | None = None,
    plan_id: str = "replay",
) -> list[RecordedAction]:
    """Run ``plan`` open-loop: auction each action at its planned start, await all.

    The plan and each action's ActionExecutionInfo go on the hub like the
    executor's, so a recorder on the same hub writes a comparable mission bag.
    Returns one record per plan item, in plan order.
    """
    clock = hub.clock
    start = clock.now()
    hub.publish(hm.Topics.EXECUTING_PLAN, hm.ExecutingPlan(plan=plan, plan_id=plan_id))

    async def run_item(index: int, item: hm.PlanItem) -> RecordedAction:
        name, *args = item.action.strip("() ").split()
        delay = item.time - (clock.now() - start)
        if delay > 0:
            await clock.sleep(delay)
        client = ActionClient(
            hub, name, tuple(args), request_id=f"{plan_id}#{index}", policy=policy
        )
        began = clock.now()
        record = RecordedAction(action=client.full_name, request_id=client.request_id)
        record.started = began
        _info(hub, record, hm.ActionStatus.EXECUTING, began, item.duration)
        outcome = await client.run()
        record.performer = outcome.performer
        record.success = outcome.success
        record.status = outcome.status
        record.completion = outcome.completion
        record.cancelled = outcome.cancelled
        record.finished = clock.now()
        status = hm.ActionStatus.SUCCEEDED if outcome.success else hm.ActionStatus.FAILED
        _info(hub, record, status, began, item.duration)
        return record

    return list(await asyncio.gather(*(run_item(i, item) for i, item in enumerate(plan.items))))


def rerun_mission(
    mission: MissionConfig,
    recorded: RecordedMission | str | Path,
    record_to: str | Path,
    *,
    performer_overrides: Mapping[str, Any] | None = None,
) -> RecordedMission:
    """Re-run a recorded plan with the performers of ``mission``, recorded to ``record_to``.

    The performers, knowledge and clock are built from the mission file exactly as
    ``plansys-bridge run`` builds them (``performer_overrides`` changes settings of
    every performer entry, e.g. to try another rate); the plan is the recorded one,
    replayed with :func:`replay_plan`. Returns the new recording, ready for
    :func:`compare_missions`.
    """
    from plansys_bridge.mission import MissionSession, build_knowledge, load_domain, make_clock

    first = recorded if isinstance(recorded, RecordedMission) else read_mission(recorded)
    plan = first.plan
    if plan is None:
        raise MissionBagError(f"{first.path}: the recording holds no plan to re-run")
    config = mission.model_copy(update={"record": str(record_to)})
    domain = load_domain(config)
    knowledge = build_knowledge(config, domain)
    clock = make_clock(config)

    async def rerun() -> None:
        async with MissionSession(
            config, domain, knowledge, clock, performer_overrides=dict(performer_overrides or {})
        ) as session:
            await replay_plan(session.hub, plan)

    run(rerun(), clock)
    return read_mission(record_to)


def _info(
    hub: Hub, record: RecordedAction, status: hm.ActionStatus, began: float, duration: float
) -> None:
    name, *args = record.action.strip("()").split()
    hub.publish(
        hm.Topics.ACTION_EXECUTION_INFO,
        hm.ActionExecutionInfo(
            status=status,
            start_stamp=began,
            status_stamp=hub.clock.now(),
            action_full_name=record.action,
            action=name,
            arguments=tuple(args),
            duration=duration,
            completion=record.completion,
            message_status=record.status,
        ),
    )
