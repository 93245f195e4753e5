"""The type hierarchy: subtypes, either, objects of a type."""

from __future__ import annotations

from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.pddl.types import TypeHierarchy

DOMAIN = """(define (domain t) (:requirements :typing)
  (:types vehicle place - object car truck - vehicle pickup - (either car truck) garage - place))"""


def test_subtypes_and_ancestors() -> None:
    h = TypeHierarchy(parse_domain(DOMAIN))
    assert h.is_subtype("car", "vehicle") and h.is_subtype("pickup", "vehicle")
    assert h.is_subtype("pickup", "truck") and h.is_subtype("pickup", "car")
    assert h.is_subtype("garage", "object") and h.is_subtype("car", "car")
    assert not h.is_subtype("vehicle", "car") and not h.is_subtype("garage", "vehicle")
    assert h.subtypes("vehicle") == {"vehicle", "car", "truck", "pickup"}
    assert h.subtypes("object") == {
        "object",
        "vehicle",
        "place",
        "car",
        "truck",
        "pickup",
        "garage",
    }
    assert h.ancestors("pickup") == {"pickup", "car", "truck", "vehicle", "object"}
    assert h.compatible(("vehicle",), ("car",)) and not h.compatible(("place",), ("car",))
    assert h.cycle() is None


def test_objects_of_type() -> None:
    h = TypeHierarchy(parse_domain(DOMAIN))
    objects = {"c1": "car", "p1": "pickup", "t1": "truck", "g": "garage"}
    assert h.objects_of_type("car", objects) == ["c1", "p1"]
    assert h.objects_of_type("vehicle", objects) == ["c1", "p1", "t1"]
    assert h.objects_of_type("object", objects) == ["c1", "p1", "t1", "g"]
    assert h.objects_of_type("place", objects) == ["g"]
