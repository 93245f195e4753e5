"""The evaluator: conditions, derived predicates, effects, grounding, plan-graph atoms."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.evaluation import (
    EvaluationError,
    Evaluator,
    UnboundVariableError,
    UndefinedFluentError,
)
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import (
    AddEffect,
    And,
    AndEffect,
    Atom,
    Compare,
    DeleteEffect,
    DerivedPredicate,
    Domain,
    DurationRef,
    FluentRef,
    Not,
    Number,
    NumericEffect,
    PredicateDef,
    TypeDef,
    TypedName,
)
from plansys_bridge.pddl.parser import parse_condition, parse_domain, parse_effect

DOMAIN = """
(define (domain world)
  (:requirements :strips :typing :adl :fluents :durative-actions :derived-predicates)
  (:types robot drone - vehicle  vehicle place - object  dock - place  crate)
  (:constants base - dock)
  (:predicates
    (at ?v - vehicle ?p - place) (link ?a ?b - place) (reach ?a ?b - place)
    (isolated ?p - place) (carrying ?v - vehicle ?c - crate) (on ?c - crate ?p - place)
    (held ?c - (either crate vehicle)) (busy ?v - vehicle) (lit ?p - place))
  (:functions (battery ?v - vehicle) (dist ?a ?b - place) (moves))
  (:derived (reach ?a ?b - place)
    (or (link ?a ?b) (exists (?c - place) (and (reach ?a ?c) (link ?c ?b)))))
  (:derived (isolated ?p - place)
    (forall (?q - place) (imply (not (= ?p ?q)) (not (reach ?p ?q)))))
  (:durative-action fly
    :parameters (?d - drone ?a ?b - place)
    :duration (= ?duration (* 2 (dist ?a ?b)))
    :condition (and (at start (at ?d ?a)) (over all (reach ?a ?b))
                    (at start (>= (battery ?d) (* ?duration 1.5))))
    :effect (and (at start (not (at ?d ?a))) (at end (at ?d ?b))
                 (at end (decrease (battery ?d) (* ?duration 1.5)))))
  (:action drive
    :parameters (?r - robot ?a ?b - place)
    :precondition (and (at ?r ?a) (link ?a ?b))
    :effect (and (not (at ?r ?a)) (at ?r ?b) (increase (moves) 1)
                 (forall (?c - crate) (when (carrying ?r ?c)
                    (and (not (on ?c ?a)) (on ?c ?b))))))
)
"""


@pytest.fixture(scope="module")
def ev() -> Evaluator:
    return Evaluator(parse_domain(DOMAIN))


def world(*facts: str, fluents: dict[tuple[str, tuple[str, ...]], float] | None = None) -> State:
    objects = {
        "r1": "robot",
        "r2": "robot",
        "d1": "drone",
        "base": "dock",
        "hall": "place",
        "lab": "place",
        "roof": "place",
        "c1": "crate",
        "c2": "crate",
    }
    atoms = []
    for fact in facts:
        words = fact.strip("()").split()
        atoms.append(Atom(words[0], tuple(words[1:])))
    return State(atoms, fluents or {}, objects)


def cond(ev: Evaluator, text: str, variables: dict[str, tuple[str, ...]] | None = None):  # type: ignore[no-untyped-def]
    return parse_condition(text, ev.domain, variables)


def test_atoms_and_connectives(ev: Evaluator) -> None:
    s = world("(at r1 hall)", "(link hall lab)")
    assert ev.holds(cond(ev, "(at r1 hall)"), s)
    assert not ev.holds(cond(ev, "(at r1 lab)"), s)
    assert ev.holds(cond(ev, "(and (at r1 hall) (not (at r1 lab)))"), s)
    assert ev.holds(cond(ev, "(or (at r1 lab) (link hall lab))"), s)
    assert ev.holds(cond(ev, "(imply (at r1 lab) (at r2 lab))"), s)
    assert not ev.holds(cond(ev, "(imply (at r1 hall) (at r2 lab))"), s)
    assert ev.holds(cond(ev, "(and)"), s)
    assert ev.holds(cond(ev, "(at ?r hall)", {"?r": ("robot",)}), s, {"?r": "r1"})
    assert ev.holds(
        cond(ev, "(= ?a ?b)", {"?a": ("place",), "?b": ("place",)}), s, {"a": "x", "b": "x"}
    )


def test_unbound_variable_is_an_error(ev: Evaluator) -> None:
    with pytest.raises(UnboundVariableError, match=r"\?r"):
        ev.holds(cond(ev, "(at ?r hall)", {"?r": ("robot",)}), world())


def test_quantifiers_range_over_subtypes_and_constants(ev: Evaluator) -> None:
    s = world("(at r1 base)", "(at d1 base)")
    # ?v - vehicle covers robots and drones; base is a constant of subtype dock
    assert ev.holds(cond(ev, "(exists (?v - vehicle) (at ?v base))"), s)
    assert ev.holds(cond(ev, "(exists (?p - place) (and (at r1 ?p) (not (at r2 ?p))))"), s)
    assert not ev.holds(cond(ev, "(forall (?v - vehicle) (at ?v base))"), s)
    assert ev.holds(cond(ev, "(forall (?d - drone) (at ?d base))"), s)
    assert ev.holds(cond(ev, "(forall (?r - robot) (imply (at ?r base) (= ?r r1)))"), s)
    assert not ev.holds(cond(ev, "(exists (?d - dock) (at r2 ?d))"), s)
    # an atom's facts only bind objects of the variable's type (r1 is no drone)
    assert not ev.holds(cond(ev, "(exists (?d - drone) (and (at ?d base) (not (= ?d d1))))"), s)
    assert ev.holds(cond(ev, "(exists (?x - (either crate vehicle)) (= ?x c2))"), s)
    assert not ev.holds(cond(ev, "(exists (?x - (either crate drone)) (= ?x r1))"), s)
    assert ev.holds(cond(ev, "(forall (?x - (either crate drone)) (not (= ?x r1)))"), s)


def test_numeric_comparisons_and_duration(ev: Evaluator) -> None:
    s = world(fluents={("battery", ("d1",)): 30.0, ("dist", ("hall", "lab")): 5.0})
    assert ev.holds(cond(ev, "(> (battery d1) 29.5)"), s)
    assert ev.holds(cond(ev, "(= (battery d1) (* 6 (dist hall lab)))"), s)
    assert ev.holds(cond(ev, "(<= (- (battery d1) (/ (dist hall lab) 2)) 27.5)"), s)
    compare = parse_condition("(> (- (battery d1)) 0)", ev.domain)
    assert isinstance(compare, Compare)
    assert ev.value(compare.left, s) == -30.0
    with pytest.raises(UndefinedFluentError, match=r"\(battery r1\)"):
        ev.holds(cond(ev, "(> (battery r1) 0)"), s)
    fly = ev.get_action("fly")
    assert fly.__class__.__name__ == "DurativeAction"
    at_start = fly.at_start  # type: ignore[union-attr]
    assert ev.holds(
        at_start,
        s.with_changes(adds=[Atom("at", ("d1", "hall"))]),
        {"?d": "d1", "?a": "hall", "?b": "lab"},
        duration=10,
    )
    assert not ev.holds(
        at_start,
        s.with_changes(adds=[Atom("at", ("d1", "hall"))]),
        {"?d": "d1", "?a": "hall", "?b": "lab"},
        duration=21,
    )
    with pytest.raises(EvaluationError, match=r"\?duration"):
        ev.value(DurationRef(), s)
    with pytest.raises(EvaluationError, match="division by zero"):
        ev.holds(cond(ev, "(> (/ (battery d1) 0) 1)"), s)


def test_recursive_derived_predicates(ev: Evaluator) -> None:
    chain = [f"(link p{i} p{i + 1})" for i in range(30)]
    objects = {f"p{i}": "place" for i in range(31)}
    s = State(
        [Atom("link", tuple(f.strip("()").split()[1:])) for f in chain]
        + [Atom("link", ("q", "q"))],
        {},
        {**objects, "q": "place", "alone": "place"},
    )
    assert ev.holds(Atom("reach", ("p0", "p30")), s)
    assert not ev.holds(Atom("reach", ("p30", "p0")), s)
    assert len(ev.derived_facts(s)["reach"]) == 31 * 30 // 2 + 1
    # isolated needs reach complete first (it reads reach under negation)
    assert ev.holds(Atom("isolated", ("p30",)), s)
    assert ev.holds(Atom("isolated", ("alone",)), s)
    assert ev.holds(Atom("isolated", ("q",)), s)  # reaches only itself
    assert not ev.holds(Atom("isolated", ("p0",)), s)
    # a new link changes the next snapshot, not the cached one
    s2 = s.with_changes(adds=[Atom("link", ("p30", "alone"))])
    assert ev.holds(Atom("reach", ("p0", "alone")), s2)
    assert not ev.holds(Atom("isolated", ("p30",)), s2)
    assert ev.holds(Atom("isolated", ("p30",)), s)


def test_negative_cycle_in_derived_predicates_is_refused() -> None:
    p = PredicateDef("p", (TypedName("?x"),))
    q = PredicateDef("q", (TypedName("?x"),))
    domain = Domain(
        "cyclic",
        predicates=(p, q),
        derived=(
            DerivedPredicate(p, Not(Atom("q", ("?x",)))),
            DerivedPredicate(q, Atom("p", ("?x",))),
        ),
    )
    with pytest.raises(EvaluationError, match="not stratifiable"):
        Evaluator(domain)
    positive = Domain(
        "mutual",
        types=(TypeDef("thing"),),
        predicates=(p, q, PredicateDef("base", (TypedName("?x"),))),
        derived=(
            DerivedPredicate(p, Atom("q", ("?x",))),
            DerivedPredicate(q, Atom("base", ("?x",))),
            DerivedPredicate(q, Atom("p", ("?x",))),
        ),
    )
    ev = Evaluator(positive)
    s = State([Atom("base", ("a",))], {}, {"a": "thing", "b": "thing"})
    assert ev.holds(Atom("p", ("a",)), s) and not ev.holds(Atom("p", ("b",)), s)


def test_effects_read_old_state_deletes_before_adds(ev: Evaluator) -> None:
    s = world(
        "(at r1 hall)",
        "(link hall lab)",
        "(carrying r1 c1)",
        "(on c1 hall)",
        "(on c2 hall)",
        fluents={("moves", ()): 0.0},
    )
    drive = ev.get_action("drive")
    after = ev.apply(drive.effect, s, {"?r": "r1", "?a": "hall", "?b": "lab"})  # type: ignore[union-attr]
    assert Atom("at", ("r1", "lab")) in after and Atom("at", ("r1", "hall")) not in after
    assert Atom("on", ("c1", "lab")) in after and Atom("on", ("c1", "hall")) not in after
    assert Atom("on", ("c2", "hall")) in after  # not carried
    assert after.value("moves") == 1
    assert Atom("at", ("r1", "hall")) in s  # the old state is untouched
    # add and delete of the same atom: the add wins
    same = Atom("busy", ("r1",))
    assert same in ev.apply(AndEffect((AddEffect(same), DeleteEffect(same))), s)
    # every value is read in the old state; increases on one fluent accumulate
    eff = parse_effect("(and (assign (moves) (+ (moves) 10)) (increase (moves) 1))", ev.domain)
    assert ev.apply(eff, s.with_changes(fluents={("moves", ()): 5.0})).value("moves") == 16
    for op, expected in (
        ("scale-up", 10.0),
        ("scale-down", 2.5),
        ("decrease", 3.0),
        ("assign", 2.0),
    ):
        e = NumericEffect(op, FluentRef("moves"), Number(2))  # type: ignore[arg-type]
        assert ev.apply(e, s.with_changes(fluents={("moves", ()): 5.0})).value("moves") == expected
    with pytest.raises(UndefinedFluentError, match=r"\(battery r2\)"):
        ev.apply(NumericEffect("increase", FluentRef("battery", ("r2",)), Number(1)), s)
    with pytest.raises(EvaluationError, match="by zero"):
        ev.apply(NumericEffect("scale-down", FluentRef("moves"), Number(0)), s)


def test_conditional_effect_reads_old_state(ev: Evaluator) -> None:
    s = world("(lit hall)")
    eff = parse_effect("(and (not (lit hall)) (when (lit hall) (lit lab)))", ev.domain)
    after = ev.apply(eff, s)
    assert Atom("lit", ("lab",)) in after and Atom("lit", ("hall",)) not in after
    forall = parse_effect("(forall (?p - place) (lit ?p))", ev.domain)
    lit = ev.apply(forall, world())
    assert lit.tuples("lit") == {("base",), ("hall",), ("lab",), ("roof",)}


def test_ground_action(ev: Evaluator) -> None:
    s = world(
        "(at d1 hall)",
        "(link hall lab)",
        fluents={("dist", ("hall", "lab")): 4.0, ("battery", ("d1",)): 100.0},
    )
    fly = ev.ground_action("fly", ["D1", "hall", "lab"], s)
    assert fly.full_name == "(fly d1 hall lab)" and fly.durative and fly.duration == 8.0
    assert ev.holds(fly.at_start, s, duration=fly.duration)
    assert ev.holds(fly.over_all, s)
    after_start = ev.apply(fly.start_effect, s, duration=fly.duration)
    after_end = ev.apply(fly.end_effect, after_start, duration=fly.duration)
    assert Atom("at", ("d1", "lab")) in after_end and after_end.value("battery", ("d1",)) == 88
    assert ev.ground_action("fly", ["d1", "hall", "lab"]).duration is None  # needs a state
    drive = ev.ground_action(ev.get_action("drive"), ["r1", "hall", "lab"])
    assert not drive.durative and drive.duration is None
    assert drive.over_all == And((Atom("at", ("r1", "hall")), Atom("link", ("hall", "lab"))))
    assert drive.at_start == And(()) and drive.start_effect == AndEffect(())
    with pytest.raises(KnowledgeError, match="takes 3 arguments"):
        ev.ground_action("drive", ["r1"])
    with pytest.raises(KnowledgeError, match="d1 is a drone"):
        ev.ground_action("drive", ["d1", "hall", "lab"], s)
    with pytest.raises(KnowledgeError, match="unknown object 'mars'"):
        ev.ground_action("drive", ["r1", "hall", "mars"], s)
    with pytest.raises(KnowledgeError, match="unknown action"):
        ev.ground_action("teleport", [])


def test_condition_and_effect_atoms(ev: Evaluator) -> None:
    drive = ev.ground_action("drive", ["r1", "hall", "lab"])
    pos, neg = ev.condition_atoms(drive.over_all)
    assert pos == {Atom("at", ("r1", "hall")), Atom("link", ("hall", "lab"))} and neg == set()
    s = world("(carrying r1 c1)")
    adds, deletes, numeric = ev.effect_atoms(drive.end_effect, {}, s)
    assert adds == {Atom("at", ("r1", "lab")), Atom("on", ("c1", "lab"))}
    assert deletes == {Atom("at", ("r1", "hall")), Atom("on", ("c1", "hall"))}
    assert numeric == {("moves", ())}
    # derived atoms are replaced by the base facts that make them true in the state
    fly = ev.ground_action("fly", ["d1", "hall", "lab"])
    s = world("(link hall lab)", "(link hall roof)")
    pos, neg = ev.condition_atoms(fly.over_all, {}, s)
    assert pos == {Atom("link", ("hall", "lab"))}
    assert ev.condition_fluents(fly.at_start) == {("battery", ("d1",))}
    pos, neg = ev.condition_atoms(cond(ev, "(not (or (at r1 hall) (lit lab)))"))
    assert pos == set() and neg == {Atom("at", ("r1", "hall")), Atom("lit", ("lab",))}


def test_satisfying_bindings(ev: Evaluator) -> None:
    s = world("(link hall lab)", "(link lab roof)", "(link hall roof)")
    found = list(
        ev.satisfying_bindings(
            cond(ev, "(reach hall ?b)", {"?b": ("place",)}), s, [TypedName("?b", ("place",))]
        )
    )
    assert sorted(b["?b"] for b in found) == ["lab", "roof"]


# ------------------------------------------------------------------ properties

PLACES = ["hall", "lab", "roof", "base"]
facts = st.sets(
    st.tuples(st.sampled_from(PLACES), st.sampled_from(PLACES)).map(lambda t: Atom("link", t)),
    max_size=12,
)


@settings(max_examples=60, deadline=None)
@given(start=facts, added=facts, deleted=facts)
def test_apply_then_holds(
    ev: Evaluator, start: set[Atom], added: set[Atom], deleted: set[Atom]
) -> None:
    s = State(start, {}, {p: "place" for p in PLACES})
    effect = AndEffect(tuple(DeleteEffect(a) for a in deleted) + tuple(AddEffect(a) for a in added))
    after = ev.apply(effect, s)
    assert after.facts == (start - deleted) | added
    for atom in added:
        assert ev.holds(atom, after)
    for atom in deleted - added:
        assert ev.holds(Not(atom), after)


@settings(max_examples=40, deadline=None)
@given(links=facts)
def test_reach_is_transitive_closure(ev: Evaluator, links: set[Atom]) -> None:
    s = State(links, {}, {p: "place" for p in PLACES})
    closure = {a.args for a in links}
    while True:
        more = {(a, d) for a, b in closure for c, d in closure if b == c} - closure
        if not more:
            break
        closure |= more
    assert set(ev.derived_facts(s)["reach"]) == closure
    for p in PLACES:
        expected = all(q == p or (p, q) not in closure for q in PLACES)
        assert ev.holds(Atom("isolated", (p,)), s) == expected


def test_exists_after_an_atom_in_a_conjunction(ev: Evaluator) -> None:
    """The join keeps conjuncts it set aside when it opens an ``exists``."""
    s = world("(at r1 hall)", "(link roof lab)", "(lit roof)")
    c = cond(
        ev,
        "(exists (?r - robot ?p - place)"
        " (and (at ?r ?p) (lit ?p) (exists (?q - place) (link ?p ?q))))",
    )
    assert not ev.holds(c, s)  # r1 is in the hall, which is not lit
    assert ev.holds(c, s.with_changes(adds=[Atom("at", ("r2", "roof"))]))
    d = cond(
        ev,
        "(exists (?p - place) (and (or (lit ?p) (at r2 ?p)) (exists (?q - place) (link ?p ?q))))",
    )
    s2 = world("(link hall lab)", "(lit roof)")
    assert not ev.holds(d, s2)
    assert ev.holds(d, s2.with_changes(adds=[Atom("at", ("r2", "hall"))]))


@pytest.mark.parametrize(
    ("text", "value", "expected"),
    [
        # PlanSys2's utils_test expression cases
        ("(>= (moves) 3.0)", 2.9999, False),
        ("(>= (moves) 3.0)", 4.0, True),
        ("(>= (moves) 3.0)", 3.0, True),
        ("(> (moves) 3.0)", 3.0, False),
        ("(> (moves) 3.0)", 3.00001, True),
        ("(<= (moves) -3.0)", -2.9999, False),
        ("(<= (moves) -3.0)", -4.0, True),
        ("(<= (moves) -3.0)", -3.0, True),
        ("(< (moves) -3.0)", -3.0, False),
        ("(< (moves) -3.0)", -3.00001, True),
        ("(= (* (moves) 3.0) 9)", 3.0, True),
        ("(= (* (moves) 3.0) -0.003)", -0.001, True),
        ("(= (/ (moves) 3.0) -3)", -9.0, True),
        ("(= (+ (moves) 0.1) 0.3)", 0.2, True),  # float rounding does not break equality
    ],
)
def test_numeric_expressions_like_plansys2(
    ev: Evaluator, text: str, value: float, expected: bool
) -> None:
    s = world(fluents={("moves", ()): value})
    assert ev.holds(cond(ev, text), s) is expected


def test_one_evaluator_shared_by_threads(ev: Evaluator) -> None:
    """The executor, the validator and the knowledge share an evaluator across threads."""
    import threading

    links = [Atom("link", (a, b)) for a, b in (("hall", "lab"), ("lab", "roof"), ("roof", "base"))]
    query = cond(
        ev, "(forall (?p - place) (imply (reach hall ?p) (exists (?q - place) (link ?q ?p))))"
    )
    results: list[bool] = []

    def work() -> None:
        for i in range(60):
            s = world(*(str(a) for a in links[: 1 + i % 3]))
            results.append(ev.holds(query, s) and ev.holds(Atom("reach", ("hall", "lab")), s))

    threads = [threading.Thread(target=work) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == [True] * 240
