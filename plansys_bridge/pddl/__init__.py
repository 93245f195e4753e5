"""PDDL 2.1 (plus derived predicates and ADL) model, parser and writer."""

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
