"""An interactive terminal over the knowledge, the planner and the executor.

It speaks PlanSys2's ``plansys2_terminal`` language, so the ``commands`` files
shipped with PlanSys2's examples can be ``source``d as they are::

    get model types|predicates|functions|actions|deriveds
    get model predicate X|function X|action X|derived X
    get problem instances|predicates|functions|goal      get problem   get domain
    get plan
    set instance NAME TYPE        set predicate (p a b)    set function (= (f a) 3)
    set goal (and ...)
    remove instance NAME | predicate (p a b) | function (f a) | goal
    run | run num_actions N | run action (a x y) | run (a x y) | run plan-file FILE
    check actors     source FILE [0|1]     help|? [COMMAND]     quit

As in PlanSys2, only a bare ``run`` aims at the goal (and replans on failure);
``run action``, ``run num_actions`` and ``run plan-file`` execute exactly the
actions asked for and stop.

Why the shape: :meth:`Terminal.execute_line` takes one line and returns the text to
show, and never raises for bad input (an error line is returned instead), so the
REPL, ``source`` and tests all share it. Planning and execution are reached through
a planner factory and a :class:`~plansys_bridge.terminal.runner.Runner` given by the
caller (the CLI wires the embedded planner and a mission); when one is missing the
terminal says so instead of failing.
"""

from __future__ import annotations

import shlex
import sys
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any, Protocol, TextIO

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.planning.plan import Plan, PlanStep, format_plan, parse_action_text, parse_plan
from plansys_bridge.terminal.describe import (
    describe_action,
    describe_derived,
    listing,
    params,
    signature,
)
from plansys_bridge.terminal.help import help_text
from plansys_bridge.terminal.repl import run_repl
from plansys_bridge.terminal.runner import Runner
from plansys_bridge.textfile import read_text

__all__ = ["Terminal", "TerminalError"]


class TerminalError(PlansysBridgeError):
    """A terminal command is malformed or cannot be carried out."""


class _Planner(Protocol):
    def solve(self, domain: Domain, problem: Problem) -> Any: ...


PlannerFactory = Callable[[], _Planner]
"""Returns an object with ``solve(domain, problem) -> PlanResult``."""


