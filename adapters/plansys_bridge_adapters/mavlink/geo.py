"""Geodesy on the WGS84 ellipsoid, by geographiclib: metres between fixes, offsets.

Distances and bearings are geographiclib's geodesics (Karney's algorithms, accurate
to nanometres). "Metres north and east of home" are the geodesic's length and
direction from home (an azimuthal equidistant view of the ground), so
:func:`offset` and :func:`north_east_m` undo each other exactly and a location
``{north: 60}`` is 60 m from home however far from the equator home is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from geographiclib.geodesic import Geodesic

_WGS84 = Geodesic.WGS84
_INVERSE = Geodesic.DISTANCE | Geodesic.AZIMUTH
_DIRECT = Geodesic.LATITUDE | Geodesic.LONGITUDE | Geodesic.LONG_UNROLL


@dataclass(frozen=True)
class GeoPoint:
    """A position: latitude/longitude in degrees, altitude in metres above home."""

    lat: float
    lon: float
    alt: float = 0.0


def _inverse(a: GeoPoint, b: GeoPoint) -> tuple[float, float]:
    """Geodesic length (m) and initial azimuth (degrees) from ``a`` to ``b``."""
    line = _WGS84.Inverse(a.lat, a.lon, b.lat, b.lon, _INVERSE)
    return float(line["s12"]), float(line["azi1"])


def distance_m(a: GeoPoint, b: GeoPoint) -> float:
    """Horizontal distance in metres along the ellipsoid."""
    return _inverse(a, b)[0]


def distance_3d_m(a: GeoPoint, b: GeoPoint) -> float:
    """Distance in metres including the altitude difference."""
    return math.hypot(distance_m(a, b), b.alt - a.alt)


def offset(origin: GeoPoint, north_m: float, east_m: float, up_m: float = 0.0) -> GeoPoint:
    """The point ``north_m``/``east_m`` metres from ``origin`` and ``up_m`` above it."""
    length = math.hypot(north_m, east_m)
    azimuth = math.degrees(math.atan2(east_m, north_m))
    end = _WGS84.Direct(origin.lat, origin.lon, azimuth, length, _DIRECT)
    return GeoPoint(float(end["lat2"]), float(end["lon2"]), origin.alt + up_m)


def north_east_m(origin: GeoPoint, point: GeoPoint) -> tuple[float, float]:
    """Inverse of :func:`offset` (horizontal part): metres north and east of ``origin``."""
    length, azimuth = _inverse(origin, point)
    rad = math.radians(azimuth)
    return length * math.cos(rad), length * math.sin(rad)


def bearing_deg(a: GeoPoint, b: GeoPoint) -> float:
    """Initial bearing from ``a`` to ``b`` in degrees, 0 = north, clockwise, [0, 360)."""
    return _inverse(a, b)[1] % 360.0
