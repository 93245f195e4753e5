"""Solvers run as separate programs: POPF, OPTIC, TFD, LPG-td, Fast Downward, Kairos' CLI.

Each run writes ``domain.pddl`` and ``problem.pddl`` into a fresh temporary folder
(as PlanSys2's planner node does), starts the solver there with a timeout that
stops its whole process group (:mod:`.process`), and reads the plan from the
solver's output. When the solver fails, the message carries its exit status and
the tail of its stderr, so "no plan" never hides a crash or a rejected input.

Command lines and output formats follow PlanSys2's solver plugins:

- POPF: ``popf domain.pddl problem.pddl``; the plan follows "Solution Found".
- OPTIC: ``optic -N domain.pddl problem.pddl``; anytime, the last plan printed wins.
- TFD: ``tfd domain.pddl problem.pddl pddlplan``; plans in ``pddlplan.1``, ``.2``, ...
- LPG-td (binary shipped in the ``up-lpg`` wheel): ``lpg -o D -f P -n 1 -out plan``;
  upper-case plan lines ending with a stray ``)``; it separates happenings by 0.00025
  but prints four decimals, so its plans are validated with a separation of 0.0002.
- Fast Downward (``up-fast-downward`` wheel, classical only): ``fast-downward.py
  --plan-file sas_plan --alias lama-first D P``; steps are numbered 0, 1, 2, ...
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import sys
from abc import abstractmethod
from collections.abc import Sequence
from pathlib import Path
from typing import ClassVar

from pydantic import Field

from plansys_bridge.planning.capabilities import ALL_CAPABILITIES, Capability
from plansys_bridge.planning.plan import Plan, PlanFormatError, PlanStep, parse_plan
from plansys_bridge.planning.result import PlanStatus
from plansys_bridge.planning.solvers.base import PlanningTask, Solver, SolverOutcome
from plansys_bridge.planning.solvers.process import ProcessResult, run_folder, run_process
from plansys_bridge.plugins import PluginSettings

_PLAN_LINE = re.compile(r"^\s*[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?\s*:\s*\(")

_TEMPORAL = frozenset(
    {
        Capability.DURATIVE_ACTIONS,
        Capability.DURATION_INEQUALITIES,
        Capability.NUMERIC_FLUENTS,
        Capability.NEGATIVE_PRECONDITIONS,
        Capability.EQUALITY,
    }
)

CLASSICAL_ADL = frozenset(
    {
        Capability.NEGATIVE_PRECONDITIONS,
        Capability.DISJUNCTIVE_PRECONDITIONS,
        Capability.EXISTENTIAL_PRECONDITIONS,
        Capability.UNIVERSAL_PRECONDITIONS,
        Capability.CONDITIONAL_EFFECTS,
        Capability.EQUALITY,
        Capability.DERIVED_PREDICATES,
    }
)


def plan_from_lines(text: str, source: str) -> Plan:
    """The ``TIME: (action ...) [DUR]`` lines of ``text``; everything else is skipped."""
    lines = [ln for ln in text.splitlines() if _PLAN_LINE.match(ln)]
    try:
        return parse_plan("\n".join(lines), source)
    except PlanFormatError as exc:
        raise PlanFormatError(f"unreadable plan from {source}: {exc}") from exc


_FOUND: dict[tuple[type, str], Path | None] = {}
"""Where each solver class's program was found, per PATH: looking it up on every solve
cost a directory scan per PATH entry (a solver installed while the process runs, in a
folder already on PATH, is seen by the next process)."""


class ExternalSolver(Solver):
    """A solver started as a program; subclasses give the command line and the reading."""

    executables: ClassVar[tuple[str, ...]] = ()
    """Program names looked up on PATH, in order."""

    class Settings(PluginSettings):
        executable: str | None = None
        """The program to run instead of the one found on PATH."""
        keep_files: bool = False
        """Keep the run folder (PDDL written, solver output) for a look afterwards."""

    def __init__(self, options: dict[str, object] | None = None) -> None:
        super().__init__(options)

    bundled: ClassVar[tuple[str, ...]] = ()
    """``(package, *path)`` of a binary shipped inside a Python package, tried first."""
    install_hint: ClassVar[str] = ""

    @classmethod
    def find_executable(cls, override: str | None = None) -> Path | None:
        if override:
            path = Path(override).expanduser()
            return path if path.is_file() and os.access(path, os.X_OK) else None
        if cls.bundled:
            shipped = _package_file(cls.bundled[0], *cls.bundled[1:])
            if shipped is not None:
                return shipped
        key = (cls, os.environ.get("PATH", ""))
        if key in _FOUND:
            cached = _FOUND[key]
            if cached is None or cached.is_file():
                return cached
        found = next((Path(f) for name in cls.executables if (f := shutil.which(name))), None)
        _FOUND[key] = found
        return found

    @classmethod
    def unavailable_reason(cls) -> str | None:
        if cls.find_executable() is None:
            looked = ", ".join(cls.executables)
            return f"{cls.name} not found (looked for {looked} on PATH){cls.install_hint}"
        return None

    def _executable(self) -> Path | None:
        override = self.options.get("executable")
        return self.find_executable(str(override) if override else None)

    def availability(self) -> str | None:
        if self._executable() is None:
            override = self.options.get("executable")
            if override:
                return f"{self.name}: executable {override!r} does not exist or is not executable"
            return self.unavailable_reason()
        return None

    def _solve(self, task: PlanningTask, timeout: float) -> SolverOutcome:
        exe = self._executable()
        if exe is None:
            return SolverOutcome(PlanStatus.UNSUPPORTED, message=self.availability() or "")
        keep = bool(self.options.get("keep_files", False))
        with run_folder(self.name, keep=keep) as folder:
            domain_path = folder / "domain.pddl"
            problem_path = folder / "problem.pddl"
            domain_path.write_text(task.domain_text)
            problem_path.write_text(task.problem_text)
            command = self.command(exe, domain_path, problem_path, folder, timeout)
            proc = run_process(command, cwd=folder, timeout=timeout)
            outcome = self.read_outcome(proc, folder)
            if keep:
                outcome = SolverOutcome(
                    outcome.status, outcome.plan, f"{outcome.message} (files kept in {folder})"
                )
            return outcome

    @abstractmethod
    def command(
        self, exe: Path, domain: Path, problem: Path, folder: Path, timeout: float
    ) -> Sequence[str | os.PathLike[str]]:
        """The command line for one run."""

    @abstractmethod
    def read_outcome(self, proc: ProcessResult, folder: Path) -> SolverOutcome:
        """Status and plan from the finished (or stopped) process and its folder."""

    def timeout_outcome(self, proc: ProcessResult) -> SolverOutcome:
        return SolverOutcome(PlanStatus.TIMEOUT, message=proc.describe())


class _PopfLike(ExternalSolver):
    """POPF and OPTIC print the plan after ";;;; Solution Found" on stdout."""

    capabilities: ClassVar[frozenset[Capability]] = _TEMPORAL | {Capability.REQUIRED_CONCURRENCY}

    def read_outcome(self, proc: ProcessResult, folder: Path) -> SolverOutcome:
        marker = proc.stdout.rfind("Solution Found")
        if marker >= 0:
            plan = plan_from_lines(proc.stdout[marker:], f"{self.name} output")
            return SolverOutcome(PlanStatus.SOLVED, plan, proc.describe(max_lines=0))
        if proc.timed_out:
            return self.timeout_outcome(proc)
        lowered = proc.stdout.lower()
        if "unsolvable" in lowered or "no solution" in lowered:
            return SolverOutcome(PlanStatus.UNSOLVABLE, message=proc.describe(max_lines=3))
        return SolverOutcome(PlanStatus.ERROR, message=f"no plan: {proc.describe()}")


class PopfSolver(_PopfLike):
    name = "popf"
    executables = ("popf", "popf3")

    def command(
        self, exe: Path, domain: Path, problem: Path, folder: Path, timeout: float
    ) -> Sequence[str | os.PathLike[str]]:
        return [exe, domain, problem]


class OpticSolver(_PopfLike):
    name = "optic"
    executables = ("optic", "optic-cplex", "optic-clp")

    def command(
        self, exe: Path, domain: Path, problem: Path, folder: Path, timeout: float
    ) -> Sequence[str | os.PathLike[str]]:
        return [exe, "-N", domain, problem]

    def read_outcome(self, proc: ProcessResult, folder: Path) -> SolverOutcome:
        # OPTIC is anytime: when stopped by the timeout, the last plan it printed stands.
        return super().read_outcome(proc, folder)


class TfdSolver(ExternalSolver):
    name = "tfd"
    executables = ("tfd", "tfd_plan")
    capabilities: ClassVar[frozenset[Capability]] = _TEMPORAL | {Capability.CONDITIONAL_EFFECTS}

    def command(
        self, exe: Path, domain: Path, problem: Path, folder: Path, timeout: float
    ) -> Sequence[str | os.PathLike[str]]:
        return [exe, domain, problem, folder / "pddlplan"]

    def read_outcome(self, proc: ProcessResult, folder: Path) -> SolverOutcome:
        plans = sorted(
            folder.glob("pddlplan.*"),
            key=lambda p: int(p.suffix[1:]) if p.suffix[1:].isdigit() else -1,
        )
        if plans:
            plan = plan_from_lines(plans[-1].read_text(), plans[-1].name)
            return SolverOutcome(PlanStatus.SOLVED, plan, f"{len(plans)} plan(s) found")
        if proc.timed_out:
            return self.timeout_outcome(proc)
        if "no solution" in proc.stdout.lower() or "unsolvable" in proc.stdout.lower():
            return SolverOutcome(PlanStatus.UNSOLVABLE, message=proc.describe(max_lines=3))
        return SolverOutcome(PlanStatus.ERROR, message=f"no plan: {proc.describe()}")


def _package_file(package: str, *parts: str) -> Path | None:
    """A file shipped inside an installed package (solver binaries in wheels), found
    without importing the package (``up_lpg`` imports all of unified-planning)."""
    try:
        spec = importlib.util.find_spec(package)
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    path = Path(next(iter(spec.submodule_search_locations))).joinpath(*parts)
    return path if path.is_file() else None


class LpgSolver(ExternalSolver):
    name = "lpg"
    executables = ("lpg", "lpg-td")
    epsilon = 0.0002
    capabilities: ClassVar[frozenset[Capability]] = frozenset(
        {
            Capability.DURATIVE_ACTIONS,
            Capability.NUMERIC_FLUENTS,
            Capability.EQUALITY,
        }
    )

    class Settings(ExternalSolver.Settings):
        seed: int | None = None

    bundled = ("up_lpg", "lpg")
    install_hint = "; pip install 'plansys-bridge[planners]' (up-lpg)"

    def command(
        self, exe: Path, domain: Path, problem: Path, folder: Path, timeout: float
    ) -> Sequence[str | os.PathLike[str]]:
        cmd: list[str | os.PathLike[str]] = [
            exe,
            "-o",
            domain,
            "-f",
            problem,
            "-n",
            "1",
            "-out",
            folder / "plan",
            "-cputime",
            str(max(1, int(timeout))),
        ]
        if "seed" in self.options:
            cmd += ["-seed", str(self.options["seed"])]
        return cmd

    def read_outcome(self, proc: ProcessResult, folder: Path) -> SolverOutcome:
        plan_file = folder / "plan"
        if plan_file.is_file() and proc.returncode == 0:
            plan = plan_from_lines(plan_file.read_text(), "lpg plan")
            return SolverOutcome(PlanStatus.SOLVED, plan, "")
        if proc.timed_out:
            return self.timeout_outcome(proc)
        text = proc.stdout.lower()
        if "goals of the planning problem can not be reached" in text or "unsolvable" in text:
            return SolverOutcome(PlanStatus.UNSOLVABLE, message=proc.describe(max_lines=3))
        if proc.returncode == 0 and "search limit exceeded" in text:
            return SolverOutcome(
                PlanStatus.UNSOLVABLE,
                message="LPG-td gave up (search limit exceeded); it is incomplete, so a plan "
                "may still exist",
            )
        return SolverOutcome(PlanStatus.ERROR, message=f"no plan: {proc.describe()}")


class FastDownwardSolver(ExternalSolver):
    name = "fast-downward"
    executables = ("fast-downward", "fast-downward.py")
    capabilities: ClassVar[frozenset[Capability]] = CLASSICAL_ADL

    class Settings(ExternalSolver.Settings):
        alias: str | None = None

    # https://www.fast-downward.org/ExitCodes
    _UNSOLVABLE = frozenset({10, 11, 12})
    _TIMEOUT = frozenset({21, 23})

    bundled = ("up_fast_downward", "downward", "fast-downward.py")
    install_hint = "; pip install 'plansys-bridge[planners]' (up-fast-downward)"

    def command(
        self, exe: Path, domain: Path, problem: Path, folder: Path, timeout: float
    ) -> Sequence[str | os.PathLike[str]]:
        prefix: list[str | os.PathLike[str]] = [exe]
        if exe.suffix == ".py":
            prefix = [sys.executable, exe]
        return [
            *prefix,
            "--plan-file",
            folder / "sas_plan",
            "--alias",
            str(self.options.get("alias", "lama-first")),
            domain,
            problem,
        ]

    def read_outcome(self, proc: ProcessResult, folder: Path) -> SolverOutcome:
        plans = sorted(folder.glob("sas_plan*"))
        if plans and proc.returncode in (0, None):
            plan = _sequential_plan(plans[-1].read_text(), "fast-downward plan")
            return SolverOutcome(PlanStatus.SOLVED, plan, "")
        if proc.timed_out or proc.returncode in self._TIMEOUT:
            return self.timeout_outcome(proc)
        if proc.returncode in self._UNSOLVABLE:
            return SolverOutcome(PlanStatus.UNSOLVABLE, message=proc.describe(max_lines=3))
        if proc.returncode == 34:
            return SolverOutcome(PlanStatus.UNSUPPORTED, message=proc.describe())
        return SolverOutcome(PlanStatus.ERROR, message=f"no plan: {proc.describe()}")


def _sequential_plan(text: str, source: str) -> Plan:
    """``(go r a b)`` lines numbered 0, 1, 2, ... as instantaneous steps."""
    steps: list[PlanStep] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith(";"):
            continue
        try:
            step = parse_plan(f"0: {line}", f"{source}:{lineno}").steps[0]
        except PlanFormatError as exc:
            raise PlanFormatError(f"unreadable plan from {source}: {exc}") from exc
        steps.append(PlanStep(float(len(steps)), step.action, step.arguments, 0.0))
    return Plan(tuple(steps))


class KairosCliSolver(ExternalSolver):
    """Kairos run as a program: the same planner, isolated in its own process."""

    name = "kairos-cli"
    executables = ("kairos",)
    capabilities: ClassVar[frozenset[Capability]] = ALL_CAPABILITIES

    class Settings(ExternalSolver.Settings):
        threads: int = Field(1, ge=1)

    _STATUS: ClassVar[dict[int, PlanStatus]] = {
        10: PlanStatus.UNSOLVABLE,
        11: PlanStatus.TIMEOUT,
        13: PlanStatus.UNSUPPORTED,
        14: PlanStatus.UNSOLVABLE,
    }

    @classmethod
    def find_executable(cls, override: str | None = None) -> Path | None:
        if override:
            return super().find_executable(override)
        beside = Path(sys.executable).parent / "kairos"
        if beside.is_file() and os.access(beside, os.X_OK):
            return beside
        return super().find_executable()

    def command(
        self, exe: Path, domain: Path, problem: Path, folder: Path, timeout: float
    ) -> Sequence[str | os.PathLike[str]]:
        return [
            exe,
            "solve",
            domain,
            problem,
            "--no-anytime",
            "--format",
            "ipc",
            "--threads",
            str(self.options.get("threads", 1)),
            "--timeout",
            f"{timeout:g}",
            "--output",
            folder / "plan",
        ]

    def read_outcome(self, proc: ProcessResult, folder: Path) -> SolverOutcome:
        plan_file = folder / "plan"
        if proc.returncode == 0 and plan_file.is_file():
            # IPC format: timed lines for temporal plans, bare actions for classical ones
            text = plan_file.read_text()
            plan = plan_from_lines(text, "kairos plan")
            if not plan.steps:
                plan = _sequential_plan(text, "kairos plan")
            return SolverOutcome(PlanStatus.SOLVED, plan)
        if proc.timed_out:
            return self.timeout_outcome(proc)
        status = self._STATUS.get(proc.returncode or 0, PlanStatus.ERROR)
        return SolverOutcome(status, message=proc.describe(max_lines=5))
