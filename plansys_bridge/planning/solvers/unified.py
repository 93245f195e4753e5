"""unified-planning engines as a solver plugin (optional extra ``planners``).

The engine runs in a child Python process (:mod:`.up_worker`) so the planner's
timeout stops it even when the engine itself cannot be interrupted. Option
``engine`` names a unified-planning engine (``lpg``, ``fast-downward``, ``aries``,
``tamer``, ...); without it unified-planning picks one for the problem kind.

Declared features: classical ADL, which the engines of the ``planners`` extra plan
through unified-planning (Fast Downward). Its LPG engine cannot read LPG-td's own
plan output (the stray ``)``), so temporal tasks go to the ``lpg`` solver, which
drives the same binary directly; install a temporal engine (``up-aries``,
``up-tamer``) and pass ``engine`` to use one, knowing the planner then refuses
nothing: the engine's own error comes back in the message.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import ClassVar

from plansys_bridge.planning.capabilities import Capability
from plansys_bridge.planning.result import PlanStatus
from plansys_bridge.planning.solvers import up_worker
from plansys_bridge.planning.solvers.base import SolverOutcome
from plansys_bridge.planning.solvers.external import (
    CLASSICAL_ADL,
    ExternalSolver,
    plan_from_lines,
)
from plansys_bridge.planning.solvers.process import ProcessResult
from plansys_bridge.plugins import PluginSettings

_STATUS = {
    up_worker.EXIT_UNSOLVABLE: PlanStatus.UNSOLVABLE,
    up_worker.EXIT_TIMEOUT: PlanStatus.TIMEOUT,
    up_worker.EXIT_UNSUPPORTED: PlanStatus.UNSUPPORTED,
}


class UnifiedPlanningSolver(ExternalSolver):
    name = "unified-planning"
    capabilities: ClassVar[frozenset[Capability]] = CLASSICAL_ADL - {Capability.DERIVED_PREDICATES}

    def missing_capabilities(self, required: frozenset[Capability]) -> frozenset[Capability]:
        if "engine" in self.options:
            return frozenset()  # the named engine decides, and says so when it cannot
        return super().missing_capabilities(required)

    class Settings(PluginSettings):
        engine: str | None = None
        """The unified-planning engine by name (default: the first that fits)."""
        keep_files: bool = False

    @classmethod
    def find_executable(cls, override: str | None = None) -> Path | None:
        return Path(sys.executable)

    @classmethod
    def unavailable_reason(cls) -> str | None:
        if importlib.util.find_spec("unified_planning") is None:
            return "unified-planning is not installed: pip install 'plansys-bridge[planners]'"
        return None

    def availability(self) -> str | None:
        return self.unavailable_reason()

    def command(
        self, exe: Path, domain: Path, problem: Path, folder: Path, timeout: float
    ) -> Sequence[str | os.PathLike[str]]:
        cmd: list[str | os.PathLike[str]] = [
            exe,
            "-m",
            up_worker.__name__,
            "--timeout",
            f"{timeout:g}",
        ]
        if "engine" in self.options:
            cmd += ["--engine", str(self.options["engine"])]
        return [*cmd, domain, problem]

    def read_outcome(self, proc: ProcessResult, folder: Path) -> SolverOutcome:
        if proc.returncode == up_worker.EXIT_SOLVED:
            plan = plan_from_lines(proc.stdout, "unified-planning output")
            return SolverOutcome(PlanStatus.SOLVED, plan, _engine_line(proc.stderr))
        if proc.timed_out:
            return self.timeout_outcome(proc)
        status = _STATUS.get(proc.returncode or 0, PlanStatus.ERROR)
        return SolverOutcome(status, message=proc.describe(max_lines=5))


def _engine_line(stderr: str) -> str:
    for line in stderr.splitlines():
        if line.startswith("; engine"):
            return line[2:]
    return ""
