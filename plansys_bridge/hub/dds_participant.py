"""One DDS participant and its reader thread: what the hub transport and ROS 2 nodes share.

Both the hub's :class:`~plansys_bridge.hub.dds.DdsTransport` and a ROS 2 node
(:class:`~plansys_bridge.ros2.node.Ros2Node`) join a Cyclone domain the same way:
the process-wide domain with its configuration (:class:`SharedDomain`), one
participant, a wait set with a guard condition to wake it on close, and one thread
that waits on the set and lets its owner take what arrived. Endpoint QoS is built in
one place too (:func:`endpoint_qos`), the way ROS 2 on Cyclone (rmw_cyclonedds)
sets it: reliable with a 1 s blocking time, keep-last or keep-all, volatile or
transient-local, XCDR1.
"""

from __future__ import annotations

import ctypes
import logging
import threading
from collections.abc import Callable, Iterable
from typing import Any

from cyclonedds.core import DDSException, GuardCondition, Policy, Qos, WaitSet
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.util import duration

from plansys_bridge.errors import HubError

__all__ = ["DdsParticipant", "SharedDomain", "delete_entity", "endpoint_qos"]

log = logging.getLogger(__name__)

_WAIT_NS = duration(seconds=1)


class SharedDomain:
    """One Cyclone domain per id and process, shared by whoever uses it in the process.

    ``dds_create_domain`` refuses a second creation of the same id in one process, so
    transports and nodes of one process (tests, benchmarks, the bridge) share it, with
    a reference count; they must ask for the same configuration.
    """

    _lock = threading.Lock()
    _domains: dict[int, tuple[Domain, str, int]] = {}

    @classmethod
    def acquire(cls, domain_id: int, config: str) -> None:
        with cls._lock:
            entry = cls._domains.get(domain_id)
            if entry is not None:
                domain, existing, count = entry
                if existing != config:
                    raise HubError(
                        f"DDS domain {domain_id} is already open in this process with "
                        "another configuration"
                    )
                cls._domains[domain_id] = (domain, existing, count + 1)
                return
            try:
                domain = Domain(domain_id, config)
            except DDSException as exc:
                raise HubError(f"cannot create DDS domain {domain_id}: {exc}") from exc
            cls._domains[domain_id] = (domain, config, 1)

    @classmethod
    def release(cls, domain_id: int) -> None:
        with cls._lock:
            entry = cls._domains.get(domain_id)
            if entry is None:
                return
            domain, config, count = entry
            if count > 1:
                cls._domains[domain_id] = (domain, config, count - 1)
                return
            del cls._domains[domain_id]
            delete_entity(domain)


def delete_entity(entity: Any) -> None:
    """Delete a DDS entity now instead of whenever the garbage collector gets to it."""
    entity.__del__()


def endpoint_qos(
    *,
    depth: int | None,
    transient_local: bool = False,
    reliable: bool = True,
    user_data: bytes | None = None,
    ignore_local: bool = False,
) -> Qos:
    """A writer's or reader's QoS: keep-last ``depth`` (None: keep all), XCDR1.

    ``ignore_local``: no matching with endpoints of the same participant (the hub
    transport delivers its own messages itself).
    """
    policies: list[Any] = [
        Policy.Reliability.Reliable(duration(seconds=1))
        if reliable
        else Policy.Reliability.BestEffort,
        Policy.History.KeepAll if depth is None else Policy.History.KeepLast(depth),
        Policy.Durability.TransientLocal if transient_local else Policy.Durability.Volatile,
        # ROS 2 on Cyclone DDS (rmw_cyclonedds) speaks XCDR1; say so rather than rely
        # on defaults.
        Policy.DataRepresentation(use_cdrv0_representation=True),
    ]
    if ignore_local:
        policies.append(Policy.IgnoreLocal.Participant)
    if user_data is not None:
        policies.append(Policy.Userdata(user_data))
    return Qos(*policies)


