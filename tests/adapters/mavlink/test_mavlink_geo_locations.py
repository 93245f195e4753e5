from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st
from plansys_bridge_adapters.mavlink.geo import (
    GeoPoint,
    bearing_deg,
    distance_m,
    north_east_m,
    offset,
)
from plansys_bridge_adapters.mavlink.locations import load_locations, parse_locations

from plansys_bridge.errors import ConfigError

HOME = GeoPoint(-35.363261, 149.165230, 584.0)


@given(st.floats(-2000, 2000), st.floats(-2000, 2000))
def test_offset_round_trips_and_measures(north: float, east: float) -> None:
    point = offset(HOME, north, east)
    n, e = north_east_m(HOME, point)
    assert n == pytest.approx(north, abs=1e-6)
    assert e == pytest.approx(east, abs=1e-6)
    assert distance_m(HOME, point) == pytest.approx(math.hypot(north, east), rel=2e-3, abs=1e-3)


def test_bearing_points_the_right_way() -> None:
    assert bearing_deg(HOME, offset(HOME, 100, 0)) == pytest.approx(0.0, abs=1e-6)
    assert bearing_deg(HOME, offset(HOME, 0, 100)) == pytest.approx(90.0, abs=1e-6)
    assert bearing_deg(HOME, offset(HOME, -100, 0)) == pytest.approx(180.0, abs=1e-6)


def test_locations_file_resolves_offsets_from_each_home(tmp_path: Path) -> None:
    locs = load_locations("mavlink_locations.yaml", Path(__file__).parents[3] / "configs", "k")
    place = locs.get("North_Field")
    assert place.alt == 15
    point = place.resolve(HOME, locs.origin, default_alt=10)
    assert north_east_m(HOME, point) == pytest.approx((60, 10), abs=1e-6)
    assert point.alt == 15
    other_home = offset(HOME, 0, 100)
    assert north_east_m(other_home, place.resolve(other_home, None, 10)) == pytest.approx(
        (60, 10), abs=1e-6
    )
    assert locs.get("gate").resolve(HOME, None, 7).alt == 7


def test_origin_and_absolute_locations() -> None:
    locs = parse_locations(
        {
            "origin": {"lat": HOME.lat, "lon": HOME.lon},
            "locations": {"a": {"north": 10, "east": 0}, "b": {"lat": -35.0, "lon": 149.0}},
        },
        source="inline",
        key="performers[0].locations",
    )
    elsewhere = offset(HOME, 500, 500)
    assert north_east_m(HOME, locs.get("a").resolve(elsewhere, locs.origin, 5)) == pytest.approx(
        (10, 0), abs=1e-6
    )
    assert locs.get("b").resolve(elsewhere, locs.origin, 5) == GeoPoint(-35.0, 149.0, 5)


@pytest.mark.parametrize(
    ("data", "key"),
    [
        ({"locations": {"a": {"north": 1, "lat": 2}}}, "performers[0].locations.locations.a"),
        ({"locations": {"a": {"north": "x"}}}, "performers[0].locations.locations.a.north"),
        ({"locations": {"a": {"up": 1}}}, "performers[0].locations.locations.a.up"),
        ({"locations": {"a": {"lat": 1}}}, "performers[0].locations.locations.a"),
        ({"locations": {}}, "performers[0].locations.locations"),
        ({"places": {}}, "performers[0].locations.places"),
        ({"locations": {"a": {}, "A": {}}}, "performers[0].locations.locations.A"),
    ],
)
def test_bad_locations_name_the_key(data: object, key: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_locations(data, source="inline", key="performers[0].locations")
    assert info.value.key == key


def test_unknown_location_lists_known_ones() -> None:
    locs = parse_locations({"locations": {"a": {"north": 1}}}, source="f.yaml", key="")
    with pytest.raises(KeyError, match=r"f.yaml: no location 'zz' \(known: a\)"):
        locs.get("zz")


def test_missing_locations_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read locations file"):
        load_locations("nope.yaml", tmp_path, "performers[1].locations")
