"""The PDDL walkers: every walker covers every node class, read off ``model.py``, and a
construct added as one dataclass (with a ``lower()``) works everywhere unedited."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
from dataclasses import dataclass
from pathlib import Path

import pytest

from plansys_bridge.errors import KnowledgeError, PddlSemanticError
from plansys_bridge.knowledge.formulas import free_vars, negate
from plansys_bridge.knowledge.grounding import substitute_condition, substitute_effect
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl import model
from plansys_bridge.pddl.checks import check_condition
from plansys_bridge.pddl.model import (
    And,
    AndEffect,
    Atom,
    Condition,
    Exists,
    Forall,
    Imply,
    Not,
    Or,
    TypedName,
    WhenEffect,
)
from plansys_bridge.pddl.parser import parse_condition, parse_domain
from plansys_bridge.pddl.walkers import (
    NODE_KINDS,
    NODE_TYPES,
    Collector,
    Transformer,
    Visitor,
    Walker,
    bound_variables,
    children,
    iter_nodes,
    terms,
)
from plansys_bridge.pddl.writer import write_condition
from plansys_bridge.planning.capabilities import Capability, required_capabilities
from plansys_bridge.ros2.trees import condition_tree, tree_text

BASES = "plansys_bridge.pddl.walkers"
PACKAGE = Path(__file__).resolve().parents[2] / "plansys_bridge"

# Dataclasses of model.py that are not walked: declarations, actions, whole files.
NOT_NODES = {
    "TypedName",
    "TypeDef",
    "PredicateDef",
    "FunctionDef",
    "DurationConstraint",
    "Action",
    "DurativeAction",
    "DerivedPredicate",
    "Domain",
    "FluentValue",
    "Metric",
    "Problem",
}
# Fields of a node that are neither children, terms, bound variables nor a place.
PLAIN_FIELDS = {"op", "predicate", "name", "value"}


def _model_dataclasses() -> dict[str, type]:
    return {
        name: obj
        for name, obj in vars(model).items()
        if inspect.isclass(obj)
        and dataclasses.is_dataclass(obj)
        and obj.__module__ == model.__name__
    }


def _project_walkers() -> list[type[Walker[object]]]:
    """Every walker class defined in the package (modules using the walkers imported)."""
    for path in sorted(PACKAGE.rglob("*.py")):
        if "pddl.walkers import" in path.read_text(encoding="utf-8"):
            module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
            importlib.import_module(module)
    found: list[type[Walker[object]]] = []
    stack: list[type[Walker[object]]] = [Walker]
    while stack:
        cls = stack.pop()
        for sub in cls.__subclasses__():
            stack.append(sub)
            if sub.__module__.startswith("plansys_bridge.") and sub.__module__ != BASES:
                found.append(sub)
    return found


def test_every_model_dataclass_is_a_node_or_a_declaration() -> None:
    classes = _model_dataclasses()
    nodes = {t.__name__ for t in NODE_TYPES}
    assert set(classes) == nodes | NOT_NODES, (
        "a new dataclass in model.py must join Condition, Effect or NumExpr (or NOT_NODES)"
    )


@pytest.mark.parametrize("node_type", NODE_TYPES, ids=lambda t: t.__name__)
def test_every_node_field_is_understood(node_type: type) -> None:
    """Each field is a child, a term, a bound-variable list or plain data, so generic
    walks miss nothing."""
    example = _example(node_type)
    kids = set(map(id, children(example)))
    for f in dataclasses.fields(node_type):
        value = getattr(example, f.name)
        if f.name == "loc" or f.name in PLAIN_FIELDS:
            continue
        if f.name == "variables":
            assert bound_variables(example) == tuple(v.name for v in value)
            continue
        items = value if isinstance(value, tuple) else (value,)
        if all(isinstance(v, str) for v in items):
            assert set(items) <= set(terms(example)), f"{node_type.__name__}.{f.name}"
        else:
            assert {id(v) for v in items} <= kids, f"{node_type.__name__}.{f.name}"


def test_walkers_exist_in_every_module_that_walks() -> None:
    modules = {w.__module__ for w in _project_walkers()}
    for name in (
        "plansys_bridge.knowledge.admission",
        "plansys_bridge.knowledge.formulas",
        "plansys_bridge.knowledge.grounding",
        "plansys_bridge.knowledge.inputs",
        "plansys_bridge.knowledge.plan_atoms",
        "plansys_bridge.knowledge.reasoner",
        "plansys_bridge.pddl.checks",
        "plansys_bridge.pddl.writer",
        "plansys_bridge.planning.capabilities",
        "plansys_bridge.ros2.trees",
    ):
        assert name in modules


def test_every_walker_covers_every_node_of_its_kinds() -> None:
    """A Visitor needs a method for each node class it can meet unless the node has a
    ``lower()``; Collectors and Transformers recurse on their own."""
    missing = []
    for walker in _project_walkers():
        for kind in walker.kinds:
            for node_type in NODE_KINDS[kind]:
                if walker.handles(node_type) or hasattr(node_type, "lower"):
                    continue
                if issubclass(walker, Collector | Transformer):
                    continue
                if walker.default is not Walker.default and not issubclass(walker, Visitor):
                    continue  # a walker with its own catch-all
                missing.append(f"{walker.__module__}.{walker.__qualname__}: {node_type.__name__}")
    assert not missing, "walkers without a method for a node class:\n" + "\n".join(missing)


def test_lowered_forms_mean_the_same() -> None:
    a, b = Atom("p", ("?x",)), Atom("q", ())
    assert Imply(a, b).lower() == Or((Not(a), b))
    variables = (TypedName("?x", ("room",)),)
    assert Forall(variables, a).lower() == Not(Exists(variables, Not(a)))


# ---------------------------------------------------------------- shape helpers


def test_iter_nodes_is_parents_first_in_field_order() -> None:
    cond = And((Atom("p", ("?x",)), Not(Atom("q", ()))))
    names = [type(n).__name__ for n in iter_nodes(cond)]
    assert names == ["And", "Atom", "Not", "Atom"]


def test_transformer_returns_the_same_node_when_nothing_changes() -> None:
    cond = And((Atom("p", ("a",)), Exists((TypedName("?y"),), Atom("q", ("?y",)))))
    assert Transformer().walk(cond) is cond


def test_substitution_respects_quantifier_scope() -> None:
    inner = Exists((TypedName("?x"),), Atom("p", ("?x", "?y")))
    cond = And((Atom("p", ("?x", "?y")), inner))
    got = substitute_condition(cond, {"?x": "a", "?y": "b"})
    assert got == And((Atom("p", ("a", "b")), Exists((TypedName("?x"),), Atom("p", ("?x", "b")))))
    assert free_vars(cond) == {"?x", "?y"}
    assert free_vars(inner) == {"?y"}


def test_visitor_without_method_or_lowering_names_both() -> None:
    class Texts(Visitor[str]):
        def walk_atom(self, node: Atom) -> str:
            return str(node)

    with pytest.raises(TypeError, match=r"Texts has no walk_and and And has no lower\(\)"):
        Texts().walk(And(()))


# ---------------------------------------------------------------- a new construct


@dataclass(frozen=True)
class Xor:
    """Exactly one of two conditions: defined here only, as a user would add it."""

    left: Condition
    right: Condition

    def lower(self) -> Condition:
        return Or((And((self.left, Not(self.right))), And((Not(self.left), self.right))))


def test_a_new_construct_is_walked_without_edits() -> None:
    domain = parse_domain(
        """(define (domain d) (:requirements :adl)
             (:predicates (p ?x) (q ?x)))"""
    )
    xor = Xor(Atom("p", ("?x",)), Exists((TypedName("?x"),), Atom("q", ("?x",))))
    assert children(xor) == (xor.left, xor.right)
    assert free_vars(xor) == {"?x"}
    grounded = substitute_condition(xor, {"?x": "a"})  # type: ignore[arg-type]
    assert grounded == Xor(Atom("p", ("a",)), xor.right)
    assert write_condition(grounded) == write_condition(grounded.lower())  # type: ignore[attr-defined]
    effect = WhenEffect(xor, AndEffect(()))  # type: ignore[arg-type]
    assert substitute_effect(effect, {"?x": "a"}) == WhenEffect(grounded, AndEffect(()))  # type: ignore[arg-type]
    assert negate(xor) == Not(xor)  # type: ignore[arg-type]
    goal = parse_condition("(p a)", domain)
    problem = dataclasses.replace(_problem(), goal=And((goal, xor)))  # type: ignore[arg-type]
    caps = required_capabilities(domain, problem)
    assert Capability.DISJUNCTIVE_PRECONDITIONS in caps
    assert Capability.EXISTENTIAL_PRECONDITIONS in caps


def test_a_new_construct_is_checked_stored_evaluated_and_sent_unedited() -> None:
    domain = parse_domain(
        """(define (domain d) (:requirements :adl :typing) (:types thing)
             (:predicates (p ?x - thing) (q ?x - thing)))"""
    )
    check_condition(Xor(Atom("p", ("?x",)), Atom("q", ("?x",))), domain, {"?x": ("thing",)}, {})  # type: ignore[arg-type]
    with pytest.raises(PddlSemanticError, match="unknown predicate 'r'"):
        check_condition(Xor(Atom("p", ("?x",)), Atom("r", ())), domain, {"?x": ("thing",)}, {})  # type: ignore[arg-type]
    knowledge = ProblemExpert(domain)
    knowledge.add_instance("a", "thing")
    knowledge.add_instance("b", "thing")
    knowledge.add_predicate("(p a)")
    knowledge.add_predicate("(q b)")
    goal = And(
        (Xor(Atom("p", ("a",)), Atom("q", ("a",))), Xor(Atom("p", ("b",)), Atom("q", ("b",))))
    )
    assert knowledge.set_goal(goal)  # type: ignore[arg-type]
    assert knowledge.is_goal_satisfied()
    knowledge.add_predicate("(q a)")
    assert not knowledge.is_goal_satisfied()
    with pytest.raises(KnowledgeError, match="unknown object 'c'"):
        knowledge.set_goal(Xor(Atom("p", ("c",)), Atom("q", ("a",))))  # type: ignore[arg-type]
    pos, neg = knowledge.evaluator.condition_atoms(goal, {}, knowledge.state())  # type: ignore[arg-type]
    assert Atom("p", ("a",)) in pos | neg
    tree = condition_tree(Xor(Atom("p", ("a",)), Atom("q", ("a",))))  # type: ignore[arg-type]
    assert tree_text(tree) == "(or (and (p a) (not (q a))) (and (not (p a)) (q a)))"


# ---------------------------------------------------------------- helpers


def _problem() -> model.Problem:
    return model.Problem("p", "d")


def _example(node_type: type) -> object:
    """One instance of ``node_type`` with a distinct value in every field."""
    a, b = Atom("p", ("?x", "o")), Atom("q", ("?y",))
    ref = model.FluentRef("f", ("?x",))
    examples: dict[str, object] = {
        "Atom": a,
        "Equals": model.Equals("?x", "o"),
        "Not": Not(a),
        "And": And((a, b)),
        "Or": Or((a, b)),
        "Imply": Imply(a, b),
        "Exists": Exists((TypedName("?x"),), a),
        "Forall": Forall((TypedName("?x"),), a),
        "Compare": model.Compare("<", ref, model.Number(1.0)),
        "AddEffect": model.AddEffect(a),
        "DeleteEffect": model.DeleteEffect(a),
        "NumericEffect": model.NumericEffect("increase", ref, model.Number(2.0)),
        "AndEffect": AndEffect((model.AddEffect(a), model.DeleteEffect(b))),
        "WhenEffect": WhenEffect(a, model.AddEffect(b)),
        "ForallEffect": model.ForallEffect((TypedName("?x"),), model.AddEffect(a)),
        "Number": model.Number(3.0),
        "FluentRef": ref,
        "DurationRef": model.DurationRef(),
        "BinaryOp": model.BinaryOp("+", ref, model.Number(1.0)),
        "Negate": model.Negate(ref),
    }
    return examples[node_type.__name__]