class DdsParticipant:
    """A participant on a shared domain, a wait set, and the thread that waits on it.

    ``open()`` joins the domain (``HubError`` if it cannot); ``start(poll)`` runs
    ``poll()`` on a thread after every wake-up of the wait set (conditions the owner
    ``attach``-es); ``start(poll, keyed=True)`` runs ``poll(keys)`` with the keys the
    owner attached the conditions that fired under, and only when one fired (a
    hub transport has a reader per topic and most wake-ups concern one of them);
    ``close(entities)`` stops the thread and deletes the owner's entities, then its
    own, then leaves the domain.
    """

    def __init__(self, domain_id: int, config: str, what: str) -> None:
        self.domain_id = domain_id
        self.config = config
        self.what = what
        """Names the owner in errors, logs and the thread's name."""
        self.participant: Any = None
        self._waitset: Any = None
        self._guard: Any = None
        self._thread: threading.Thread | None = None
        self._stopping = False
        self._domain_held = False
        self._keyed = 0
        """Conditions attached with a key (see :meth:`attach`)."""

    @property
    def running(self) -> bool:
        return self._thread is not None

    def open(self) -> None:
        SharedDomain.acquire(self.domain_id, self.config)
        self._domain_held = True
        try:
            self.participant = DomainParticipant(self.domain_id)
            self._waitset = WaitSet(self.participant)
            self._guard = GuardCondition(self.participant)
            self._waitset.attach(self._guard)
        except DDSException as exc:
            self.close(())
            raise HubError(f"{self.what}: cannot join DDS domain {self.domain_id}: {exc}") from exc

    def attach(self, condition: Any, key: int | None = None) -> None:
        """Wake the thread when ``condition`` fires; with ``key`` (> 0) a keyed poll is
        told so by that key (the wait set's attach argument, Cyclone's own way)."""
        if key is None:
            self._waitset.attach(condition)
            return
        if key <= 0:
            raise ValueError(f"attach key {key} is not > 0")
        ret = self._waitset._waitset_attach(self._waitset._ref, condition._ref, key)
        if ret < 0:
            raise DDSException(ret, f"{self.what}: attaching a condition to the wait set")
        self._keyed += 1

    def detach(self, condition: Any) -> None:
        self._waitset.detach(condition)

    def start(self, poll: Callable[..., None], *, keyed: bool = False) -> None:
        self._thread = threading.Thread(
            target=self._run, args=(poll, keyed), name=self.what, daemon=True
        )
        self._thread.start()

    def _run(self, poll: Callable[..., None], keyed: bool) -> None:
        try:
            if keyed:
                self._wait_keyed(poll)
                return
            while not self._stopping:
                self._waitset.wait(_WAIT_NS)
                if self._stopping:
                    break
                poll()
        except (RuntimeError, HubError):  # the loop or the owner closed: nobody to deliver to
            return
        except Exception:  # pragma: no cover - a DDS failure must not die silently
            log.exception("%s: DDS reader thread failed", self.what)

    def _wait_keyed(self, poll: Callable[[list[int]], None]) -> None:
        """The thread's loop for ``poll(keys)``: the keys of the conditions that fired."""
        waitset = self._waitset
        wait, ref = waitset._waitset_wait, waitset._ref
        fired = (ctypes.c_void_p * (self._keyed + 1))()  # the guard condition too
        size = len(fired)
        while not self._stopping:
            n = wait(ref, fired, size, _WAIT_NS)
            if n < 0:
                raise DDSException(n, f"{self.what}: waiting on the wait set")
            if self._stopping:
                break
            if n:
                poll([fired[i] or 0 for i in range(min(n, size))])

    def close(self, entities: Iterable[Any]) -> None:
        self._stopping = True
        thread, self._thread = self._thread, None
        if thread is not None:
            self._guard.set(True)
            thread.join(timeout=5.0)
            if thread.is_alive():  # pragma: no cover - the wait set wakes within 1 s
                log.error("%s: DDS reader thread did not stop", self.what)
        for entity in [*entities, self._guard, self._waitset, self.participant]:
            if entity is not None:
                delete_entity(entity)
        self._guard = self._waitset = self.participant = None
        if self._domain_held:
            self._domain_held = False
            SharedDomain.release(self.domain_id)
