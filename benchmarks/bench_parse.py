"""Parse speed: plansys-bridge's PDDL parser against the ``pddl`` package and
unified-planning's PDDLReader, on PlanSys2's corpus and on a large generated task.

Run:  python benchmarks/bench_parse.py [--repeat 5] [--objects 5000]

Each number is the best of ``--repeat`` runs (seconds), every parser parsing the
same text from memory. Ratios are peer time / our time, so > 1 means we are
faster. Ours includes the semantic checks (types, arity, objects) it always runs;
the ``pddl`` package is timed twice: through its public ``parse_domain`` /
``parse_problem`` functions (which build a new lark parser per call) and with
parser objects built once and reused (its fastest use). Files a peer cannot
parse (most of the corpus is temporal PDDL, which ``pddl`` does not support) show
the error class instead of a time and are left out of that peer's totals. For
PDDLReader, empty ``(:functions )`` sections are removed before timing (it rejects
them; PlanSys2's domains have many). The first two columns are our own pipeline
with lark's contextual lexer and parse loop, and with lark's parse loop under our
lexer: the figures the hand-written lexer and LALR driver are kept for.
"""

from __future__ import annotations

import argparse
import os
import random
import re
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from bench_support import FIXTURES
from lark import Lark

from plansys_bridge.errors import PddlError
from plansys_bridge.pddl import parser as pddl_parser
from plansys_bridge.pddl.model import Domain
from plansys_bridge.pddl.parser import parse_domain, parse_problem

BROKEN = re.compile(r"error|problem_unexpected_syntax|problem_simple_3|domain_simple_derived")

# ---------------------------------------------------------------- generated task


