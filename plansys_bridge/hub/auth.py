"""Fleet authentication: the hub trusts only messages signed with the fleet's key.

Without it any process on the DDS domain can bid, win an auction and report FINISH.
With a key (``auth: {key_file: ...}`` in the mission file), :class:`AuthTransport`
wraps the hub's transport in every process of the fleet:

* every auction message (``actions_hub``: REQUEST, RESPONSE, CONFIRM, REJECT,
  FEEDBACK, FINISH, CANCEL) and every performer heartbeat (``performers_status``) is
  sent only as a :class:`SignedMessage` on ``plansys_bridge/signed``: the message as
  canonical JSON, the sender's id (random per process run), a counter, a timestamp
  and an HMAC-SHA256 over all of them with the key;
* on receipt the HMAC is checked (a forged or altered message is refused), the
  counter must be above the last one accepted from that sender (a replayed message
  is refused) and the timestamp within ``window`` seconds of the receiver's clock (an
  old message replayed after a restart is refused);
* plain, unsigned messages on those topics (a stock PlanSys2 performer, anyone on
  the domain) are refused. Each refusal is logged once per sender and reason.

Other topics (knowledge, plans, execution info, DOT graph) pass unchanged. This is
authentication, not secrecy: anyone on the network can read the traffic. Encryption
and access control belong to DDS Security (see the README).
"""

from __future__ import annotations

import asyncio
import dataclasses
import hashlib
import hmac
import itertools
import json
import logging
import time
import uuid
from collections.abc import Callable
from enum import IntEnum
from pathlib import Path
from typing import Any

from plansys_bridge.errors import ConfigError, HubError
from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionPerformerStatus,
    ExecutionType,
    PerformerState,
    Topics,
)
from plansys_bridge.hub.transport import Subscription, Transport, report_subscriber_error

__all__ = [
    "SIGNED_TOPIC",
    "AuthTransport",
    "SignedMessage",
    "Signer",
    "Verifier",
    "load_key",
]

log = logging.getLogger(__name__)

SIGNED_TOPIC = Topics.SIGNED
"""The hub topic signed messages travel on (``rt/plansys_bridge/signed`` on DDS)."""

PROTECTED: dict[str, type] = {
    Topics.ACTIONS_HUB: ActionExecution,
    Topics.PERFORMERS_STATUS: ActionPerformerStatus,
}
"""The topics whose messages must be signed, with the message type each carries."""

_ENUMS: dict[str, type[IntEnum]] = {"type": ExecutionType, "state": PerformerState}
MIN_KEY_BYTES = 16


@dataclasses.dataclass(frozen=True)
class SignedMessage:
    """One hub message with its sender, counter, timestamp and HMAC."""

    topic: str
    sender: str
    counter: int
    stamp: float
    payload: str
    """The message as canonical JSON (:func:`canonical`)."""
    mac: bytes


def load_key(path: str | Path, key: str = "auth.key_file") -> bytes:
    """The fleet key: the file's bytes without surrounding whitespace (16 bytes or more)."""
    try:
        data = Path(path).read_bytes().strip()
    except OSError as exc:
        raise ConfigError(f"cannot read the key file {path}: {exc.strerror}", key=key) from exc
    if len(data) < MIN_KEY_BYTES:
        raise ConfigError(
            f"the key in {path} is {len(data)} bytes; use at least {MIN_KEY_BYTES} "
            "(e.g. head -c 32 /dev/urandom | base64 > fleet.key)",
            key=key,
        )
    return data


def canonical(msg: object) -> str:
    """A message as JSON with sorted keys: the same text on every machine."""
    fields = {f.name: getattr(msg, f.name) for f in dataclasses.fields(msg)}  # type: ignore[arg-type]
    return json.dumps(
        {k: list(v) if isinstance(v, tuple) else v for k, v in fields.items()},
        sort_keys=True,
        separators=(",", ":"),
    )


def _message(topic: str, payload: str) -> object:
    cls = PROTECTED[topic]
    data = json.loads(payload)
    if not isinstance(data, dict):
        raise ValueError("payload is not an object")
    for name, enum in _ENUMS.items():
        if name in data:
            data[name] = enum(data[name])
    for name, value in data.items():
        if isinstance(value, list):
            data[name] = tuple(value)
    return cls(**data)


def _mac(key: bytes, topic: str, sender: str, counter: int, stamp: float, payload: str) -> bytes:
    text = json.dumps([topic, sender, counter, repr(stamp), payload], separators=(",", ":"))
    return hmac.new(key, text.encode(), hashlib.sha256).digest()


class Signer:
    """Signs this process's messages: one sender id, one rising counter."""

    def __init__(self, key: bytes, *, now: Callable[[], float] = time.time) -> None:
        self._key = key
        self._now = now
        self.sender = uuid.uuid4().hex
        self._counter = itertools.count(1)

    def sign(self, topic: str, msg: object) -> SignedMessage:
        payload = canonical(msg)
        counter, stamp = next(self._counter), self._now()
        mac = _mac(self._key, topic, self.sender, counter, stamp, payload)
        return SignedMessage(topic, self.sender, counter, stamp, payload, mac)


