"""What a performer hears on ``actions_hub``, and which of its methods hears it.

Routed (:mod:`plansys_bridge.hub.routing`): the REQUESTs for the actions it serves
(only those matching its specialised arguments, unless it decides what it serves
itself), and the CONFIRM/REJECT/CANCEL messages naming it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

from plansys_bridge.hub.messages import Topics
from plansys_bridge.hub.routing import performer_keys
from plansys_bridge.hub.transport import Subscription

if TYPE_CHECKING:
    from plansys_bridge.hub.hub import Hub

__all__ = ["listen"]

Callback = Callable[[object], None]


def listen(
    hub: Hub,
    node_name: str,
    actions: Mapping[str, Sequence[str]],
    *,
    by_arguments: bool,
    on_message: Callback,
    on_request: Callback | None = None,
) -> list[Subscription]:
    """Subscribe a performer: every message it hears goes to ``on_message``, or, with
    ``on_request``, the REQUESTs go there directly (a call less for every bidder of
    every auction) and the messages naming the node to ``on_message``. A routed
    message goes under one key, so each still arrives once.

    ``by_arguments``: route a REQUEST by the specialised arguments too (False: every
    REQUEST of the actions, for a performer that decides what it serves)."""
    keys = performer_keys(node_name, dict(actions) if by_arguments else list(actions))
    if on_request is None:
        return [hub.subscribe(Topics.ACTIONS_HUB, on_message, keys=keys)]
    node_key = ("node", node_name)
    return [
        hub.subscribe(Topics.ACTIONS_HUB, on_request, keys=[k for k in keys if k != node_key]),
        hub.subscribe(Topics.ACTIONS_HUB, on_message, keys=[node_key]),
    ]
