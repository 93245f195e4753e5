"""Read a recorded mission (a bag from ``--record``) into a watch, for a report.

The bag holds what the hub carried: the plans as they started (with their
``plan_id`` on ``/plansys_bridge/executing_plan``), every action status, the
auction messages (with request ids on ``/plansys_bridge/actions_hub``), the
heartbeats and the DOT graphs. Each is turned back into its hub message and fed to
a :class:`~plansys_bridge.monitoring.watch.MissionWatch` at its log time, so the
report of a recording is drawn exactly as the report of a live run.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

from plansys_bridge.hub import messages as hm
from plansys_bridge.monitoring.watch import Listener, MissionWatch
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


def watch_recording(
    path: str | Path, listener: Listener | None = None
) -> tuple[MissionWatch, float, float]:
    """The watch fed with every mission message of the bag at ``path`` (each change
    also handed to ``listener``); with the log times of the first and the last
    message (mission seconds).

    MCAP recordings (what ``--record`` writes) are read front to back, so damage or
    a recording cut short is one error naming the file and the byte offset; other
    bag formats go through rosbags' reader.
    """
    from plansys_bridge.monitoring.mcap_scan import mcap_files

    path = Path(path)
    if not path.exists():
        raise RecordingError(f"{path}: no such recording")
    stamp = [0.0]
    watch = MissionWatch(lambda: stamp[0], listener)
    topics = _topics()
    files = mcap_files(path)
    messages = _scan(files, topics) if files else _any_reader(path, topics)
    first: float | None = None
    last = 0.0
    for topic, ros, now in messages:
        hub_topic, kind = topics[topic]
        first = now if first is None else first
        last = max(last, now)
        stamp[0] = now
        watch.feed(hub_topic, _convert(kind, ros), now)
    if first is None:
        raise RecordingError(f"{path}: no mission topics (expected {', '.join(sorted(topics))})")
    return watch, first, last


Recorded = Iterator[tuple[str, Any, float]]
"""(bag topic, ROS message, log time in seconds) in log-time order."""


def _scan(files: list[Path], topics: dict[str, tuple[str, str]]) -> Recorded:
    from plansys_bridge.monitoring import msgs
    from plansys_bridge.monitoring.mcap_scan import McapScanError, scan_mcap
    from plansys_bridge.monitoring.recorder import BRIDGE_PREFIX

    store = msgs.hub_typestore()
    found = []
    try:
        for file in files:
            found += list(scan_mcap(file, set(topics)))
    except McapScanError as exc:
        raise RecordingError(str(exc)) from exc
    present = {m.topic for m in found}
    # the bridge topics carry the same messages with their ids
    skip = {t for t in topics if BRIDGE_PREFIX + t in present}
    found = sorted((m for m in found if m.topic not in skip), key=lambda m: m.log_time)
    for m in found:
        try:
            ros = store.deserialize_cdr(m.data, m.msgtype)
        except Exception as exc:  # rosbags raises several kinds on a bad payload
            raise RecordingError(
                f"{m.place}: cannot decode {m.topic} as {m.msgtype or 'an unknown type'}: {exc}"
            ) from exc
        yield m.topic, ros, m.log_time / 1e9


def _any_reader(path: Path, topics: dict[str, tuple[str, str]]) -> Recorded:
    from plansys_bridge.monitoring import msgs
    from plansys_bridge.monitoring.recorder import BRIDGE_PREFIX
    from plansys_bridge.monitoring.rosbags_api import (
        AnyReader,
        AnyReaderError,
        ReaderError,
        SerdeError,
    )

    try:
        with AnyReader([path], default_typestore=msgs.hub_typestore()) as reader:
            present = {c.topic for c in reader.connections}
            skip = {t for t in topics if BRIDGE_PREFIX + t in present}
            conns = [c for c in reader.connections if c.topic in topics and c.topic not in skip]
            for conn, timestamp, raw in reader.messages(conns):
                yield conn.topic, reader.deserialize(raw, conn.msgtype), timestamp / 1e9
    except (AnyReaderError, ReaderError, SerdeError, OSError, KeyError, ValueError) as exc:
        raise RecordingError(f"{path}: cannot read recording: {exc}") from exc


_DECODERS: dict[str, Any] = {}


def _convert(kind: str, ros: Any) -> object:
    decoders = _decoders()
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


def _decoders() -> dict[str, Any]:
    """ROS message -> hub message, per kind of topic (built once)."""
    if not _DECODERS:
        from plansys_bridge.hub.dds_convert import hub_decoder
        from plansys_bridge.monitoring import msgs

        _DECODERS.update(
            info=hub_decoder(hm.ActionExecutionInfo, msgs.ACTION_EXECUTION_INFO),
            execution=hub_decoder(hm.ActionExecution, msgs.ACTION_EXECUTION),
            status=hub_decoder(hm.ActionPerformerStatus, msgs.ACTION_PERFORMER_STATUS),
            plan=hub_decoder(hm.Plan, msgs.PLAN),
        )
    return _DECODERS
