"""``plansys-bridge new-adapter NAME``: the files of a new adapter package.

The package is complete as generated: a pyproject registering the performer under
the ``plansys_bridge.performers`` entry point, one performer module, a test that
runs the performer contract (:mod:`plansys_bridge.testing`) and a mission using the
new kind. ``pip install -e DIR && pytest DIR`` passes before any line is changed;
the user then replaces the body of ``execute`` with calls to the hardware.
"""

from __future__ import annotations

import keyword
import re
from pathlib import Path

from plansys_bridge.errors import ConfigError

__all__ = ["adapter_files", "write_adapter"]

_NAME = re.compile(r"[a-z][a-z0-9_]*\Z")

PYPROJECT = """\
[build-system]
requires = ["setuptools>=68", "wheel"]
build-backend = "setuptools.build_meta"

[project]
name = "plansys-bridge-{dist}"
version = "0.1.0"
description = "A plansys-bridge action performer: {name}"
requires-python = ">=3.11"
dependencies = ["plansys-bridge"]

[project.optional-dependencies]
test = ["pytest>=8"]

[project.entry-points."plansys_bridge.performers"]
{name} = "{package}.performer:{cls}"

[tool.setuptools]
packages = ["{package}"]
"""

PERFORMER = '''\
"""The ``{name}`` performer: what a mission's ``kind: {name}`` entry runs."""

from __future__ import annotations

import asyncio
from typing import Any

from pydantic import Field

from plansys_bridge.performers.base import ActionFailed, ActionGoal, ActionPerformer
from plansys_bridge.plugins import PluginSettings


class {cls}(ActionPerformer):
    """Does each action in ``steps`` steps of ``step_time`` seconds (mission time).

    Replace the loop in :meth:`execute` with the calls to your hardware; keep the
    ``self.clock.sleep`` waits (they make the virtual clock work) and the feedback.
    """

    class Settings(PluginSettings):
        """The mission-file keys of ``kind: {name}`` besides kind, name and actions;
        checked when the mission loads, errors naming file, line and key."""

        step_time: float = Field(0.5, gt=0)
        steps: int = Field(4, ge=1)

    def __init__(self, *args: Any, settings: {cls}.Settings, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.step_time = settings.step_time
        self.steps = settings.steps

    async def execute(self, goal: ActionGoal) -> str | None:
        if "broken" in goal.arguments:
            raise ActionFailed(f"{{goal.full_name}}: cannot act on 'broken'")
        for step in range(self.steps):
            await self.clock.sleep(self.step_time)
            self.feedback((step + 1) / self.steps, f"step {{step + 1}}/{{self.steps}}")
        return f"{{goal.full_name}} done"

    async def on_cancel(self, goal: ActionGoal) -> None:
        """Stop the hardware here (the running ``execute`` was already cancelled)."""
        await asyncio.sleep(0)
'''

TEST = '''\
"""The performer contract of plansys-bridge, run against ``kind: {name}``."""

from plansys_bridge.testing import PerformerContract


class Test{cls}Contract(PerformerContract):
    entry = {{"kind": "{name}", "name": "{name}_1", "actions": {{"work": ["robot1"]}}}}
    goal = ("work", ("robot1", "table"))
    failing_goal = ("work", ("robot1", "broken"))
    bad_settings = [({{"step_time": -1}}, "step_time"), ({{"colour": "red"}}, "colour")]
'''

DOMAIN = """\
(define (domain {name}_world)
  (:requirements :typing :durative-actions)
  (:types robot place)
  (:predicates (done ?p - place))
  (:durative-action work
    :parameters (?r - robot ?p - place)
    :duration (= ?duration 2)
    :effect (at end (done ?p))))
"""

MISSION = """\
# Run with: plansys-bridge run mission.yaml
name: {name}_demo
domain: domain.pddl
knowledge:
  instances: {{robot1: robot, table: place, shelf: place}}
goal: (and (done table) (done shelf))
performers:
  - {{kind: {name}, name: {name}_1, actions: {{work: [robot1]}}, step_time: 0.5, steps: 4}}
clock: {{kind: virtual}}
"""

README = """\
# plansys-bridge-{dist}

A plansys-bridge action performer, `kind: {name}`.

```sh
pip install -e '.[test]'       # registers kind '{name}' (pyproject entry point)
pytest                         # the performer contract of plansys-bridge
plansys-bridge run mission.yaml
```

Edit `{package}/performer.py`: replace the loop in `execute` with your hardware calls,
declare your mission-file settings as fields of the `Settings` model (they arrive
validated as `settings` in `__init__`) and stop the hardware in `on_cancel`.
"""


def adapter_files(name: str) -> dict[str, str]:
    """Relative path -> text of the package for performer kind ``name``."""
    if not _NAME.match(name) or keyword.iskeyword(name):
        raise ConfigError(
            "an adapter name is lower-case letters, digits and _ (starting with a letter)",
            key=repr(name),
        )
    package = f"plansys_bridge_{name}"
    values = {
        "name": name,
        "dist": name.replace("_", "-"),
        "package": package,
        "cls": "".join(part.capitalize() for part in name.split("_")) + "Performer",
    }
    templates = {
        "pyproject.toml": PYPROJECT,
        f"{package}/__init__.py": '"""The {name} performer for plansys-bridge."""\n',
        f"{package}/performer.py": PERFORMER,
        "tests/test_contract.py": TEST,
        "domain.pddl": DOMAIN,
        "mission.yaml": MISSION,
        "README.md": README,
    }
    return {path: text.format(**values) for path, text in templates.items()}


def write_adapter(name: str, folder: Path) -> list[Path]:
    """Write the package into ``folder`` (created; must not hold any of its files)."""
    files = adapter_files(name)
    clashes = [p for p in files if (folder / p).exists()]
    if clashes:
        raise ConfigError(f"would overwrite {', '.join(clashes)}", key=str(folder))
    written = []
    for rel, text in files.items():
        path = folder / rel
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
        except OSError as exc:
            raise ConfigError(f"cannot write: {exc.strerror or exc}", key=str(path)) from exc
        written.append(path)
    return written
