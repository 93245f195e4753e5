"""An atom's hash is worked out once, when it is made; everything else stays the dataclass's."""

from __future__ import annotations

import copy
import dataclasses
import os
import pickle
import subprocess
import sys

import pytest

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
