"""Build hook: wheels carry the example missions and demo bags as package data.

configs/ (mission files, PDDL domains, DBC files) and bags/ (the generated demo bags)
stay at the top of the checkout, where users run ``plansys-bridge run configs/...``;
a built wheel copies them to ``plansys_bridge/data/`` so ``plansys-bridge demo`` and
the examples work from an installation anywhere. Editable installs read the checkout.
"""

from __future__ import annotations

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

SHIPPED = ("configs", "bags")


class BuildWithExamples(build_py):
    """build_py that also copies configs/ and bags/ into plansys_bridge/data/."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        root = Path(__file__).resolve().parent
        for name in SHIPPED:
            target = Path(self.build_lib) / "plansys_bridge" / "data" / name
            self.copy_tree(str(root / name), str(target))


setup(cmdclass={"build_py": BuildWithExamples})
