"""What the planner side knows about the base, from the frames it hears.

:class:`BaseMonitor` is the bus client's listener. It keeps the latest pose, twist
and status with the (mission) time each arrived, notices when the heartbeat's alive
counter last moved, and counts error frames and driver errors. :meth:`problem`
turns all that into the one sentence that ends an action: a bus error, a fault bit,
the e-stop, a lost heartbeat or stale odometry.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

import can

from plansys_bridge.clock import Clock

from .dbc import (
    BaseState,
    BaseStatus,
    EStopCommand,
    Frame,
    OdomPose,
    OdomTwist,
    VelocityCommand,
)

_LOG = logging.getLogger(__name__)

# SocketCAN error classes (linux/can/error.h), carried in an error frame's ID.
_ERROR_CLASSES = (
    (0x001, "TX timeout"),
    (0x002, "lost arbitration"),
    (0x004, "controller problem"),
    (0x008, "protocol violation"),
    (0x010, "transceiver problem"),
    (0x020, "no ACK on transmission"),
    (0x040, "bus-off"),
    (0x080, "bus error"),
    (0x100, "controller restarted"),
)

_CAN_ERR_CRTL = 0x004
# Controller status in data[1] of a "controller problem" frame (linux/can/error.h):
# which one it is matters (warning levels and error-passive versus back to active).
_CONTROLLER_STATES = (
    (0x01, "RX overflow"),
    (0x02, "TX overflow"),
    (0x04, "RX error warning"),
    (0x08, "TX error warning"),
    (0x10, "RX error-passive"),
    (0x20, "TX error-passive"),
    (0x40, "back to error-active"),
)


def describe_error_frame(msg: can.Message) -> str:
    """Name the error classes of a CAN error frame (``bus-off, no ACK``).

    A controller problem also says which (``controller problem (RX error-passive)``).
    """
    names = []
    for bit, name in _ERROR_CLASSES:
        if msg.arbitration_id & bit:
            if bit == _CAN_ERR_CRTL and len(msg.data) > 1:
                states = [text for flag, text in _CONTROLLER_STATES if msg.data[1] & flag]
                if states:
                    name = f"{name} ({', '.join(states)})"
            names.append(name)
    return ", ".join(names) if names else f"error class 0x{msg.arbitration_id:X}"


@dataclass(frozen=True)
class Problem:
    """Why the base cannot be driven; ``transient`` problems may clear while a link comes up."""

    message: str
    transient: bool = False


@dataclass(frozen=True)
class Mark:
    """Error counts at a moment (an action's start): later problems are counted from here."""

    error_frames: int
    bus_errors: int


class BaseMonitor:
    """Listener for :class:`~.bus.CanBusClient` that tracks the base's state."""

    def __init__(self, clock: Clock, where: str) -> None:
        self.clock = clock
        self.where = where
        self.pose: OdomPose | None = None
        self.pose_time: float | None = None
        self.twist: OdomTwist | None = None
        self.twist_time: float | None = None
        self.status: BaseStatus | None = None
        self.status_time: float | None = None
        self.heartbeat_time: float | None = None
        """When the status alive counter last changed (a frozen counter is a hung base)."""
        self.error_frames = 0
        self.last_error_frame: can.Message | None = None
        self.bus_errors = 0
        self.last_bus_error: Exception | None = None
        self.foreign_commands = 0
        self.status_callbacks: list[Callable[[BaseStatus], None]] = []
        self.pose_callbacks: list[Callable[[OdomPose], None]] = []

    # -- FrameListener ------------------------------------------------------------

    def on_frame(self, frame: Frame) -> None:
        now = self.clock.now()
        if isinstance(frame, OdomPose):
            self.pose, self.pose_time = frame, now
            for pose_callback in self.pose_callbacks:
                pose_callback(frame)
        elif isinstance(frame, OdomTwist):
            self.twist, self.twist_time = frame, now
        elif isinstance(frame, BaseStatus):
            if self.status is None or frame.counter != self.status.counter:
                self.heartbeat_time = now
            self.status, self.status_time = frame, now
            for callback in self.status_callbacks:
                callback(frame)
        elif isinstance(frame, VelocityCommand | EStopCommand):
            # Another node commands this base: two masters on one bus is a setup error.
            self.foreign_commands += 1
            count = self.foreign_commands
            if count & (count - 1) == 0:
                _LOG.warning(
                    "%s: another sender commands the base (%s); %d such frames so far",
                    self.where,
                    frame,
                    count,
                )

    def on_error_frame(self, msg: can.Message) -> None:
        self.error_frames += 1
        self.last_error_frame = msg
        _LOG.warning("%s: CAN error frame: %s", self.where, describe_error_frame(msg))

    def on_bus_error(self, exc: Exception) -> None:
        self.bus_errors += 1
        self.last_bus_error = exc

    # -- queries --------------------------------------------------------------------

    def mark(self) -> Mark:
        return Mark(self.error_frames, self.bus_errors)

    def is_stopped(self, linear_eps: float, angular_eps: float, since: float) -> bool:
        """Has a twist received after ``since`` shown the base at standstill?"""
        return (
            self.twist is not None
            and self.twist_time is not None
            and self.twist_time > since
            and abs(self.twist.linear) <= linear_eps
            and abs(self.twist.angular) <= angular_eps
        )

    def problem(
        self,
        now: float,
        mark: Mark,
        *,
        heartbeat_timeout: float,
        odometry_timeout: float,
        error_frame_limit: int,
        ignore_watchdog: bool = False,
    ) -> Problem | None:
        """Why the base cannot be driven now, or None when all is well.

        ``ignore_watchdog``: a latched watchdog bit is no problem (while idle: it only
        says the base stopped when commands stopped; the next command clears it).
        """
        if self.bus_errors > mark.bus_errors:
            return Problem(f"CAN bus error on {self.where}: {self.last_bus_error}")
        new_error_frames = self.error_frames - mark.error_frames
        if error_frame_limit > 0 and new_error_frames >= error_frame_limit:
            assert self.last_error_frame is not None
            return Problem(
                f"CAN bus error on {self.where}: {new_error_frames} error frame(s), last: "
                f"{describe_error_frame(self.last_error_frame)}"
            )
        if _stale(now, self.heartbeat_time, heartbeat_timeout):
            age = (
                "never received"
                if self.heartbeat_time is None
                else (f"none with a new counter for {now - self.heartbeat_time:.2f} s")
            )
            return Problem(
                f"base heartbeat lost on {self.where}: BASE_Status {age} "
                f"(timeout {heartbeat_timeout:g} s)",
                transient=True,
            )
        status = self.status
        assert status is not None
        faults = status.faults
        if faults.motor or faults.overcurrent:
            names = [n for n in faults.names() if n in ("motor fault", "overcurrent")]
            return Problem(f"base fault: {', '.join(names)} (state {status.state.name})")
        if faults.estop or status.state is BaseState.ESTOP:
            return Problem("base e-stop active")
        if faults.watchdog and not ignore_watchdog:
            return Problem(
                "base command watchdog tripped: velocity commands stopped reaching the base",
                transient=True,
            )
        if status.state is BaseState.FAULT:
            return Problem("base reports state FAULT")
        if _stale(now, self.pose_time, odometry_timeout):
            heard = max(t for t in (self.pose_time, self.status_time, -math.inf) if t is not None)
            if now - heard > odometry_timeout:
                return Problem(
                    f"base silent on {self.where}: no odometry and no status for "
                    f"{now - heard:.2f} s (odometry timeout {odometry_timeout:g} s)",
                    transient=True,
                )
            age = (
                "never received"
                if self.pose_time is None
                else (f"last {now - self.pose_time:.2f} s ago")
            )
            return Problem(
                f"odometry lost on {self.where}: BASE_OdomPose {age} "
                f"(timeout {odometry_timeout:g} s)",
                transient=True,
            )
        return None


def _stale(now: float, last: float | None, timeout: float) -> bool:
    return last is None or now - last > timeout
