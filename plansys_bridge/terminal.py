"""An interactive terminal over the knowledge, the planner and the executor.

It speaks PlanSys2's ``plansys2_terminal`` language, so the ``commands`` files
shipped with PlanSys2's examples can be ``source``d as they are::

    get model types|predicates|functions|actions|predicate X|function X|action X
    get problem instances|predicates|functions|goal      get problem   get domain
    get plan
    set instance NAME TYPE        set predicate (p a b)    set function (= (f a) 3)
    set goal (and ...)
    remove instance NAME | predicate (p a b) | function (f a) | goal
    run | run num_actions N | run action (a x y) | run (a x y) | run plan-file FILE
    check actors     source FILE     help     quit

Why the shape: :meth:`Terminal.execute_line` takes one line and returns the text to
show, and never raises for bad input (an error line is returned instead), so the
REPL, ``source`` and tests all share it. Planning and execution are reached through
factories given by the caller (the CLI wires the embedded planner and a mission
executor); when one is missing the terminal says so instead of failing.
"""

from __future__ import annotations

import contextlib
import shlex
import sys
from collections.abc import Callable, Collection, Iterable
from pathlib import Path
from typing import Any, Protocol, TextIO

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Action, AnyAction, Domain, Problem, TypedName
from plansys_bridge.planning.plan import Plan, PlanStep, format_plan, parse_action_text, parse_plan
from plansys_bridge.textfile import read_text

__all__ = ["HELP", "Terminal", "TerminalError"]


class TerminalError(PlansysBridgeError):
    """A terminal command is malformed or cannot be carried out."""


class _Planner(Protocol):
    def solve(self, domain: Domain, problem: Problem) -> Any: ...


PlannerFactory = Callable[[], _Planner]
"""Returns an object with ``solve(domain, problem) -> PlanResult``."""

ExecutorFactory = Callable[[Plan], object]
"""Executes a plan to its end; the returned result is shown with ``str()``."""

HELP = """\
Commands:
  get model types | predicates | functions | actions
  get model predicate NAME | function NAME | action NAME
  get problem instances | predicates | functions | goal
  get problem                   the knowledge as a PDDL problem
  get domain                    the (merged) domain as PDDL
  get plan                      plan from the current knowledge to the goal
  set instance NAME TYPE
  set predicate (p a b)
  set function (= (f a b) 3)
  set goal (and (p a b) ...)
  remove instance NAME | predicate (p a b) | function (f a b) | goal
  run                           plan and execute
  run num_actions N             plan and execute the first N actions
  run action (a x y)            execute one action (also: run (a x y))
  run plan-file FILE            execute a plan file
  check actors                  the action performers that are alive
  source FILE                   run the commands in FILE
  help                          this text
  quit                          leave (also: exit, Ctrl-D)"""


