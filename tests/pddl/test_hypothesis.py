"""Property tests: random models round-trip through the writer; random damage to
corpus files only ever raises the project's own PDDL errors."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pddl_corpus import CORPUS, candidate_domains, files, is_broken

from plansys_bridge.errors import PddlError
from plansys_bridge.pddl import model as m
from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.pddl.writer import write_domain, write_problem

KEYWORDS = {
    "and",
    "or",
    "not",
    "imply",
    "exists",
    "forall",
    "when",
    "either",
    "define",
    "domain",
    "problem",
    "assign",
    "increase",
    "decrease",
    "scale-up",
    "scale-down",
    "minimize",
    "maximize",
    "total-time",
}

names = st.from_regex(r"[a-z][a-z0-9_\-]{0,6}", fullmatch=True).filter(lambda s: s not in KEYWORDS)
variables = names.map(lambda s: "?" + s).filter(lambda s: s != "?duration")
terms = st.one_of(names, variables)
type_lists = st.lists(names, min_size=1, max_size=2, unique=True).map(tuple)
typed = st.builds(m.TypedName, variables, type_lists)
typed_lists = st.lists(typed, max_size=3).map(tuple)
numbers = st.floats(allow_nan=False, allow_infinity=False, width=64).map(m.Number)
atoms = st.builds(m.Atom, names, st.lists(terms, max_size=3).map(tuple))
fluents = st.builds(m.FluentRef, names, st.lists(terms, max_size=2).map(tuple))


def num_exprs(duration: bool) -> st.SearchStrategy[m.NumExpr]:
    leaves = st.one_of(numbers, fluents, *([st.just(m.DurationRef())] if duration else []))
    return st.recursive(
        leaves,
        lambda inner: st.one_of(
            st.builds(m.BinaryOp, st.sampled_from(["+", "-", "*", "/"]), inner, inner),
            st.builds(m.Negate, inner),
        ),
        max_leaves=4,
    )


def conditions(duration: bool = False) -> st.SearchStrategy[m.Condition]:
    nums = num_exprs(duration)
    leaves = st.one_of(
        atoms,
        st.builds(m.Equals, terms, terms),
        st.builds(m.Compare, st.sampled_from(["<", "<=", "=", ">=", ">"]), nums, nums),
    )
    return st.recursive(
        leaves,
        lambda inner: st.one_of(
            st.builds(m.And, st.lists(inner, max_size=3).map(tuple)),
            st.builds(m.Or, st.lists(inner, max_size=3).map(tuple)),
            st.builds(m.Not, inner),
            st.builds(m.Imply, inner, inner),
            st.builds(m.Exists, typed_lists, inner),
            st.builds(m.Forall, typed_lists, inner),
        ),
        max_leaves=6,
    )


def effects(duration: bool = False) -> st.SearchStrategy[m.Effect]:
    ops = st.sampled_from(["assign", "increase", "decrease", "scale-up", "scale-down"])
    leaves = st.one_of(
        st.builds(m.AddEffect, atoms),
        st.builds(m.DeleteEffect, atoms),
        st.builds(m.NumericEffect, ops, fluents, num_exprs(duration)),
    )
    return st.recursive(
        leaves,
        lambda inner: st.one_of(
            st.builds(m.AndEffect, st.lists(inner, max_size=3).map(tuple)),
            st.builds(m.WhenEffect, conditions(duration), inner),
            st.builds(m.ForallEffect, typed_lists, inner),
        ),
        max_leaves=5,
    )


actions = st.builds(m.Action, names, typed_lists, conditions(), effects())
durative_actions = st.builds(
    m.DurativeAction,
    names,
    typed_lists,
    st.lists(
        st.builds(m.DurationConstraint, st.sampled_from(["=", "<=", ">="]), num_exprs(False)),
        max_size=2,
    ).map(tuple),
    conditions(True),
    conditions(True),
    conditions(True),
    effects(True),
    effects(True),
)


def _unique(items: list, key) -> tuple:  # type: ignore[no-untyped-def]
    seen: dict[str, object] = {}
    for item in items:
        seen.setdefault(key(item), item)
    return tuple(seen.values())


@st.composite
def domains(draw: st.DrawFn) -> m.Domain:
    type_names = draw(st.lists(names.filter(lambda n: n != "object"), max_size=4, unique=True))
    types = tuple(
        m.TypeDef(
            t,
            tuple(
                draw(
                    st.lists(
                        st.sampled_from(["object", *type_names[:i]]),
                        min_size=1,
                        max_size=2,
                        unique=True,
                    )
                )
            ),
        )
        for i, t in enumerate(type_names)
    )
    skeleton = st.tuples(names, typed_lists)
    preds = draw(st.lists(skeleton, max_size=4))
    funcs = draw(st.lists(skeleton, max_size=3))
    return m.Domain(
        name=draw(names),
        requirements=tuple(
            draw(
                st.lists(
                    st.sampled_from(
                        [":strips", ":typing", ":adl", ":fluents", ":durative-actions"]
                    ),
                    unique=True,
                )
            )
        ),
        types=types,
        constants=_unique(
            draw(st.lists(st.builds(m.TypedName, names, type_lists), max_size=3)), lambda c: c.name
        ),
        predicates=_unique([m.PredicateDef(n, p) for n, p in preds], lambda p: p.name),
        functions=_unique([m.FunctionDef(n, p) for n, p in funcs], lambda f: f.name),
        actions=_unique(
            draw(st.lists(st.one_of(actions, durative_actions), max_size=3)), lambda a: a.name
        ),
        derived=tuple(
            dict.fromkeys(
                draw(
                    st.lists(
                        st.builds(
                            m.DerivedPredicate,
                            st.builds(m.PredicateDef, names, typed_lists),
                            conditions(),
                        ),
                        max_size=2,
                    )
                )
            )
        ),
    )


problems = st.builds(
    m.Problem,
    names,
    st.one_of(st.just(""), names),
    st.just(()),
    st.lists(st.builds(m.TypedName, names, type_lists), max_size=4, unique_by=lambda o: o.name).map(
        tuple
    ),
    st.lists(st.builds(m.Atom, names, st.lists(names, max_size=3).map(tuple)), max_size=5).map(
        tuple
    ),
    st.lists(
        st.builds(
            m.FluentValue,
            st.builds(m.FluentRef, names, st.lists(names, max_size=2).map(tuple)),
            st.floats(allow_nan=False, allow_infinity=False),
        )
    ).map(tuple),
    conditions(),
    st.one_of(
        st.none(),
        st.builds(
            m.Metric,
            st.sampled_from(["minimize", "maximize"]),
            st.one_of(st.just("total-time"), num_exprs(False)),
        ),
    ),
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(domains())
def test_random_domains_round_trip(domain: m.Domain) -> None:
    text = write_domain(domain)
    assert parse_domain(text, check=False) == domain


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems)
def test_random_problems_round_trip(problem: m.Problem) -> None:
    assert parse_problem(write_problem(problem)) == problem


CORPUS_FILES = [p for p in files("domain") + files("problem") if not is_broken(p)] if CORPUS else []


def _mutate(data: bytes, edits: list[tuple[int, int, int]]) -> bytes:
    buf = bytearray(data)
    for kind, where, value in edits:
        if not buf:
            break
        pos = where % len(buf)
        if kind == 0:
            del buf[pos]
        elif kind == 1:
            buf.insert(pos, value)
        else:
            buf[pos] = value
    return bytes(buf)


edit_bytes = st.one_of(st.sampled_from(b"()?-:;= \n0aZ"), st.integers(0, 255))
edits = st.lists(
    st.tuples(st.integers(0, 2), st.integers(0, 1 << 20), edit_bytes), min_size=1, max_size=4
)


@pytest.mark.skipif(CORPUS is None, reason="PlanSys2 PDDL corpus not found")
@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(CORPUS_FILES or [Path()]), edits)
def test_mutated_corpus_only_raises_pddl_errors(
    path: Path, changes: list[tuple[int, int, int]]
) -> None:
    text = _mutate(path.read_bytes(), changes).decode("utf-8", errors="replace")
    try:
        if "(problem" in path.read_text(encoding="utf-8").lower().replace("( problem", "(problem"):
            parse_problem(text, candidate_domains(path)[0][1], "mutated.pddl")
        else:
            parse_domain(text, "mutated.pddl")
    except PddlError as exc:
        assert exc.location is None or exc.location.file == "mutated.pddl"
