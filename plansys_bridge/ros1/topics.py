"""TCPROS publishers and subscribers of a :class:`~plansys_bridge.ros1.node.Node`.

A publisher serialises each message once and writes the frame to every connected
subscriber; a subscriber whose socket is not draining (more than ``queue_bytes``
waiting) misses messages instead of growing memory, like ROS's queue_size. A latched
publisher sends its last message to every new subscriber.

A subscriber keeps one connection task per publisher the master lists. A publisher
that goes away (crash, restart, network) is retried until the master stops listing
it; a publisher whose header or frame is malformed is dropped with one log line
naming the topic and the peer, and the other connections keep going.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket
from collections.abc import Callable, Coroutine
from typing import Any, Protocol

from plansys_bridge.ros1.errors import MasterError, ProtocolError, Ros1Error
from plansys_bridge.ros1.master import xmlrpc_call
from plansys_bridge.ros1.tcpros import encode_header, frame, read_frame, read_header
from plansys_bridge.ros1.types import Ros1Types

__all__ = ["Connection", "Publisher", "Subscriber", "TopicNode"]

log = logging.getLogger(__name__)

Callback = Callable[[Any], None]


class TopicNode(Protocol):
    """What a publisher or subscriber needs from the node that made it.

    Declared here, beside its users, so that topics never import the node that owns
    them; :class:`~plansys_bridge.ros1.node.Node` has all of it.
    """

    @property
    def name(self) -> str: ...

    @property
    def types(self) -> Ros1Types: ...

    def types_ros1_name(self, type_name: str) -> str: ...

    def spawn(self, coro: Coroutine[Any, Any, None], name: str) -> asyncio.Task[None]: ...

    async def unadvertise(self, pub: Publisher) -> None: ...

    async def unsubscribe(self, sub: Subscriber) -> None: ...


class Connection:
    """One TCPROS connection of a publisher to a subscriber."""

    def __init__(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, callerid: str, peer: str
    ) -> None:
        self.reader = reader
        self.writer = writer
        self.callerid = callerid
        self.peer = peer
        self.dropped = 0
        """Messages not written because the subscriber was not reading."""


def set_nodelay(writer: asyncio.StreamWriter) -> None:
    sock = writer.get_extra_info("socket")
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


class Publisher:
    """Publishes ``type_name`` messages on ``topic``; made by ``Node.advertise``."""

    def __init__(
        self, node: TopicNode, topic: str, type_name: str, *, latch: bool, queue_bytes: int
    ) -> None:
        self.node = node
        self.topic = topic
        self.type_name = node.types.check(type_name)
        self.definition, self.md5sum = node.types.definition(type_name)
        self.latch = latch
        self.queue_bytes = queue_bytes
        self.connections: list[Connection] = []
        self._latched: bytes | None = None
        self._changed = asyncio.Event()

    @property
    def num_connections(self) -> int:
        return len(self.connections)

    def publish(self, msg: object) -> None:
        self.publish_raw(self.node.types.serialize(msg, self.type_name))

    def publish_raw(self, body: bytes) -> None:
        """Send an already serialised message (what a bridge or a replay has)."""
        data = frame(body)
        if self.latch:
            self._latched = data
        for conn in list(self.connections):
            transport = conn.writer.transport
            if transport.is_closing():
                continue
            if transport.get_write_buffer_size() > self.queue_bytes:
                conn.dropped += 1
                continue
            conn.writer.write(data)

    async def wait_for_subscribers(self, count: int = 1, timeout: float = 10.0) -> None:
        """Until ``count`` subscribers are connected; TimeoutError otherwise."""
        async with asyncio.timeout(timeout):
            while len(self.connections) < count:
                self._changed.clear()
                await self._changed.wait()

    def header(self) -> dict[str, str]:
        return {
            "callerid": self.node.name,
            "md5sum": self.md5sum,
            "type": self.node.types_ros1_name(self.type_name),
            "message_definition": self.definition,
            "latching": "1" if self.latch else "0",
            "topic": self.topic,
        }

    async def serve(self, conn: Connection, nodelay: bool) -> None:
        """Keep ``conn`` until the subscriber closes it (it sends nothing after its header)."""
        if nodelay:
            set_nodelay(conn.writer)
        if self._latched is not None:
            conn.writer.write(self._latched)
        self.connections.append(conn)
        self._changed.set()
        try:
            while await conn.reader.read(65536):
                pass
        except OSError:
            pass
        finally:
            with contextlib.suppress(ValueError):
                self.connections.remove(conn)
            self._changed.set()

    def close_connections(self) -> None:
        for conn in self.connections:
            conn.writer.close()

    async def unadvertise(self) -> None:
        await self.node.unadvertise(self)


class Subscriber:
    """Receives ``topic`` from every publisher the master names; made by ``Node.subscribe``."""

    def __init__(
        self,
        node: TopicNode,
        topic: str,
        type_name: str,
        callback: Callback,
        *,
        raw: bool,
        tcp_nodelay: bool,
    ) -> None:
        self.node = node
        self.topic = topic
        self.type_name = node.types.check(type_name)
        self.definition, self.md5sum = node.types.definition(type_name)
        self.callback = callback
        self.raw = raw
        self.tcp_nodelay = tcp_nodelay
        self.publishers: list[str] = []
        self._tasks: dict[str, asyncio.Task[None]] = {}
        self._dropped: set[str] = set()
        self.connected: dict[str, str] = {}
        """Publisher URI -> its callerid, for the connections that are up."""
        self.received = 0

    @property
    def num_connections(self) -> int:
        return len(self.connected)

    def update_publishers(self, uris: list[str]) -> None:
        """The master's current publisher list: connect to new ones, drop gone ones."""
        self.publishers = list(uris)
        wanted = set(uris)
        self._dropped &= wanted
        for uri, task in list(self._tasks.items()):
            if uri not in wanted:
                task.cancel()
                del self._tasks[uri]
        for uri in wanted:
            if uri not in self._tasks and uri not in self._dropped:
                self._tasks[uri] = self.node.spawn(self._follow(uri), f"ros1 {self.topic} {uri}")

    async def close(self) -> None:
        tasks = list(self._tasks.values())
        self._tasks.clear()
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)

    async def unsubscribe(self) -> None:
        await self.node.unsubscribe(self)

    async def wait_for_publishers(self, count: int = 1, timeout: float = 10.0) -> None:
        async with asyncio.timeout(timeout):
            while len(self.connected) < count:
                await asyncio.sleep(0.02)

    def _header(self) -> dict[str, str]:
        return {
            "callerid": self.node.name,
            "topic": self.topic,
            "md5sum": self.md5sum,
            "type": self.node.types_ros1_name(self.type_name),
            "tcp_nodelay": "1" if self.tcp_nodelay else "0",
            "message_definition": self.definition,
        }

    async def _follow(self, uri: str) -> None:
        """Stay connected to the publisher at ``uri`` while the master lists it."""
        delay = 0.1
        try:
            while True:
                try:
                    await self._connect_once(uri)
                    delay = 0.1
                except ProtocolError as exc:
                    log.warning("ROS 1 topic %s: %s; connection dropped", self.topic, exc)
                    self._dropped.add(uri)
                    return
                except (OSError, EOFError, MasterError, Ros1Error) as exc:
                    log.debug("ROS 1 topic %s: publisher %s: %r", self.topic, uri, exc)
                await asyncio.sleep(delay)
                delay = min(2.0, delay * 2)
        finally:
            if self._tasks.get(uri) is asyncio.current_task():
                del self._tasks[uri]

    async def _connect_once(self, uri: str) -> None:
        code, message, proto = await xmlrpc_call(
            uri, "requestTopic", self.node.name, self.topic, [["TCPROS"]], timeout=3.0
        )
        if code != 1 or not isinstance(proto, list) or len(proto) < 3 or proto[0] != "TCPROS":
            raise Ros1Error(f"{uri} refused {self.topic}: {message}")
        host, port = str(proto[1]), int(proto[2])
        peer = f"{uri} (TCPROS {host}:{port})"
        reader, writer = await asyncio.open_connection(host, port)
        try:
            if self.tcp_nodelay:
                set_nodelay(writer)
            writer.write(encode_header(self._header()))
            await writer.drain()
            try:
                header = await read_header(reader)
            except ProtocolError as exc:
                raise ProtocolError(f"malformed connection header from {peer}: {exc}") from exc
            if "error" in header:
                raise Ros1Error(f"{peer} refused the connection: {header['error']}")
            theirs = header.get("md5sum", "")
            if theirs not in (self.md5sum, "*"):
                raise ProtocolError(
                    f"publisher {header.get('callerid', '?')} at {peer} sends "
                    f"{header.get('type', '?')} md5 {theirs}, expected "
                    f"{self.node.types_ros1_name(self.type_name)} md5 {self.md5sum}"
                )
            who = f"{header.get('callerid', '?')} at {peer}"
            self.connected[uri] = header.get("callerid", "?")
            try:
                await self._receive(reader, who)
            finally:
                self.connected.pop(uri, None)
        finally:
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    async def _receive(self, reader: asyncio.StreamReader, who: str) -> None:
        types, name = self.node.types, self.type_name
        while True:
            try:
                body = await read_frame(reader)
            except ProtocolError as exc:
                raise ProtocolError(f"malformed frame from {who}: {exc}") from exc
            if self.raw:
                msg: Any = body
            else:
                try:
                    msg = types.deserialize(body, name)
                except Ros1Error as exc:
                    raise ProtocolError(f"malformed message from {who}: {exc}") from exc
            self.received += 1
            try:
                self.callback(msg)
            except Exception:
                log.exception("ROS 1 topic %s: the callback failed on a message", self.topic)
