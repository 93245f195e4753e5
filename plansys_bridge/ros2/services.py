"""ROS 2 services over Cyclone DDS, named and framed exactly as rmw_cyclonedds does.

What a ROS 2 node on Cyclone DDS puts on the wire (ros2/rmw_cyclonedds, branch
rolling, release 3.2.0, ``rmw_cyclonedds_cpp/src/rmw_node.cpp``):

* ``rmw_init_cs``: a client writes requests on ``rq/<service>Request`` and reads
  replies on ``rr/<service>Reply`` (``make_fqtopic(ROS_SERVICE_REQUESTER_PREFIX,
  service_name, "Request", ...)``, prefixes ``rq`` / ``rr``; the service name is fully
  qualified, so ``/problem_expert/add_problem`` gives ``rq/problem_expert/add_problemRequest``).
  The server does the reverse. Reader and writer carry ``clientid=<id>;`` or
  ``serviceid=<id>;`` in their USER_DATA so a server can tell when a client's reply
  reader has been matched (``check_for_response_reader``; a client without one is
  assumed ready).
* The types are the service's request and response messages,
  ``pkg::srv::dds_::Name_Request_`` and ``pkg::srv::dds_::Name_Response_``, each sample
  preceded by a ``cdds_request_header_t { uint64_t guid; int64_t seq; }``
  (``rmw_node.cpp``), which ``serdata.cpp`` injects into the CDR stream before the
  message (``ser >> wrap->header.guid; ser >> wrap->header.seq``). In XCDR1 that is the
  same bytes as a struct whose first members are ``guid`` and ``seq`` followed by the
  message's own members, which is how :func:`wire_types` lays it out.
* ``rmw_send_request``: ``header.guid`` is the instance handle of the client's
  request writer (``info->client.pub->pubiid``) and ``header.seq`` a process-wide
  counter starting at 1 (``++next_request_id``). ``rmw_send_response`` copies the
  request's header into the reply; ``rmw_take_response`` keeps only replies whose
  ``guid`` is the client's own writer handle.

QoS: ``rmw_qos_profile_services_default`` (reliable, volatile, keep last 10).
"""

from __future__ import annotations

import asyncio
import dataclasses
import inspect
import itertools
import logging
import threading
from collections.abc import Awaitable, Callable
from functools import cache
from typing import Any

from cyclonedds.idl import IdlMeta, IdlStruct
from cyclonedds.idl import types as idl

from plansys_bridge.errors import HubError, PlansysBridgeError
from plansys_bridge.interfaces.dds import dds_type, dds_type_name
from plansys_bridge.ros2.node import SERVICES_QOS, Ros2Node

__all__ = [
    "ServiceClient",
    "ServiceServer",
    "fields_of",
    "service_topics",
    "wire_types",
]

log = logging.getLogger(__name__)

Handler = Callable[[Any], Awaitable[Any] | Any]
"""Takes the request (its message fields as attributes) and returns the response message."""

_next_request_id = itertools.count(1)
"""rmw_cyclonedds numbers requests with one counter per process (``next_request_id``)."""
_csid_lock = threading.Lock()
_csid_counter = itertools.count(1)


def service_topics(service: str) -> tuple[str, str]:
    """``/problem_expert/add_problem`` -> (``rq/problem_expert/add_problemRequest``,
    ``rr/problem_expert/add_problemReply``)."""
    name = service.strip("/")
    if not name:
        raise HubError(f"invalid service name {service!r}")
    return f"rq/{name}Request", f"rr/{name}Reply"


def fields_of(msg: Any) -> dict[str, Any]:
    """The message fields of a generated message (or of a wire sample, header left out)."""
    return {f.name: getattr(msg, f.name) for f in dataclasses.fields(msg) if f.name not in _HEADER}


_HEADER = ("guid", "seq")


@cache
def _wrapped(message: str) -> type[Any]:
    """``message``'s DDS type with rmw_cyclonedds' request header in front (same type name)."""
    plain = dds_type(message)
    annotations: dict[str, Any] = {"guid": idl.uint64, "seq": idl.int64}
    defaults: dict[str, Any] = {"guid": 0, "seq": 0}
    for f in dataclasses.fields(plain):
        annotations[f.name] = f.type
        if f.default_factory is not dataclasses.MISSING:
            defaults[f.name] = dataclasses.field(default_factory=f.default_factory)
        else:
            defaults[f.name] = f.default
    class_name = message.rsplit("/", 1)[1] + "_"
    namespace: Any = IdlMeta.__prepare__(class_name, (IdlStruct,), typename=dds_type_name(message))
    namespace["__annotations__"].update(annotations)
    namespace.update(defaults)
    namespace["__module__"] = __name__
    namespace["__doc__"] = f"``{message}`` as a service sample: request header, then the message."
    cls: type[Any] = dataclasses.dataclass(IdlMeta(class_name, (IdlStruct,), namespace))
    return cls


def wire_types(service_type: str) -> tuple[type[Any], type[Any]]:
    """The request and reply sample types of ``pkg/srv/Name`` (header + message)."""
    return _wrapped(f"{service_type}_Request"), _wrapped(f"{service_type}_Response")


