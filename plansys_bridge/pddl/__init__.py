"""PDDL 2.1 (plus derived predicates and ADL) model, parser and writer.

Names are imported lazily, so ``plansys_bridge.pddl.model`` does not load the
parser (and lark) for code that only handles the model.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from plansys_bridge.pddl.parser import (
        parse_atom,
        parse_condition,
        parse_domain,
        parse_domain_files,
        parse_effect,
        parse_fluent_value,
        parse_problem,
    )
    from plansys_bridge.pddl.writer import (
        write_atom,
        write_condition,
        write_domain,
        write_effect,
        write_num_expr,
        write_problem,
    )

__all__ = [
    "parse_atom",
    "parse_condition",
    "parse_domain",
    "parse_domain_files",
    "parse_effect",
    "parse_fluent_value",
    "parse_problem",
    "write_atom",
    "write_condition",
    "write_domain",
    "write_effect",
    "write_num_expr",
    "write_problem",
]

_EXPORTS = {name: "parser" if name.startswith("parse_") else "writer" for name in __all__}


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)
