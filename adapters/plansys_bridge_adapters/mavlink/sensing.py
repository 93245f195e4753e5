"""MAVLink messages as a sensing source:
``{from: mavlink, performer: copter1, message: BATTERY_STATUS, when: "battery_remaining < 25"}``.

Message and field names are those of pymavlink's ArduPilot dialect (the one the
adapter speaks), checked when the mission loads. Array fields are read by index
(``voltages[0]``) and a HEARTBEAT also carries ``mode``, the flight mode's name as
ArduPilot's ground stations show it (``GUIDED``, ``RTL``). At run time the rule
listens on the performer's vehicle (live link or replayed log) after the vehicle's
own handling, so it sees exactly the messages the adapter acts on, from the
vehicle it flies. ``field`` is the value a function rule writes (an expression:
``voltage_battery / 1000``).
"""

from __future__ import annotations

from typing import Any, ClassVar

from pydantic import BaseModel
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from plansys_bridge.errors import ConfigError
from plansys_bridge.plugins import PluginSettings
from plansys_bridge.sensing.expressions import Expression, ExpressionError, parse_expression
from plansys_bridge.sensing.source import Detach, Feed, RuleSite, SensingSource

__all__ = ["MavlinkMessageSource", "message_fields", "message_sample"]

_CLASSES: dict[str, Any] = {cls.msgname: cls for cls in mavlink2.mavlink_map.values()}


class MavlinkMessageSettings(PluginSettings):
    message: str
    """A message of the ArduPilot dialect, e.g. ``BATTERY_STATUS``."""
    field: str | None = None
    """The value a function rule writes: a field or an expression over fields."""


def message_fields(name: str) -> frozenset[str]:
    """Every field path a sample of message ``name`` carries (KeyError if unknown)."""
    cls = _CLASSES[name]
    paths: set[str] = set()
    for field, length in zip(cls.fieldnames, _array_lengths(cls), strict=True):
        paths.add(field)
        paths.update(f"{field}[{i}]" for i in range(length))
    if name == "HEARTBEAT":
        paths.add("mode")
    return frozenset(paths)


def _array_lengths(cls: Any) -> list[int]:
    by_name = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
    return [by_name.get(f, 0) for f in cls.fieldnames]


def message_sample(msg: Any) -> dict[str, Any]:
    """A received message as ``{field path: value}``."""
    sample: dict[str, Any] = {}
    for field in msg.get_fieldnames():
        value = getattr(msg, field)
        sample[field] = value
        if isinstance(value, list | tuple):
            for i, item in enumerate(value):
                sample[f"{field}[{i}]"] = item
    if msg.get_type() == "HEARTBEAT":
        sample["mode"] = mavutil.mode_string_v10(msg)
    return sample


class MavlinkMessageSource(SensingSource):
    """One message type from a ``mavlink`` (or replayed ``tlog``) performer's vehicle."""

    Settings: ClassVar[type[BaseModel]] = MavlinkMessageSettings
    performer_kinds: ClassVar[tuple[str, ...]] = ("mavlink", "mavlink_replay")

    def __init__(self, settings: BaseModel) -> None:
        super().__init__(settings)
        assert isinstance(settings, MavlinkMessageSettings)
        self.message = settings.message
        self._value: Expression | None = None

    def describe(self) -> str:
        return self.message

    def check(self, site: RuleSite) -> frozenset[str]:
        assert isinstance(self.settings, MavlinkMessageSettings)
        if self.message not in _CLASSES:
            import difflib

            close = difflib.get_close_matches(self.message.upper(), list(_CLASSES), n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise ConfigError(
                f"no MAVLink message {self.message!r} in the ArduPilot dialect{hint}",
                key="message",
            )
        fields = message_fields(self.message)
        text = self.settings.field
        if text is not None:
            try:
                self._value = parse_expression(text)
            except ExpressionError as exc:
                raise ConfigError(str(exc), key="field") from exc
            unknown = sorted(self._value.fields - fields)
            if unknown:
                raise ConfigError(
                    f"{self.message} has no field {unknown[0]!r} "
                    f"(its fields: {', '.join(_CLASSES[self.message].fieldnames)})",
                    key="field",
                )
        return fields

    def value(self) -> Expression | None:
        return self._value

    def attach(self, performer: Any, feed: Feed) -> Detach:
        vehicle = performer.vehicle
        if vehicle is None:
            raise ConfigError(
                f"performer {performer.node_name!r} has no vehicle link yet", key="performer"
            )
        wanted = self.message

        def on_message(msg: Any) -> None:
            if msg.get_type() == wanted:
                feed(message_sample(msg))

        return vehicle.add_listener(on_message)
