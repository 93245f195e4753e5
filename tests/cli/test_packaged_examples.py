"""The example missions ship inside the package: ``plansys-bridge demo`` works away
from the checkout, from what the build puts in a wheel (setup.py's build hook)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_demo_runs_from_a_build_outside_the_checkout(tmp_path: Path) -> None:
    lib = tmp_path / "lib"
    meta = tmp_path / "meta"  # the distribution's metadata (entry points), as a wheel has
    meta.mkdir()
    steps = ["egg_info", "--egg-base", str(meta), "build_py", "--build-lib", str(lib)]
    build = subprocess.run(
        [sys.executable, "setup.py", "-q", *steps],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert build.returncode == 0, build.stderr
    shipped = lib / "plansys_bridge" / "data"
    assert (shipped / "configs" / "demo_cooking.yaml").is_file()
    assert (shipped / "configs" / "pddl" / "cooking_domain.pddl").is_file()
    assert (shipped / "bags" / "kitchen_nav.segments.yaml").is_file()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(lib), str(meta)])}
    run = subprocess.run(
        [sys.executable, "-c", "import plansys_bridge; print(plansys_bridge.__file__)"],
        cwd=elsewhere,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert Path(run.stdout.strip()).is_relative_to(lib), run.stdout + run.stderr
    demo = subprocess.run(
        [sys.executable, "-m", "plansys_bridge", "demo", "--clock", "virtual", "--json"],
        cwd=elsewhere,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert demo.returncode == 0, demo.stderr
    summary = json.loads(demo.stdout[demo.stdout.index("{") :])
    assert summary["status"].upper() == "SUCCEEDED", summary
