"""Vehicle telemetry into the knowledge base, so plans can react to it.

With ``battery_function: battery`` the performer keeps ``(= (battery uav1) 87)`` up
to date; with ``low_battery_predicate: battery_low`` it adds ``(battery_low uav1)``
when the remaining charge falls below ``low_battery_threshold`` and removes it once
the charge is ``hysteresis`` above again. A knowledge change is what makes the
executor re-check over-all conditions and replan, as in PlanSys2's battery demos.
Updates are rate-limited to changes of at least ``battery_step`` percent.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from plansys_bridge.errors import ConfigError, PlansysBridgeError

from ..checks import mapping
from .vehicle import MavlinkVehicle

log = logging.getLogger(__name__)


class KnowledgeSink(Protocol):
    """The part of the problem expert telemetry writes to."""

    def set_function(self, fv: Any) -> Any: ...

    def add_predicate(self, fact: Any) -> Any: ...

    def remove_predicate(self, fact: Any) -> Any: ...

    def exist_predicate(self, fact: Any) -> bool: ...


_KEYS = (
    "battery_function",
    "low_battery_predicate",
    "low_battery_threshold",
    "hysteresis",
    "battery_step",
)


@dataclass(frozen=True)
class TelemetryConfig:
    battery_function: str | None = None
    low_battery_predicate: str | None = None
    low_battery_threshold: float = 25.0
    hysteresis: float = 5.0
    battery_step: float = 1.0

    @property
    def enabled(self) -> bool:
        return bool(self.battery_function or self.low_battery_predicate)

    @classmethod
    def from_mapping(cls, data: object, key: str) -> TelemetryConfig:
        if data is None:
            return cls()
        data = mapping(data, key, _KEYS, "must be a mapping, e.g. {battery_function: battery}")
        values: dict[str, Any] = {}
        for name in ("battery_function", "low_battery_predicate"):
            value = data.get(name)
            if value is not None and (not isinstance(value, str) or not value.strip()):
                raise ConfigError(f"must be a PDDL name, got {value!r}", key=f"{key}.{name}")
            values[name] = value.strip().lower() if isinstance(value, str) else None
        for name in ("low_battery_threshold", "hysteresis", "battery_step"):
            if name in data:
                value = data[name]
                if isinstance(value, bool) or not isinstance(value, int | float) or value < 0:
                    raise ConfigError(f"must be a number >= 0, got {value!r}", key=f"{key}.{name}")
                values[name] = float(value)
        return cls(**values)


class TelemetryPublisher:
    """Writes one vehicle's battery into the knowledge base as it changes."""

    def __init__(
        self,
        vehicle: MavlinkVehicle,
        knowledge: KnowledgeSink,
        vehicle_object: str,
        config: TelemetryConfig,
    ) -> None:
        self.vehicle = vehicle
        self.knowledge = knowledge
        self.obj = vehicle_object
        self.config = config
        self.last_published: float | None = None
        self.low = False
        self._remove: Callable[[], None] | None = None
        self._disabled: set[str] = set()

    @property
    def disabled(self) -> frozenset[str]:
        """Settings the knowledge refused (e.g. a function the domain lacks)."""
        return frozenset(self._disabled)

    def start(self) -> None:
        if self._remove is None and self.config.enabled:
            self._remove = self.vehicle.add_listener(self._on_message)

    def stop(self) -> None:
        if self._remove is not None:
            self._remove()
            self._remove = None

    def _on_message(self, msg: Any) -> None:
        if msg.get_type() == "SYS_STATUS" and msg.battery_remaining >= 0:
            self.update(float(msg.battery_remaining))

    def update(self, remaining: float) -> None:
        """Publish ``remaining`` (percent) if it moved enough or crossed the threshold."""
        cfg = self.config
        if cfg.battery_function and (
            self.last_published is None or abs(remaining - self.last_published) >= cfg.battery_step
        ):
            text = f"(= ({cfg.battery_function} {self.obj}) {remaining:g})"
            if self._apply("battery_function", lambda: self.knowledge.set_function(text)):
                self.last_published = remaining
        if cfg.low_battery_predicate:
            fact = f"({cfg.low_battery_predicate} {self.obj})"
            if not self.low and remaining < cfg.low_battery_threshold:
                if self._apply("low_battery_predicate", lambda: self.knowledge.add_predicate(fact)):
                    self.low = True
                    log.warning(
                        "%s: battery %.0f %% < %g %%: %s",
                        self.vehicle.url,
                        remaining,
                        cfg.low_battery_threshold,
                        fact,
                    )
            elif (
                self.low
                and remaining >= cfg.low_battery_threshold + cfg.hysteresis
                and self._apply(
                    "low_battery_predicate", lambda: self.knowledge.remove_predicate(fact)
                )
            ):
                self.low = False

    def _apply(self, what: str, change: Callable[[], Any]) -> bool:
        if what in self._disabled:
            return False
        try:
            change()
        except PlansysBridgeError as exc:
            # A domain without that function/predicate: say so once, keep flying.
            self._disabled.add(what)
            log.error(
                "%s: telemetry %s disabled, the knowledge refused it: %s",
                self.vehicle.url,
                what,
                exc,
            )
            return False
        return True
