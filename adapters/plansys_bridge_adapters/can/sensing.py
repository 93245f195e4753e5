"""CAN signals as a sensing source:
``{from: can, performer: base1, signal: BASE_Status.BatteryPercent}``.

The signal is named as ``MESSAGE.SIGNAL`` of the DBC database the performer uses
(its ``dbc:`` setting, else the packaged ``mobile_base.dbc``), checked with cantools
when the mission loads. At run time the rule reads the performer's own bus client:
every data frame of that message is decoded with the same database and its signals
become the sample (``BatteryPercent`` and ``BASE_Status.BatteryPercent``), so a
rule's ``when`` may combine any signals of the message. Frames that do not decode
are the bus client's business (counted and logged there), never a sample.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import can
import cantools
from cantools.database.can import Database
from pydantic import BaseModel

from plansys_bridge.errors import ConfigError
from plansys_bridge.plugins import PluginSettings
from plansys_bridge.sensing.expressions import Expression, parse_expression
from plansys_bridge.sensing.source import Detach, Feed, RuleSite, SensingSource

from .dbc import default_dbc_path

__all__ = ["CanSignalSource"]


class CanSignalSettings(PluginSettings):
    signal: str
    """``MESSAGE.SIGNAL`` of the performer's DBC."""


def _database(site: RuleSite) -> tuple[Database, str]:
    entry = site.performer or {}
    dbc = entry.get("dbc")
    path = default_dbc_path() if dbc is None else Path(str(dbc))
    if not path.is_absolute():
        path = site.base_dir / path
    try:
        db = cantools.database.load_file(str(path), database_format="dbc")
    except (OSError, cantools.database.UnsupportedDatabaseFormatError) as exc:
        raise ConfigError(f"cannot read the performer's DBC {path}: {exc}", key="signal") from exc
    if not isinstance(db, Database):
        raise ConfigError(f"{path} is not a CAN database", key="signal")
    return db, str(path)


class CanSignalSource(SensingSource):
    """One DBC message's signals, from a ``can`` performer's bus."""

    Settings: ClassVar[type[BaseModel]] = CanSignalSettings
    performer_kinds: ClassVar[tuple[str, ...]] = ("can",)

    def __init__(self, settings: BaseModel) -> None:
        super().__init__(settings)
        assert isinstance(settings, CanSignalSettings)
        self.message_name, _, self.signal_name = settings.signal.partition(".")

    def describe(self) -> str:
        assert isinstance(self.settings, CanSignalSettings)
        return self.settings.signal

    def check(self, site: RuleSite) -> frozenset[str]:
        if not self.message_name or not self.signal_name:
            raise ConfigError(
                "name the signal as MESSAGE.SIGNAL, e.g. BASE_Status.BatteryPercent", key="signal"
            )
        db, path = _database(site)
        try:
            message = db.get_message_by_name(self.message_name)
        except KeyError:
            known = ", ".join(sorted(m.name for m in db.messages))
            raise ConfigError(
                f"no message {self.message_name!r} in {path} (its messages: {known})", key="signal"
            ) from None
        names = [s.name for s in message.signals]
        if self.signal_name not in names:
            raise ConfigError(
                f"message {self.message_name} of {path} has no signal {self.signal_name!r} "
                f"(its signals: {', '.join(names)})",
                key="signal",
            )
        return frozenset(names) | {f"{self.message_name}.{n}" for n in names}

    def value(self) -> Expression:
        return parse_expression(f"{self.message_name}.{self.signal_name}")

    def attach(self, performer: Any, feed: Feed) -> Detach:
        client = performer.client
        message = performer.dbc.database.get_message_by_name(self.message_name)
        key = (message.frame_id, message.is_extended_frame)
        prefix = self.message_name

        def on_frame(msg: can.Message) -> None:
            if (msg.arbitration_id, msg.is_extended_id) != key:
                return
            try:
                signals = message.decode(bytes(msg.data), decode_choices=False)
            except Exception:  # malformed: the bus client counts and logs it
                return
            sample: dict[str, Any] = {}
            for name, value in signals.items():
                sample[name] = sample[f"{prefix}.{name}"] = value
            feed(sample)

        client.frame_hooks.append(on_frame)

        def detach() -> None:
            if on_frame in client.frame_hooks:
                client.frame_hooks.remove(on_frame)

        return detach
