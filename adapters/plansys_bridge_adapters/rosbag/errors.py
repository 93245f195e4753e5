"""Errors of the ROS-bag adapter.

Every bag error names the bag file, and where known the topic and the bag timestamp
(nanoseconds, as ``ros2 bag info`` prints them) of the last message that was read
correctly, so a broken recording can be located and cut without guessing.
"""

from __future__ import annotations

from pathlib import Path

from plansys_bridge.errors import AdapterError


class BagError(AdapterError):
    """A bag could not be read, or does not hold what the configuration says."""

    def __init__(
        self,
        message: str,
        path: str | Path,
        topic: str | None = None,
        timestamp: int | None = None,
    ) -> None:
        self.path = str(path)
        self.topic = topic
        self.timestamp = timestamp
        self.message = message
        where = self.path
        if topic is not None:
            where += f" topic {topic}"
        if timestamp is not None:
            where += f" at t={timestamp} ns ({timestamp / 1e9:.3f} s)"
        super().__init__(f"{where}: {message}")


class BagTopicError(BagError):
    """The topic is not in the bag (the message lists the topics that are)."""


class BagTypeError(BagError):
    """The topic's message type is not one the reader can turn into a pose, or unknown."""


class BagCorruptError(BagError):
    """The bag is truncated or damaged: index, chunk or message bytes are unreadable."""
