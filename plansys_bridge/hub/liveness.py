"""One table of performer heartbeats per hub, read by every auction client.

Each performer sends a heartbeat per action it serves every second. When every
:class:`~plansys_bridge.hub.auction.ActionClient` listened to them itself, a plan with
many actions in flight and many performers spent most of its time handing heartbeats
to clients that ignore them. The table takes each heartbeat once and keeps what the
clients ask for:

* when a node was last heard RUNNING (a confirmed performer's liveness: the client
  reads it when its deadline comes instead of being told on every heartbeat);
* a performer going from RUNNING to READY for an action: the clients waiting for a
  performer of that action (``watch``) are told at once, so they ask again without
  waiting for their next periodic REQUEST.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Sequence

from plansys_bridge.hub.messages import ActionPerformerStatus, PerformerState

__all__ = ["LivenessTable", "could_serve"]

FreedCallback = Callable[[ActionPerformerStatus], None]

_RUNNING = PerformerState.RUNNING
_READY = PerformerState.READY


class LivenessTable:
    """Heartbeats of ``performers_status``, one entry per node and action."""

    def __init__(self) -> None:
        self._states: dict[tuple[str, str], PerformerState] = {}
        self._last_running: dict[str, float] = {}
        self._watchers: dict[str, list[FreedCallback]] = {}
        self.heartbeats = 0
        """Heartbeats taken so far, for statistics."""

    def on_status(self, msg: object) -> None:
        """The ``performers_status`` subscriber."""
        self.on_statuses((msg,))

    def on_statuses(self, messages: Sequence[object]) -> None:
        """:meth:`on_status` for each of ``messages`` in order: a performer publishes a
        status per action it serves on every change of state, together, and the
        in-process transport hands them over in one call. They were sent at one moment,
        so the loop's time is read once for them."""
        states = self._states
        now: float | None = None
        for msg in messages:
            # The class compared first (isinstance is a call) and the states read from
            # module constants.
            if msg.__class__ is not ActionPerformerStatus and not isinstance(
                msg, ActionPerformerStatus
            ):
                continue
            self.heartbeats += 1
            state = msg.state
            key = (msg.node_name, msg.action)
            previous = states.get(key)
            states[key] = state
            if state is _RUNNING:
                if now is None:
                    now = asyncio.get_running_loop().time()
                self._last_running[msg.node_name] = now
            elif state is _READY and previous is _RUNNING and msg.action in self._watchers:
                for callback in list(self._watchers[msg.action]):
                    callback(msg)

    def last_running(self, node_name: str) -> float | None:
        """Loop time of the last RUNNING heartbeat of ``node_name`` (None: never heard)."""
        return self._last_running.get(node_name)

    def state(self, node_name: str, action: str) -> PerformerState | None:
        """The last state ``node_name`` reported for ``action``."""
        return self._states.get((node_name, action))

    def watch(self, action: str, callback: FreedCallback) -> Callable[[], None]:
        """Call ``callback(status)`` when a performer of ``action`` goes from RUNNING to
        READY; returns the function that stops watching."""
        self._watchers[action] = [*self._watchers.get(action, ()), callback]

        def unwatch() -> None:
            watchers = self._watchers.get(action, ())
            if len(watchers) == 1 and watchers[0] is callback:  # the usual: alone
                del self._watchers[action]
                return
            remaining = [c for c in watchers if c is not callback]
            if remaining:
                self._watchers[action] = remaining
            else:
                self._watchers.pop(action, None)

        return unwatch


def could_serve(msg: ActionPerformerStatus, action: str, arguments: tuple[str, ...]) -> bool:
    """Does this heartbeat come from a performer whose action and specialised
    arguments (empty string = any) fit a request for ``action`` with ``arguments``?"""
    if msg.action != action or len(msg.specialized_arguments) > len(arguments):
        return False
    return all(
        want in ("", have) for want, have in zip(msg.specialized_arguments, arguments, strict=False)
    )
