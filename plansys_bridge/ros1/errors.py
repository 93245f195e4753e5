"""Errors of the ROS 1 client; each names the master URL, topic or peer involved."""

from __future__ import annotations

from plansys_bridge.errors import AdapterError

__all__ = ["MasterError", "MasterUnreachable", "ProtocolError", "Ros1Error"]


class Ros1Error(AdapterError):
    """Something on the ROS 1 side failed: a type, the master, a connection."""


class MasterError(Ros1Error):
    """The master answered a call with a failure code (the text says which call)."""


class MasterUnreachable(MasterError):
    """No master answers at the configured URI (not started, restarted, wrong port)."""


class ProtocolError(Ros1Error):
    """A peer sent a malformed TCPROS connection header or frame."""
