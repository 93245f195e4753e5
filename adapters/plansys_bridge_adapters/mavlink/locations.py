"""Named places: PDDL location objects mapped to positions a vehicle can fly or drive to.

A locations file (or an inline mapping in a mission) reads::

    origin: {lat: -35.363261, lon: 149.165230}   # optional
    default_alt: 10                              # optional, metres above home
    locations:
      base:   {north: 0, east: 0}
      wp_a:   {north: 40, east: 10, alt: 15}
      field:  {lat: -35.36290, lon: 149.16590}

``north``/``east`` are metres from ``origin`` or, without one, from each vehicle's
own home (so one file serves vehicles started in different places); ``lat``/``lon``
are absolute. ``alt`` is metres above home; a copter without one flies at the
performer's cruise altitude, a rover ignores it. Names are lower-cased like PDDL.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plansys_bridge.errors import ConfigError
from plansys_bridge.yaml_files import load_yaml_document

from .geo import GeoPoint, offset

_LOCATION_KEYS = frozenset({"north", "east", "lat", "lon", "alt"})
_FILE_KEYS = frozenset({"origin", "default_alt", "locations"})


@dataclass(frozen=True)
class Location:
    """One named place, either absolute (lat/lon) or an offset (north/east)."""

    name: str
    lat: float | None = None
    lon: float | None = None
    north: float | None = None
    east: float | None = None
    alt: float | None = None

    def resolve(self, home: GeoPoint, origin: GeoPoint | None, default_alt: float) -> GeoPoint:
        """Latitude/longitude and altitude above home of this place."""
        alt = default_alt if self.alt is None else self.alt
        if self.lat is not None and self.lon is not None:
            return GeoPoint(self.lat, self.lon, alt)
        base = origin if origin is not None else home
        point = offset(base, self.north or 0.0, self.east or 0.0)
        return GeoPoint(point.lat, point.lon, alt)


@dataclass(frozen=True)
class LocationMap:
    """All named places of a mission."""

    locations: Mapping[str, Location]
    origin: GeoPoint | None = None
    default_alt: float | None = None
    source: str = "locations"

    def get(self, name: str) -> Location:
        try:
            return self.locations[name.lower()]
        except KeyError:
            known = ", ".join(sorted(self.locations)) or "none"
            raise KeyError(f"{self.source}: no location {name!r} (known: {known})") from None

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name.lower() in self.locations


def load_locations(spec: str | Path | Mapping[str, Any], base_dir: Path, key: str) -> LocationMap:
    """A :class:`LocationMap` from a YAML file path (relative to ``base_dir``) or a mapping.

    Errors are :class:`ConfigError` naming the offending key; in a file, with the
    file's line and column and the mission key that named the file (the mistake is
    in the locations file, but the user starts from the mission).
    """
    if isinstance(spec, str | Path):
        path = Path(spec)
        if not path.is_absolute():
            path = base_dir / path
        data, positions = load_yaml_document(path, "locations file", key)
        try:
            return parse_locations(data, source=str(path), key="")
        except ConfigError as exc:
            placed = positions.relocate(exc)
            raise ConfigError(
                f"{placed.reason} (in the locations file of {key})",
                key=placed.key,
                file=placed.file,
                line=placed.line,
                column=placed.column,
            ) from exc
    return parse_locations(spec, source=key, key=key)


def parse_locations(data: object, *, source: str, key: str) -> LocationMap:
    """Check and convert the mapping form described in the module docstring."""
    file = source if not key else None

    def err(message: str, where: str) -> ConfigError:
        full = f"{key}.{where}" if key and where else (key or where)
        return ConfigError(message, key=full or None, file=file)

    if not isinstance(data, Mapping):
        raise err("locations must be a mapping with a 'locations' key", "")
    for name in data:
        if name not in _FILE_KEYS:
            raise err(f"unknown key (allowed: {', '.join(sorted(_FILE_KEYS))})", str(name))
    origin = None
    if data.get("origin") is not None:
        o = data["origin"]
        if not isinstance(o, Mapping) or "lat" not in o or "lon" not in o:
            raise err("origin needs lat and lon", "origin")
        origin = GeoPoint(
            _number(o["lat"], err, "origin.lat"),
            _number(o["lon"], err, "origin.lon"),
            _number(o.get("alt", 0.0), err, "origin.alt"),
        )
    default_alt = None
    if data.get("default_alt") is not None:
        default_alt = _number(data["default_alt"], err, "default_alt")
        if default_alt <= 0:
            raise err(f"must be > 0 metres above home, got {default_alt:g}", "default_alt")
    raw = data.get("locations")
    if not isinstance(raw, Mapping) or not raw:
        raise err("must map location names to positions", "locations")
    places: dict[str, Location] = {}
    for name, entry in raw.items():
        where = f"locations.{name}"
        if not isinstance(name, str) or not name.strip():
            raise err(f"location names must be strings, got {name!r}", "locations")
        if not isinstance(entry, Mapping):
            raise err("must be a mapping like {north: 10, east: 5} or {lat: .., lon: ..}", where)
        for field_name in entry:
            if field_name not in _LOCATION_KEYS:
                raise err(
                    f"unknown key (allowed: {', '.join(sorted(_LOCATION_KEYS))})",
                    f"{where}.{field_name}",
                )
        values = {k: _number(v, err, f"{where}.{k}") for k, v in entry.items()}
        absolute = "lat" in values or "lon" in values
        relative = "north" in values or "east" in values
        if absolute and relative:
            raise err("give either lat/lon or north/east, not both", where)
        if absolute and not ("lat" in values and "lon" in values):
            raise err("an absolute location needs both lat and lon", where)
        if absolute and not (-90 <= values["lat"] <= 90 and -180 <= values["lon"] <= 180):
            raise err("lat must be in [-90, 90] and lon in [-180, 180]", where)
        lname = name.strip().lower()
        if lname in places:
            raise err(f"location {lname!r} given twice (names are case-insensitive)", where)
        places[lname] = Location(lname, **values)
    return LocationMap(places, origin, default_alt, source)


def _number(value: object, err: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise err(f"must be a number, got {value!r}", where)
    return float(value)
