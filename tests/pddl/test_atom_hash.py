"""An atom's hash is worked out once, when it is made; everything else stays the dataclass's."""

from __future__ import annotations

import copy
import dataclasses
import os
import pickle
import subprocess
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

from plansys_bridge.errors import SourceLocation
from plansys_bridge.pddl.model import Atom


def test_hash_and_equality_are_those_of_predicate_and_arguments() -> None:
    a = Atom("at", ("r1", "k"))
    b = Atom("at", ("r1", "k"), SourceLocation("d.pddl", 3, 4))
    assert hash(a) == hash(("at", ("r1", "k")))
    assert a == b and hash(a) == hash(b)
    assert a != Atom("at", ("r1", "j")) and a != Atom("in", ("r1", "k"))
    assert len({a, b, Atom("at", ("r1", "j"))}) == 2
    assert repr(a) == "Atom(predicate='at', args=('r1', 'k'))" and str(a) == "(at r1 k)"
    assert [f.name for f in dataclasses.fields(a)] == ["predicate", "args", "loc"]
    assert dataclasses.replace(a, args=("r2", "k")) == Atom("at", ("r2", "k"))
    assert Atom(predicate="p") == Atom("p", ())


def test_an_atom_stays_frozen() -> None:
    a = Atom("at", ("r1", "k"))
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.args = ("r2",)  # type: ignore[misc]


def test_unhashable_arguments_fail_when_hashed_not_when_made() -> None:
    a = Atom("at", ["r1"])  # type: ignore[arg-type]  # what a careless caller hands in
    assert a.args == ["r1"]
    with pytest.raises(TypeError):
        hash(a)


def test_copies_and_pickles_work_the_hash_out_again() -> None:
    a = Atom("at", ("r1", "k"), SourceLocation("d.pddl", 3, 4))
    assert "_hash" not in a.__getstate__()
    for other in (pickle.loads(pickle.dumps(a)), copy.copy(a), copy.deepcopy(a)):
        assert other == a and hash(other) == hash(a) and other.loc == a.loc


def test_a_pickle_loads_with_the_hash_of_the_loading_process() -> None:
    # String hashes differ between processes: a hash carried in the pickle would
    # make the loaded atom miss its equal in every set and dict.
    code = (
        "import pickle, sys; from plansys_bridge.pddl.model import Atom; "
        "a = pickle.loads(sys.stdin.buffer.read()); "
        "print(hash(a) == hash(Atom('at', ('r1', 'k'))), a in {Atom('at', ('r1', 'k'))})"
    )
    env = {**os.environ, "PYTHONHASHSEED": "12345"}
    out = subprocess.run(
        [sys.executable, "-c", code],
        input=pickle.dumps(Atom("at", ("r1", "k"))),
        capture_output=True,
        env=env,
        check=True,
    )
    assert out.stdout.decode().split() == ["True", "True"]


def test_every_pickle_protocol_and_a_weak_reference_keep_working() -> None:
    import weakref

    a = Atom("at", ("r1", "k"), SourceLocation("d.pddl", 3, 4))
    for protocol in range(pickle.HIGHEST_PROTOCOL + 1):
        other = pickle.loads(pickle.dumps(a, protocol))
        assert other == a and hash(other) == hash(a) and other.loc == a.loc
    assert weakref.ref(a)() is a
    assert vars(a) == {"predicate": "at", "args": ("r1", "k"), "loc": a.loc}


def test_unhashable_arguments_fail_with_the_tuples_own_error() -> None:
    a = Atom("at", ["r1"])  # type: ignore[arg-type]
    with pytest.raises(TypeError) as got:
        hash(a)
    with pytest.raises(TypeError) as expected:
        hash(("at", ["r1"]))
    assert str(got.value) == str(expected.value)
    with pytest.raises(TypeError):
        _ = {a}


def test_hashing_runs_no_python_code() -> None:
    # The point of the kept hash: no Python frame per dict or set operation.
    a = Atom("at", ("r1", "k"))
    frames: list[str] = []

    def watch(frame: object, event: str, _arg: object) -> None:
        if event == "call":
            frames.append(frame.f_code.co_name)  # type: ignore[attr-defined]

    table = {a: None}
    sys.setprofile(watch)
    try:
        found = a in table and a in {a} and hash(a) == a.__hash__()
    finally:
        sys.setprofile(None)
    assert found and frames == []


@given(
    st.text(min_size=1, max_size=8),
    st.lists(st.text(max_size=6), max_size=4).map(tuple),
)
def test_hash_and_membership_are_those_of_the_pair(predicate: str, args: tuple[str, ...]) -> None:
    a = Atom(predicate, args)
    assert hash(a) == hash((predicate, args)) == a.__hash__()
    twin = copy.copy(a)
    assert twin is not a and twin in {a} and {a: 1}[twin] == 1
    assert Atom(predicate + "x", args) not in {a}
