"""Read a recorded mission (a bag from ``--record``) into a watch, for a report.

The bag holds what the hub carried: the plans as they started (with their
``plan_id`` on ``/plansys_bridge/executing_plan``), every action status, the
auction messages (with request ids on ``/plansys_bridge/actions_hub``), the
heartbeats and the DOT graphs. Each is turned back into its hub message and fed to
a :class:`~plansys_bridge.monitoring.watch.MissionWatch` at its log time, so the
report of a recording is drawn exactly as the report of a live run.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

from plansys_bridge.hub import messages as hm
from plansys_bridge.monitoring.watch import MissionWatch
from plansys_bridge.report.model import ReportError

__all__ = ["RecordingError", "watch_recording"]


class RecordingError(ReportError):
    """A recording that cannot be read as a mission."""


def _topics() -> dict[str, tuple[str, str]]:
    """bag topic -> (hub topic, how to convert)."""
    from plansys_bridge.monitoring.recorder import BRIDGE_PREFIX, bag_topic

    T = hm.Topics
    return {
        bag_topic(T.EXECUTING_PLAN): (T.EXECUTING_PLAN, "plan"),
        BRIDGE_PREFIX + bag_topic(T.EXECUTING_PLAN): (T.EXECUTING_PLAN, "bridge_plan"),
        bag_topic(T.ACTION_EXECUTION_INFO): (T.ACTION_EXECUTION_INFO, "info"),
        bag_topic(T.ACTIONS_HUB): (T.ACTIONS_HUB, "execution"),
        BRIDGE_PREFIX + bag_topic(T.ACTIONS_HUB): (T.ACTIONS_HUB, "bridge_execution"),
        bag_topic(T.PERFORMERS_STATUS): (T.PERFORMERS_STATUS, "status"),
        bag_topic(T.DOT_GRAPH): (T.DOT_GRAPH, "dot"),
    }


def watch_recording(path: str | Path) -> tuple[MissionWatch, float, float]:
    """The watch fed with every mission message of the bag at ``path``; with the
    log times of the first and the last message (mission seconds)."""
    from plansys_bridge.hub.dds_convert import hub_decoder
    from plansys_bridge.monitoring import msgs
    from plansys_bridge.monitoring.recorder import BRIDGE_PREFIX
    from plansys_bridge.monitoring.rosbags_api import (
        AnyReader,
        AnyReaderError,
        ReaderError,
        SerdeError,
    )

    path = Path(path)
    if not path.exists():
        raise RecordingError(f"{path}: no such recording")
    stamp = [0.0]
    watch = MissionWatch(lambda: stamp[0])
    topics = _topics()
    decoders = {
        "info": hub_decoder(hm.ActionExecutionInfo, msgs.ACTION_EXECUTION_INFO),
        "execution": hub_decoder(hm.ActionExecution, msgs.ACTION_EXECUTION),
        "status": hub_decoder(hm.ActionPerformerStatus, msgs.ACTION_PERFORMER_STATUS),
        "plan": hub_decoder(hm.Plan, msgs.PLAN),
    }
    first: float | None = None
    last = 0.0
    try:
        with AnyReader([path], default_typestore=msgs.hub_typestore()) as reader:
            present = {c.topic for c in reader.connections}
            # the bridge topics carry the same messages with their ids
            skip = {t for t in topics if BRIDGE_PREFIX + t in present}
            conns = [c for c in reader.connections if c.topic in topics and c.topic not in skip]
            if not conns:
                raise RecordingError(
                    f"{path}: no mission topics (expected {', '.join(sorted(topics))})"
                )
            for conn, timestamp, raw in reader.messages(conns):
                ros: Any = reader.deserialize(raw, conn.msgtype)
                hub_topic, kind = topics[conn.topic]
                now = timestamp / 1e9
                first = now if first is None else first
                last = max(last, now)
                stamp[0] = now
                watch.feed(hub_topic, _convert(kind, ros, decoders), now)
    except (AnyReaderError, ReaderError, SerdeError, OSError, KeyError, ValueError) as exc:
        raise RecordingError(f"{path}: cannot read recording: {exc}") from exc
    return watch, first or 0.0, last


def _convert(kind: str, ros: Any, decoders: dict[str, Any]) -> object:
    if kind == "plan":
        return hm.ExecutingPlan(decoders["plan"](ros), "")
    if kind == "bridge_plan":
        return hm.ExecutingPlan(decoders["plan"](ros.plan), ros.plan_id)
    if kind == "bridge_execution":
        execution = decoders["execution"](ros.execution)
        return replace(execution, request_id=ros.request_id, bid=ros.bid if ros.has_bid else None)
    if kind == "dot":
        return hm.DotGraph(ros.data)
    return decoders[kind](ros)
