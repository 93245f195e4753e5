"""The node's own XML-RPC server: the ROS 1 "slave API" the master and peers call.

The master tells a subscriber which publishers exist (``publisherUpdate``); a
subscriber asks a publisher where to connect (``requestTopic``); tools ask for
``getBusInfo``, ``getPid`` and so on. ``xmlrpc.server`` is blocking, so the server
runs in its own thread and hands anything that touches the node to the node's event
loop.
"""

from __future__ import annotations

import logging
import os
import socketserver
import threading
from collections.abc import Callable, Collection
from typing import Any, Protocol
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer

__all__ = ["SlaveNode", "SlaveServer", "XmlRpcServer"]

log = logging.getLogger(__name__)


class XmlRpcServer(socketserver.ThreadingMixIn, SimpleXMLRPCServer):
    """One thread per request (a slow caller never blocks the others), no request log."""

    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, address: tuple[str, int]) -> None:
        super().__init__(address, requestHandler=_Quiet, allow_none=True, logRequests=False)


class _Quiet(SimpleXMLRPCRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        return None


class SlaveNode(Protocol):
    """What the slave API answers from: the node it serves.

    Declared here, beside its user, so that the server never imports the node that
    owns it; :class:`~plansys_bridge.ros1.node.Node` has all of it.
    """

    @property
    def name(self) -> str: ...

    @property
    def master_uri(self) -> str: ...

    @property
    def host(self) -> str: ...

    @property
    def tcp_port(self) -> int: ...

    @property
    def publishers(self) -> Collection[str]: ...

    def call_soon(self, fn: Callable[..., None], *args: Any) -> None: ...

    def publisher_update(self, topic: str, uris: list[str]) -> None: ...

    def publications(self) -> list[list[str]]: ...

    def subscriptions(self) -> list[list[str]]: ...

    def bus_info(self) -> list[list[Any]]: ...


class SlaveServer:
    """Serves the slave API of ``node`` on ``bind``:0 until :meth:`close`."""

    def __init__(self, node: SlaveNode, bind: str) -> None:
        self.node = node
        self._server = XmlRpcServer((bind, 0))
        self.port: int = self._server.server_address[1]
        for name in (
            "getBusStats",
            "getBusInfo",
            "getMasterUri",
            "shutdown",
            "getPid",
            "getSubscriptions",
            "getPublications",
            "paramUpdate",
            "publisherUpdate",
            "requestTopic",
        ):
            self._server.register_function(getattr(self, name), name)
        self._thread = threading.Thread(
            target=self._server.serve_forever,
            kwargs={"poll_interval": 0.1},
            name=f"ros1-xmlrpc-{node.name}",
            daemon=True,
        )
        self._thread.start()

    def close(self) -> None:
        self._server.shutdown()
        self._server.server_close()
        self._thread.join(timeout=5)

    # ------------------------------------------------------------ the slave API

    def getBusStats(self, caller_id: str) -> list[Any]:
        return [1, "", [[], [], []]]

    def getBusInfo(self, caller_id: str) -> list[Any]:
        return [1, "", self.node.bus_info()]

    def getMasterUri(self, caller_id: str) -> list[Any]:
        return [1, "", self.node.master_uri]

    def shutdown(self, caller_id: str, msg: str = "") -> list[Any]:
        log.warning("ROS 1 node %s: %s asked it to shut down (%s)", self.node.name, caller_id, msg)
        return [1, "", 0]

    def getPid(self, caller_id: str) -> list[Any]:
        return [1, "", os.getpid()]

    def getSubscriptions(self, caller_id: str) -> list[Any]:
        return [1, "", self.node.subscriptions()]

    def getPublications(self, caller_id: str) -> list[Any]:
        return [1, "", self.node.publications()]

    def paramUpdate(self, caller_id: str, key: str, value: Any) -> list[Any]:
        return [1, "", 0]

    def publisherUpdate(self, caller_id: str, topic: str, publishers: list[str]) -> list[Any]:
        self.node.call_soon(self.node.publisher_update, topic, list(publishers))
        return [1, "", 0]

    def requestTopic(self, caller_id: str, topic: str, protocols: list[Any]) -> list[Any]:
        if topic not in self.node.publishers:
            return [-1, f"{self.node.name} does not publish {topic}", []]
        if not any(isinstance(p, list) and p and p[0] == "TCPROS" for p in protocols):
            return [0, "only TCPROS is supported", []]
        return [1, "ready on TCPROS", ["TCPROS", self.node.host, self.node.tcp_port]]
