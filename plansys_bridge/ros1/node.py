"""A ROS 1 node in plain Python: master registration, slave API, TCPROS topics.

No rospy and no ROS install: the master is reached over XML-RPC, peers over TCPROS,
and types come from rosbags' typestore. The node follows ROS's environment:
``ROS_MASTER_URI`` (default ``http://127.0.0.1:11311``), ``ROS_HOSTNAME`` then
``ROS_IP`` for the address it advertises. It binds ``127.0.0.1`` unless an address
is configured (``bind=``, ``ROS_IP``, or a ``ROS_HOSTNAME`` that is not loopback,
then all interfaces), so a test or a demo never opens a port to the network.

The master is watched once a second (``getPid``). When it stops answering the node
logs one error and keeps its publishers and subscribers; when it answers again, or
answers with another pid (restarted, registrations lost), every registration is
renewed and the subscribers get the current publisher lists.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import secrets
from collections.abc import Callable, Coroutine
from typing import Any

from plansys_bridge.ros1.errors import MasterError, MasterUnreachable, ProtocolError, Ros1Error
from plansys_bridge.ros1.master import MasterClient
from plansys_bridge.ros1.slave import SlaveServer
from plansys_bridge.ros1.tcpros import encode_header, read_header
from plansys_bridge.ros1.topics import Callback, Connection, Publisher, Subscriber
from plansys_bridge.ros1.types import Ros1Types, ros1_name

__all__ = ["DEFAULT_MASTER_URI", "Node", "resolve_topic"]

log = logging.getLogger(__name__)

DEFAULT_MASTER_URI = "http://127.0.0.1:11311"
_LOOPBACK = {"127.0.0.1", "localhost", "::1"}


def resolve_topic(name: str) -> str:
    """Global ROS 1 name: ``chatter`` -> ``/chatter``; empty or spaced names are refused."""
    text = name.strip()
    if not text or any(c.isspace() for c in text) or "//" in text:
        raise Ros1Error(f"not a ROS topic name: {name!r}")
    return text if text.startswith("/") else "/" + text


class Node:
    """One ROS 1 node; ``async with Node("name") as node:`` starts and stops it."""

    def __init__(
        self,
        name: str,
        *,
        master_uri: str | None = None,
        host: str | None = None,
        bind: str | None = None,
        anonymous: bool = True,
        types: Ros1Types | None = None,
        watch_period: float = 1.0,
    ) -> None:
        base = resolve_topic(name)
        self.name = f"{base}_{os.getpid()}_{secrets.token_hex(3)}" if anonymous else base
        env = os.environ
        self.master_uri = master_uri or env.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI
        self.master = MasterClient(self.master_uri, self.name)
        self.host = host or env.get("ROS_HOSTNAME") or env.get("ROS_IP") or "127.0.0.1"
        self.bind = (
            bind or env.get("ROS_IP") or ("127.0.0.1" if self.host in _LOOPBACK else "0.0.0.0")
        )
        self.types = types or Ros1Types.default()
        self.watch_period = watch_period
        self.publishers: dict[str, Publisher] = {}
        self.subscribers: dict[str, Subscriber] = {}
        self.tcp_port = 0
        self.master_ok: bool | None = None
        """None before the first answer, then whether the master answers."""
        self.on_master_change: list[Callable[[bool], None]] = []
        self._master_pid: int | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._server: asyncio.Server | None = None
        self._slave: SlaveServer | None = None
        self._tasks: set[asyncio.Task[Any]] = set()
        self._watch: asyncio.Task[None] | None = None
        self._master_event = asyncio.Event()

    @property
    def uri(self) -> str:
        """The node's XML-RPC URI, as registered with the master."""
        port = self._slave.port if self._slave is not None else 0
        return f"http://{self.host}:{port}/"

    # ------------------------------------------------------------ lifecycle

    async def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._server = await asyncio.start_server(self._accept, self.bind, 0)
        self.tcp_port = self._server.sockets[0].getsockname()[1]
        self._slave = SlaveServer(self, self.bind)
        await self._check_master()
        self._watch = self._loop.create_task(self._watch_master(), name=f"ros1 {self.name} master")

    async def close(self) -> None:
        if self._watch is not None:
            self._watch.cancel()
            await asyncio.gather(self._watch, return_exceptions=True)
            self._watch = None
        if self.master_ok:
            calls = [self.master.unregister_publisher(t, self.uri) for t in self.publishers]
            calls += [self.master.unregister_subscriber(t, self.uri) for t in self.subscribers]
            self.master.timeout = 1.0
            await asyncio.gather(*calls, return_exceptions=True)
        for sub in self.subscribers.values():
            await sub.close()
        for pub in self.publishers.values():
            pub.close_connections()
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None
        tasks = list(self._tasks)
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        if self._slave is not None:
            await asyncio.to_thread(self._slave.close)
            self._slave = None

    async def __aenter__(self) -> Node:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def wait_for_master(self, timeout: float = 10.0) -> None:
        """Until the master answers; MasterUnreachable naming the URI otherwise."""
        try:
            async with asyncio.timeout(timeout):
                while not self.master_ok:
                    self._master_event.clear()
                    await self._master_event.wait()
        except TimeoutError:
            raise MasterUnreachable(f"no ROS master answers at {self.master_uri}") from None

    # ------------------------------------------------------------ topics

    async def advertise(
        self, topic: str, type_name: str, *, latch: bool = False, queue_bytes: int = 1 << 22
    ) -> Publisher:
        """A publisher; registered now if the master answers, else when it is back."""
        name = resolve_topic(topic)
        if name in self.publishers:
            raise Ros1Error(f"{self.name} already publishes {name}")
        pub = Publisher(self, name, type_name, latch=latch, queue_bytes=queue_bytes)
        self.publishers[name] = pub
        if self.master_ok:
            with contextlib.suppress(MasterError):
                await self.master.register_publisher(name, ros1_name(pub.type_name), self.uri)
        return pub

    async def subscribe(
        self,
        topic: str,
        type_name: str,
        callback: Callback,
        *,
        raw: bool = False,
        tcp_nodelay: bool = True,
    ) -> Subscriber:
        """A subscriber calling ``callback`` with each message (bytes when ``raw``)."""
        name = resolve_topic(topic)
        if name in self.subscribers:
            raise Ros1Error(f"{self.name} already subscribes to {name}")
        sub = Subscriber(self, name, type_name, callback, raw=raw, tcp_nodelay=tcp_nodelay)
        self.subscribers[name] = sub
        if self.master_ok:
            with contextlib.suppress(MasterError):
                uris = await self.master.register_subscriber(
                    name, ros1_name(sub.type_name), self.uri
                )
                sub.update_publishers(uris)
        return sub

    async def unadvertise(self, pub: Publisher) -> None:
        if self.publishers.get(pub.topic) is pub:
            del self.publishers[pub.topic]
            pub.close_connections()
            if self.master_ok:
                with contextlib.suppress(MasterError):
                    await self.master.unregister_publisher(pub.topic, self.uri)

    async def unsubscribe(self, sub: Subscriber) -> None:
        if self.subscribers.get(sub.topic) is sub:
            del self.subscribers[sub.topic]
            await sub.close()
            if self.master_ok:
                with contextlib.suppress(MasterError):
                    await self.master.unregister_subscriber(sub.topic, self.uri)

    def types_ros1_name(self, type_name: str) -> str:
        return ros1_name(type_name)

    # ------------------------------------------------------------ called by the slave API

    def call_soon(self, fn: Callable[..., None], *args: Any) -> None:
        """Run ``fn(*args)`` on the node's loop (from the XML-RPC thread)."""
        if self._loop is not None and not self._loop.is_closed():
            with contextlib.suppress(RuntimeError):
                self._loop.call_soon_threadsafe(fn, *args)

    def publisher_update(self, topic: str, uris: list[str]) -> None:
        sub = self.subscribers.get(topic)
        if sub is not None:
            sub.update_publishers(uris)

    def publications(self) -> list[list[str]]:
        return [[t, ros1_name(p.type_name)] for t, p in list(self.publishers.items())]

    def subscriptions(self) -> list[list[str]]:
        return [[t, ros1_name(s.type_name)] for t, s in list(self.subscribers.items())]

    def bus_info(self) -> list[list[Any]]:
        info: list[list[Any]] = []
        for topic, pub in list(self.publishers.items()):
            info += [
                [i, c.callerid, "o", "TCPROS", topic, True] for i, c in enumerate(pub.connections)
            ]
        for topic, sub in list(self.subscribers.items()):
            info += [[0, uri, "i", "TCPROS", topic, True] for uri in list(sub.connected)]
        return info

    def spawn(self, coro: Coroutine[Any, Any, None], name: str) -> asyncio.Task[None]:
        task = asyncio.get_running_loop().create_task(coro, name=name)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    # ------------------------------------------------------------ TCPROS server side

    async def _accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        address = writer.get_extra_info("peername")
        peer = f"{address[0]}:{address[1]}" if address else "?"
        task = asyncio.current_task()
        if task is not None:
            self._tasks.add(task)
        try:
            await self._serve_connection(reader, writer, peer)
        except asyncio.CancelledError:
            # Node.close() cancels open connections; asyncio's stream server would log
            # a cancelled handler task as an error, so the cancel ends it quietly.
            pass
        finally:
            writer.close()
            if task is not None:
                self._tasks.discard(task)

    async def _serve_connection(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, peer: str
    ) -> None:
        try:
            async with asyncio.timeout(10):
                header = await read_header(reader)
        except (EOFError, TimeoutError, OSError):
            return
        except ProtocolError as exc:
            log.warning(
                "ROS 1 node %s (TCPROS port %d): malformed connection header from %s: %s; "
                "connection dropped",
                self.name,
                self.tcp_port,
                peer,
                exc,
            )
            return
        topic = header.get("topic", "")
        who = f"{header.get('callerid', '?')} at {peer}"
        pub = self.publishers.get(topic)
        error = None
        if "service" in header:
            error = "services are not supported by this node"
        elif pub is None:
            error = f"{self.name} does not publish {topic!r}"
        elif header.get("md5sum") not in (pub.md5sum, "*"):
            error = (
                f"{topic}: md5sum {header.get('md5sum')} ({header.get('type')}) does not match "
                f"{pub.md5sum} ({ros1_name(pub.type_name)})"
            )
        if error is not None or pub is None:
            log.warning("ROS 1 topic %s: refused subscriber %s: %s", topic or "?", who, error)
            writer.write(encode_header({"error": error or "refused"}))
            with contextlib.suppress(OSError):
                await writer.drain()
            return
        writer.write(encode_header(pub.header()))
        if header.get("probe") == "1":
            with contextlib.suppress(OSError):
                await writer.drain()
            return
        conn = Connection(reader, writer, header.get("callerid", "?"), peer)
        await pub.serve(conn, header.get("tcp_nodelay") == "1")

    # ------------------------------------------------------------ the master watch

    async def _watch_master(self) -> None:
        while True:
            await asyncio.sleep(self.watch_period)
            await self._check_master()

    async def _check_master(self) -> None:
        try:
            pid = await self.master.get_pid()
        except MasterError as exc:
            if self.master_ok is not False:
                log.error(
                    "ROS 1 node %s: the ROS master at %s does not answer (%s); "
                    "retrying every %g s, registrations are renewed when it is back",
                    self.name,
                    self.master_uri,
                    exc,
                    self.watch_period,
                )
                self._set_master(False)
            return
        if self.master_ok and pid == self._master_pid:
            return
        again = self.master_ok is not None
        try:
            await self._register_all()
        except MasterError as exc:
            log.error(
                "ROS 1 node %s: registering with %s failed: %s", self.name, self.master_uri, exc
            )
            self._set_master(False)
            return
        self._master_pid = pid
        if again:
            log.warning(
                "ROS 1 node %s: the ROS master at %s answers again (pid %d); "
                "%d registrations renewed",
                self.name,
                self.master_uri,
                pid,
                len(self.publishers) + len(self.subscribers),
            )
        self._set_master(True)

    async def _register_all(self) -> None:
        for topic, pub in list(self.publishers.items()):
            await self.master.register_publisher(topic, ros1_name(pub.type_name), self.uri)
        for topic, sub in list(self.subscribers.items()):
            uris = await self.master.register_subscriber(topic, ros1_name(sub.type_name), self.uri)
            sub.update_publishers(uris)

    def _set_master(self, ok: bool) -> None:
        changed = self.master_ok != ok
        self.master_ok = ok
        self._master_event.set()
        if changed:
            for callback in list(self.on_master_change):
                try:
                    callback(ok)
                except Exception:
                    log.exception("ROS 1 node %s: a master-state callback failed", self.name)
