"""The auction clients of one hub's ``actions_hub`` router, by request id.

Each executed action's client used to take a subscription of its own (``client_keys``
through ``Hub.subscribe`` into the router's keyed lists, and out again when it ended):
about a dozen calls per action for what is a dictionary entry. Here the router holds
one table; a client joins with ``by_request.setdefault`` and leaves with
``by_request.pop`` (:class:`~plansys_bridge.hub.auction.ActionClient` does both
itself), and the router looks a RESPONSE/FEEDBACK/FINISH up by its request id.

Delivery order is kept exactly: a client takes its place number (``order``) from the
router's own counter when it joins, as its subscription did, and the router merges it
with the other subscribers by that number. A message without a request id (a foreign
performer's) reaches every client of its action text, as the text key did.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any, Protocol

__all__ = ["ClientTable", "TableClient"]


class TableClient(Protocol):
    """What the router needs of a client in the table."""

    order: int
    closed: bool
    request_id: str
    action: str
    arguments: tuple[str, ...]

    def callback(self, msg: object) -> None: ...


class ClientTable:
    """The clients of one router (see the module's docstring)."""

    __slots__ = ("by_request", "order")

    def __init__(self, order: Iterator[int]) -> None:
        self.by_request: dict[str, Any] = {}
        """Request id -> its client, or the list of clients sharing it, in order."""
        self.order = order
        """The router's counter of subscriptions: a client's place among them."""

    def join(self, client: TableClient) -> None:
        """``client`` starts listening (what a client does inline, for others)."""
        client.order = next(self.order)
        client.closed = False
        held = self.by_request.setdefault(client.request_id, client)
        if held is not client:
            self.shared(held, client)

    def shared(self, held: Any, client: TableClient) -> None:
        """A second client with the request id of ``held`` joined."""
        others = held if held.__class__ is list else [held]
        self.by_request[client.request_id] = [*others, client]

    def leave(self, client: TableClient) -> None:
        """``client`` stops listening (inline in a client: see :meth:`unshare`)."""
        client.closed = True
        held = self.by_request.pop(client.request_id, None)
        if held is not client and held is not None:
            self.unshare(held, client)

    def unshare(self, held: Any, client: TableClient) -> None:
        """``client`` left, and ``held`` (popped) was not it alone: put the rest back."""
        if held.__class__ is not list:
            self.by_request[client.request_id] = held
            return
        left = [c for c in held if c is not client]
        if left:
            self.by_request[client.request_id] = left[0] if len(left) == 1 else left

    def for_request(self, request_id: str) -> Sequence[TableClient]:
        """The clients of ``request_id``, in order."""
        held = self.by_request.get(request_id)
        if held is None:
            return ()
        return held if held.__class__ is list else (held,)

    def everyone(self) -> list[TableClient]:
        """Every client, in order."""
        found: list[TableClient] = []
        for held in self.by_request.values():
            if held.__class__ is list:
                found.extend(held)
            else:
                found.append(held)
        found.sort(key=_order)
        return found

    def for_text(self, action: str, arguments: Sequence[str]) -> list[TableClient]:
        """The clients whose action text is ``action(arguments)``, in order (for a
        message without request id, as ``client_keys``' text key took them)."""
        wanted = tuple(arguments)
        return [c for c in self.everyone() if c.action == action and c.arguments == wanted]

    def close(self) -> None:
        """The router closed: nobody is delivered to any more."""
        for client in self.everyone():
            client.closed = True
        self.by_request.clear()


def _order(client: TableClient) -> int:
    return client.order