class Refused(HubError):
    """A signed message that fails verification; the text says why."""


class Verifier:
    """Checks signed messages: HMAC, then counter, then timestamp (see module docs)."""

    def __init__(
        self, key: bytes, *, window: float = 30.0, now: Callable[[], float] = time.time
    ) -> None:
        self._key = key
        self.window = window
        self._now = now
        self._last: dict[str, int] = {}

    def verify(self, signed: SignedMessage) -> object:
        """The message, or Refused saying why (forged, replayed, stale, malformed)."""
        expected = _mac(
            self._key, signed.topic, signed.sender, signed.counter, signed.stamp, signed.payload
        )
        if not hmac.compare_digest(expected, bytes(signed.mac)):
            raise Refused("bad signature (forged, altered, or signed with another key)")
        if signed.counter <= self._last.get(signed.sender, 0):
            raise Refused(f"replayed (counter {signed.counter} already seen)")
        if abs(self._now() - signed.stamp) > self.window:
            raise Refused(f"stale (timestamp {self._now() - signed.stamp:.0f} s off)")
        if signed.topic not in PROTECTED:
            raise Refused(f"signed for topic {signed.topic!r}, which needs no signature")
        try:
            msg = _message(signed.topic, signed.payload)
        except (ValueError, TypeError, KeyError) as exc:
            raise Refused(f"malformed payload: {exc}") from exc
        self._last[signed.sender] = signed.counter
        return msg


class _Fanout:
    __slots__ = ("callbacks", "plain")

    def __init__(self) -> None:
        self.callbacks: list[Callable[[object], None]] = []
        self.plain: Subscription | None = None


class _AuthSubscription:
    def __init__(self, transport: AuthTransport, topic: str, callback: Callable[[object], None]):
        self._transport, self._topic, self._callback = transport, topic, callback

    def close(self) -> None:
        self._transport._unsubscribe(self._topic, self._callback)


class AuthTransport:
    """A transport whose auction and heartbeat messages are signed and verified.

    Wraps any :class:`~plansys_bridge.hub.transport.Transport` (in-process, DDS);
    other attributes (``domain_id``, ``wait_for_peers``...) are the inner transport's.
    """

    def __init__(self, inner: Transport, key: bytes, *, window: float = 30.0) -> None:
        self.inner = inner
        self.signer = Signer(key)
        self.verifier = Verifier(key, window=window)
        self._topics: dict[str, _Fanout] = {}
        self._signed_sub: Subscription | None = None
        self._warned: set[tuple[str, str]] = set()
        self.refused = 0
        """Messages refused so far (unsigned, forged, replayed, stale)."""

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)

    def has_audience(self, topic: str) -> bool:
        """Always yes: a signed topic's messages travel on the inner transport under
        another name, so the inner transport's answer would not be about ``topic``."""
        return True

    async def start(self) -> None:
        await self.inner.start()

    async def close(self) -> None:
        await self.inner.close()

    def publish(self, topic: str, msg: object) -> None:
        cls = PROTECTED.get(topic)
        if cls is not None and isinstance(msg, cls):
            self.inner.publish(SIGNED_TOPIC, self.signer.sign(topic, msg))
        else:
            self.inner.publish(topic, msg)

    def subscribe(self, topic: str, callback: Callable[[object], None]) -> Subscription:
        if topic not in PROTECTED:
            return self.inner.subscribe(topic, callback)
        fanout = self._topics.get(topic)
        if fanout is None:
            fanout = self._topics[topic] = _Fanout()
            fanout.plain = self.inner.subscribe(topic, lambda m: self._refuse_plain(topic, m))
        if self._signed_sub is None:
            self._signed_sub = self.inner.subscribe(SIGNED_TOPIC, self._on_signed)
        fanout.callbacks.append(callback)
        return _AuthSubscription(self, topic, callback)

    def _unsubscribe(self, topic: str, callback: Callable[[object], None]) -> None:
        fanout = self._topics.get(topic)
        if fanout is not None and callback in fanout.callbacks:
            fanout.callbacks.remove(callback)

    def _on_signed(self, signed: object) -> None:
        if not isinstance(signed, SignedMessage):
            return
        try:
            msg = self.verifier.verify(signed)
        except Refused as exc:
            self._refuse(f"signer {signed.sender[:8]}", str(exc), signed.topic)
            return
        fanout = self._topics.get(signed.topic)
        for callback in list(fanout.callbacks if fanout else ()):
            try:
                callback(msg)
            except Exception as exc:  # one broken subscriber must not starve the others
                report_subscriber_error(asyncio.get_running_loop(), signed.topic, exc)

    def _refuse_plain(self, topic: str, msg: object) -> None:
        sender = getattr(msg, "node_id", "") or getattr(msg, "node_name", "") or "?"
        self._refuse(f"{type(msg).__name__} from {sender!r}", "unsigned", topic)

    def _refuse(self, who: str, why: str, topic: str) -> None:
        self.refused += 1
        reason = why.split(" (")[0]
        if (who, reason) not in self._warned:
            self._warned.add((who, reason))
            log.warning("%s: refused %s: %s (this hub requires signed messages)", topic, who, why)