class Terminal:
    """Executes terminal commands against a problem expert (see module docs)."""

    def __init__(
        self,
        domain_expert: DomainExpert,
        problem_expert: ProblemExpert,
        planner_factory: PlannerFactory | None = None,
        executor_factory: ExecutorFactory | None = None,
        out: TextIO | None = None,
        *,
        actors: Callable[[], Iterable[str]] | None = None,
        base_dir: Path | None = None,
        problem_name: str = "problem",
    ) -> None:
        self.domain_expert = domain_expert
        self.problem_expert = problem_expert
        self.planner_factory = planner_factory
        self.executor_factory = executor_factory
        self.actors = actors
        self.out = out if out is not None else sys.stdout
        self.base_dir = base_dir if base_dir is not None else Path.cwd()
        self.problem_name = problem_name
        self.finished = False
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
        """Read commands until ``quit`` or end of input; returns an exit code.

        The prompt is shown only when the input is a terminal (so piped command files
        produce clean output); on a terminal, line editing and history are on and
        Ctrl-C abandons the line being typed instead of ending the session.
        """
        source = inp if inp is not None else sys.stdin
        interactive = source is sys.stdin and source.isatty()
        if prompt is None:
            prompt = "> " if source.isatty() else ""
        if interactive:
            with contextlib.suppress(ImportError):
                import readline  # noqa: F401  (enables editing and history for input())
        while not self.finished:
            if interactive:
                try:
                    line = input(prompt)
                except EOFError:
                    break
                except KeyboardInterrupt:
                    self.out.write("\n")
                    continue
            else:
                if prompt:
                    self.out.write(prompt)
                    self.out.flush()
                line = source.readline()
                if not line:
                    break
            result = self.execute_line(line)
            if result:
                self.out.write(result + "\n")
                self.out.flush()
        return 0

    def source(self, path: str | Path, skip: Collection[str] = ()) -> str:
        """Run every line of a commands file; returns the collected output.

        Lines whose command word is in ``skip`` (``{"run"}`` to only build the
        knowledge) are passed over.
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
                result = self.execute_line(line)
                if result.startswith(("error:", "internal error:")):
                    result = f"{file}:{number}: {result}"
                if result:
                    outputs.append(result)
        finally:
            self._sourcing.pop()
        return "\n".join(outputs)

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
            if not rest:
                raise TerminalError("usage: source FILE")
            return self.source(_unquote(rest))
        if command == "help":
            return HELP
        if command in ("quit", "exit"):
            self.finished = True
            return ""
        shown = head if len(head) <= 40 else head[:40] + "..."  # binary fed to stdin
        raise TerminalError(f"unknown command {shown!r} (try: help)")

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
            "usage: get model types|predicates|functions|actions|predicate X|function X|"
            "action X, get problem [instances|predicates|functions|goal], get domain, get plan"
        )

    def _get_model(self, what: str, names: list[str]) -> str:
        de = self.domain_expert
        if what == "types" and not names:
            types = de.get_types()
            return _listing("Types", types)
        if what == "predicates" and not names:
            return _listing(
                "Predicates", [_signature(p.name, p.parameters) for p in de.get_predicates()]
            )
        if what == "functions" and not names:
            return _listing(
                "Functions", [_signature(f.name, f.parameters) for f in de.get_functions()]
            )
        if what == "actions" and not names:
            items = [f"{a.name} (action)" for a in de.get_actions()]
            items += [f"{a.name} (durative action)" for a in de.get_durative_actions()]
            return _listing("Actions", items)
        if what == "predicate" and len(names) == 1:
            pred = de.get_predicate(names[0])
            if pred is None:
                raise TerminalError(f"unknown predicate {names[0]!r}")
            derived = " (derived)" if de.is_derived(pred.name) else ""
            return _listing(f"Predicate {pred.name}{derived} parameters", _params(pred.parameters))
        if what == "function" and len(names) == 1:
            func = de.get_function(names[0])
            if func is None:
                raise TerminalError(f"unknown function {names[0]!r}")
            return _listing(f"Function {func.name} parameters", _params(func.parameters))
        if what == "action" and len(names) == 1:
            action = de.get_action(names[0])
            if action is None:
                raise TerminalError(f"unknown action {names[0]!r}")
            return _describe_action(action)
        raise TerminalError(
            "usage: get model types|predicates|functions|actions|predicate X|function X|action X"
        )

    def _get_problem(self, what: str) -> str:
        from plansys_bridge.pddl.writer import write_condition, write_fluent_value

        pe = self.problem_expert
        if what == "instances":
            return _listing("Instances", [f"{n}\t{t}" for n, t in pe.get_instances().items()])
        if what == "predicates":
            return _listing("Predicates", [str(a) for a in pe.get_predicates()], indent="")
        if what == "functions":
            return _listing(
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

    def _execute(self, plan: Plan) -> str:
        assert self.executor_factory is not None
        result = self.executor_factory(plan)
        return str(result) if result is not None else ""

    def _run(self, rest: str) -> str:
        words = rest.split()
        if self.executor_factory is None:
            raise TerminalError(
                "no executor is configured: this terminal can plan (get plan) but not run; "
                "start it with a mission to execute"
            )
        if not words:
            return self._execute(self._solve().plan)
        kind = words[0].lower()
        if kind == "num_actions":
            if len(words) != 2 or not words[1].isdigit():
                raise TerminalError("usage: run num_actions N")
            count = int(words[1])
            plan = Plan(self._solve().plan.sorted().steps[:count])
            return self._execute(plan)
        if kind == "plan-file":
            if len(words) < 2:
                raise TerminalError("usage: run plan-file FILE")
            file = self._resolve(_unquote(rest.split(None, 1)[1]))
            return self._execute(parse_plan(read_text(file, "plan file"), str(file)))
        action_text = rest.split(None, 1)[1] if kind == "action" and len(words) > 1 else rest
        if not action_text.startswith("("):
            raise TerminalError(
                "usage: run | run num_actions N | run action (a x y) | run plan-file F"
            )
        name, args = parse_action_text(action_text)
        ground = self.domain_expert.evaluator.ground_action(name, args, self.problem_expert.state())
        duration = ground.duration if ground.duration is not None else 1.0
        return self._execute(Plan((PlanStep(0.0, name, args, duration),)))

    def _check_actors(self) -> str:
        if self.actors is None:
            return "no hub is connected: no action performers are known"
        names = sorted(self.actors())
        return _listing("Actors", names)

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


def _listing(title: str, items: list[str], indent: str = "\t") -> str:
    return "\n".join([f"{title}: {len(items)}", *(indent + i for i in items)])


def _params(params: tuple[TypedName, ...]) -> list[str]:
    return [f"{p.name} - {_types(p.types)}" for p in params]


def _types(types: tuple[str, ...]) -> str:
    return types[0] if len(types) == 1 else "(either " + " ".join(types) + ")"


def _signature(name: str, params: tuple[TypedName, ...]) -> str:
    return "(" + " ".join([name, *_params(params)]) + ")"


def _describe_action(action: AnyAction) -> str:
    from plansys_bridge.pddl.writer import write_condition, write_effect, write_num_expr

    lines = [
        f"Type: {'action' if isinstance(action, Action) else 'durative-action'}",
        f"Name: {action.name}",
        _listing("Parameters", _params(action.parameters)),
    ]
    if isinstance(action, Action):
        lines.append(f"Precondition: {write_condition(action.precondition)}")
        lines.append(f"Effect: {write_effect(action.effect)}")
    else:
        for constraint in action.duration:
            lines.append(
                f"Duration: ({constraint.op} ?duration {write_num_expr(constraint.value)})"
            )
        lines.append(f"At start requirements: {write_condition(action.at_start)}")
        lines.append(f"Over all requirements: {write_condition(action.over_all)}")
        lines.append(f"At end requirements: {write_condition(action.at_end)}")
        lines.append(f"At start effect: {write_effect(action.start_effect)}")
        lines.append(f"At end effect: {write_effect(action.end_effect)}")
    return "\n".join(lines)
