"""Errors of the MAVLink adapter; every one names the link URL it happened on."""

from __future__ import annotations

from plansys_bridge.errors import AdapterError


class MavlinkError(AdapterError):
    """Something went wrong on one MAVLink link; ``url`` names the link."""

    def __init__(self, url: str, message: str) -> None:
        self.url = url
        self.reason = message
        super().__init__(f"{url}: {message}")


class LinkError(MavlinkError):
    """The link could not be opened, was closed, or the heartbeat stopped."""


class CommandRefused(MavlinkError):
    """The vehicle answered a command with a COMMAND_ACK other than ACCEPTED.

    ``attempts`` > 1: the answer is to a repeat sent because no ACK came in time, so
    the first sending may have been obeyed (its ACK lost) and caused the refusal.
    """

    def __init__(
        self, url: str, command: str, result: str, detail: str = "", attempts: int = 1
    ) -> None:
        self.command = command
        self.result = result
        self.attempts = attempts
        text = f"{command} refused ({result})"
        if detail:
            text = f"{text}: {detail}"
        super().__init__(url, text)


class CommandTimeout(MavlinkError):
    """A command got no COMMAND_ACK after every retry."""


class WaitTimeout(MavlinkError):
    """The vehicle did not reach a state (EKF ready, altitude, mode) in time."""


class VehicleFault(MavlinkError):
    """The vehicle did something the action did not ask for.

    A failsafe, a mode changed by someone else, or a STATUSTEXT error.
    ``took_over``: the vehicle (a failsafe) or someone else (a pilot, another ground
    station) has taken control, so the adapter must not switch modes after it.
    """

    def __init__(self, url: str, message: str, *, took_over: bool = False) -> None:
        self.took_over = took_over
        super().__init__(url, message)