def generate_task(objects: int, seed: int = 7) -> tuple[str, str]:
    """A typed logistics-like domain with many predicates/actions and a problem with
    ``objects`` objects and about four facts per object."""
    rng = random.Random(seed)
    n_kinds = 40
    kinds = [f"kind{i}" for i in range(n_kinds)]
    types = "\n    ".join(["location vehicle package - object"] + [f"{k} - package" for k in kinds])
    preds = [
        "(at ?v - vehicle ?l - location)",
        "(pkg_at ?p - package ?l - location)",
        "(in ?p - package ?v - vehicle)",
        "(road ?a ?b - location)",
        "(free ?v - vehicle)",
    ]
    preds += [f"(ready_{k} ?p - {k})" for k in kinds]
    preds += [f"(done_{k} ?p - {k} ?l - location)" for k in kinds]
    actions = [
        """(:action drive
    :parameters (?v - vehicle ?from ?to - location)
    :precondition (and (at ?v ?from) (road ?from ?to) (not (= ?from ?to)))
    :effect (and (not (at ?v ?from)) (at ?v ?to)))"""
    ]
    for k in kinds:
        actions.append(
            f"""(:action load_{k}
    :parameters (?p - {k} ?v - vehicle ?l - location)
    :precondition (and (pkg_at ?p ?l) (at ?v ?l) (free ?v) (ready_{k} ?p))
    :effect (and (not (pkg_at ?p ?l)) (in ?p ?v) (not (free ?v))))
  (:action unload_{k}
    :parameters (?p - {k} ?v - vehicle ?l - location)
    :precondition (and (in ?p ?v) (at ?v ?l)
                       (or (road ?l ?l) (exists (?o - location) (road ?o ?l))))
    :effect (and (pkg_at ?p ?l) (not (in ?p ?v)) (free ?v) (done_{k} ?p ?l)))"""
        )
    domain = (
        "(define (domain generated)\n"
        "  (:requirements :strips :typing :negative-preconditions :equality "
        ":disjunctive-preconditions :existential-preconditions)\n"
        f"  (:types\n    {types})\n"
        "  (:predicates\n    " + "\n    ".join(preds) + ")\n  " + "\n  ".join(actions) + "\n)\n"
    )
    n_loc = max(objects // 10, 2)
    n_veh = max(objects // 10, 1)
    n_pkg = max(objects - n_loc - n_veh, 1)
    locs = [f"loc{i}" for i in range(n_loc)]
    vehs = [f"truck{i}" for i in range(n_veh)]
    pkgs = [(f"pkg{i}", kinds[i % n_kinds]) for i in range(n_pkg)]
    obj_lines = [" ".join(locs) + " - location", " ".join(vehs) + " - vehicle"]
    obj_lines += [f"{p} - {k}" for p, k in pkgs]
    init = [f"(road {locs[i]} {locs[(i + 1) % n_loc]})" for i in range(n_loc)]
    init += [f"(road {rng.choice(locs)} {rng.choice(locs)})" for _ in range(n_loc * 3)]
    init += [f"(at {v} {rng.choice(locs)})" for v in vehs]
    init += [f"(free {v})" for v in vehs]
    init += [f"(pkg_at {p} {rng.choice(locs)})" for p, _ in pkgs]
    init += [f"(ready_{k} {p})" for p, k in pkgs]
    goal = [f"(done_{k} {p} {rng.choice(locs)})" for p, k in pkgs[:: max(n_pkg // 200, 1)]]
    problem = (
        "(define (problem generated-1)\n  (:domain generated)\n"
        "  (:objects\n    " + "\n    ".join(obj_lines) + ")\n"
        "  (:init\n    " + "\n    ".join(init) + ")\n"
        "  (:goal (and\n    " + "\n    ".join(goal) + ")))\n"
    )
    return domain, problem


# ---------------------------------------------------------------- parsers


Runner = Callable[[str, str | None], object]
"""Parse a domain text and, when given, a problem text."""


def _ours(domain_text: str, problem_text: str | None) -> object:
    domain = parse_domain(domain_text, "domain.pddl")
    if problem_text is None:
        return domain
    return parse_problem(problem_text, domain, "problem.pddl")


_lark_parsers: dict[str, Any] = {}


def _ours_with(which: str) -> Runner:
    """Our whole pipeline (same grammar, builder and checks) with lark doing more of
    the work: ``lark`` is lark's own contextual lexer and parse loop, ``loop`` our
    lexer under lark's parse loop. Shows what the hand-written lexer
    (pddl/lexer.py) and LALR driver (pddl/driver.py) are worth."""

    def run(domain_text: str, problem_text: str | None) -> object:
        if which not in _lark_parsers:
            if which == "lark":
                grammar = resources.files("plansys_bridge.pddl").joinpath("grammar.lark")
                _lark_parsers[which] = Lark(
                    grammar.read_text("utf-8"),
                    parser="lalr",
                    lexer="contextual",
                    start=list(pddl_parser._STARTS),
                    transformer=pddl_parser._builder,
                    maybe_placeholders=False,
                )
            else:
                _lark_parsers[which] = pddl_parser._parser()
        saved = pddl_parser._get_driver()
        pddl_parser._driver = _lark_parsers[which]
        try:
            return _ours(domain_text, problem_text)
        finally:
            pddl_parser._driver = saved

    return run


def _pddl_public(domain_text: str, problem_text: str | None) -> object:
    import pddl

    with tempfile.TemporaryDirectory() as tmp:
        dpath = os.path.join(tmp, "domain.pddl")
        Path(dpath).write_text(domain_text)
        result: object = pddl.parse_domain(dpath)
        if problem_text is not None:
            ppath = os.path.join(tmp, "problem.pddl")
            Path(ppath).write_text(problem_text)
            result = pddl.parse_problem(ppath)
    return result


_pddl_parsers: dict[str, object] = {}


def _pddl_reused(domain_text: str, problem_text: str | None) -> object:
    from pddl.parser.domain import DomainParser
    from pddl.parser.problem import ProblemParser

    if not _pddl_parsers:
        _pddl_parsers["domain"] = DomainParser()
        _pddl_parsers["problem"] = ProblemParser()
    result = _pddl_parsers["domain"](domain_text)  # type: ignore[operator]
    if problem_text is not None:
        result = _pddl_parsers["problem"](problem_text)  # type: ignore[operator]
    return result


def _up(domain_text: str, problem_text: str | None) -> object:
    from unified_planning.io import PDDLReader

    return PDDLReader().parse_problem_string(domain_text, problem_text)


_EMPTY_FUNCTIONS = re.compile(r"\(\s*:functions(?:\s+|;[^\n]*)*\)", re.IGNORECASE)


def _up_friendly(text: str | None) -> str | None:
    """PDDLReader rejects an empty ``(:functions )``, which PlanSys2 domains often
    have; drop it (outside the timed region) so more of the corpus compares."""
    return None if text is None else _EMPTY_FUNCTIONS.sub("", text)


def _same(text: str | None) -> str | None:
    return text


PEERS: list[tuple[str, Runner, Callable[[str | None], str | None]]] = [
    ("ours, lark's lexer and loop", _ours_with("lark"), _same),
    ("ours, lark's parse loop", _ours_with("loop"), _same),
    ("pddl (reused parser)", _pddl_reused, _same),
    ("pddl (parse_domain/problem)", _pddl_public, _same),
    ("unified-planning PDDLReader", _up, _up_friendly),
]


def peer_times(domain_text: str, problem_text: str | None, repeat: int) -> list[float | str]:
    out: list[float | str] = []
    for _, run, adapt in PEERS:
        dtext = adapt(domain_text)
        assert dtext is not None
        out.append(best_time(run, dtext, adapt(problem_text), repeat))
    return out


@dataclass
class Row:
    label: str
    ours: float
    peers: list[float | str] = field(default_factory=list)


def best_time(run: Runner, domain_text: str, problem_text: str | None, repeat: int) -> float | str:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        try:
            run(domain_text, problem_text)
        except Exception as exc:  # a peer rejecting a file is a result, not a crash
            return type(exc).__name__
        best = min(best, time.perf_counter() - start)
    return best


# ---------------------------------------------------------------- corpus


def corpus_tasks(corpus: Path) -> list[tuple[str, str, str | None]]:
    """(label, domain text, problem text or None) for every valid corpus file."""
    domains: dict[Path, tuple[str, Domain]] = {}
    problems: list[Path] = []
    for path in sorted(corpus.rglob("*.pddl")):
        if BROKEN.search(path.name):
            continue
        text = path.read_text(encoding="utf-8")
        if re.search(r"\(\s*define\s*\(\s*problem", text, re.IGNORECASE):
            problems.append(path)
            continue
        try:
            domains[path] = (text, parse_domain(text, str(path)))
        except PddlError:
            continue
    tasks: list[tuple[str, str, str | None]] = [
        (path.relative_to(corpus).as_posix(), text, None) for path, (text, _) in domains.items()
    ]
    for path in problems:
        text = path.read_text(encoding="utf-8")
        ordered = sorted(domains.items(), key=lambda kv: kv[0].parent != path.parent)
        for dpath, (dtext, domain) in ordered:
            try:
                parse_problem(text, domain)
            except PddlError:
                continue
            tasks.append((f"{path.relative_to(corpus).as_posix()} + {dpath.name}", dtext, text))
            break
    return tasks


# ---------------------------------------------------------------- report


def _fmt(value: float | str, ours: float) -> str:
    if isinstance(value, str):
        return f"{'n/a (' + value + ')':>26}"
    return f"{value * 1e3:9.2f} ms  x{value / ours:7.1f}    "


def print_table(title: str, rows: list[Row]) -> None:
    names = [name for name, _, _ in PEERS]
    print(f"\n== {title}")
    print(f"{'':58} {'ours':>10}  " + "  ".join(f"{n[:26]:>26}" for n in names))
    for row in rows:
        cells = "  ".join(_fmt(p, row.ours) for p in row.peers)
        print(f"{row.label[:58]:58} {row.ours * 1e3:7.2f} ms  {cells}")


def print_totals(rows: list[Row]) -> None:
    print("\n== totals (ratio = peer / ours over the files that peer parsed)")
    for index, (name, _, _) in enumerate(PEERS):
        both = [(r.ours, r.peers[index]) for r in rows if not isinstance(r.peers[index], str)]
        if not both:
            print(f"{name:32} parsed none of these")
            continue
        ours = sum(o for o, _ in both)
        peer = sum(float(p) for _, p in both)
        print(
            f"{name:32} {len(both):3}/{len(rows)} files  ours {ours * 1e3:9.2f} ms  "
            f"peer {peer * 1e3:9.2f} ms  peer/ours x{peer / ours:.1f}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per measurement (best kept)")
    parser.add_argument("--objects", type=int, default=5000, help="objects in the large problem")
    parser.add_argument("--corpus", type=Path, default=FIXTURES)
    parser.add_argument("--skip-corpus", action="store_true")
    args = parser.parse_args(argv)
    sys.setrecursionlimit(10000)
    _ours(*generate_task(20))  # build our parser once, as a long-running process would

    if not args.skip_corpus:
        rows: list[Row] = []
        for label, dtext, ptext in corpus_tasks(args.corpus):
            ours = best_time(_ours, dtext, ptext, args.repeat)
            assert isinstance(ours, float), f"our parser failed on {label}: {ours}"
            rows.append(Row(label, ours, peer_times(dtext, ptext, args.repeat)))
        print_table("PlanSys2 corpus (domain alone, or problem + its domain)", rows)
        print_totals(rows)

    dtext, ptext = generate_task(args.objects)
    ours_d = best_time(_ours, dtext, None, args.repeat)
    ours_dp = best_time(_ours, dtext, ptext, args.repeat)
    assert isinstance(ours_d, float) and isinstance(ours_dp, float)
    facts = ptext.count("\n    (")
    large = [
        Row(f"generated domain ({dtext.count(':action')} actions)", ours_d,
            peer_times(dtext, None, args.repeat)),
        Row(f"generated domain + problem ({args.objects} objects, ~{facts} facts)", ours_dp,
            peer_times(dtext, ptext, max(1, args.repeat // 2))),
    ]  # fmt: skip
    print_table("large generated task", large)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
