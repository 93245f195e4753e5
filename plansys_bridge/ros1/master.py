"""The ROS master's XML-RPC API and the node-to-node ``requestTopic`` call.

Every master call answers ``[code, status message, value]``; code 1 is success.
Calls run in a worker thread (``xmlrpc.client`` is blocking) with a timeout so a
master that hangs cannot stall the node. A refused or timed-out connection is
:class:`MasterUnreachable` naming the URI, a failure code is :class:`MasterError`
naming the call.
"""

from __future__ import annotations

import asyncio
import http.client
import xmlrpc.client
from typing import Any
from urllib.parse import urlsplit

from plansys_bridge.ros1.errors import MasterError, MasterUnreachable, Ros1Error

__all__ = ["MasterClient", "check_uri", "xmlrpc_call"]


def check_uri(uri: str, what: str = "master_uri") -> str:
    """``http://host:port`` or Ros1Error naming ``what``."""
    parts = urlsplit(uri.strip())
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise Ros1Error(f"{what} must look like http://HOST:PORT, got {uri!r}")
    try:
        _ = parts.port
    except ValueError as exc:
        raise Ros1Error(f"{what} has a bad port: {uri!r}") from exc
    return uri.strip()


class _Transport(xmlrpc.client.Transport):
    def __init__(self, timeout: float) -> None:
        super().__init__()
        self._timeout = timeout

    def make_connection(self, host: Any) -> http.client.HTTPConnection:
        conn = super().make_connection(host)
        conn.timeout = self._timeout
        return conn


def _call_sync(uri: str, method: str, args: tuple[Any, ...], timeout: float) -> Any:
    proxy = xmlrpc.client.ServerProxy(uri, transport=_Transport(timeout), allow_none=True)
    with proxy:
        return getattr(proxy, method)(*args)


async def xmlrpc_call(uri: str, method: str, *args: Any, timeout: float = 5.0) -> Any:
    """``[code, msg, value]`` of ``method`` at ``uri``; MasterUnreachable if nobody answers."""
    try:
        reply = await asyncio.to_thread(_call_sync, uri, method, args, timeout)
    except (TimeoutError, OSError, http.client.HTTPException) as exc:
        raise MasterUnreachable(f"{uri}: {method} failed: {exc}") from exc
    except xmlrpc.client.Fault as exc:
        raise MasterError(f"{uri}: {method} failed: {exc.faultString}") from exc
    if not isinstance(reply, list | tuple) or len(reply) != 3:
        raise MasterError(f"{uri}: {method} answered {reply!r}, not [code, message, value]")
    return reply


class MasterClient:
    """The master calls a node makes, as ``caller_id``."""

    def __init__(self, uri: str, caller_id: str, *, timeout: float = 5.0) -> None:
        self.uri = check_uri(uri)
        self.caller_id = caller_id
        self.timeout = timeout

    async def call(self, method: str, *args: Any) -> Any:
        code, message, value = await xmlrpc_call(
            self.uri, method, self.caller_id, *args, timeout=self.timeout
        )
        if code != 1:
            raise MasterError(f"master {self.uri}: {method}{args!r} refused: {message}")
        return value

    async def get_pid(self) -> int:
        return int(await self.call("getPid"))

    async def register_publisher(self, topic: str, type_name: str, caller_api: str) -> list[str]:
        """Register; the answer lists the subscribers' node URIs."""
        return list(await self.call("registerPublisher", topic, type_name, caller_api))

    async def unregister_publisher(self, topic: str, caller_api: str) -> None:
        await self.call("unregisterPublisher", topic, caller_api)

    async def register_subscriber(self, topic: str, type_name: str, caller_api: str) -> list[str]:
        """Register; the answer lists the publishers' node URIs."""
        return list(await self.call("registerSubscriber", topic, type_name, caller_api))

    async def unregister_subscriber(self, topic: str, caller_api: str) -> None:
        await self.call("unregisterSubscriber", topic, caller_api)

    async def lookup_node(self, node_name: str) -> str:
        return str(await self.call("lookupNode", node_name))

    async def system_state(self) -> tuple[dict[str, list[str]], ...]:
        """``(publishers, subscribers, services)``, each ``{name: [node, ...]}``."""
        state = await self.call("getSystemState")
        return tuple({name: list(nodes) for name, nodes in part} for part in state)

    async def published_topics(self, subgraph: str = "") -> dict[str, str]:
        return {name: typ for name, typ in await self.call("getPublishedTopics", subgraph)}

    async def get_param(self, key: str) -> Any:
        return await self.call("getParam", key)

    async def set_param(self, key: str, value: Any) -> None:
        await self.call("setParam", key, value)

    async def has_param(self, key: str) -> bool:
        return bool(await self.call("hasParam", key))

    async def delete_param(self, key: str) -> None:
        await self.call("deleteParam", key)

    async def param_names(self) -> list[str]:
        return list(await self.call("getParamNames"))
