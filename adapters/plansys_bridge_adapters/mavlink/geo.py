"""Small-distance geodesy: metres between fixes and offsets from home.

Missions span at most a few kilometres, so a spherical Earth is accurate to well
under a metre, which is below GPS noise; no projection library is needed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

EARTH_RADIUS_M = 6_378_137.0


@dataclass(frozen=True)
class GeoPoint:
    """A position: latitude/longitude in degrees, altitude in metres above home."""

    lat: float
    lon: float
    alt: float = 0.0


def distance_m(a: GeoPoint, b: GeoPoint) -> float:
    """Horizontal great-circle distance in metres (haversine)."""
    phi1, phi2 = math.radians(a.lat), math.radians(b.lat)
    dphi = phi2 - phi1
    dlmb = math.radians(b.lon - a.lon)
    h = math.sin(dphi / 2) ** 2 + math.cos(phi1) * math.cos(phi2) * math.sin(dlmb / 2) ** 2
    return 2 * EARTH_RADIUS_M * math.asin(min(1.0, math.sqrt(h)))


def distance_3d_m(a: GeoPoint, b: GeoPoint) -> float:
    """Distance in metres including the altitude difference."""
    return math.hypot(distance_m(a, b), b.alt - a.alt)


def offset(origin: GeoPoint, north_m: float, east_m: float, up_m: float = 0.0) -> GeoPoint:
    """The point ``north_m``/``east_m`` metres from ``origin`` and ``up_m`` above it."""
    dlat = math.degrees(north_m / EARTH_RADIUS_M)
    dlon = math.degrees(east_m / (EARTH_RADIUS_M * math.cos(math.radians(origin.lat))))
    return GeoPoint(origin.lat + dlat, origin.lon + dlon, origin.alt + up_m)


def north_east_m(origin: GeoPoint, point: GeoPoint) -> tuple[float, float]:
    """Inverse of :func:`offset` (horizontal part): metres north and east of ``origin``."""
    north = math.radians(point.lat - origin.lat) * EARTH_RADIUS_M
    east = (
        math.radians(point.lon - origin.lon) * EARTH_RADIUS_M * math.cos(math.radians(origin.lat))
    )
    return north, east


def bearing_deg(a: GeoPoint, b: GeoPoint) -> float:
    """Initial bearing from ``a`` to ``b`` in degrees, 0 = north, clockwise, [0, 360)."""
    north, east = north_east_m(a, b)
    return math.degrees(math.atan2(east, north)) % 360.0
