"""The package's import graph: layers only import downwards, and no module imports
itself back through others.

Every import counts, also those under ``TYPE_CHECKING`` and inside functions: a
cycle there is still two modules that cannot be read apart. Package ``__init__``
modules that only re-export their submodules lazily are left out (importing a
submodule runs its package's ``__init__`` first, which is not a dependency).
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

PACKAGE = Path(__file__).resolve().parents[1] / "plansys_bridge"

LAYERS = (
    "errors",
    "clock",
    "hub",
    "pddl",
    "knowledge",
    "planning",
    "performers",
    "execution",
    "mission",
    "cli",
)
"""Lowest first."""

PLACES = {
    "": "errors",  # the package's own __init__
    "textfile": "errors",
    "cancellation": "errors",  # stopping tasks; asyncio only
    "yaml_files": "clock",  # strict YAML reading with key positions (uses plugins)
    "retry": "clock",
    "plugins": "clock",
    "interfaces": "clock",  # message definitions and typestores the hub speaks
    "ros1": "clock",  # the ROS 1 wire protocol, no project types
    "testing": "performers",  # the shared suite every performer plugin passes
    "mission_config": "mission",
    "monitoring": "mission",
    "report": "mission",
    "learning": "mission",
    "bridge": "mission",
    "ros2": "mission",
    "sensing": "mission",
    "experiments": "mission",
    "scaffold": "mission",
    "terminal": "cli",
    "__main__": "cli",
}
"""Where each top-level module that is not a layer of its own sits."""

KNOWN_CYCLES: set[frozenset[str]] = set()
"""Cycles older than this test, to be taken apart; empty: the package has none."""


def _modules() -> dict[str, Path]:
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts).removesuffix(".__init__")
        found[name] = path
    return found


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    out: set[str] = set()
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            targets = [base, *(f"{base}.{alias.name}" for alias in node.names)]
        for target in targets:
            if target in modules and target != name and not name.startswith(target + "."):
                out.add(target)
    return out


def _graph() -> nx.DiGraph:
    modules = _modules()
    graph = nx.DiGraph()
    for name, path in modules.items():
        graph.add_node(name)
        for target in _imports(name, path, modules):
            if modules[target].name != "__init__.py":
                graph.add_edge(name, target)
    return graph


def _top(module: str) -> str:
    return module.split(".")[1] if "." in module else ""


def _layer(module: str) -> int | None:
    top = _top(module)
    top = PLACES.get(top, top)
    return LAYERS.index(top) if top in LAYERS else None


def test_no_new_import_cycle() -> None:
    cycles = {frozenset(c) for c in nx.simple_cycles(_graph())}
    assert cycles == KNOWN_CYCLES, sorted(sorted(c) for c in cycles ^ KNOWN_CYCLES)


def test_every_top_level_module_has_a_layer() -> None:
    unplaced = sorted({_top(m) for m in _modules() if _layer(m) is None})
    assert unplaced == [], f"add these to LAYERS or PLACES: {unplaced}"


def test_layers_import_only_downwards() -> None:
    upward = []
    for source, target in _graph().edges:
        low, high = _layer(source), _layer(target)
        if low is not None and high is not None and high > low:
            upward.append(f"{source} ({LAYERS[low]}) imports {target} ({LAYERS[high]})")
    assert upward == []
