"""Taking what arrived on the hub's DDS readers and turning it into hub messages.

The reader thread of a :class:`~plansys_bridge.hub.dds.DdsTransport` wakes when
samples arrive and asks an :class:`Intake` to take those of the readers whose
condition fired (not every reader of every topic: with an auction's samples all on
one topic, taking from the idle readers was a good part of a wake-up). Each sample
becomes a message of the endpoint's hub topic, in arrival order, or is dropped with one log line
naming the DDS topic and the writer (its GUID and its participant's) when it cannot
be read or fails the transport's check: a foreign node's bad sample costs that
sample only, never the connection or the other samples of the batch.

Plain samples of project writers are skipped without decoding: a project process
also writes the complete message on the wrapper topic, which is the one delivered.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

from cyclonedds._clayer import ddspy_take
from cyclonedds.core import DDSException, InstanceState, Policy, SampleState, ViewState

from plansys_bridge.errors import HubError
from plansys_bridge.hub.dds_checks import SampleCheck, check_sample
from plansys_bridge.hub.dds_codec import Channel, Route
from plansys_bridge.hub.messages import ActionExecution

__all__ = ["ANY_SAMPLE", "PROJECT_MARKER", "Endpoint", "Intake"]

log = logging.getLogger(__name__)

PROJECT_MARKER = b"plansys_bridge"
"""USER_DATA of this project's plain-topic writers (their messages also go wrapped)."""

ANY_SAMPLE = SampleState.Any | ViewState.Any | InstanceState.Any
_TAKE_BATCH = 256
"""Samples taken per call: an auction's burst (a RESPONSE or a REJECT per bidder) in
one or two; a take that returns fewer found the reader empty, and samples arriving
after it fire the read condition again, so no further take is needed to see that."""


@dataclass
class Endpoint:
    """The DDS entities of one channel."""

    route: Route
    channel: Channel
    topic: Any
    writer: Any
    reader: Any
    condition: Any


class Intake:
    """The endpoints a transport reads, and what it takes from them.

    ``check`` is what a received message must pass (:mod:`~plansys_bridge.hub.dds_checks`);
    ``dropped`` counts the samples that could not be turned into hub messages.
    """

    def __init__(self, check: SampleCheck) -> None:
        self.endpoints: list[Endpoint] = []
        self.check = check
        self.dropped = 0
        self._project_writers: set[int] = set()

    def take(self, ep: Endpoint, batch: list[object]) -> None:
        """Append the hub message of each sample ``ep`` has, in order (all of the
        endpoint's hub topic)."""
        skip_marked = not ep.channel.project and ep.route.project is not None
        topic = ep.route.hub_topic
        read = ep.channel.read
        check = self.check
        # check_sample's own test for an ActionExecution (nearly every sample),
        # inlined: what passes it is accepted here, what fails goes to check() so the
        # reason is check_sample's.
        quick = check is check_sample
        append = batch.append
        while True:
            samples = ddspy_take(ep.reader._ref, ANY_SAMPLE, _TAKE_BATCH)
            if isinstance(samples, int):  # pragma: no cover - a reader deleted under us
                raise HubError(f"{ep.channel.dds_topic}: take failed ({samples})")
            if not samples:
                return
            for data, info in samples:
                if not info.valid_data:
                    continue
                if skip_marked and self._from_project(ep, info.publication_handle):
                    continue
                try:
                    msg = read(data)
                    if quick and msg.__class__ is ActionExecution:
                        bid = msg.bid
                        if (bid is None or bid >= 0) and 0.0 <= msg.completion <= 1.0:
                            append(msg)
                            continue
                    reason = check(topic, msg)
                except Exception as exc:  # a foreign writer's malformed sample
                    reason = str(exc)
                if reason is None:
                    append(msg)
                    continue
                self.dropped += 1
                log.warning(
                    "%s: dropped a sample from %s: %s",
                    ep.channel.dds_topic,
                    self._writer_name(ep, info.publication_handle),
                    reason,
                )
            if len(samples) < _TAKE_BATCH:
                return

    def _writer_name(self, ep: Endpoint, handle: int) -> str:
        """The writer as DDS knows it: its GUID and its participant's."""
        try:
            endpoint = ep.reader.get_matched_publication_data(handle)
        except DDSException:
            endpoint = None
        if endpoint is None:
            return f"writer {handle:#x} (already gone)"
        return f"writer {endpoint.key} of participant {endpoint.participant_key}"

    def _from_project(self, ep: Endpoint, handle: int) -> bool:
        """Whether the writer ``handle`` is a project writer (its message comes wrapped).

        A project writer carries the USER_DATA marker, and its participant also writes
        the wrapper topic. Either sign suffices: right after discovery the matched
        writer's QoS may still lack its USER_DATA. Only "yes" is remembered.
        """
        if handle in self._project_writers:
            return True
        endpoint = ep.reader.get_matched_publication_data(handle)
        if endpoint is None:
            # The writer left before we looked: only project writers publish both
            # copies and leave together with their wrapper, so assume it was one.
            return True
        try:
            marked = endpoint.qos[Policy.Userdata].data == PROJECT_MARKER
        except (KeyError, AttributeError):
            marked = False
        if not marked:
            marked = endpoint.participant_key in self._wrapper_participants(ep.route)
        if marked:
            self._project_writers.add(handle)
        return marked

    def _wrapper_participants(self, route: Route) -> set[Any]:
        """Participants with a writer on ``route``'s wrapper topic: project processes."""
        wrapper = next(e for e in self.endpoints if e.route is route and e.channel.project)
        keys = set()
        for handle in wrapper.reader.get_matched_publications():
            endpoint = wrapper.reader.get_matched_publication_data(handle)
            if endpoint is not None:
                keys.add(endpoint.participant_key)
        return keys
