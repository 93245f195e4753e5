"""The hub over Eclipse Cyclone DDS, so executor and performers can run in separate processes.

:class:`DdsTransport` implements :class:`~plansys_bridge.hub.transport.Transport`. Hub
topics travel as ROS 2 would carry PlanSys2's messages (``rt/actions_hub`` with type
``plansys2_msgs::msg::dds_::ActionExecution_``, XCDR1, reliable, depth 100), plus
the project's wrapper topics for fields PlanSys2 lacks (see
:mod:`plansys_bridge.hub.dds_codec`). Each process joins a DDS domain configured by
:func:`~plansys_bridge.hub.dds_config.loopback_config`: loopback only, no multicast.

Delivery: one reader thread per transport waits on a DDS wait set, takes the samples
of the readers that have some (:mod:`~plansys_bridge.hub.dds_intake`), and hands what
one wake-up took to the loop in one ``call_soon_threadsafe``, where each reader's
messages go as one batch (``publish_many``) to an
:class:`~plansys_bridge.hub.transport.InProcessTransport` that fans them out to this
process's subscribers:
callbacks run on the loop, in arrival order per topic
(DDS orders per writer; messages of different topics or writers may interleave
differently than in the in-process transport). A message a transport publishes
reaches its own subscribers directly, as in the in-process transport, when one of
them wants it (:mod:`~plansys_bridge.hub.local_interest`), and goes out on DDS to
everybody else; its readers ignore their own participant's samples, so nothing
arrives twice and nothing is decoded that was never encoded.
:meth:`~DdsTransport.publish_many` writes a batch (an auction's REJECTs) one sample
per message, as publishing each would, and hands the local ones to the fan-out as one
batch.

Duplicates: on a topic with a project wrapper, a project process writes the wrapper,
and the plain message as well while a reader of the plain topic outside the project
is matched (a ROS 2 node, ``ros2 topic echo``) or the topic is latched (a late
joiner gets its history). Receivers take the complete message from the wrapper
topic and skip plain samples of project writers, known by their USER_DATA marker or
by their participant also writing the wrapper topic, without decoding them; plain
samples from other DDS nodes (a ROS 2 PlanSys2 node) are delivered as they are.

Bytes: samples are written and taken as raw XCDR1 through
:mod:`~plansys_bridge.hub.dds_wire`, which does what Cyclone's Python serialiser does
about ten times faster (with every bidder answering, serialisation was most of an
auction's cost), and ``ActionExecution``, nearly all the traffic, through
:mod:`~plansys_bridge.hub.dds_execution`, which writes and reads the part all
messages of one auction share once.

Topics without a DDS type (an adapter's own topic) are delivered inside the process
only, as the in-process transport would; the first such publish logs a warning.

DDS needs the wall clock: the virtual clock jumps over idle time, which would expire
every protocol timeout while a message is still in flight between processes.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Sequence
from typing import Any

from cyclonedds._clayer import ddspy_write
from cyclonedds.core import DDSException, Listener, Qos, ReadCondition
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from plansys_bridge.clock import VirtualTimeEventLoop
from plansys_bridge.errors import HubError
from plansys_bridge.hub.dds_checks import SampleCheck, check_sample
from plansys_bridge.hub.dds_codec import ROUTES, Channel, Route, check_accepts
from plansys_bridge.hub.dds_config import check_domain_id, loopback_config
from plansys_bridge.hub.dds_discovery import publish_discovery_info
from plansys_bridge.hub.dds_intake import ANY_SAMPLE, PROJECT_MARKER, Endpoint, Intake
from plansys_bridge.hub.dds_participant import DdsParticipant, endpoint_qos
from plansys_bridge.hub.local_interest import LocalInterest, Wants
from plansys_bridge.hub.messages import Topics
from plansys_bridge.hub.transport import InProcessTransport, Subscription

__all__ = ["PROJECT_MARKER", "DdsTransport"]

log = logging.getLogger(__name__)

Callback = Callable[[object], None]
Send = Callable[[object], None]


def _checked(ret: int, channel: Channel | None) -> None:
    """Raise for what ``ddspy_write`` returned when it failed."""
    if ret < 0:
        raise DDSException(ret, f"writing on {channel.dds_topic if channel else '?'}")


def _reader_participants(writer: Any) -> set[Any]:
    """The participants of the readers matched with ``writer`` (None: one already gone)."""
    keys = set()
    for handle in writer.get_matched_subscriptions():
        endpoint = writer.get_matched_subscription_data(handle)
        keys.add(None if endpoint is None else endpoint.participant_key)
    return keys


def _qos(channel: Channel, *, reader: bool = False, marked: bool = False) -> Qos:
    """PlanSys2's QoS for the channel's topic (:mod:`~plansys_bridge.hub.dds_qos`), XCDR1.

    Readers keep every sample until the reader thread takes it, so a burst longer
    than the depth is not cut short on arrival; they ask for the writer's durability
    so a latched topic's history reaches a late joiner; they ignore the samples of
    their own participant, whose messages the transport delivers itself.
    """
    qos = channel.qos
    return endpoint_qos(
        depth=None if reader else qos.depth,
        transient_local=qos.transient_local,
        reliable=qos.reliable,
        user_data=PROJECT_MARKER if marked else None,
        ignore_local=True,
    )


class DdsTransport:
    """Hub topics on a Cyclone DDS domain (loopback-only configuration by default).

    ``domain_id`` keeps unrelated runs apart (tests pick a random one); ``config`` is
    Cyclone XML and defaults to :func:`loopback_config` for that domain. Start it on the
    running loop before publishing; ``close()`` stops the reader thread and deletes
    every DDS entity.
    """

    def __init__(
        self,
        domain_id: int = 0,
        *,
        config: str | None = None,
        check: SampleCheck | None = None,
        node_name: str = "plansys_bridge",
    ) -> None:
        self.domain_id = check_domain_id(domain_id)
        self.config = config if config is not None else loopback_config(domain_id)
        self.node_name = node_name
        """The ROS 2 node this process shows as on ``ros_discovery_info``."""
        self._discovery: tuple[Any, Any] | None = None
        self._intake = Intake(check if check is not None else check_sample)
        """The endpoints, and what is taken from their readers (what a received
        message must pass: :mod:`~plansys_bridge.hub.dds_checks`)."""
        self._endpoints = self._intake.endpoints
        self._fanout = InProcessTransport()
        self._interest = LocalInterest()
        """Local fan-out to this process's subscribers, on the loop, in arrival order."""
        self._writers: dict[str, tuple[Endpoint, Endpoint | None]] = {}
        self._out: dict[str, Send] = {}
        """Per hub topic with a DDS type: what writes one message on DDS (see
        :meth:`_sender`); filled while the transport runs (started, not closing), so
        that one look-up tells publish() that it may write."""
        self._matches_changed = False
        """Set by DDS when a writer's matched readers change: look for foreign readers."""
        self._plain_copy: dict[str, bool] = {}
        """Per wrapped hub topic: must the plain sample be written too (a reader outside
        the project reads the plain topic, or the topic is latched)? Unknown: yes."""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._dds = DdsParticipant(self.domain_id, self.config, f"dds-hub-{self.domain_id}")
        self._closed = False
        self._warned_local: set[str] = set()
        self.published = 0
        """Messages published so far (all topics), for statistics."""

    @property
    def dropped(self) -> int:
        """Samples received that could not be turned into hub messages."""
        return self._intake.dropped

    # -- lifecycle ---------------------------------------------------------------------
    async def start(self) -> None:
        if self._closed:
            raise HubError("cannot start a closed DDS transport")
        if self._dds.running:
            return
        loop = asyncio.get_running_loop()
        if isinstance(loop, VirtualTimeEventLoop):
            raise HubError(
                "the DDS transport needs the wall clock: the virtual clock would expire "
                "protocol timeouts while messages travel between processes"
            )
        self._loop = loop
        await self._fanout.start()
        try:
            out = self._open()
        except BaseException:
            self._teardown()
            raise
        self._dds.start(self._poll, keyed=True)
        self._out = out

    def _open(self) -> dict[str, Send]:
        """Join the domain and make every endpoint; return what publish() needs per topic."""
        self._dds.open()
        out = {}
        try:
            for route in ROUTES.values():
                made = []
                for channel in route.channels:
                    endpoint = self._endpoint(route, channel)
                    self._endpoints.append(endpoint)
                    made.append(endpoint)
                project = made[1] if len(made) > 1 else None
                self._writers[route.hub_topic] = (made[0], project)
                out[route.hub_topic] = self._sender(
                    route, made[0].writer._ref, None if project is None else project.writer._ref
                )
            self._discovery = publish_discovery_info(
                self._dds.participant,
                self.node_name,
                readers=[ep.reader for ep in self._endpoints],
                writers=[ep.writer for ep in self._endpoints],
            )
        except DDSException as exc:
            raise HubError(f"DDS domain {self.domain_id}: cannot create endpoints: {exc}") from exc
        return out

    def _endpoint(self, route: Route, channel: Channel) -> Endpoint:
        p = self._dds.participant
        topic = Topic(p, channel.dds_topic, channel.idl_type)
        marked = not channel.project and route.project is not None
        listener = Listener(on_publication_matched=self._on_matched)
        writer = DataWriter(p, topic, _qos(channel, marked=marked), listener=listener)
        reader = DataReader(p, topic, _qos(channel, reader=True))
        condition = ReadCondition(reader, ANY_SAMPLE)
        # keyed by its place in the list of endpoints (from 1)
        self._dds.attach(condition, len(self._endpoints) + 1)
        return Endpoint(route, channel, topic, writer, reader, condition)

    def _on_matched(self, *_: object) -> None:
        """On a DDS thread: a writer's matched readers changed (see :meth:`_plain_needed`)."""
        self._matches_changed = True

    async def close(self) -> None:
        self._closed = True
        self._out = {}  # publish() refuses from now on
        await self._fanout.close()
        self._teardown()

    def _teardown(self) -> None:
        entities: list[Any] = list(self._discovery or ())
        self._discovery = None
        for ep in self._endpoints:
            entities += [ep.condition, ep.reader, ep.writer, ep.topic]
        self._dds.close(entities)
        self._endpoints.clear()
        self._writers.clear()
        self._out = {}

    @property
    def closed(self) -> bool:
        return self._closed

    # -- publish / subscribe -----------------------------------------------------------
    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        return self.subscribe_wanting(topic, callback, None)

    def subscribe_wanting(
        self, topic: str, callback: Callback, wants: Wants | None
    ) -> Subscription:
        """As :meth:`subscribe`, for a subscriber that says which messages it wants: a
        message published here reaches this process's subscribers only if one of them
        wants it (see :mod:`~plansys_bridge.hub.local_interest`)."""
        if self._closed:
            raise HubError(f"cannot subscribe to {topic!r}: transport closed")
        return self._interest.track(topic, self._fanout.subscribe(topic, callback), wants)

    def subscriber_count(self, topic: str) -> int:
        return self._fanout.subscriber_count(topic)

    def publish(self, topic: str, msg: object) -> None:
        send = self._out.get(topic)
        if send is None:  # not running, or a topic without a DDS type
            self._publish_unrouted(topic, msg)
            return
        send(msg)
        self.published += 1
        if self._interest.wanted(topic, msg):
            self._fanout.publish(topic, msg)

    def publish_many(self, topic: str, messages: Sequence[object]) -> None:
        """Publish ``messages`` on ``topic`` in order, as :meth:`publish` one by one
        would: the same samples in the same order on DDS, and the same deliveries to
        this process's subscribers in that order; in one call, and at home as one
        batch (the REJECTs that end an auction among N bidders, the statuses of a
        performer's change of state). A message that cannot be published raises as
        :meth:`publish` would, after those before it went out."""
        send = self._out.get(topic)
        if send is None:
            for msg in messages:
                self.publish(topic, msg)
            return
        sent = 0
        try:
            for msg in messages:
                send(msg)
                sent += 1
        finally:
            self.published += sent
            done = messages if sent == len(messages) else messages[:sent]
            wants = self._interest.wants(topic)
            local = done if wants is None else [msg for msg in done if wants(msg)]
            if local:
                self._fanout.publish_many(topic, local)

    def _sender(self, route: Route, plain_ref: int, project_ref: int | None) -> Send:
        """What writes one message of ``route`` on DDS, raising HubError if it cannot:
        the wrapper sample and, while :meth:`_plain_needed` says so, the plain one, as
        XCDR1 bytes through ``ddspy_write`` (what ``DataWriter.write`` does, faster)."""
        topic = route.hub_topic
        accepts = route.accepts
        plain, wrapped = route.to_bytes
        if project_ref is None or wrapped is None:
            wrapped = None

        def send(msg: object) -> None:
            if not isinstance(msg, accepts):
                check_accepts(route, msg)  # raises, naming what the topic carries
            try:
                if wrapped is None:
                    _checked(ddspy_write(plain_ref, plain(msg)), route.plain)
                    return
                ret = ddspy_write(project_ref, wrapped(msg))
                if ret < 0:
                    _checked(ret, route.project)
                # the plain copy is skipped with one look-up while nothing changed
                if (self._matches_changed or self._plain_copy.get(topic, True)) and (
                    self._plain_needed(route)
                ):
                    _checked(ddspy_write(plain_ref, plain(msg)), route.plain)
            except (DDSException, ValueError, TypeError, OverflowError) as exc:
                raise HubError(
                    f"cannot publish {type(msg).__name__} on {route.plain.dds_topic}: {exc}"
                ) from exc

        return send

    def _plain_needed(self, route: Route) -> bool:
        """Must the plain copy of a wrapped message be written too?

        Only project processes read the wrapper, and they skip plain copies of project
        writers: the plain copy is for readers outside the project, and for a late
        joiner of a latched topic. Which readers are matched is looked at again only
        after DDS reported a change.
        """
        if self._matches_changed:
            self._matches_changed = False
            self._plain_copy = {
                r.hub_topic: r.plain.qos.transient_local or self._has_foreign_reader(r)
                for r in ROUTES.values()
                if r.project is not None
            }
        return self._plain_copy.get(route.hub_topic, True)

    def _has_foreign_reader(self, route: Route) -> bool:
        """Is a reader of ``route``'s plain topic in a participant not reading its wrapper?"""
        plain_ep, project_ep = self._writers[route.hub_topic]
        if project_ep is None:  # pragma: no cover - only asked for wrapped routes
            return True
        project = _reader_participants(project_ep.writer)
        plain = _reader_participants(plain_ep.writer)
        return None in plain or not plain <= project

    def _publish_unrouted(self, topic: str, msg: object) -> None:
        """Refuse to publish before start and after close; deliver a topic without a DDS
        type inside this process only."""
        if self._closed:
            raise HubError(f"cannot publish on {topic!r}: transport closed")
        if not self._dds.running or self._loop is None:
            raise HubError(f"cannot publish on {topic!r}: start the DDS transport first")
        if topic not in self._warned_local:
            self._warned_local.add(topic)
            log.warning(
                "topic %r has no DDS type: delivered inside this process only (DDS carries %s)",
                topic,
                ", ".join(ROUTES),
            )
        self.published += 1
        self._fanout.publish(topic, msg)

    async def wait_for_peers(
        self, count: int = 1, *, topic: str = Topics.ACTIONS_HUB, timeout: float = 10.0
    ) -> None:
        """Wait until ``count`` other participants read ``topic`` (HubError on timeout).

        DDS drops what is written before a reader is matched; a caller that must not
        lose its first messages waits here (the auction re-sends REQUESTs anyway).
        Every DDS topic of the hub topic counts: the plain one and the project wrapper.
        """
        if not self._dds.running:
            raise HubError("start the DDS transport before waiting for peers")
        route = ROUTES.get(topic)
        if route is None:
            raise HubError(f"topic {topic!r} has no DDS type")
        writers = [ep.writer for ep in self._writers[topic] if ep is not None]
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while True:
            # Our own readers ignore our writers: every matched reader is a peer's.
            matched = min(w.get_publication_matched_status().current_count for w in writers)
            if matched >= count:
                return
            if loop.time() >= deadline:
                raise HubError(
                    f"DDS domain {self.domain_id}: {matched} of {count} peers on "
                    f"{', '.join(c.dds_topic for c in route.channels)} after {timeout:g} s"
                )
            await asyncio.sleep(0.02)

    # -- receiving ---------------------------------------------------------------------
    def _poll(self, fired: list[int]) -> None:
        """On the reader thread: take what the readers whose condition fired hold (in
        the order of the endpoints), hand it to the loop in one call, as one batch
        per endpoint (one hub topic each)."""
        runs: list[tuple[str, list[object]]] = []
        endpoints = self._endpoints
        take = self._intake.take
        count = len(endpoints)
        for key in sorted(k for k in fired if k and k <= count):
            ep = endpoints[key - 1]
            taken: list[object] = []
            take(ep, taken)
            if taken:
                runs.append((ep.route.hub_topic, taken))
        if runs:
            if self._closed or self._loop is None:
                raise HubError("DDS transport closed")  # ends the reader thread
            self._loop.call_soon_threadsafe(self._deliver, runs)

    def _deliver(self, runs: list[tuple[str, list[object]]]) -> None:
        """On the loop: what the reader thread took goes to the fan-out, each batch in
        one call (a hub's router that takes batches gets it so)."""
        fanout = self._fanout
        if fanout.closed:
            return
        for topic, messages in runs:
            fanout.publish_many(topic, messages)

    def __repr__(self) -> str:
        state = "closed" if self._closed else "started" if self._dds.running else "new"
        return f"DdsTransport(domain_id={self.domain_id}, {state})"
