"""A solver's program is looked up on PATH once per PATH, not on every solve."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from plansys_bridge.planning.solvers import external
from plansys_bridge.planning.solvers.external import PopfSolver


def test_the_program_is_looked_up_once_per_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[str] = []
    real_which = external.shutil.which

    def counting_which(name: str) -> str | None:
        calls.append(name)
        return real_which(name)

    monkeypatch.setattr(external.shutil, "which", counting_which)
    empty = tmp_path / "empty"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))
    assert PopfSolver.find_executable() is None
    assert PopfSolver.find_executable() is None
    assert calls == ["popf", "popf3"]  # the second look-up used the first one's answer

    with_popf = tmp_path / "bin"
    with_popf.mkdir()
    program = with_popf / "popf"
    program.write_text("#!/bin/sh\n")
    program.chmod(program.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("PATH", os.pathsep.join((str(with_popf), str(empty))))
    assert PopfSolver.find_executable() == program  # a new PATH is looked at again
    assert PopfSolver.find_executable() == program
    assert calls == ["popf", "popf3", "popf"]
    program.unlink()  # a cached program that went away is looked up again
    assert PopfSolver.find_executable() is None