class Terminal:
    """Executes terminal commands against a problem expert (see module docs)."""

    def __init__(
        self,
        domain_expert: DomainExpert,
        problem_expert: ProblemExpert,
        planner_factory: PlannerFactory | None = None,
        runner: Runner | None = None,
        out: TextIO | None = None,
        *,
        base_dir: Path | None = None,
        problem_name: str = "problem",
    ) -> None:
        self.domain_expert = domain_expert
        self.problem_expert = problem_expert
        self.planner_factory = planner_factory
        self.runner = runner
        self.out = out if out is not None else sys.stdout
        self.base_dir = base_dir if base_dir is not None else Path.cwd()
        self.problem_name = problem_name
        self.finished = False
        self.stream_source = False
        """True: ``source`` writes each command's output as it comes (a ``run`` in
        the file shows live progress, so the outputs before it must be out first)
        and returns only what is left; False: it returns all of it."""
        self._planner: _Planner | None = None
        self._sourcing: list[Path] = []

    # ================================================================ entry points

    def execute_line(self, line: str) -> str:
        """Run one command; returns what to show (errors included, never raised)."""
        text = line.strip()
        if not text or text.startswith(("#", ";")):
            return ""
        try:
            return self._dispatch(text)
        except PlansysBridgeError as exc:
            return f"error: {exc}"
        except OSError as exc:
            return f"error: {exc.filename or ''}: {exc.strerror or exc}".replace(": : ", ": ")
        except Exception as exc:  # a bug must not end the operator's session
            return f"internal error: {type(exc).__name__}: {exc}"

    def repl(self, inp: TextIO | None = None, prompt: str | None = None) -> int:
        """Read commands until ``quit`` or end of input (see :mod:`.repl`)."""
        return run_repl(self, inp, prompt)

    def source(self, path: str | Path, skip: Collection[str] = (), echo: bool = False) -> str:
        """Run every line of a commands file; returns the collected output.

        Lines whose command word is in ``skip`` (``{"run"}`` to only build the
        knowledge) are passed over; ``echo`` shows each command before its output
        (PlanSys2's ``source FILE 1``).
        """
        file = self._resolve(path)
        if file in self._sourcing:
            raise TerminalError(f"{file}: sourced recursively")
        lines = read_text(file, "command file").splitlines()
        outputs: list[str] = []
        self._sourcing.append(file)
        try:
            for number, line in enumerate(lines, start=1):
                if self.finished:
                    break
                words = line.split(None, 1)
                if words and words[0].lower() in skip:
                    continue
                if echo and line.strip():
                    outputs.append(f"> {line.strip()}")
                result = self.execute_line(line)
                if result.startswith(("error:", "internal error:")):
                    result = f"{file}:{number}: {result}"
                if result:
                    outputs.append(result)
                if self.stream_source:
                    self._write(outputs)
        finally:
            self._sourcing.pop()
        return "\n".join(outputs)

    def _write(self, outputs: list[str]) -> None:
        for text in outputs:
            self.out.write(text + "\n")
        self.out.flush()
        outputs.clear()

    # ================================================================ dispatch

    def _dispatch(self, text: str) -> str:
        head, _, rest = text.partition(" ")
        command = head.lower()
        rest = rest.strip()
        if command == "get":
            return self._get(rest)
        if command == "set":
            return self._set(rest)
        if command == "remove":
            return self._remove(rest)
        if command == "run":
            return self._run(rest)
        if command == "check":
            if rest.lower() != "actors":
                raise TerminalError("usage: check actors")
            return self._check_actors()
        if command == "source":
            return self._source_command(rest)
        if command in ("help", "?"):
            words = rest.split()
            found = help_text(words[0] if words else None)
            if found is None or len(words) > 1:
                raise TerminalError(f"no command {rest!r} (try: help)")
            return found
        if command in ("quit", "exit"):
            self.finished = True
            return ""
        shown = head if len(head) <= 40 else head[:40] + "..."  # binary fed to stdin
        raise TerminalError(f"unknown command {shown!r} (try: help)")

    def _source_command(self, rest: str) -> str:
        usage = "usage: source FILE [0|1]"
        try:
            words = shlex.split(rest)
        except ValueError:
            words = rest.split()
        if not words or len(words) > 2 or (len(words) == 2 and words[1] not in ("0", "1")):
            raise TerminalError(usage)
        return self.source(words[0], echo=len(words) == 2 and words[1] == "1")

    # ---------------------------------------------------------------- get

    def _get(self, rest: str) -> str:
        words = rest.split()
        what = [w.lower() for w in words]
        if what[:1] == ["model"] and len(what) >= 2:
            return self._get_model(what[1], what[2:])
        if what == ["problem"]:
            return self.problem_expert.get_problem_text(self.problem_name)
        if what[:1] == ["problem"] and len(what) == 2:
            return self._get_problem(what[1])
        if what == ["domain"]:
            return self.domain_expert.get_domain_text()
        if what == ["plan"]:
            result = self._solve()
            return format_plan(result.plan).rstrip("\n") or "(empty plan: the goal already holds)"
        raise TerminalError(
            "usage: get model types|predicates|functions|actions|deriveds|predicate X|function X|"
            "action X|derived X, get problem [instances|predicates|functions|goal], get domain,"
            " get plan"
        )

    def _get_model(self, what: str, names: list[str]) -> str:
        de = self.domain_expert
        if what == "types" and not names:
            types = de.get_types()
            return listing("Types", types)
        if what == "predicates" and not names:
            return listing(
                "Predicates", [signature(p.name, p.parameters) for p in de.get_predicates()]
            )
        if what == "functions" and not names:
            return listing(
                "Functions", [signature(f.name, f.parameters) for f in de.get_functions()]
            )
        if what == "deriveds" and not names:
            heads = {r.head.name: r.head for r in de.get_derived()}
            return listing(
                "Derived predicates", [signature(h.name, h.parameters) for h in heads.values()]
            )
        if what == "derived" and len(names) == 1:
            rules = de.get_derived(names[0])
            if not rules:
                raise TerminalError(f"no derived predicate {names[0]!r}")
            return describe_derived(rules)
        if what == "actions" and not names:
            items = [f"{a.name} (action)" for a in de.get_actions()]
            items += [f"{a.name} (durative action)" for a in de.get_durative_actions()]
            return listing("Actions", items)
        if what == "predicate" and len(names) == 1:
            pred = de.get_predicate(names[0])
            if pred is None:
                raise TerminalError(f"unknown predicate {names[0]!r}")
            derived = " (derived)" if de.is_derived(pred.name) else ""
            return listing(f"Predicate {pred.name}{derived} parameters", params(pred.parameters))
        if what == "function" and len(names) == 1:
            func = de.get_function(names[0])
            if func is None:
                raise TerminalError(f"unknown function {names[0]!r}")
            return listing(f"Function {func.name} parameters", params(func.parameters))
        if what == "action" and len(names) == 1:
            action = de.get_action(names[0])
            if action is None:
                raise TerminalError(f"unknown action {names[0]!r}")
            return describe_action(action)
        raise TerminalError(
            "usage: get model types|predicates|functions|actions|deriveds"
            "|predicate X|function X|action X|derived X"
        )

    def _get_problem(self, what: str) -> str:
        from plansys_bridge.pddl.writer import write_condition, write_fluent_value

        pe = self.problem_expert
        if what == "instances":
            return listing("Instances", [f"{n}\t{t}" for n, t in pe.get_instances().items()])
        if what == "predicates":
            return listing("Predicates", [str(a) for a in pe.get_predicates()], indent="")
        if what == "functions":
            return listing(
                "Functions", [write_fluent_value(f) for f in pe.get_functions()], indent=""
            )
        if what == "goal":
            goal = pe.get_goal()
            text = write_condition(goal) if goal is not None else "(none)"
            return f"Goal: {text}"
        raise TerminalError("usage: get problem instances|predicates|functions|goal")

    # ---------------------------------------------------------------- set / remove

    def _set(self, rest: str) -> str:
        kind, _, arg = rest.partition(" ")
        kind, arg = kind.lower(), arg.strip()
        pe = self.problem_expert
        if kind == "instance":
            parts = arg.split()
            if len(parts) != 2:
                raise TerminalError("usage: set instance NAME TYPE")
            if not pe.add_instance(parts[0], parts[1]):
                return f"instance {parts[0].lower()} already exists"
            return ""
        if kind == "predicate":
            if not pe.add_predicate(_atom_text(arg, "set predicate (p a b)")):
                return f"{_atom_text(arg, '')} already holds"
            return ""
        if kind == "function":
            if not arg:
                raise TerminalError("usage: set function (= (f a) 3)")
            pe.set_function(arg)
            return ""
        if kind == "goal":
            if not arg:
                raise TerminalError("usage: set goal (and ...)")
            pe.set_goal(arg)
            return ""
        raise TerminalError("usage: set instance|predicate|function|goal ...")

    def _remove(self, rest: str) -> str:
        kind, _, arg = rest.partition(" ")
        kind, arg = kind.lower(), arg.strip()
        pe = self.problem_expert
        if kind == "instance":
            parts = arg.split()
            if len(parts) not in (1, 2):  # PlanSys2 accepts "remove instance NAME TYPE" too
                raise TerminalError("usage: remove instance NAME")
            if not pe.remove_instance(parts[0]):
                return f"no instance {parts[0].lower()}"
            return ""
        if kind == "predicate":
            atom = _atom_text(arg, "remove predicate (p a b)")
            if not pe.remove_predicate(atom):
                return f"{atom} does not hold"
            return ""
        if kind == "function":
            if not arg:
                raise TerminalError("usage: remove function (f a)")
            if not pe.remove_function(arg):
                return f"function {arg} has no value"
            return ""
        if kind == "goal" and not arg:
            pe.clear_goal()
            return ""
        raise TerminalError(
            "usage: remove instance NAME | predicate (p a b) | function (f a) | goal"
        )

    # ---------------------------------------------------------------- planning / running

    def _planner_instance(self) -> _Planner:
        if self._planner is None:
            if self.planner_factory is not None:
                self._planner = self.planner_factory()
            else:
                try:
                    from plansys_bridge.planning.planner import Planner
                except ImportError as exc:
                    raise TerminalError(f"planning is not available: {exc}") from exc
                self._planner = Planner()
        return self._planner

    def _solve(self) -> Any:
        pe = self.problem_expert
        if pe.get_goal() is None:
            raise TerminalError("no goal is set (set goal (and ...))")
        result = self._planner_instance().solve(
            self.domain_expert.domain, pe.to_problem(self.problem_name)
        )
        if result.plan is None:
            status = getattr(result.status, "name", result.status)
            raise TerminalError(f"no plan found ({status}): {result.message}".rstrip(": "))
        return result

    def _run(self, rest: str) -> str:
        runner = self.runner
        if runner is None:
            raise TerminalError(
                "no executor is configured: this terminal can plan (get plan) but not run; "
                "start it with a mission to execute"
            )
        words = rest.split()
        if not words:
            return runner.execute(self._solve().plan, to_goal=True)
        kind = words[0].lower()
        if kind == "num_actions":
            if len(words) != 2 or not words[1].isdigit():
                raise TerminalError("usage: run num_actions N")
            count = int(words[1])
            # the first N as ``get plan`` lists them (same start: the plan's order)
            steps = sorted(self._solve().plan.steps, key=lambda s: s.time)
            if not 0 < count <= len(steps):
                raise TerminalError(f"cannot execute {count} actions: the plan has {len(steps)}")
            return runner.execute(Plan(tuple(steps[:count])), to_goal=False)
        if kind == "plan-file":
            if len(words) < 2:
                raise TerminalError("usage: run plan-file FILE")
            file = self._resolve(_unquote(rest.split(None, 1)[1]))
            plan = parse_plan(read_text(file, "plan file"), str(file))
            return runner.execute(plan, to_goal=False)
        action_text = rest.split(None, 1)[1] if kind == "action" and len(words) > 1 else rest
        if not action_text.startswith("("):
            raise TerminalError(
                "usage: run | run num_actions N | run action (a x y) | run plan-file F"
            )
        return runner.execute(Plan((self._ground_step(action_text),)), to_goal=False)

    def _ground_step(self, action_text: str) -> PlanStep:
        """The one-action plan for ``run action``: the action must exist, its objects
        too with the right types (the executor checks its requirements on start)."""
        name, args = parse_action_text(action_text)
        ground = self.domain_expert.evaluator.ground_action(name, args, self.problem_expert.state())
        duration = ground.duration if ground.duration is not None else 1.0
        return PlanStep(0.0, ground.name, ground.args, duration)

    def _check_actors(self) -> str:
        if self.runner is None:
            return "no hub is connected: no action performers are known"
        actors = self.runner.actors()
        return listing(
            "Actors",
            [
                f"[{a.name}] {', '.join(a.actions)}\t{a.state}\tlast seen {a.seen_ago:.1f} s ago"
                for a in sorted(actors, key=lambda a: a.name)
            ],
        )

    # ---------------------------------------------------------------- helpers

    def _resolve(self, path: str | Path) -> Path:
        file = Path(path).expanduser()
        if not file.is_absolute():
            here = self._sourcing[-1].parent if self._sourcing else self.base_dir
            file = here / file
        return file


def _unquote(text: str) -> str:
    text = text.strip()
    try:
        parts = shlex.split(text)
    except ValueError:
        return text
    return parts[0] if len(parts) == 1 else text


def _atom_text(arg: str, usage: str) -> str:
    """``(p a b)``; PlanSys2's older ``p a b`` form is accepted too."""
    text = arg.strip()
    if not text:
        raise TerminalError(f"usage: {usage}")
    return text if text.startswith("(") else f"({text})"