def _csid(kind: str, participant_guid: Any) -> bytes:
    """rmw_cyclonedds' ``clientid=``/``serviceid=`` USER_DATA: participant prefix + counter."""
    with _csid_lock:
        number = next(_csid_counter)
    prefix = bytes(getattr(participant_guid, "bytes", b""))[:12]
    data = prefix.ljust(12, b"\0") + number.to_bytes(4, "big")
    return f"{kind}={'.'.join(f'{b:x}' for b in data)};".encode()


class ServiceServer:
    """Serves ``service`` of type ``pkg/srv/Name`` with ``handler`` on a started node.

    The handler gets each request (a sample with the request's fields as attributes)
    on the loop and returns the response message (``dds_type(...Response)`` instance),
    sync or async. Requests are answered concurrently; a handler that raises is logged
    with the service and the client's request id, and that request gets no reply, as
    a ROS 2 service whose callback throws.
    """

    def __init__(self, node: Ros2Node, service: str, service_type: str, handler: Handler) -> None:
        self.node = node
        self.service = "/" + service.strip("/")
        self.service_type = service_type
        self._handler = handler
        self._request_type, self._reply_type = wire_types(service_type)
        request_topic, reply_topic = service_topics(service)
        user_data = _csid("serviceid", node.participant.guid)
        self._writer = node.writer(reply_topic, self._reply_type, SERVICES_QOS, user_data)
        self._reader = node.reader(
            request_topic, self._request_type, SERVICES_QOS, self._on_request, user_data
        )
        self._tasks: set[asyncio.Task[None]] = set()
        self.served = 0

    def _on_request(self, sample: Any) -> None:
        task = self.node.loop.create_task(self._serve(sample))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _serve(self, request: Any) -> None:
        try:
            response = self._handler(request)
            if inspect.isawaitable(response):
                response = await response
            reply = self._reply_type(guid=request.guid, seq=request.seq, **fields_of(response))
            self._writer.write(reply)
            self.served += 1
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            kind = "" if isinstance(exc, PlansysBridgeError) else f"{type(exc).__name__}: "
            log.error(
                "service %s: request %x:%d from a client failed: %s%s",
                self.service,
                request.guid,
                request.seq,
                kind,
                exc,
            )

    async def close(self) -> None:
        for task in list(self._tasks):
            task.cancel()
        if self._tasks:
            await asyncio.gather(*self._tasks, return_exceptions=True)
        self.node.remove(self._reader, self._writer)


class ServiceClient:
    """Calls ``service`` of type ``pkg/srv/Name`` the way an rmw_cyclonedds client does."""

    def __init__(self, node: Ros2Node, service: str, service_type: str) -> None:
        self.node = node
        self.service = "/" + service.strip("/")
        self.service_type = service_type
        self._request_type, self._reply_type = wire_types(service_type)
        self._plain_request = dds_type(f"{service_type}_Request")
        request_topic, reply_topic = service_topics(service)
        user_data = _csid("clientid", node.participant.guid)
        self._writer = node.writer(request_topic, self._request_type, SERVICES_QOS, user_data)
        self._reader = node.reader(
            reply_topic, self._reply_type, SERVICES_QOS, self._on_reply, user_data
        )
        # Python's cyclonedds gives the handle as a signed 64-bit number; the header's is unsigned.
        self.guid: int = self._writer.instance_handle & 0xFFFF_FFFF_FFFF_FFFF
        self._pending: dict[int, asyncio.Future[Any]] = {}

    def request(self, **fields: Any) -> Any:
        """A request message with ``fields`` set (the others zero)."""
        return self._plain_request(**fields)

    def is_ready(self) -> bool:
        """Whether a server's request reader and reply writer are both matched."""
        return (
            self._writer.get_publication_matched_status().current_count > 0
            and self._reader.get_subscription_matched_status().current_count > 0
        )

    async def wait_for_service(self, timeout: float = 10.0) -> None:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while not self.is_ready():
            if loop.time() >= deadline:
                raise HubError(f"service {self.service}: no server after {timeout:g} s")
            await asyncio.sleep(0.01)

    async def call(self, request: Any = None, *, timeout: float = 10.0) -> Any:
        """Send ``request`` (a request message, or None for all zero) and await the reply.

        The reply is a sample with the response fields as attributes (plus ``guid`` and
        ``seq``). HubError after ``timeout`` seconds without a reply.
        """
        if request is None:
            request = self._plain_request()
        seq = next(_next_request_id)
        future: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        self._pending[seq] = future
        try:
            self._writer.write(self._request_type(guid=self.guid, seq=seq, **fields_of(request)))
            return await asyncio.wait_for(future, timeout)
        except TimeoutError:
            raise HubError(
                f"service {self.service}: no reply to request {seq} after {timeout:g} s"
            ) from None
        finally:
            self._pending.pop(seq, None)

    def _on_reply(self, sample: Any) -> None:
        if sample.guid != self.guid:
            return  # another client's reply (rmw_take_response's source filter)
        future = self._pending.get(sample.seq)
        if future is not None and not future.done():
            future.set_result(sample)

    async def close(self) -> None:
        for future in self._pending.values():
            future.cancel()
        self._pending.clear()
        self.node.remove(self._reader, self._writer)
