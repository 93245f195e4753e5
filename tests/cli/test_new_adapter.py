"""``plansys-bridge new-adapter``: the generated package installs and passes its tests
unchanged, and its mission runs with the new performer kind."""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

from plansys_bridge.cli import main


def _fresh_venv(where: Path) -> Path:
    """A new virtual environment that sees this one's packages (plansys-bridge and its
    dependencies, as a user's environment would have them) but none of its own."""
    venv.create(where, with_pip=False)
    python = where / "bin" / "python"
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    ours = sysconfig.get_path("purelib")
    # addsitedir also runs the .pth files there (the editable install's finder)
    (Path(purelib) / "base_env.pth").write_text(f"import site; site.addsitedir({ours!r})\n")
    return python


def test_scaffold_installs_and_passes_its_contract(tmp_path: Path) -> None:
    package = tmp_path / "gripper"
    assert main(["new-adapter", "gripper", "--dir", str(package)]) == 0
    python = _fresh_venv(tmp_path / "venv")
    install = subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps", "."],
        cwd=package,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert install.returncode == 0, install.stderr
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    tests = subprocess.run(
        [str(python), "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests"],
        cwd=package,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert tests.returncode == 0, tests.stdout + tests.stderr
    assert "7 passed" in tests.stdout
    mission = subprocess.run(
        [str(python), "-m", "plansys_bridge", "run", "mission.yaml", "--json"],
        cwd=package,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert mission.returncode == 0, mission.stdout + mission.stderr
    assert '"success": true' in mission.stdout


@pytest.mark.parametrize("name", ["Gripper", "2arm", "class", "a-b"])
def test_bad_names_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    assert main(["new-adapter", name, "--dir", str(tmp_path / "x")]) == 2
    assert "an adapter name is" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_existing_files_are_not_overwritten(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "pyproject.toml").write_text("mine")
    assert main(["new-adapter", "gripper", "--dir", str(tmp_path)]) == 2
    assert "would overwrite pyproject.toml" in capsys.readouterr().err
    assert (tmp_path / "pyproject.toml").read_text() == "mine"
