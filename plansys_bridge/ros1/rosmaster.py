"""A ROS 1 master in plain Python, for demos and tests on machines without ROS.

``python -m plansys_bridge.ros1.rosmaster [--port 11311] [--bind 127.0.0.1]`` serves
the parts of the master API nodes use: registering and unregistering publishers and
subscribers (subscribers are told about publishers with ``publisherUpdate``, as
rosmaster does), ``lookupNode``, ``getSystemState``, ``getPublishedTopics``,
``getTopicTypes``, ``getUri``, ``getPid`` and the parameter server (``getParam``,
``setParam``, ``hasParam``, ``deleteParam``, ``getParamNames``, ``searchParam``).
Services are registered and looked up (nodes serve them). rospy and roscpp
nodes work against it as against roscore; the interop tests use Debian's roscore.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import threading
import xmlrpc.client
from collections import defaultdict
from typing import Any

from plansys_bridge.ros1.slave import XmlRpcServer

__all__ = ["Master", "main"]

log = logging.getLogger(__name__)


_API = (
    "getPid",
    "getUri",
    "registerPublisher",
    "unregisterPublisher",
    "registerSubscriber",
    "unregisterSubscriber",
    "lookupNode",
    "lookupService",
    "registerService",
    "unregisterService",
    "getSystemState",
    "getPublishedTopics",
    "getTopicTypes",
    "getParam",
    "setParam",
    "hasParam",
    "deleteParam",
    "getParamNames",
    "searchParam",
    "subscribeParam",
    "unsubscribeParam",
)


def _ok(value: Any, message: str = "") -> list[Any]:
    return [1, message, value]


class Master:
    """``with Master(port=0) as m:`` a master at ``m.uri`` until the block ends."""

    def __init__(self, port: int = 11311, bind: str = "127.0.0.1") -> None:
        self._server = XmlRpcServer((bind, port))
        self.port: int = self._server.server_address[1]
        host = "127.0.0.1" if bind in ("127.0.0.1", "0.0.0.0") else bind
        self.uri = f"http://{host}:{self.port}/"
        self._lock = threading.RLock()
        self.nodes: dict[str, str] = {}
        """Node name -> its XML-RPC URI."""
        self.publishers: dict[str, list[str]] = defaultdict(list)
        self.subscribers: dict[str, list[str]] = defaultdict(list)
        self.types: dict[str, str] = {}
        self.params: dict[str, Any] = {}
        self.services: dict[str, tuple[str, str]] = {}
        """Service name -> (provider node, its rosrpc URI); served by the nodes, not here."""
        for name in _API:
            self._server.register_function(getattr(self, name), name)
        self._thread: threading.Thread | None = None

    def start(self) -> Master:
        self._thread = threading.Thread(
            target=self._server.serve_forever,
            kwargs={"poll_interval": 0.1},
            name="ros1-master",
            daemon=True,
        )
        self._thread.start()
        return self

    def close(self) -> None:
        if self._thread is not None:
            self._server.shutdown()
            self._thread.join(timeout=5)
            self._thread = None
        self._server.server_close()

    def __enter__(self) -> Master:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------ helpers

    def _node(self, caller_id: str, caller_api: str) -> None:
        self.nodes[caller_id] = caller_api

    def _notify(self, topic: str) -> None:
        """Tell every subscriber of ``topic`` the current publisher list (in a thread)."""
        with self._lock:
            uris = [self.nodes[n] for n in self.publishers.get(topic, []) if n in self.nodes]
            targets = [self.nodes[n] for n in self.subscribers.get(topic, []) if n in self.nodes]

        def send() -> None:
            for target in targets:
                with contextlib.suppress(Exception):
                    xmlrpc.client.ServerProxy(target).publisherUpdate("/master", topic, uris)

        threading.Thread(target=send, name="ros1-master-update", daemon=True).start()

    def _pub_uris(self, topic: str) -> list[str]:
        return [self.nodes[n] for n in self.publishers.get(topic, []) if n in self.nodes]

    # ------------------------------------------------------------ the master API

    def getPid(self, caller_id: str) -> list[Any]:
        return _ok(os.getpid())

    def getUri(self, caller_id: str) -> list[Any]:
        return _ok(self.uri)

    def registerPublisher(
        self, caller_id: str, topic: str, topic_type: str, caller_api: str
    ) -> list[Any]:
        with self._lock:
            self._node(caller_id, caller_api)
            if caller_id not in self.publishers[topic]:
                self.publishers[topic].append(caller_id)
            self.types.setdefault(topic, topic_type)
            subs = [self.nodes[n] for n in self.subscribers.get(topic, []) if n in self.nodes]
        self._notify(topic)
        return _ok(subs, f"registered {caller_id} as publisher of {topic}")

    def unregisterPublisher(self, caller_id: str, topic: str, caller_api: str) -> list[Any]:
        with self._lock:
            found = caller_id in self.publishers.get(topic, [])
            if found:
                self.publishers[topic].remove(caller_id)
        if found:
            self._notify(topic)
        return _ok(1 if found else 0)

    def registerSubscriber(
        self, caller_id: str, topic: str, topic_type: str, caller_api: str
    ) -> list[Any]:
        with self._lock:
            self._node(caller_id, caller_api)
            if caller_id not in self.subscribers[topic]:
                self.subscribers[topic].append(caller_id)
            if topic_type != "*":
                self.types.setdefault(topic, topic_type)
            return _ok(self._pub_uris(topic), f"subscribed {caller_id} to {topic}")

    def unregisterSubscriber(self, caller_id: str, topic: str, caller_api: str) -> list[Any]:
        with self._lock:
            found = caller_id in self.subscribers.get(topic, [])
            if found:
                self.subscribers[topic].remove(caller_id)
        return _ok(1 if found else 0)

    def lookupNode(self, caller_id: str, node_name: str) -> list[Any]:
        with self._lock:
            uri = self.nodes.get(node_name)
        return _ok(uri) if uri else [-1, f"unknown node [{node_name}]", ""]

    def registerService(
        self, caller_id: str, service: str, service_api: str, caller_api: str
    ) -> list[Any]:
        with self._lock:
            self._node(caller_id, caller_api)
            self.services[service] = (caller_id, service_api)
        return _ok(1, f"registered {caller_id} as provider of {service}")

    def unregisterService(self, caller_id: str, service: str, service_api: str) -> list[Any]:
        with self._lock:
            found = self.services.get(service, ("", ""))[1] == service_api
            if found:
                del self.services[service]
        return _ok(1 if found else 0)

    def lookupService(self, caller_id: str, service: str) -> list[Any]:
        with self._lock:
            entry = self.services.get(service)
        return _ok(entry[1]) if entry else [-1, f"no provider for {service}", ""]

    def getSystemState(self, caller_id: str) -> list[Any]:
        with self._lock:
            pubs = [[t, list(n)] for t, n in self.publishers.items() if n]
            subs = [[t, list(n)] for t, n in self.subscribers.items() if n]
            srvs = [[name, [node]] for name, (node, _api) in self.services.items()]
        return _ok([pubs, subs, srvs])

    def getPublishedTopics(self, caller_id: str, subgraph: str) -> list[Any]:
        with self._lock:
            return _ok([[t, self.types.get(t, "*")] for t, n in self.publishers.items() if n])

    def getTopicTypes(self, caller_id: str) -> list[Any]:
        with self._lock:
            return _ok([[t, typ] for t, typ in self.types.items()])

    # ------------------------------------------------------------ parameters

    @staticmethod
    def _key(key: str) -> str:
        return "/" + key.strip("/")

    def _get(self, key: str) -> Any:
        key = self._key(key)
        if key in self.params:
            return self.params[key]
        prefix = key.rstrip("/") + "/"
        tree: dict[str, Any] = {}
        for name, value in self.params.items():
            if name.startswith(prefix):
                node = tree
                *parents, leaf = name[len(prefix) :].split("/")
                for part in parents:
                    node = node.setdefault(part, {})
                node[leaf] = value
        if not tree:
            raise KeyError(key)
        return tree

    def getParam(self, caller_id: str, key: str) -> list[Any]:
        with self._lock:
            try:
                return _ok(self._get(key))
            except KeyError:
                return [-1, f"Parameter [{self._key(key)}] is not set", 0]

    def setParam(self, caller_id: str, key: str, value: Any) -> list[Any]:
        with self._lock:
            key = self._key(key)
            for name in [n for n in self.params if n.startswith(key.rstrip("/") + "/")]:
                del self.params[name]
            if isinstance(value, dict):
                for sub, item in value.items():
                    self.setParam(caller_id, f"{key}/{sub}", item)
            else:
                self.params[key] = value
        return _ok(0)

    def hasParam(self, caller_id: str, key: str) -> list[Any]:
        with self._lock:
            try:
                self._get(key)
            except KeyError:
                return _ok(False)
            return _ok(True)

    def deleteParam(self, caller_id: str, key: str) -> list[Any]:
        with self._lock:
            key = self._key(key)
            names = [n for n in self.params if n == key or n.startswith(key.rstrip("/") + "/")]
            for name in names:
                del self.params[name]
        return _ok(0) if names else [-1, f"parameter [{key}] is not set", 0]

    def getParamNames(self, caller_id: str) -> list[Any]:
        with self._lock:
            return _ok(sorted(self.params))

    def searchParam(self, caller_id: str, key: str) -> list[Any]:
        with self._lock:
            name = self._key(key)
            return _ok(name) if name in self.params else [-1, f"cannot find {key}", 0]

    def subscribeParam(self, caller_id: str, caller_api: str, key: str) -> list[Any]:
        return self.getParam(caller_id, key)

    def unsubscribeParam(self, caller_id: str, caller_api: str, key: str) -> list[Any]:
        return _ok(1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m plansys_bridge.ros1.rosmaster")
    parser.add_argument("--port", type=int, default=11311)
    parser.add_argument("--bind", default="127.0.0.1", help="address to listen on")
    args = parser.parse_args(argv)
    with Master(args.port, args.bind) as master:
        print(f"ROS master at {master.uri}", flush=True)
        with contextlib.suppress(KeyboardInterrupt):
            threading.Event().wait()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
